"""Frame times and lens of image sequences: EXIF capture times, --times files, and the one-line
errors and warnings when they do not fit."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest
from PIL import Image
from typer.testing import CliRunner

from rotrate_cli.cli import app
from rotrate_cli.errors import InputError
from rotrate_cli.video.clock import exif_focal_px, exif_times, read_times
from rotrate_cli.video.decode import FrameSource

runner = CliRunner()


def _photographs(folder: Path, seconds: list[float], focal_35mm: int | None = 28) -> Path:
    """JPEG pictures of a turning texture, with DateTimeOriginal + SubSecTimeOriginal (and the
    35 mm-equivalent focal length) in their EXIF, one per time."""
    folder.mkdir()
    rng = np.random.default_rng(5)
    texture = cv2.GaussianBlur(rng.uniform(0, 255, (120, 160)).astype(np.float32), (0, 0), 2).astype(np.uint8)
    for index, second in enumerate(seconds):
        turned = cv2.warpAffine(texture, cv2.getRotationMatrix2D((80, 60), 10.0 * index, 1.0), (160, 120))
        image = Image.fromarray(turned).convert("RGB")
        exif = Image.Exif()
        whole = int(second)
        stamp = f"2008:03:12 10:{44 + whole // 60:02d}:{whole % 60:02d}"
        ifd = exif.get_ifd(0x8769)
        ifd[36867] = stamp
        ifd[37521] = f"{round((second - whole) * 100):02d}"
        if focal_35mm is not None:
            ifd[41989] = focal_35mm
        image.save(folder / f"{index:03d}.jpg", exif=exif, quality=95)
    return folder


def test_exif_capture_times_are_the_clock(tmp_path: Path) -> None:
    seconds = [0.0, 1.2, 2.0, 3.5, 4.4, 5.9]
    folder = _photographs(tmp_path / "turntable", seconds)
    clock = exif_times(sorted(folder.glob("*.jpg")))
    assert clock is not None and clock.source == "exif"
    assert clock.times_s == pytest.approx(seconds, abs=0.011)
    assert clock.resolution_s == pytest.approx(0.01)
    source = FrameSource(folder)
    assert source.info.clock == "exif"
    assert [frame.time_s for frame in source.frames()] == pytest.approx(seconds, abs=0.011)
    assert exif_focal_px(folder / "000.jpg", 160) == pytest.approx(28 / 36 * 160)


def test_fps_that_contradicts_the_exif_times_is_warned_of(tmp_path: Path) -> None:
    folder = _photographs(tmp_path / "turntable", [0.0, 2.0, 4.0, 6.0, 8.0])  # 0.5 frames/s
    source = FrameSource(folder, fps=1.0)
    assert source.info.clock == "fps"
    assert any("EXIF" in warning and "0.5" in warning for warning in source.warnings)
    assert not FrameSource(folder, fps=0.5).warnings


def test_images_without_times_need_fps(tmp_path: Path) -> None:
    folder = tmp_path / "plain"
    folder.mkdir()
    for index in range(4):
        cv2.imwrite(str(folder / f"{index}.png"), np.full((20, 30), 40 * index, np.uint8))
    with pytest.raises(InputError, match="`fps` .* or `times_s`"):
        FrameSource(folder)


def test_times_file(tmp_path: Path) -> None:
    path = tmp_path / "times.txt"
    path.write_text("time_s\n10.0\n10.5  # a comment\n\n11.25\n12,extra\n")
    assert read_times(path) == pytest.approx([0.0, 0.5, 1.25, 2.0])


@pytest.mark.parametrize(("text", "words"), [
    ("0\n1\n1\n2\n", "must increase"),
    ("0\n2\n1\n", "must increase"),
    ("0\nabc\n", "line 2"),
    ("5\n", "1 time"),
])
def test_bad_times_file_is_one_line_exit_2(tmp_path: Path, text: str, words: str) -> None:
    path = tmp_path / "times.txt"
    path.write_text(text)
    folder = _photographs(tmp_path / "turntable", [0.0, 1.0, 2.0, 3.0])
    result = runner.invoke(app, ["analyze", str(folder), "--fixation", "auto", "--times", str(path), "-q"])
    assert result.exit_code == 2, result.output
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("rotrate: error: ") and words in lines[0]


def test_times_with_the_wrong_count_is_one_line_exit_2(tmp_path: Path) -> None:
    path = tmp_path / "times.txt"
    path.write_text("0\n1\n2\n")
    folder = _photographs(tmp_path / "turntable", [0.0, 1.0, 2.0, 3.0])
    result = runner.invoke(app, ["analyze", str(folder), "--fixation", "auto", "--times", str(path), "-q"])
    assert result.exit_code == 2, result.output
    assert "3 times for 4 images" in result.stderr
    both = runner.invoke(app, ["analyze", str(folder), "--fixation", "auto", "--times", str(path), "--fps", "2"])
    assert both.exit_code == 2 and "not both" in both.stderr


def test_times_on_a_video_must_match_its_frames(tmp_path: Path) -> None:
    clip = Path(__file__).resolve().parents[1] / "sample_videos" / "box_ortho.mp4"
    path = tmp_path / "times.txt"
    path.write_text("\n".join(str(0.1 * k) for k in range(10)))
    result = runner.invoke(app, ["analyze", str(clip), "--fixation", "auto", "--times", str(path), "-q"])
    assert result.exit_code == 2, result.output
    assert "--times gives 10 times" in result.stderr


def test_fps_that_contradicts_a_videos_own_rate_is_warned_of() -> None:
    clip = Path(__file__).resolve().parents[1] / "sample_videos" / "box_ortho.mp4"  # 30 fps
    assert any("`fps=25` differs from the stream's own rate (30" in w for w in FrameSource(clip, fps=25.0).warnings)
    assert not FrameSource(clip, fps=30.0).warnings
    result = runner.invoke(app, ["analyze", str(clip), "--fixation", "319.5,179.5", "--fps", "25", "-q", "-f", "json"])
    assert result.exit_code == 0 and "differs from the stream's own rate" in result.stderr
