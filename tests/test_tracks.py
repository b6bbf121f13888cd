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
