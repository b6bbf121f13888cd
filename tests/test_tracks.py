"""The tracks stage (rotrate_cli.stages.tracks): a source's frames decoded and its points
followed, on the part of the clip asked for, as a tidy table."""

from __future__ import annotations

import cv2
import pytest

from rotrate_cli.config import AnalysisConfig
from rotrate_cli.errors import InputError
from rotrate_cli.stages import tracks


def test_the_footage_holds_tidy_tracks_of_the_part_asked_for(box_ortho) -> None:
    footage = tracks.read_footage(box_ortho.path, AnalysisConfig(fixation_px=box_ortho.fixation_px,
                                                                 start_s=1.0, end_s=2.0))
    table = footage.tracks
    assert {"frame", "time_s", "track", "x_px", "y_px"} <= set(table.columns)
    assert table["time_s"].min() >= 1.0 - 1e-9 and table["time_s"].max() <= 2.0 + 1e-9
    assert table["track"].nunique() >= 50  # a textured box: many points
    assert footage.duration_s == pytest.approx(1.0, abs=0.05)
    assert 0 <= table["x_px"].min() and table["x_px"].max() <= footage.info.width_px


def test_a_window_with_no_frame_is_a_bad_input(box_ortho) -> None:
    with pytest.raises(InputError, match="no frame"):
        tracks.read_footage(box_ortho.path, AnalysisConfig(fixation_px=box_ortho.fixation_px, start_s=60.0))


def test_videos_are_followed_with_the_window_laid_along_the_rows_and_stills_as_given(
        monkeypatch, tmp_path, box_ortho) -> None:
    """By source, as the tracker's other choices (see TrackerConfig.laid_along_rows)."""
    chosen = []
    follow = tracks.track_frames

    def noted(stream, size_px, config, *args, **kwargs):
        chosen.append(config.laid_along_rows)
        return follow(stream, size_px, config, *args, **kwargs)

    monkeypatch.setattr(tracks, "track_frames", noted)
    clip = box_ortho.path
    tracks.read_footage(clip, AnalysisConfig(fixation_px=(319.5, 179.5), end_s=1.0))
    capture = cv2.VideoCapture(str(clip))
    for index in range(12):
        ok, image = capture.read()
        assert ok
        cv2.imwrite(str(tmp_path / f"still{index:02d}.png"), image)
    capture.release()
    # Lucas-Kanade by name: on stills the default matches features (tracking/matched.py)
    tracks.read_footage(tmp_path, AnalysisConfig(fixation_px=(319.5, 179.5), fps=30.0, tracker_kind="klt"))
    assert chosen[0] is True and chosen[-1] is False


def test_a_camera_that_wobbles_back_to_where_it_started_moves_the_rim() -> None:
    """The picture's rim tells a camera that moves from a disc turning before a still background.
    A camera that wobbled about where it started, and ended near it, moves the rim all through
    the clip: it was judged by the first and last frames alone, taken for still, and a tilted
    clock filmed so read +199%, weak, from a return of its swaying picture."""
    import math

    import numpy as np

    from rotrate_cli.stages.period import Thumbnails
    from rotrate_cli.video.frames import Frame

    rng = np.random.default_rng(6)
    wall = cv2.resize(rng.random((40, 50)).astype(np.float32), (400, 320), interpolation=cv2.INTER_CUBIC)
    wall = (wall * 180 + 40).astype(np.uint8)

    def rim_moves(shift_px) -> bool:
        kept = Thumbnails()
        frames = []
        for k in range(120):
            dx, dy = shift_px(k / 30.0)
            frames.append(Frame(k, k / 30.0, cv2.warpAffine(wall, np.float32([[1, 0, dx - 40], [0, 1, dy - 40]]),
                                                            (320, 240), flags=cv2.INTER_LINEAR)))
        for _ in kept.tap(iter(frames)):
            pass
        return tracks._rim_moves(kept)

    # 12 px to and fro, two whole sways in the 4 s: the last frame is the first's
    assert rim_moves(lambda t: (12 * math.sin(math.pi * t), 9 * math.sin(math.pi * t)))
    assert not rim_moves(lambda t: (0.0, 0.0))

    # a textured disc turning before the still wall, reaching the picture's foot: one side of the
    # rim moves, as no turning camera's does (its turn was taken for the camera's)
    disc = np.zeros((240, 320), np.float32)
    cv2.circle(disc, (160, 250), 110, 1.0, -1)
    face = cv2.resize(rng.random((30, 30)).astype(np.float32), (320, 240), interpolation=cv2.INTER_CUBIC) * 200 + 30
    still = wall[40:280, 40:360].astype(np.float32)
    kept = Thumbnails()
    frames = []
    for k in range(60):
        turned = cv2.warpAffine(face, cv2.getRotationMatrix2D((160.0, 250.0), 3.0 * k, 1.0), (320, 240))
        frames.append(Frame(k, k / 30.0, (still * (1 - disc) + turned * disc).astype(np.uint8)))
    for _ in kept.tap(iter(frames)):
        pass
    assert not tracks._rim_moves(kept)
