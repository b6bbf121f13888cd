"""Reading tracks files: good tables, and every malformed one gives a clean InputError."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from rotrate_cli import InputError, analyze_tracks, read_tracks
from rotrate_cli.cli import app


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "tracks.csv"
    path.write_text(text)
    return path


def test_reads_feature_or_track_ids_comments_and_time(tmp_path: Path) -> None:
    table = read_tracks(_write(tmp_path, "# a comment\nfeature,frame,time_s,x\n2,1,0.1,5\n1,0,0.0,3\n1,1,0.1,4\n"))
    assert list(table.columns) == ["track", "frame", "position", "time_s"]
    assert table["track"].tolist() == [1, 1, 2]


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("track,frame\n1,0\n", "lacks the column"),
        ("track,frame,x\n1,0,abc\n", "non-numeric"),
        ("track,frame,x\n1,0,\n", "missing"),
        ("track,frame,x\n1,0,nan\n", "missing or non-numeric"),
        ("track,frame,x\n1,0,1\n1,0,2\n", "more than once"),
        ("track,frame,x\n1,0.5,1\n", "whole numbers"),
        ("track,frame,x\n", "no rows"),
        ("", "could not read"),
        ("track,frame,x\n1,0,1,7\n", "more values than the header"),
    ],
)
def test_malformed_tables(tmp_path: Path, text: str, message: str) -> None:
    with pytest.raises(InputError, match=message):
        read_tracks(_write(tmp_path, text))


def test_binary_file(tmp_path: Path) -> None:
    path = tmp_path / "x.csv"
    path.write_bytes(bytes(range(256)))
    with pytest.raises(InputError):
        read_tracks(path)


def test_analyze_tracks_uses_time_column_without_fps(tmp_path: Path) -> None:
    rows = ["track,frame,time_s,x"]
    for track, amplitude in enumerate((30.0, 45.0, 60.0)):
        for frame in range(40):
            t = frame / 10
            rows.append(f"{track},{frame},{t},{100 + amplitude * np.cos(0.9 * t + track)}")
    table = read_tracks(_write(tmp_path, "\n".join(rows) + "\n"))
    result = analyze_tracks(table, 100.0)
    assert result.omega_rad_s == pytest.approx(0.9, rel=1e-6)
    assert result.fps == pytest.approx(10.0)


def test_cli_omega_errors_are_one_line(tmp_path: Path) -> None:
    result = CliRunner().invoke(app, ["omega", str(_write(tmp_path, "track,frame,x\n1,0,1\n")), "--fixation", "0"])
    assert result.exit_code == 2
    assert result.stderr.strip().startswith("rotrate: error:") and "--fps" in result.stderr
    missing = CliRunner().invoke(app, ["omega", str(tmp_path / "none.csv"), "--fixation", "0"])
    assert missing.exit_code == 2 and "no such file" in missing.stderr
