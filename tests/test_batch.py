"""Batch runs, CI regression checks, and bad input in a batch (issue 5)."""

from __future__ import annotations

import io
import json
import shutil
from pathlib import Path
from xml.etree import ElementTree as ET

import pandas as pd
import pytest
from typer.testing import CliRunner

from rotrate_cli.batch import SUMMARY_COLUMNS, check_expected, expand_inputs
from rotrate_cli.cli import app
from tests.conftest import SAMPLES

runner = CliRunner()
CLIPS = [SAMPLES / f"{name}.mp4" for name in ("box_ortho", "cylinder_ortho", "sphere_ortho")]


@pytest.fixture
def broken(tmp_path: Path) -> list[Path]:
    """Three bad inputs: text named .mp4, an empty file, a file that does not exist."""
    text = tmp_path / "notes.mp4"
    text.write_text("not a video")
    empty = tmp_path / "empty.mp4"
    empty.write_bytes(b"")
    return [text, empty, tmp_path / "missing.mp4"]


def _batch(*args: str) -> tuple[int, str, str]:
    result = runner.invoke(app, ["analyze", *args])
    return result.exit_code, result.stdout, result.stderr


def test_a_batch_gives_one_row_per_input_and_goes_past_bad_files(broken: list[Path], tmp_path: Path) -> None:
    out = tmp_path / "reports"
    out.mkdir()
    code, stdout, stderr = _batch(*map(str, CLIPS + broken), "--fixation", "auto", "--format", "csv",
                                  "--output-dir", str(out))
    assert code == 2  # the worst input was bad input
    assert "Traceback" not in stdout + stderr
    table = pd.read_csv(io.StringIO(stdout)).fillna({"error": "", "direction": ""})
    assert tuple(table.columns) == SUMMARY_COLUMNS
    assert table["file"].tolist() == [str(p) for p in CLIPS + broken]
    assert table["status"].tolist() == ["ok"] * 3 + ["bad_input"] * 3
    for expected, row in zip((0.6, 0.4, 1.0), table.head(3).itertuples(), strict=True):
        assert row.omega == pytest.approx(expected, rel=0.01)
    assert "could not" in table.loc[3, "error"] and "empty" in table.loc[4, "error"]
    assert "no such file" in table.loc[5, "error"]
    # the quality beside the status, and an input's warnings in their own column, not in `error`
    assert table["quality"].tolist()[:3] == ["good"] * 3
    assert (table["error"].head(3) == "").all() and "warnings" in table.columns
    assert sorted(p.name for p in out.iterdir()) == ["box_ortho.csv", "cylinder_ortho.csv", "sphere_ortho.csv"]


def test_parallel_and_serial_batches_agree_row_for_row(broken: list[Path]) -> None:
    inputs = [*map(str, CLIPS[:2]), str(broken[0])]
    # their first 3 s: the rows are compared, not the rates
    serial = _batch(*inputs, "--fixation", "auto", "--end", "3", "--format", "json")
    parallel = _batch(*inputs, "--fixation", "auto", "--end", "3", "--format", "json", "--jobs", "2")
    assert serial[0] == parallel[0] == 2
    assert json.loads(serial[1]) == json.loads(parallel[1])


def test_all_good_inputs_exit_zero_and_the_table_lists_them(tmp_path: Path) -> None:
    folder = tmp_path / "clips"
    folder.mkdir()
    for clip in CLIPS[:2]:
        shutil.copy(clip, folder / clip.name)
    code, stdout, _ = _batch(str(folder), "--fixation", "auto")  # a folder of videos is a batch
    assert code == 0
    assert "box_ortho.mp4" in stdout and "cylinder_ortho.mp4" in stdout and "ok" in stdout


