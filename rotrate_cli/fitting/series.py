"""omega(t): the rate over a sliding window, for objects whose speed changes.

Each window's tracks (cut to the window) go through the same per-track fits, outlier rejection
and joint fit as the whole clip. A rate that changes within the window is measured in two
passes: a constant rate per window first, then each window again with its times warped by the
rate's change that the first pass found (:func:`_warp`): on a rendered box spinning up at
0.15 rad/s^2 the constant-rate windows were off by up to 16%. What remains is a mean
over the window's samples, which is the rate at their mean time, not at the window's centre
when tracks crowd one end of it (the start and end of a clip, a view that opens up): measured
on analytic tracks spinning up, the error at the first and last centres was 4-6%. So each
window's rate is placed at its samples' mean time, and the series is interpolated from those
times to the fixed centres (linearly, with the interval's half-widths alike).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from rotrate_cli.fitting.outliers import Combined
from rotrate_cli.runtime.lazy import pandas as pd

SERIES_COLUMNS = ("time_s", "omega_rad_s", "omega_low_rad_s", "omega_high_rad_s", "tracks_used")


def default_step_s(window_s: float) -> float:
    """About eight steps per window, chosen so that whole seconds are window centres."""
    return 1.0 / max(1, math.ceil(8.0 / window_s)) if window_s <= 8 else 1.0


def window_centres(first_s: float, last_s: float, window_s: float, step_s: float | None = None) -> list[float]:
    """The windows' centres: multiples of ``step_s`` (:func:`default_step_s` where None) whose
    window lies within ``first_s``-``last_s``."""
    step = default_step_s(window_s) if step_s is None else step_s
    half = window_s / 2.0
    centres = []
    index = math.ceil((first_s + half) / step - 1e-9)
    while index * step + half <= last_s + 1e-9:
        centres.append(index * step)
        index += 1
    return centres


#: Passes over the windows: the first with a constant rate in each, the next with the change of
#: rate the first found (see :func:`_warp`).
_PASSES = 3


def _relative_slopes(centres: np.ndarray, omega: np.ndarray, span_s: float) -> np.ndarray:
    """``(d omega / dt) / omega`` at each centre: a straight line through the series' finite
    values within ``span_s`` of it (0 where fewer than three)."""
    ok = np.isfinite(omega) & (omega > 0)
    slopes = np.zeros(len(centres))
    for i, centre in enumerate(centres):
        near = ok & (np.abs(centres - centre) <= span_s + 1e-9)
        if near.sum() >= 3:
            slope, intercept = np.polyfit(centres[near] - centre, omega[near], 1)
            if intercept > 0:
                slopes[i] = slope / intercept
    return slopes


def _warp(time_s: np.ndarray, centre_s: float, relative_slope: float) -> np.ndarray:
    """Times in which a rate changing as ``omega (1 + relative_slope (t - c))`` turns evenly at
    the centre's rate: the turned angle is ``omega (u + relative_slope u^2 / 2)``, ``u = t - c``.
    Fitting a constant rate to warped times measures the rate at the centre, where a constant
    fit to a spinning-up track confuses the chirp with amplitude and phase."""
    u = time_s - centre_s
    return centre_s + u + 0.5 * relative_slope * u * u


def _interpolate(x: np.ndarray, xp: np.ndarray, fp: np.ndarray) -> np.ndarray:
    """Linear interpolation, extended linearly beyond the ends (by the end intervals' slopes)."""
    y = np.interp(x, xp, fp)
    if len(xp) >= 2 and xp[1] > xp[0] and xp[-1] > xp[-2]:
        low, high = x < xp[0], x > xp[-1]
        y[low] = fp[0] + (x[low] - xp[0]) * (fp[1] - fp[0]) / (xp[1] - xp[0])
        y[high] = fp[-1] + (x[high] - xp[-1]) * (fp[-1] - fp[-2]) / (xp[-1] - xp[-2])
    return y


def rate_series(
    offsets: pd.DataFrame,
    window_s: float,
    estimate: Callable[[pd.DataFrame], Combined],
    step_s: float | None = None,
) -> pd.DataFrame:
    """One row per window centre (multiples of ``step_s`` whose window lies inside the clip):
    ``time_s, omega_rad_s, omega_low_rad_s, omega_high_rad_s, tracks_used`` (NaN where the
    window gave no rate). ``estimate`` turns a table of offsets into a combined rate."""
    times = offsets["time_s"].to_numpy()
    rows: list[tuple] = []
    if len(times):
        half = window_s / 2.0
        centres = window_centres(float(times.min()), float(times.max()), window_s, step_s)
        slopes = np.zeros(len(centres))
        for _ in range(_PASSES):
            rows = []
            for centre, slope in zip(centres, slopes, strict=True):
                inside = (times >= centre - half - 1e-9) & (times <= centre + half + 1e-9)
                part = offsets[inside]
                if slope != 0.0:
                    part = part.assign(time_s=_warp(part["time_s"].to_numpy(), centre, slope))
                combined = estimate(part)
                rows.append((round(centre, 9), float(times[inside].mean()), combined.omega_rad_s,
                             combined.omega_low_rad_s, combined.omega_high_rad_s, combined.tracks_used))
            slopes = _relative_slopes(np.array(centres), np.array([r[2] for r in rows], dtype=float), window_s)
    raw = pd.DataFrame(rows, columns=["time_s", "sample_time_s", "omega_rad_s", "omega_low_rad_s",
                                      "omega_high_rad_s", "tracks_used"])
    ok = np.isfinite(raw["omega_rad_s"].to_numpy())
    if ok.sum() >= 2:
        when = raw.loc[ok, "sample_time_s"].to_numpy()
        order = np.argsort(when, kind="stable")
        centres = raw["time_s"].to_numpy()
        value = _interpolate(centres, when[order], raw.loc[ok, "omega_rad_s"].to_numpy()[order])
        for column in ("omega_low_rad_s", "omega_high_rad_s"):
            width = (raw.loc[ok, column] - raw.loc[ok, "omega_rad_s"]).to_numpy()[order]
            raw.loc[ok, column] = value[ok] + _interpolate(centres[ok], when[order], width)
        raw.loc[ok, "omega_rad_s"] = value[ok]
    return raw[list(SERIES_COLUMNS)].astype(
        {"time_s": np.float64, "omega_rad_s": np.float64, "omega_low_rad_s": np.float64,
         "omega_high_rad_s": np.float64, "tracks_used": np.int64})


def running_rate(offsets: pd.DataFrame, measure: Callable[[pd.DataFrame], Combined],
                 step_s: float | None = None) -> pd.DataFrame:
    """The rate as it would have been measured up to each time: :data:`SERIES_COLUMNS` every
    ``step_s`` (default: a twentieth of the clip, at least half a second). ``offsets``: ``track,
    frame, time_s, offset_px``; ``measure``: the combined rate of a part of them (the analysis's
    own rules). NaN until enough of a turn has been seen; no row where no track has a sample."""
    times = offsets["time_s"].to_numpy()
    if len(times) == 0:
        return pd.DataFrame(columns=list(SERIES_COLUMNS))
    first, last = float(times.min()), float(times.max())
    step = step_s if step_s is not None else max(0.5, (last - first) / 20.0)
    rows = []
    for end in np.arange(first + step, last + step / 2, step):
        try:
            combined = measure(offsets[times <= end])
        except (ValueError, IndexError):
            combined = Combined(math.nan, math.nan, math.nan, 0)
        rows.append((float(min(end, last)), combined.omega_rad_s, combined.omega_low_rad_s,
                     combined.omega_high_rad_s, combined.tracks_used))
    return pd.DataFrame(rows, columns=list(SERIES_COLUMNS))
