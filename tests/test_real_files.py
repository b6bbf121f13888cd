"""The files people have, made at test time with FFmpeg (imageio-ffmpeg, a dev dependency) from
the bundled box clip (truth 0.6 rad/s): interlaced H.264, a damaged spot, an MP4 cut before its
index was written, one cut after, a stream-copied trim; and an OpenCV without ``cv2.utils.logging``
(4.9-4.12, the declared floor)."""

from __future__ import annotations

import subprocess
from pathlib import Path

import cv2
import numpy as np
import pytest
from typer.testing import CliRunner

from rotrate_cli.analysis import AnalysisConfig, analyze
from rotrate_cli.cli import app
from tests.conftest import SAMPLES

imageio_ffmpeg = pytest.importorskip("imageio_ffmpeg", reason="imageio-ffmpeg (a dependency) makes these files")
BOX = SAMPLES / "box_ortho.mp4"
FIXATION = ["--fixation", "319.5,179.5"]
runner = CliRunner()


def _ffmpeg(*arguments: str) -> None:
    subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-hide_banner", "-loglevel", "error", "-y", *arguments],
                   check=True)


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("real_files")
    made = {name: folder / name for name in ("interlaced.mp4", "h264.mp4", "damaged.mp4", "no_index.mp4",
                                             "faststart.mp4", "cut.mp4", "trim.mp4", "vfr.mp4")}
    _ffmpeg("-i", str(BOX), "-c:v", "libx264", "-flags", "+ildct+ilme", "-x264-params", "interlaced=1:tff=1",
            "-pix_fmt", "yuv420p", str(made["interlaced.mp4"]))
    _ffmpeg("-i", str(BOX), "-c:v", "libx264", "-g", "30", "-pix_fmt", "yuv420p", str(made["h264.mp4"]))
    whole = made["h264.mp4"].read_bytes()
    damaged = bytearray(whole)
    spot = int(len(whole) * 0.4)
    damaged[spot:spot + 3000] = bytes(3000)  # 3 KB of zeros in the middle of the picture data
    made["damaged.mp4"].write_bytes(bytes(damaged))
    made["no_index.mp4"].write_bytes(whole[:int(len(whole) * 0.6)])  # its index comes last: cut away
    _ffmpeg("-i", str(made["h264.mp4"]), "-c", "copy", "-movflags", "+faststart", str(made["faststart.mp4"]))
    indexed = made["faststart.mp4"].read_bytes()
    made["cut.mp4"].write_bytes(indexed[:int(len(indexed) * 0.6)])  # index first, pictures cut short
    _ffmpeg("-ss", "1.3", "-i", str(made["h264.mp4"]), "-t", "3", "-c", "copy", str(made["trim.mp4"]))
    # variable rate: the second half's frames twice as far apart (20.3 frames/s on average)
    _ffmpeg("-i", str(BOX), "-vf", "setpts='if(lt(N,75),N,75+(N-75)*2)/(30*TB)'", "-fps_mode", "vfr",
            "-c:v", "libx264", "-pix_fmt", "yuv420p", str(made["vfr.mp4"]))
    return made


def test_interlaced_video_measures_right(files: dict[str, Path]) -> None:
    # OpenCV >= 4.13 decodes flagged-interlaced streams black; FFmpeg reads them instead
    analysis = analyze(files["interlaced.mp4"], AnalysisConfig(fixation_px=None))
    assert analysis.omega_rad_s == pytest.approx(0.6, rel=0.01)
    assert analysis.omega_low_rad_s <= 0.6 <= analysis.omega_high_rad_s


def test_frame_of_an_interlaced_video_is_a_picture(files: dict[str, Path], tmp_path: Path) -> None:
    still = tmp_path / "still.png"
    result = runner.invoke(app, ["frame", str(files["interlaced.mp4"]), "-o", str(still), "--at", "1"])
    assert result.exit_code == 0, result.stderr
    assert cv2.imread(str(still)).mean() > 20  # not black