def test_expect_and_tolerance_on_one_input() -> None:
    clip = str(CLIPS[0])
    assert _batch(clip, "--fixation", "319.5,179.5", "-f", "json", "--expect", "0.6", "--tolerance", "1")[0] == 0
    code, stdout, stderr = _batch(clip, "--fixation", "319.5,179.5", "-f", "json", "--expect", "0.5",
                                  "--tolerance", "2")
    assert code == 1
    assert json.loads(stdout)["omega"] == pytest.approx(0.6, rel=0.01)  # the report is still there
    lines = [line for line in stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and "from the expected 0.5" in lines[0]


def test_expect_in_a_batch_marks_rows_off_target() -> None:
    code, stdout, _ = _batch(*map(str, CLIPS[:2]), "--fixation", "auto", "-f", "csv", "--expect", "0.6",
                             "--tolerance", "1")
    table = pd.read_csv(io.StringIO(stdout))
    assert table["status"].tolist() == ["ok", "off_target"] and code == 1


@pytest.mark.parametrize(("options", "word"), [
    (["--expect", "0.5"], "--tolerance"),
    (["--expect", "-1", "--tolerance", "1"], "--expect"),
    (["--expect", "0.5", "--tolerance", "-3"], "--tolerance"),
])
def test_expectation_and_output_dir_usage_errors(options: list[str], word: str) -> None:
    code, _, stderr = _batch(str(CLIPS[0]), "--fixation", "auto", *options)
    lines = [line for line in stderr.splitlines() if line.strip()]
    assert code == 2 and len(lines) == 1 and word in lines[0]


def test_existing_detail_reports_are_kept_without_force(tmp_path: Path) -> None:
    (tmp_path / "box_ortho.json").write_text("mine")
    code, _, stderr = _batch(*map(str, CLIPS[:2]), "--fixation", "auto", "--output-dir", str(tmp_path))
    assert code == 2 and "--force" in stderr
    assert (tmp_path / "box_ortho.json").read_text() == "mine"
    assert not (tmp_path / "cylinder_ortho.json").exists()  # refused before running anything


@pytest.mark.slow  # about 10 s: in make test-slow (each sample stays in test_samples, JUnit in the failing manifest)
def test_the_sample_manifest_passes_and_writes_junit(tmp_path: Path) -> None:
    junit = tmp_path / "junit.xml"
    result = runner.invoke(app, ["check", str(SAMPLES / "manifest.csv"), "--junit", str(junit)])
    assert result.exit_code == 0, result.output
    assert result.stdout.count("pass") == 6
    suite = ET.parse(junit).getroot()
    assert suite.tag == "testsuite" and suite.get("tests") == "6" and suite.get("failures") == "0"


def test_a_failing_manifest_row_fails_the_check(tmp_path: Path, broken: list[Path]) -> None:
    manifest = tmp_path / "m.csv"
    manifest.write_text(f"file,expected_omega,tolerance_pct,fixation\n{CLIPS[0]},0.6,1,auto\n"
                        f"{CLIPS[1]},0.5,1,auto\n{broken[0]},1,1,auto\n")
    junit = tmp_path / "junit.xml"
    result = runner.invoke(app, ["check", str(manifest), "--junit", str(junit)])
    assert result.exit_code == 1
    assert result.stdout.count("FAIL") == 2
    assert "2 of 3 manifest rows failed" in result.stderr
    suite = ET.parse(junit).getroot()
    assert (suite.get("failures"), suite.get("errors")) == ("1", "1")


def test_manifest_rows_carry_the_angle_source_and_elevation(tmp_path: Path) -> None:
    from rotrate_cli import AnalysisConfig
    from rotrate_cli.batch import read_manifest

    manifest = tmp_path / "m.csv"
    manifest.write_text("file,expected_omega,tolerance_pct,fov,angle_from,elevation\n"
                        "a.mp4,0.5,1,25,paths,\nb.mp4,0.5,1,25,,30\nc.mp4,0.5,1,,,\n")
    a, b, c = (job.config for job in read_manifest(manifest, AnalysisConfig(fixation_px=None)))
    assert (a.angle_from, a.elevation_deg, a.fov_deg) == ("paths", None, 25.0)
    assert (b.angle_from, b.elevation_deg) == ("auto", 30.0)
    assert (c.angle_from, c.elevation_deg, c.fov_deg) == ("auto", None, None)


@pytest.mark.parametrize(("text", "word"), [
    ("file,expected_omega\nx.mp4,1\n", "tolerance_pct"),
    ("file,expected_omega,tolerance_pct\nx.mp4,fast,1\n", "line 2"),
    ("file,expected_omega,tolerance_pct,colour\nx.mp4,1,1,red\n", "colour"),
    ("file,expected_omega,tolerance_pct,fixation\nx.mp4,1,1,3\n", "fixation"),
    ("file,expected_omega,tolerance_pct\n", "no file"),
])
def test_bad_manifests_are_usage_errors(tmp_path: Path, text: str, word: str) -> None:
    manifest = tmp_path / "m.csv"
    manifest.write_text(text)
    result = runner.invoke(app, ["check", str(manifest)])
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert result.exit_code == 2 and len(lines) == 1 and word in lines[0]


def test_inputs_expand_globs_and_folders_of_videos(tmp_path: Path) -> None:
    for name in ("b.mp4", "a.mov", "notes.txt"):
        (tmp_path / name).write_bytes(b"x")
    images = tmp_path / "frames"
    images.mkdir()
    (images / "f1.png").write_bytes(b"x")
    assert expand_inputs([str(tmp_path)]) == [str(tmp_path / "a.mov"), str(tmp_path / "b.mp4"), str(images)][:2]
    assert expand_inputs([str(tmp_path / "*.mp4"), str(tmp_path / "b.mp4")]) == [str(tmp_path / "b.mp4")]
    assert expand_inputs([str(images)]) == [str(images)]  # a folder of images is one image sequence
    assert expand_inputs([str(tmp_path / "none*.mp4")]) == [str(tmp_path / "none*.mp4")]  # reported, not lost


def test_the_expectation_rule_is_the_point_estimate() -> None:
    assert check_expected(0.605, 0.6, 1) == ""
    assert "+1.67%" in check_expected(0.61, 0.6, 1)


def test_ctrl_c_mid_run_exits_130_and_leaves_no_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from rotrate_cli import analysis

    def interrupted(*_args: object, **_kwargs: object) -> None:
        raise KeyboardInterrupt

    target = tmp_path / "report.json"
    monkeypatch.setattr(analysis, "analyze", interrupted)  # the command imports it when it runs
    result = runner.invoke(app, ["analyze", str(CLIPS[0]), "--fixation", "auto", "-f", "json", "-o", str(target)])
    assert result.exit_code == 130 and "interrupted" in result.stderr
    assert list(tmp_path.iterdir()) == []


def test_ctrl_c_while_writing_leaves_neither_half_a_file_nor_a_temporary(tmp_path: Path,
                                                                          monkeypatch: pytest.MonkeyPatch) -> None:
    import os

    def interrupted(*_args: object, **_kwargs: object) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(os, "replace", interrupted)
    target = tmp_path / "report.csv"
    result = runner.invoke(app, ["analyze", str(CLIPS[0]), "--fixation", "319.5,179.5", "-f", "csv", "--end", "2",
                                 "-o", str(target)])
    assert result.exit_code == 130
    assert list(tmp_path.iterdir()) == []


def test_a_batch_on_a_local_dask_cluster_gives_the_same_rows(broken: list[Path]) -> None:
    distributed = pytest.importorskip("dask.distributed", reason="the dask extra is not installed")
    inputs = [str(CLIPS[0]), str(broken[0])]
    serial = _batch(*inputs, "--fixation", "auto", "--end", "3", "--format", "json")
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        on_dask = _batch(*inputs, "--fixation", "auto", "--end", "3", "--format", "json", "--scheduler",
                         cluster.scheduler_address)
    assert on_dask[0] == serial[0] == 2
    assert json.loads(on_dask[1]) == json.loads(serial[1])


def test_a_bad_scheduler_address_is_one_line() -> None:
    # (an unreachable one is the same message after the 10 s connection timeout)
    pytest.importorskip("dask.distributed", reason="the dask extra is not installed")
    code, _, stderr = _batch(*map(str, CLIPS[:2]), "--fixation", "auto", "--scheduler", "tcp://localhost:port")
    lines = [line for line in stderr.splitlines() if line.strip()]
    assert code == 2 and len(lines) == 1 and "Dask scheduler" in lines[0]


def test_a_video_cut_off_mid_file_is_measured_and_said_so(tmp_path: Path) -> None:
    import cv2

    capture = cv2.VideoCapture(str(CLIPS[0]))
    whole = tmp_path / "whole.avi"
    writer = cv2.VideoWriter(str(whole), cv2.VideoWriter_fourcc(*"MJPG"), 30, (640, 360))
    while True:
        ok, frame = capture.read()
        if not ok:
            break
        writer.write(frame)
    writer.release()
    cut = tmp_path / "cut.avi"
    data = whole.read_bytes()
    cut.write_bytes(data[: int(len(data) * 0.6)])
    result = runner.invoke(app, ["analyze", str(cut), "--fixation", "319.5,179.5", "-f", "json"])
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout)["omega"] == pytest.approx(0.6, rel=0.01)
    warnings = [line for line in result.stderr.splitlines() if line.strip()]
    assert len(warnings) == 1 and "cut off" in warnings[0]


