"""Outputs that cannot be written fail before any frame is read (issue 50, item 2): one line, exit 2."""

from __future__ import annotations

import time
from pathlib import Path

import pytest
from typer.testing import CliRunner

from rotrate_cli.cli import app
from tests.conftest import SAMPLES

runner = CliRunner()
CLIP = SAMPLES / "box_ortho.mp4"


def _run(*args: str) -> tuple[int, str, float]:
    started = time.monotonic()
    result = runner.invoke(app, list(args))
    return result.exit_code, result.stderr, time.monotonic() - started


def test_a_plot_in_a_format_matplotlib_does_not_write_fails_first(tmp_path: Path) -> None:
    code, stderr, _ = _run("analyze", str(CLIP), "--fixation", "auto", "--plot", str(tmp_path / "out.xyz"))
    assert code == 2
    lines = stderr.strip().splitlines()
    assert len(lines) == 1 and "--plot" in lines[0] and ".png" in lines[0]
    assert not list(tmp_path.iterdir())


def test_a_plot_without_matplotlib_fails_first(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import importlib.util

    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == "matplotlib" else real(name, *a))
    code, stderr, _ = _run("analyze", str(CLIP), "--fixation", "auto", "--plot", str(tmp_path / "out.png"))
    assert code == 2 and "rotrate[plot]" in stderr and len(stderr.strip().splitlines()) == 1


def test_frame_to_a_name_no_picture_format_has_fails_first(tmp_path: Path) -> None:
    code, stderr, _ = _run("frame", str(CLIP), "-o", str(tmp_path / "f.txt"))
    assert code == 2
    lines = stderr.strip().splitlines()
    assert len(lines) == 1 and ".png" in lines[0] and "Traceback" not in stderr
    assert not (tmp_path / "f.txt").exists()
