"""The user docs hold what is true now: the CLI reference is the commands' own help, and the API
page's example runs."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def test_the_cli_reference_is_the_commands_help():
    """Fails when an option's help changed and docs/cli.md was not made again (``make docs``)."""
    from rotrate_cli.cli.docs import reference

    assert (ROOT / "docs" / "cli.md").read_text() == reference(), "docs/cli.md is stale: run make docs"


def test_the_cli_reference_lists_every_command():
    text = (ROOT / "docs" / "cli.md").read_text()
    for command in ("analyze", "check", "frame", "omega", "synth"):
        assert f"## `rotrate {command}`" in text


def test_the_api_page_s_example_runs(monkeypatch, capsys):
    text = (ROOT / "docs" / "api.md").read_text()
    example = re.search(r"```python\n(.*?)```", text, re.S).group(1)
    monkeypatch.chdir(ROOT)
    exec(compile(example, "docs/api.md", "exec"), {})  # noqa: S102 - the doc's own example
    printed = capsys.readouterr().out.splitlines()
    assert printed[0].endswith("good repetition") or "rad/s" in printed[0]
    assert printed[1].startswith("every - `every` must be a whole number")


@pytest.mark.parametrize("page", ["README.md", "docs/usage.md", "docs/method.md", "docs/api.md", "docs/accuracy.md"])
def test_user_docs_link_to_pages_that_exist(page):
    text = (ROOT / page).read_text()
    for target in re.findall(r"\]\(([^)#:]+\.md)\)", text):
        assert (ROOT / page).parent.joinpath(target).resolve().is_file(), f"{page} links to missing {target}"
