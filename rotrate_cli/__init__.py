"""rotrate: measure how fast a rigid object spins, in rad/s, from an ordinary video.

One call does the whole job::

    from rotrate_cli import AnalysisConfig, analyze
    result = analyze("car.mp4", AnalysisConfig(fixation_px=(640, 360)))
    print(result.omega_rad_s, result.omega_low_rad_s, result.omega_high_rad_s)

The library never prints or exits; it raises :class:`InputError` (bad input) and
:class:`NoResultError` (no trustworthy result), both :class:`RotrateError`; a
:class:`SettingError` (an :class:`InputError`) names the setting at fault. See docs/api.md.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from rotrate_cli.analysis import Analysis, AnalysisConfig, analyze, analyze_tracks
    from rotrate_cli.errors import InputError, NoResultError, OutputError, RotrateError, SettingError
    from rotrate_cli.fitting.outliers import RejectionConfig
    from rotrate_cli.tracking.klt import Roi, TrackerConfig
    from rotrate_cli.tracking.tracks_io import read_tracks

#: Where each public name lives: imported when first used, so that the command line's start
#: (``rotrate --help``) does not pay for OpenCV, pandas and SciPy.
_HOMES = {
    "Analysis": "analysis", "AnalysisConfig": "analysis", "analyze": "analysis", "analyze_tracks": "analysis",
    "InputError": "errors", "NoResultError": "errors", "OutputError": "errors", "RotrateError": "errors",
    "SettingError": "errors",
    "RejectionConfig": "fitting.outliers", "Roi": "tracking.klt", "TrackerConfig": "tracking.klt",
    "read_tracks": "tracking.tracks_io",
}

__all__ = [
    "Analysis", "AnalysisConfig", "InputError", "NoResultError", "OutputError", "RejectionConfig", "Roi",
    "RotrateError", "SettingError", "TrackerConfig", "analyze", "analyze_tracks", "read_tracks",
]
__version__ = "0.1.0"


def __getattr__(name: str) -> Any:
    if name in _HOMES:
        return getattr(importlib.import_module(f"rotrate_cli.{_HOMES[name]}"), name)
    raise AttributeError(f"module 'rotrate_cli' has no attribute {name!r}")