def test_a_still_opencv_decodes_black_or_garbled_is_read_through_ffmpeg(files: dict[str, Path],
                                                                         monkeypatch: pytest.MonkeyPatch) -> None:
    """What OpenCV gives in the openings where the interlaced stream defeats it, made to happen:
    the still at 1 s comes mostly black from OpenCV; through FFmpeg it is the picture."""
    from rotrate_cli.output.overlay import frame_at
    from rotrate_cli.video.decode import FrameSource

    # the premise is an opening whose first frame OpenCV decodes as a picture: the first openings
    # in a process can decode black and switch to FFmpeg at once (so the test depended on its order)
    source = next(s for s in (FrameSource(files["interlaced.mp4"]) for _ in range(8))
                  if not any("read through FFmpeg" in w for w in s.warnings))
    opencv_frames = FrameSource._video_frames

    def garbled(self, capture, start_s, end_s, convert, quiet=False):  # noqa: ANN001, ANN202
        for frame in opencv_frames(self, capture, start_s, end_s, convert, quiet):
            image = frame.image.copy()
            image[image.shape[0] // 8:] = 0  # a band of picture, the rest black
            yield type(frame)(frame.index, frame.time_s, image)

    monkeypatch.setattr(FrameSource, "_video_frames", garbled)
    assert source.looks_undecoded(np.zeros((360, 640, 3), np.uint8))
    still = frame_at(source, 1.0)
    assert not source.looks_undecoded(still.image) and still.image.mean() > 20
    assert any("read through FFmpeg" in warning for warning in source.warnings)


def test_ffmpeg_tells_an_interlaced_stream(files: dict[str, Path]) -> None:
    from rotrate_cli.video.pipe import ffmpeg_program, interlaced

    program = ffmpeg_program()
    assert program is not None
    assert interlaced(program, str(files["interlaced.mp4"]))
    assert not interlaced(program, str(files["h264.mp4"]))
    assert not interlaced(program, str(SAMPLES / "box_ortho.mp4"))


def test_interlaced_without_ffmpeg_is_measured_or_explained(files: dict[str, Path],
                                                             monkeypatch: pytest.MonkeyPatch) -> None:
    # OpenCV decodes such a file black in some openings and not in others: either the run
    # measures it, or it stops with one line that says what to do; never "no point could be tracked"
    monkeypatch.setattr("rotrate_cli.video.pipe.ffmpeg_program", lambda: None)
    result = runner.invoke(app, ["analyze", str(files["interlaced.mp4"]), *FIXATION, "-f", "json"])
    if result.exit_code == 0:
        assert '"omega": 0.6' in result.stdout or '"omega": 0.59' in result.stdout
    else:  # 2 for black frames, 1 for one frozen garbled picture
        lines = [line for line in result.stderr.splitlines() if "error" in line]
        assert result.exit_code in (1, 2) and len(lines) == 1 and "interlaced" in lines[0]


def test_every_frame_black_is_said(tmp_path: Path) -> None:
    black = tmp_path / "black.avi"
    writer = cv2.VideoWriter(str(black), cv2.VideoWriter_fourcc(*"MJPG"), 30, (160, 120))
    for _ in range(40):
        writer.write(np.zeros((120, 160, 3), np.uint8))
    writer.release()
    result = runner.invoke(app, ["analyze", str(black), "--fixation", "80,60"])
    assert result.exit_code == 2 and "decode black" in result.stderr and "interlaced" in result.stderr


def test_a_damaged_spot_is_read_past(files: dict[str, Path]) -> None:
    # before: decoding stopped at the spot (55 of 150 frames) and warned "it may be cut off"
    analysis = analyze(files["damaged.mp4"], AnalysisConfig(fixation_px=(319.5, 179.5)))
    assert analysis.frames >= 140
    assert analysis.omega_rad_s == pytest.approx(0.6, rel=0.01)
    assert any("could not be decoded between" in warning for warning in analysis.warnings)
    assert not any("cut off" in warning for warning in analysis.warnings)


def test_frames_garbled_after_a_damaged_spot_are_no_cut(tmp_path: Path) -> None:
    """100 KB of random bytes over the middle of the file (the bundled box, MPEG-4 part 2): 24
    frames cannot be decoded, the 11 after them decode garbled up to the next key frame, where the
    picture jumps back. That jump was taken for a cut: 84 of 126 decoded frames measured, weak,
    +1.5%. Now the garbled frames alone are left out and both sides are measured."""
    damaged = bytearray(BOX.read_bytes())
    spot = len(damaged) // 2
    damaged[spot:spot + 100_000] = np.random.default_rng(0).integers(0, 256, 100_000, dtype=np.uint8).tobytes()
    clip = tmp_path / "corrupt_mid.mp4"
    clip.write_bytes(bytes(damaged))
    analysis = analyze(clip, AnalysisConfig(fixation_px=(319.5, 179.5)))
    assert analysis.frames >= 110
    assert analysis.omega_rad_s == pytest.approx(0.6, rel=0.01)
    assert analysis.omega_low_rad_s <= 0.6 <= analysis.omega_high_rad_s
    assert not any("cuts" in warning for warning in analysis.warnings)
    assert any("decode garbled and are left out" in warning for warning in analysis.warnings)


def test_an_mp4_without_its_index_is_called_truncated(files: dict[str, Path]) -> None:
    result = runner.invoke(app, ["analyze", str(files["no_index.mp4"]), *FIXATION])
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert result.exit_code == 2 and len(lines) == 1
    assert "damaged or truncated" in lines[0] and "is it a video file" not in lines[0]


def test_an_mp4_cut_after_its_index_warns_and_measures(files: dict[str, Path]) -> None:
    analysis = analyze(files["cut.mp4"], AnalysisConfig(fixation_px=(319.5, 179.5)))
    assert analysis.omega_rad_s == pytest.approx(0.6, rel=0.02)
    assert any("cut off or damaged" in warning for warning in analysis.warnings)


def test_a_stream_copied_trim_is_not_called_cut_off(files: dict[str, Path]) -> None:
    # it announces the frames from the key frame before its cut (101), and shows 92
    analysis = analyze(files["trim.mp4"], AnalysisConfig(fixation_px=(319.5, 179.5)))
    assert analysis.omega_rad_s == pytest.approx(0.6, rel=0.01)
    assert not any("cut off" in warning or "could not be decoded" in warning for warning in analysis.warnings)


def test_an_opencv_without_its_logging_module_still_decodes(monkeypatch: pytest.MonkeyPatch) -> None:
    # OpenCV 4.9-4.12 have no cv2.utils.logging; the luma path used it on every frame
    from rotrate_cli.video.decode import FrameSource

    monkeypatch.setattr(cv2, "utils", object(), raising=False)
    frames = list(FrameSource(BOX).frames(grey=True, end_s=0.5))
    assert len(frames) == 16 and frames[0].image.ndim == 2


def test_frozen_frames_from_opencv_are_read_again_through_ffmpeg(files: dict[str, Path],
                                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    # some openings of an interlaced file give one garbled picture, over and over: as if
    # OpenCV did so on every opening, the run reads the file again through FFmpeg
    from rotrate_cli.video import decode

    garbled = np.random.default_rng(0).integers(0, 255, (360, 640, 3), dtype=np.uint8)

    def frozen(self, capture, start_s, end_s, convert, quiet=False):  # noqa: ANN001, ANN202
        capture.release()
        for index in range(150):
            yield decode.Frame(index, index / 30.0, convert(garbled.copy()))

    monkeypatch.setattr(decode.FrameSource, "_video_frames", frozen)
    analysis = analyze(files["h264.mp4"], AnalysisConfig(fixation_px=(319.5, 179.5)))
    assert analysis.omega_rad_s == pytest.approx(0.6, rel=0.01)
    assert any("read through FFmpeg" in warning for warning in analysis.warnings)


def test_fps_that_contradicts_a_variable_rate_stream_is_warned_of(files: dict[str, Path]) -> None:
    result = runner.invoke(app, ["analyze", str(files["vfr.mp4"]), *FIXATION, "--fps", "30", "-f", "json"])
    assert result.exit_code == 0
    assert "--fps 30 differs from the stream's own rate (20.27" in result.stderr
    assert "cut off" not in result.stderr  # the file's duration is in its own times, not --fps's


def test_the_fits_are_announced_after_the_frames() -> None:
    """Each stage after the frames is told as it starts (issue 50: the fits, their checks and the
    verdict had run under the tracking's full bar, its clock stopped)."""
    calls: list[object] = []
    analyze(BOX, AnalysisConfig(fixation_px=(319.5, 179.5), end_s=2.0),
            progress=lambda done, total: calls.append(done), stage=calls.append)
    stages = [call for call in calls if isinstance(call, str)]
    assert calls[calls.index(stages[0]) - 1] == 61  # after the last frame
    assert stages == ["placing the axis and the lens", "fitting the tracks", "checking the rate",
                      "weighing the tracks, the return and the picture's turning"]


def test_a_stage_after_the_frames_starts_its_own_clock() -> None:
    """The command line's bar: once the frames' bar is full, the next stage's clock runs again."""
    import time

    from rich.progress import Progress

    from rotrate_cli.cli import next_stage

    with Progress(disable=True) as progress:
        task = progress.add_task("frames", total=None)
        progress.update(task, completed=61, total=61)
        assert progress.tasks[0].finished  # rich stops a full bar's clock
        next_stage(progress, task, "fitting the tracks")
        time.sleep(0.02)
        shown = progress.tasks[0]
        assert not shown.finished and shown.description == "fitting the tracks"
        assert shown.elapsed is not None and shown.elapsed >= 0.02
