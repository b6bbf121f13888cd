"""Writing output files safely: never over a user's file without ``--force``, never half a file.

Every file rotrate writes (reports, series, overlays, plots, stills) goes through
:func:`replacing`: a temporary name beside the target, renamed over it only once complete, and
removed if anything (an error, Ctrl-C) stops the writing.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from rotrate_cli.errors import OutputError


def check_output_path(path: Path, force: bool) -> None:
    """Raise OutputError unless ``path`` can be written (and may be replaced)."""
    if path.is_dir():
        raise OutputError(f"{path} is a folder; give a file name")
    if path.exists() and not force:
        raise OutputError(f"{path} exists; pass --force to replace it")
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.is_dir():
        raise OutputError(f"the folder {parent} does not exist")
    if not os.access(parent, os.W_OK):
        raise OutputError(f"cannot write into the folder {parent}")


@contextmanager
def replacing(path: Path, force: bool, suffix: str = ".partial") -> Iterator[Path]:
    """A temporary path to write ``path``'s content to; renamed over ``path`` when the block
    ends normally, removed when it does not. ``suffix`` ends the temporary name (writers that
    pick the format from the name need the real one)."""
    check_output_path(path, force)
    parent = path.parent if str(path.parent) else Path(".")
    handle, temporary = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=suffix, dir=parent)
    os.close(handle)
    try:
        yield Path(temporary)
        os.replace(temporary, path)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


def write_text(path: Path, text: str, force: bool) -> None:
    """Write ``text`` to ``path`` through a temporary file and a rename: never half a file."""
    with replacing(path, force) as temporary:
        temporary.write_text(text, encoding="utf-8")