def test_every_track_rejected_is_exit_1_with_the_reasons(tmp_path: Path) -> None:
    tracks = tmp_path / "short.csv"
    tracks.write_text("track,frame,x\n" + "".join(f"{k},{f},{10 * k + f}\n" for k in range(3) for f in range(3)))
    result = runner.invoke(app, ["omega", str(tracks), "--fixation", "0", "--fps", "30"])
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert result.exit_code == 1 and len(lines) == 1 and "short" in lines[0]


def test_an_output_folder_that_cannot_be_written(tmp_path: Path) -> None:
    import os

    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    try:
        if os.access(locked, os.W_OK):
            pytest.skip("running as a user who can write anywhere (root): permissions cannot be tested")
        result = runner.invoke(app, ["analyze", str(CLIPS[0]), "--fixation", "auto", "-o", str(locked / "r.json")])
        lines = [line for line in result.stderr.splitlines() if line.strip()]
        assert result.exit_code == 2 and len(lines) == 1 and "cannot write" in lines[0]
    finally:
        locked.chmod(0o700)


def test_output_dir_takes_one_input_too(tmp_path: Path) -> None:
    """A glob the shell expanded to one file (README recipe 6): its report is written all the same."""
    code, stdout, _ = _batch(str(CLIPS[0]), "--fixation", "auto", "--output-dir", str(tmp_path))
    assert code == 0 and (tmp_path / f"{CLIPS[0].stem}.json").is_file()
    assert CLIPS[0].name in stdout


