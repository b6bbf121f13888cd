"""Command-line polish: a window longer than the clip, the format from the output's name, file
modes, output folders made, honest help and --version, the paper's method at its own spacing."""

from __future__ import annotations

import json
import os
import re
import stat
from pathlib import Path

import pytest
from typer.testing import CliRunner

from rotrate_cli.cli import app
from tests.conftest import SAMPLES

runner = CliRunner()
CLIP = str(SAMPLES / "box_ortho.mp4")
FIX = ["--fixation", "319.5,179.5", "-q"]


def _one_error_line(result, code: int, *words: str) -> None:
    assert result.exit_code == code, result.output
    lines = [line for line in result.stderr.splitlines() if line.startswith("rotrate: error: ")]
    assert len(lines) == 1 and "Traceback" not in result.output
    for word in words:
        assert word in lines[0]


def test_a_window_longer_than_the_clip_is_one_line_exit_2() -> None:
    _one_error_line(runner.invoke(app, ["analyze", CLIP, *FIX, "--window", "20"]), 2, "--window", "longer")


@pytest.mark.parametrize(("name", "check"), [
    ("out.json", lambda text: json.loads(text)["omega"] > 0),
    ("out.csv", lambda text: text.startswith("feature,frame,time_s")),
    ("out.txt", lambda text: "omega" in text and "rad/s" in text),
])
def test_the_format_comes_from_the_output_name(tmp_path: Path, name: str, check) -> None:
    target = tmp_path / name
    result = runner.invoke(app, ["analyze", CLIP, *FIX, "-o", str(target)])
    assert result.exit_code == 0, result.output
    assert check(target.read_text())


def test_a_format_that_contradicts_the_name_is_refused(tmp_path: Path) -> None:
    target = tmp_path / "out.json"
    _one_error_line(runner.invoke(app, ["analyze", CLIP, *FIX, "-f", "table", "-o", str(target)]), 2, "contradicts")
    assert not target.exists()


def test_output_files_honour_the_umask(tmp_path: Path) -> None:
    previous = os.umask(0o022)
    try:
        target = tmp_path / "out.json"
        assert runner.invoke(app, ["analyze", CLIP, *FIX, "-o", str(target)]).exit_code == 0
    finally:
        os.umask(previous)
    assert stat.S_IMODE(target.stat().st_mode) == 0o644


def test_output_dir_is_made_with_its_parents(tmp_path: Path) -> None:
    folder = tmp_path / "reports" / "today"
    result = runner.invoke(app, ["analyze", CLIP, str(SAMPLES / "cylinder_ortho.mp4"), "--fixation", "auto", "-q",
                                 "--output-dir", str(folder)])
    assert result.exit_code == 0, result.output
    assert sorted(p.name for p in folder.iterdir()) == ["box_ortho.json", "cylinder_ortho.json"]


def test_help_says_what_each_command_has() -> None:
    check = runner.invoke(app, ["check", "--help"]).stdout
    assert "Table I" not in check and "--output file" not in check and "--junit file" in check
    analyze = runner.invoke(app, ["analyze", "--help"]).stdout
    for metavar in ("X,Y|auto", "SECONDS", "DEG", "PATH"):
        assert metavar in analyze
    assert "<str>" not in analyze and "<float>" not in analyze
    flags = [line for line in analyze.splitlines() if "--force" in line or "--strict" in line]
    assert flags and not any("<bool>" in line for line in flags)
    for command in ([], ["analyze"], ["check"], ["synth"], ["frame"], ["omega"]):  # --help is a flag too
        shown = runner.invoke(app, [*command, "--help"]).stdout
        assert "--help" in shown and "<bool>" not in shown, command
    version = runner.invoke(app, ["--version"])
    assert version.exit_code == 0 and version.stdout.startswith("rotrate ")


@pytest.mark.parametrize(("command", "usage"), [
    ("analyze", "[OPTIONS] VIDEO..."), ("check", "[OPTIONS] MANIFEST"), ("frame", "[OPTIONS] VIDEO"),
    ("omega", "[OPTIONS] TRACKS"), ("synth", "[OPTIONS] OUTPUT")])
def test_usage_lines_name_arguments_as_other_tools_do(command: str, usage: str) -> None:
    line = next(line for line in runner.invoke(app, [command, "--help"]).stdout.splitlines() if "Usage:" in line)
    assert line.split("Usage: ")[1].strip() == f"rotrate {command} {usage}"  # not Typer's {VIDEO}...


