"""Stage 8, after the verdict: the view read from the tracks' paths at the reported rate.

The view (how far the axis leans out of the picture, the turning centre) needs the rate, so it
is read once the verdict has said which rate stands; where that rate is the clip's repetition
and the axis was to be found, the paths' turning centre becomes the axis.
"""

from __future__ import annotations

import math
from dataclasses import replace

from rotrate_cli.runtime.lazy import pandas as pd
from rotrate_cli.scene.view import view_from_paths
from rotrate_cli.stages.geometry import Geometry


def view_at_rate(geometry: Geometry, view_tracks: pd.DataFrame, omega_rad_s: float, rate_from: str,
                size_px: tuple[int, int]) -> Geometry:
    """Step 3: the geometry with the view read from the tracks' paths at the reported rate. Where
    that rate is the clip's repetition and the fixation was to be found, the found fixation is
    the paths' turning centre: the tracks' own axis search assumes a side view (on the record
    clip it put the spindle 380 px off; the paths' centre is 25 px off, and 37 px off where the
    picture is cropped to leave the spindle outside it)."""
    view = view_from_paths(view_tracks, omega_rad_s)
    if view is None:
        return geometry
    estimate = geometry.lens.estimate
    if estimate is not None and math.isfinite(estimate.focal_px) and math.isfinite(geometry.elevation_deg):
        # the paths read their ellipses as seen from far away; through the lens found, its fit's
        # elevation is the view's (from 60 degrees above through a 65-degree lens: paths 50, lens 59)
        view = replace(view, elevation_deg=abs(geometry.elevation_deg))
    changes_: dict[str, object] = {"view": view}
    if math.isnan(geometry.elevation_deg):
        changes_["elevation_deg"] = view.elevation_deg
    if geometry.fixation_found and rate_from == "repetition":
        changes_["fixation_px"] = view.centre_px
        x, y = view.centre_px
        if not (0 <= x <= size_px[0] - 1 and 0 <= y <= size_px[1] - 1):
            changes_["notes"] = (*geometry.notes, f"the axis found, ({x:.0f}, {y:.0f}), lies outside the "
                                 f"{size_px[0]}x{size_px[1]} frame")
    return replace(geometry, **changes_)  # type: ignore[arg-type]