def test_an_interrupted_batch_keeps_the_reports_of_the_inputs_done(tmp_path: Path,
                                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    """Each report is written as its input finishes, with a progress line: an interrupt at the
    second input leaves the first's report (before, every report waited for the batch's end)."""
    import rotrate_cli.batch as batch

    real = batch.run_one
    calls = []

    def interrupted(job: batch.Job) -> batch.Outcome:
        calls.append(job.source)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return real(job)

    monkeypatch.setattr(batch, "run_one", interrupted)
    code, _, stderr = _batch(*map(str, CLIPS), "--fixation", "auto", "--output-dir", str(tmp_path))
    assert code != 0
    assert sorted(p.name for p in tmp_path.iterdir()) == [f"{CLIPS[0].stem}.json"]
    assert f"[1/3] {CLIPS[0]}: " in stderr and "rad/s, good" in stderr


def test_resume_skips_the_inputs_whose_reports_are_there(tmp_path: Path) -> None:
    """Run again with --resume: the inputs with a report are skipped (and said so); the others run."""
    first = tmp_path / f"{CLIPS[0].stem}.csv"
    first.write_text("kept\n")
    code, stdout, stderr = _batch(*map(str, CLIPS[:2]), "--fixation", "auto", "--output-dir", str(tmp_path),
                                  "--resume", "--format", "csv")
    assert code == 0
    assert first.read_text() == "kept\n"  # nothing the user has is overwritten
    assert (tmp_path / f"{CLIPS[1].stem}.csv").is_file()
    table = pd.read_csv(io.StringIO(stdout))
    assert table["status"].tolist() == ["skipped", "ok"]
    assert "[2/2]" in stderr
    # without --resume an existing report stops the batch before any work
    code, _, stderr = _batch(*map(str, CLIPS[:2]), "--fixation", "auto", "--output-dir", str(tmp_path),
                             "--format", "csv")
    assert code == 2 and "exists" in stderr


def test_resume_needs_an_output_dir() -> None:
    code, _, stderr = _batch(str(CLIPS[0]), "--fixation", "auto", "--resume")
    assert code == 2 and "--output-dir" in stderr
