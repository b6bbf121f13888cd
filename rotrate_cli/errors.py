"""Typed exceptions of the rotrate library.

The library raises these and never prints or exits; the CLI maps each class to an exit code
and prints its message as one line. Messages are plain text and say what to do.
"""

from __future__ import annotations


class RotrateError(Exception):
    """Base class of every error the library raises on purpose."""

    exit_code: int = 2


class InputError(RotrateError):
    """The input or an option is unusable (missing file, bad value, unreadable video). Exit 2."""

    exit_code = 2


class NoResultError(RotrateError):
    """The run completed but produced no trustworthy rotation rate. Exit 1."""

    exit_code = 1


class OutputError(RotrateError):
    """An output file cannot be written, or exists and --force was not given. Exit 2."""

    exit_code = 2