def test_the_papers_method_takes_the_papers_spacing() -> None:
    """At --every 1 the paper's second differences are noise (1.463 for 0.6); by default the
    spacing is about a sixth of a radian, as the paper's 16 frames at 30 fps."""
    result = runner.invoke(app, ["analyze", CLIP, *FIX, "--method", "paper", "-f", "json"])
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout)["omega"] == pytest.approx(0.6, rel=0.05)


def test_the_command_line_starts_without_the_heavy_libraries() -> None:
    """`rotrate --help` (and a shell loop's every start) must not pay for OpenCV, pandas or
    SciPy: the commands import the stages they run. Timed in `make bench`; checked here."""
    import subprocess
    import sys

    code = ("import sys, rotrate_cli.cli, rotrate_cli; "
            "print(','.join(m for m in ('cv2', 'pandas', 'scipy', 'numpy') if m in sys.modules))")
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert loaded == ""


def test_the_floor_job_pins_the_declared_floors() -> None:
    """make test-floor installs constraints/floor.txt: it must pin exactly the lowest versions
    pyproject.toml declares, so the floor that is tested is the floor that is promised."""
    import re
    import tomllib

    root = Path(__file__).resolve().parents[1]
    declared = {}
    for requirement in tomllib.loads((root / "pyproject.toml").read_text())["project"]["dependencies"]:
        name, floor = re.fullmatch(r"([A-Za-z0-9_.-]+)>=([0-9.]+)", requirement.replace(" ", "")).groups()
        declared[name.lower()] = floor
    pinned = dict(line.split("==") for line in (root / "constraints" / "floor.txt").read_text().splitlines()
                  if line and not line.startswith("#"))
    pinned = {name.lower(): version for name, version in pinned.items()}
    for name, floor in declared.items():
        assert name in pinned, f"{name} is not pinned in constraints/floor.txt"
        assert pinned[name].startswith(floor), f"{name}: declared >={floor}, tested {pinned[name]}"


def test_library_messages_name_settings_and_the_command_line_says_its_flags():
    """A library caller reads the setting it set (`every`); the command line's user reads the flag."""
    from rotrate_cli import AnalysisConfig, SettingError, analyze
    from rotrate_cli.cli import in_flags

    with pytest.raises(SettingError, match="`every` must be a whole number") as caught:
        analyze(SAMPLES / "box_ortho.mp4", AnalysisConfig(fixation_px=None, every=0))
    assert caught.value.setting == "every"
    assert "--" not in str(caught.value)
    assert in_flags(str(caught.value)).startswith("--every must be a whole number")
    assert in_flags("use `fixation_px=None` or `find_focal=False`; `every=3`; `not_a_setting`") == (
        "use --fixation auto or --fov ortho; --every 3; `not_a_setting`")


def test_no_library_message_names_a_flag():
    """Flags belong to the command line (rotrate_cli/cli/): a library string never names one."""
    import ast

    package = Path(__file__).resolve().parents[1] / "rotrate_cli"
    named = []
    for path in package.rglob("*.py"):
        if "cli" in path.relative_to(package).parts[:1]:
            continue
        tree = ast.parse(path.read_text())
        docstrings = {id(node.body[0].value) for node in ast.walk(tree)
                      if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef)
                      and node.body and isinstance(node.body[0], ast.Expr)
                      and isinstance(node.body[0].value, ast.Constant)}
        for node in ast.walk(tree):
            if (isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docstrings
                    and re.search(r"(?<![\w-])--[a-z][a-z-]+", node.value)):
                named.append(f"{path.name}:{node.lineno}: {node.value[:60]}")
    assert not named, named


def test_output_dash_is_standard_output(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """``-o -`` writes the report to standard output, not to a file named '-'."""
    monkeypatch.chdir(tmp_path)
    result = runner.invoke(app, ["analyze", str(SAMPLES / "box_ortho.mp4"), "--fixation", "auto", "-o", "-",
                                 "-f", "json", "-q"])
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout)["omega"] > 0
    assert not (tmp_path / "-").exists()


@pytest.mark.parametrize("args", [["analyze", "--bogus", "x"], ["analyze"], ["nosuch"]])
def test_usage_errors_are_one_line_and_exit_2(args: list[str]) -> None:
    """Click's framed usage box was five lines; the README promises one line for every error."""
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-m", "rotrate_cli", *args], capture_output=True, text=True, timeout=60)
    assert done.returncode == 2
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("rotrate: error: ") and "--help" in lines[0]
    assert "Traceback" not in done.stderr
