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
        raise OutputError(f"{path} exists; pass `force` to replace it")
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
    # mkstemp makes the file 0600: give it the mode any other tool would (0666 less the umask)
    os.chmod(temporary, 0o666 & ~_umask())
    try:
        yield Path(temporary)
        os.replace(temporary, path)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


def _umask() -> int:
    """The process's umask (read by setting it and setting it back: there is no getter)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def output_format(path: Path | None, given: str | None, default: str = "table") -> str:
    """The report format: ``given`` (``--format``) or, when not given, the output file's extension
    (``.json``, ``.csv``), else ``default``.

    Raises:
        OutputError: the extension contradicts the format given.
    """
    by_name = {".json": "json", ".csv": "csv"}.get(path.suffix.lower()) if path is not None else None
    if given is None:
        return by_name or default
    if by_name is not None and by_name != given:
        raise OutputError(f"`format={given}` contradicts the file name {path} ({by_name}); "
                          "drop `format`, or name the file to match")
    return given


def make_folder(folder: Path) -> None:
    """Create ``folder`` and its parents (as ``mkdir -p``).

    Raises:
        OutputError: it cannot be created (a file in the way, no permission).
    """
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"cannot create the folder {folder}: {exc.strerror or exc}") from None


def write_text(path: Path, text: str, force: bool) -> None:
    """Write ``text`` to ``path`` through a temporary file and a rename: never half a file."""
    with replacing(path, force) as temporary:
        temporary.write_text(text, encoding="utf-8")
