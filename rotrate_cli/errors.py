"""Typed exceptions of the rotrate library.

The library raises these and never prints or exits. Messages are plain text in the library's
own terms: a setting is named as the parameter a Python caller sets, in backquotes
(`fixation_px`, `every=3`). The command line alone turns those into its flags, maps each class
to an exit code and prints one line.
"""

from __future__ import annotations


class RotrateError(Exception):
    """Base class of every error the library raises on purpose."""


class InputError(RotrateError):
    """The input or a setting is unusable (missing file, bad value, unreadable video)."""


class SettingError(InputError):
    """A setting's value is unusable, or two settings contradict each other.

    Attributes:
        setting: the setting at fault, as :class:`~rotrate_cli.config.AnalysisConfig` names it
            (``"angle_from"``); for two that contradict, the first named.
    """

    def __init__(self, message: str, setting: str) -> None:
        super().__init__(message)
        self.setting = setting


class NoResultError(RotrateError):
    """The run completed but produced no trustworthy rotation rate."""


class OutputError(RotrateError):
    """An output file cannot be written, or exists and replacing it was not asked for."""
