"""The tracks' rate checked before it is judged (:func:`check_rate`): by the found lens's
uncertainty, a given fixation the tracks disagree with, a rate that changes over the clip, and,
seen obliquely or face on, the rate of the tracks' paths in both image coordinates. Each either
widens the interval or names a doubt that makes a tracks-only result weak."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from rotrate_cli.camera import with_lens_doubt
from rotrate_cli.config import AnalysisConfig
from rotrate_cli.fits import RateResult, rate_change
from rotrate_cli.geometry import Geometry, fixation_doubt
from rotrate_cli.lazy import pandas as pd
from rotrate_cli.outliers import Combined
from rotrate_cli.view import rate_from_paths, view_from_paths


@dataclass(frozen=True)
class Checked:
    """The tracks' result after the checks.

    Attributes:
        result: the result, its interval widened where a check asked.
        doubts: doubts about the tracks' rate (they make a tracks-only result weak).
        notes: what the user should know (an interval widened).
    """

    result: RateResult
    doubts: tuple[str, ...] = ()
    notes: tuple[str, ...] = ()


def check_rate(result: RateResult, geometry: Geometry, config: AnalysisConfig, size_px: tuple[int, int],
               view_tracks: pd.DataFrame, repeating: bool) -> Checked:
    """The checks of the module's notes. ``repeating``: the clip's repetition gives the rate,
    which needs no axis and no lens and is its own check of a steady rate: only the lens's
    uncertainty is then carried (it shows in the tracks' own interval)."""
    result = with_lens_doubt(result, geometry.lens, geometry.fixation_px, geometry.axis_angle_deg, config, size_px)
    if repeating or result.combined.tracks_used == 0:
        return Checked(result)
    doubts: tuple[str, ...] = ()
    camera = geometry.camera(size_px)
    doubt = fixation_doubt(result, geometry, config, size_px)
    if doubt is not None:
        doubts += (doubt,)
    change = rate_change(result, config, camera)
    if change is not None:
        doubts += (change,)
    result, note = with_paths_rate(result, view_tracks)
    return Checked(result, doubts, (note,) if note else ())


def with_paths_rate(result: RateResult, view_tracks: pd.DataFrame) -> tuple[RateResult, str | None]:
    """Seen obliquely or face on, the result with its interval widened to hold the rate of the
    tracks' paths in both image coordinates (:func:`rotrate_cli.view.rate_from_paths`), and a
    note saying so; as it was in a side view, or where the two agree. The offsets across one
    image direction assume the paths' centres line up across it, which an axis leaning towards
    the camera breaks (rendered box from 60 degrees above: -2.5%, interval [-4.7%, -0.3%]; its
    paths: +0.6%)."""
    combined = result.combined
    view = view_from_paths(view_tracks, combined.omega_rad_s)
    if view is None or view.name == "side":
        return result, None
    paths = rate_from_paths(view_tracks, combined.omega_rad_s) * (1.0 if combined.omega_rad_s >= 0 else -1.0)
    if not math.isfinite(paths) or combined.omega_low_rad_s <= paths <= combined.omega_high_rad_s:
        return result, None
    widened = Combined(combined.omega_rad_s, min(combined.omega_low_rad_s, paths),
                       max(combined.omega_high_rad_s, paths), combined.tracks_used)
    note = (f"seen {view.name} ({view.elevation_deg:.0f} deg), the tracks' paths fitted in both image coordinates "
            f"give {paths:.4g} rad/s, outside the offsets' interval: the interval is widened to hold it")
    return replace(result, combined=widened), note
