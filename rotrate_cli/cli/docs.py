"""docs/cli.md: the command-line reference, made from the commands' own help (``make docs``)."""

from __future__ import annotations

import typer
from typer.cli import get_docs_for_click


def reference() -> str:
    """The Markdown reference of every command and option, as Typer's ``utils docs`` writes it."""
    from rotrate_cli.cli import app

    command = typer.main.get_command(app)
    return get_docs_for_click(obj=command, ctx=typer.Context(command), name="rotrate").strip() + "\n"


if __name__ == "__main__":
    import sys

    sys.stdout.write(reference())
