"""omega(t) after the verdict: each window rated by the source behind the headline (the picture's
return inside the window, or the tracks where they agree with it), with its own quality."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from rotrate_cli.runtime.lazy import pandas as pd
from rotrate_cli.stages.period import Period, Thumbnails, find_period
from rotrate_cli.stages.roll import swaying, turned_back, zooming
from rotrate_cli.stages.verdict import MIN_TRACKS, WEAK_HALF_WIDTH, Verdict

#: Per window, the picture's angle's rate and interval, or None (see
#: :func:`rotrate_cli.scene.picture_angle.window_rates`): given the windows' centres and length.
AngleWindows = Callable[[np.ndarray, float], list[tuple[float, float, float] | None]]


def judged_series(series: pd.DataFrame, verdict: Verdict, thumbnails: Thumbnails, clock_resolution_s: float,
                  window_s: float, angle_windows: AngleWindows | None = None, roll_deg_s: float = 0.0,
                  sway_deg: float = 0.0, zoom_share: float = 0.0) -> pd.DataFrame:
    """omega(t) from the source behind the headline (``series``: the tracks' windows, see
    :func:`rotrate_cli.fitting.series.rate_series`), with ``rate_from`` and ``quality`` per window.
    Where the headline is the picture's return, each window that holds a return is rated by it
    (as many returns a turn as the headline's); a window with none keeps the tracks' rate where
    it agrees with the headline, and is weak otherwise. Where the headline is the tracks', a
    window is weak when its interval is wider than the verdict's rule or few tracks stand behind it.
    ``angle_windows``: the picture's own angle per window, which rates the windows of a headline
    from the picture's turning, and those of a return-rated one that hold no return (a window
    shorter than a turn: the wheel's 2 s windows of a 2.8 s turn). ``roll_deg_s``: the camera's
    steady roll the headline's return was found with (:mod:`rotrate_cli.stages.roll`), taken out
    of each window's pictures likewise; ``sway_deg``: the camera's sway it was found allowing
    (:func:`rotrate_cli.stages.roll.swaying`), allowed likewise (and those windows are weak);
    ``zoom_share``: the zoom it was found allowing (:func:`rotrate_cli.stages.roll.zooming`), likewise."""
    rows = series.copy()
    rate_from = np.full(len(rows), "tracks", dtype=object)
    quality = np.full(len(rows), "good", dtype=object)
    omega = rows["omega_rad_s"].to_numpy(dtype=float).copy()
    low = rows["omega_low_rad_s"].to_numpy(dtype=float).copy()
    high = rows["omega_high_rad_s"].to_numpy(dtype=float).copy()
    times = thumbnails.times_s
    images = thumbnails.images
    centres = rows["time_s"].to_numpy(dtype=float)
    returns = [None] * len(rows)
    for index, centre in enumerate(centres):
        if verdict.rate_from == "repetition" and len(times):
            inside = (times >= centre - window_s / 2 - 1e-9) & (times <= centre + window_s / 2 + 1e-9)
            if inside.sum() >= 8:
                pictures = images[inside]
                if roll_deg_s and thumbnails.shape is not None:
                    pictures = turned_back(times[inside], pictures, thumbnails.shape, roll_deg_s)
                allowing = (swaying(thumbnails.shape, sway_deg) if sway_deg and thumbnails.shape
                            else zooming(thumbnails.shape, zoom_share) if zoom_share and thumbnails.shape else None)
                returns[index] = find_period(times[inside], pictures, clock_resolution_s, allowing)
    by_angle: list[tuple[float, float, float] | None] = [None] * len(rows)
    unreturned = [index for index, found in enumerate(returns) if found is None or found.far_apart]
    if angle_windows is not None and verdict.rate_from in ("repetition", "turning") and unreturned:
        for index, rate in zip(unreturned, angle_windows(centres[unreturned], window_s), strict=True):
            by_angle[index] = rate
    for index, found in enumerate(returns):
        if found is not None and not found.far_apart:
            found = _as_headline(found, verdict)
            omega[index], low[index], high[index] = found.omega_rad_s(verdict.repeats_per_turn)
            rate_from[index] = "repetition"
            agrees = abs(omega[index] / verdict.omega_rad_s - 1.0) <= WEAK_HALF_WIDTH
            # a window's few returns read through a sway are not held to their interval (the
            # swaying record's first 12 s: one 4-s window read 3.606 within [3.577, 3.635])
            quality[index] = "good" if agrees and verdict.quality == "good" and not (sway_deg or zoom_share) else "weak"
            continue
        if by_angle[index] is not None:
            omega[index], low[index], high[index] = by_angle[index]
            rate_from[index] = "turning"
            half = max(omega[index] - low[index], high[index] - omega[index]) / omega[index]
            agrees = abs(omega[index] / verdict.omega_rad_s - 1.0) <= WEAK_HALF_WIDTH
            quality[index] = "good" if agrees and half <= WEAK_HALF_WIDTH and verdict.quality == "good" else "weak"
            continue
        half = max(omega[index] - low[index], high[index] - omega[index]) / omega[index] if omega[index] > 0 else np.inf
        told = rows["tracks_used"].iloc[index] >= MIN_TRACKS and half <= WEAK_HALF_WIDTH
        if verdict.rate_from == "repetition":
            told = told and abs(omega[index] / verdict.omega_rad_s - 1.0) <= WEAK_HALF_WIDTH
        quality[index] = "good" if told and np.isfinite(omega[index]) else "weak"
    return rows.assign(omega_rad_s=omega, omega_low_rad_s=low, omega_high_rad_s=high, rate_from=rate_from,
                       quality=quality)


def _as_headline(found: Period, verdict: Verdict) -> Period:
    """A window's return as the headline's: where it spans a whole number of the headline's (two
    turns where a sway or a light lined up only then; the swaying record's 4 s windows, one of 52
    at half the rate), that many returns."""
    rate = found.omega_rad_s(verdict.repeats_per_turn)[0]
    spans = round(verdict.omega_rad_s / rate) if rate > 0 else 0
    if spans >= 2 and abs(rate * spans / verdict.omega_rad_s - 1.0) <= WEAK_HALF_WIDTH:
        return found.over(found.turns_between * spans)
    return found
