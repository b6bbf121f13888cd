"""Decoding: videos, printf patterns and folders, times, spans, streaming."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from rotrate_cli.errors import InputError
from rotrate_cli.video.decode import FrameSource, prefetch
from tests.conftest import SAMPLES


def _write_images(folder: Path, names: list[str]) -> None:
    for value, name in enumerate(names):
        cv2.imwrite(str(folder / name), np.full((8, 12, 3), value * 10, np.uint8))


def test_video_times_come_from_the_decoder() -> None:
    source = FrameSource(SAMPLES / "box_ortho.mp4")
    assert (source.info.width_px, source.info.height_px, source.info.fps) == (640, 360, 30.0)
    times = [frame.time_s for frame in source.frames()]
    assert len(times) == 150
    assert np.allclose(np.diff(times), 1 / 30, atol=1e-6)


def test_fps_override_rescales_time() -> None:
    source = FrameSource(SAMPLES / "box_ortho.mp4", fps=60)
    times = [frame.time_s for frame in source.frames(end_s=1.0)]
    assert len(times) == 61 and times[-1] == pytest.approx(1.0)


def test_start_and_end_select_a_span() -> None:
    frames = list(FrameSource(SAMPLES / "box_ortho.mp4").frames(start_s=1.0, end_s=2.0))
    assert frames[0].index == 30 and frames[-1].index == 60
    assert frames[0].time_s == pytest.approx(1.0, abs=1e-6)


def test_folder_in_natural_order_and_pattern(tmp_path: Path) -> None:
    _write_images(tmp_path, ["img2.png", "img10.png", "img1.png"])
    values = [int(f.image[0, 0, 0]) for f in FrameSource(tmp_path, fps=2).frames()]
    assert values == [20, 0, 10]  # img1, img2, img10
    pattern_dir = tmp_path / "seq"
    pattern_dir.mkdir()
    _write_images(pattern_dir, [f"f.{i:03d}.png" for i in range(1, 5)])
    source = FrameSource(str(pattern_dir / "f.%03d.png"), fps=4)
    frames = list(source.frames())
    assert source.info.frame_count == 4 and [f.time_s for f in frames] == [0, 0.25, 0.5, 0.75]


def test_pattern_without_matches(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="no image matches"):
        FrameSource(str(tmp_path / "x.%03d.png"), fps=1)


def test_absurd_frame_rate() -> None:
    with pytest.raises(InputError, match="`fps`"):
        FrameSource(SAMPLES / "box_ortho.mp4", fps=1e9)


def test_prefetch_passes_errors_and_stops_early() -> None:
    def broken():
        yield 1
        raise InputError("boom")

    stream = prefetch(broken())
    assert next(stream) == 1
    with pytest.raises(InputError, match="boom"):
        next(stream)
    many = prefetch(iter(range(1000)), depth=2)
    assert next(many) == 0
    many.close()  # the producer thread must not hang


def test_truncated_video_decodes_what_is_there(tmp_path: Path) -> None:
    whole = tmp_path / "whole.avi"
    writer = cv2.VideoWriter(str(whole), cv2.VideoWriter_fourcc(*"MJPG"), 10, (64, 48))
    rng = np.random.default_rng(0)
    for _ in range(30):
        writer.write(rng.integers(0, 255, (48, 64, 3), dtype=np.uint8))
    writer.release()
    data = whole.read_bytes()
    cut = tmp_path / "cut.avi"
    cut.write_bytes(data[: len(data) // 2])
    source = FrameSource(cut)
    decoded = sum(1 for _ in source.frames())
    assert 5 < decoded < 30


def test_grey_frames_match_the_colour_conversion_and_keep_the_times() -> None:
    # the decoder's own luma (used for speed) must give the grey that COLOR_BGR2GRAY gives
    source = FrameSource(SAMPLES / "cylinder_ortho.mp4")
    colour = list(source.frames(end_s=1.0))
    grey = list(source.frames(end_s=1.0, grey=True))
    assert source.luma_levels() is not None  # the fast path is taken on our own H.264 clips
    assert [f.time_s for f in grey] == [f.time_s for f in colour]
    for c, g in zip(colour, grey, strict=True):
        expected = cv2.cvtColor(c.image, cv2.COLOR_BGR2GRAY).astype(int)
        assert g.image.shape == expected.shape and g.image.dtype == np.uint8
        difference = np.abs(g.image.astype(int) - expected)
        assert difference.mean() < 0.8 and np.percentile(difference, 99.9) <= 3


def test_grey_frames_of_an_image_sequence(tmp_path: Path) -> None:
    _write_images(tmp_path, ["a1.png", "a2.png"])
    frames = list(FrameSource(tmp_path, fps=1).frames(grey=True, transform=lambda image: image[:2, :2]))
    assert [f.image.tolist() for f in frames] == [[[0, 0], [0, 0]], [[10, 10], [10, 10]]]


def test_luma_levels_applied_after_the_reduction_give_the_same_tracking_image() -> None:
    from rotrate_cli.tracking.klt import tracking_image

    source = FrameSource(SAMPLES / "box_ortho.mp4")
    levels = source.luma_levels()
    assert levels is not None
    colour = next(iter(source.frames()))
    luma = next(iter(source.frames(grey=True, map_luma=False)))
    expected = tracking_image(colour.image, 0.5, 1.0).astype(int)
    got = tracking_image(luma.image, 0.5, 1.0, levels).astype(int)
    assert got.shape == expected.shape and np.abs(got - expected).max() <= 2
