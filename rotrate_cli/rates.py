"""Rotation-rate estimators: per sample and per track.

The paper's relation: with ``offset_px`` the horizontal distance of a point from the fixation
point on the rotation axis (the paper's ``y``), orthographic projection and a constant rate,
``d2 offset / dt2 = -omega^2 * offset``.

Two families are offered:

* ``paper``: the reference paper's Table I, faithfully: backward differences at the sampling
  step (first derivative from consecutive samples, second derivative from consecutive first
  derivatives), ``omega^2 = -y''/y`` per sample, and a feature's omega is the mean of its
  per-sample omegas where ``omega^2 > 0``.
* ``fit`` (ours, the default): the solution of that differential equation is
  ``offset = a cos(omega t) + b sin(omega t)``; fitting it to all of a track's samples by least
  squares uses every sample at once, needs no numerical derivative, is exact at any sampling step,
  and weighs near-singular samples (offset ~ 0) correctly instead of dividing by them. The
  per-sample columns are then the exact discrete form of the same relation at a lag chosen for
  the noise, ``cos(omega m dt) = (y[k+m] + y[k-m]) / (2 y[k])``, for inspection.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd

METHODS = ("fit", "paper")


@dataclass(frozen=True)
class TrackFit:
    """A sinusoid fitted to one track's offsets.

    Attributes:
        omega_rad_s: the fitted rate (magnitude), rad/s; NaN when the fit failed.
        omega_se_rad_s: its standard error from the fit's residuals, rad/s.
        rms_residual: root-mean-square misfit of the offsets, in their units.
        amplitude: the fitted amplitude ``sqrt(a^2 + b^2)``, in the offsets' units.
        arc_rad: the rotation angle the track spans, ``omega * duration``.
    """

    omega_rad_s: float
    omega_se_rad_s: float
    rms_residual: float
    amplitude: float
    arc_rad: float


_FAILED = TrackFit(math.nan, math.nan, math.nan, math.nan, math.nan)


def _linear_amplitudes(time_s: np.ndarray, offset: np.ndarray, omega: float) -> tuple[np.ndarray, np.ndarray]:
    basis = np.column_stack([np.cos(omega * time_s), np.sin(omega * time_s)])
    coef, *_ = np.linalg.lstsq(basis, offset, rcond=None)
    return coef, offset - basis @ coef


def recurrence_omega(time_s: np.ndarray, offset: np.ndarray) -> float:
    """Closed-form first guess from the exact three-term recurrence at the median step.

    ``y[k-1] + y[k+1] = 2 cos(omega dt) y[k]`` is solved for ``cos(omega dt)`` by least squares
    over the track (weights ``y[k]^2``, so near-singular samples count little). Returns NaN
    when the track curves away from the axis (no real solution).
    """
    if len(offset) < 3:
        return math.nan
    dt = float(np.median(np.diff(time_s)))
    middle = offset[1:-1]
    denominator = 2.0 * float(middle @ middle)
    if dt <= 0 or denominator <= 0:
        return math.nan
    cosine = float(middle @ (offset[:-2] + offset[2:])) / denominator
    if not -1.0 < cosine < 1.0:
        return math.nan if cosine >= 1.0 else math.pi / dt
    return math.acos(cosine) / dt


def fit_track(time_s: np.ndarray, offset: np.ndarray, iterations: int = 30) -> TrackFit:
    """Fit ``offset = a cos(omega t) + b sin(omega t)`` to one track by Gauss-Newton.

    ``time_s`` may be unevenly spaced. The start comes from :func:`recurrence_omega`, refined
    over ``(a, b, omega)`` jointly. The standard error is the usual ``s^2 (J^T J)^-1`` one.
    """
    n = len(offset)
    if n < 4:
        return _FAILED
    t = time_s - time_s.mean()  # centring decorrelates omega from the phase
    omega = recurrence_omega(time_s, offset)
    if not math.isfinite(omega) or omega <= 0:
        return _FAILED
    # A few trial rates around the first guess guard against a noisy start.
    candidates = omega * np.array([0.7, 0.85, 1.0, 1.15, 1.3])
    omega = float(min(candidates, key=lambda w: float(np.sum(_linear_amplitudes(t, offset, w)[1] ** 2))))
    coef, residual = _linear_amplitudes(t, offset, omega)
    a, b = coef
    for _ in range(iterations):
        cos_wt, sin_wt = np.cos(omega * t), np.sin(omega * t)
        model = a * cos_wt + b * sin_wt
        residual = offset - model
        jacobian = np.column_stack([cos_wt, sin_wt, t * (-a * sin_wt + b * cos_wt)])
        step, *_ = np.linalg.lstsq(jacobian, residual, rcond=None)
        a, b, omega = a + step[0], b + step[1], omega + step[2]
        if abs(step[2]) < 1e-12 * max(1.0, abs(omega)):
            break
    cos_wt, sin_wt = np.cos(omega * t), np.sin(omega * t)
    residual = offset - (a * cos_wt + b * sin_wt)
    jacobian = np.column_stack([cos_wt, sin_wt, t * (-a * sin_wt + b * cos_wt)])
    rss = float(residual @ residual)
    dof = max(n - 3, 1)
    try:
        covariance = np.linalg.inv(jacobian.T @ jacobian) * (rss / dof)
        se = math.sqrt(max(float(covariance[2, 2]), 0.0))
    except np.linalg.LinAlgError:
        se = math.inf
    omega = abs(float(omega))
    if not math.isfinite(omega):
        return _FAILED
    return TrackFit(
        omega_rad_s=omega,
        omega_se_rad_s=se,
        rms_residual=math.sqrt(rss / n),
        amplitude=float(math.hypot(a, b)),
        arc_rad=omega * float(time_s[-1] - time_s[0]),
    )


def paper_samples(samples: pd.DataFrame) -> pd.DataFrame:
    """The paper's per-sample derivatives and rates (Table I), per track.

    Input columns: ``track, frame, time_s, offset_px`` (sorted by track then time). Backward
    differences at the sampling step: ``dy_dt[k] = (y[k] - y[k-1]) / dt``,
    ``d2y_dt2[k] = (dy_dt[k] - dy_dt[k-1]) / dt``, ``omega2 = -d2y_dt2 / y`` and
    ``omega = sqrt(omega2)`` where ``omega2 > 0`` (NaN otherwise, as the paper left it blank).
    """
    table = samples.loc[:, ["track", "frame", "time_s", "offset_px"]].copy()
    grouped = table.groupby("track", sort=False)
    dt = grouped["time_s"].diff()
    table["dy_dt"] = grouped["offset_px"].diff() / dt
    table["d2y_dt2"] = table.groupby("track", sort=False)["dy_dt"].diff() / dt
    with np.errstate(divide="ignore", invalid="ignore"):
        table["omega2"] = -table["d2y_dt2"] / table["offset_px"]
    table["omega_rad_s"] = np.sqrt(table["omega2"].where(table["omega2"] > 0))
    return table


def local_lag(omega_dt_rad: float, n: int) -> int:
    """The lag (in samples) for per-sample second differences.

    The second difference grows as ``(omega m dt)^2`` while its noise stays ``~2 sigma``, so a
    longer lag is better until the three samples span a large arc: aim for half a radian, but
    keep at least half of the track's samples with a value.
    """
    if omega_dt_rad <= 0 or not math.isfinite(omega_dt_rad):
        return 1
    return int(max(1, min(round(0.5 / omega_dt_rad), (n - 1) // 4)))


def _track_slices(tracks: np.ndarray) -> list[slice]:
    """Slices of consecutive equal ids in a sorted id array."""
    if len(tracks) == 0:
        return []
    edges = np.flatnonzero(np.diff(tracks)) + 1
    bounds = np.concatenate([[0], edges, [len(tracks)]])
    return [slice(int(a), int(b)) for a, b in zip(bounds[:-1], bounds[1:], strict=True)]


def fit_samples(samples: pd.DataFrame, fits: dict[int, TrackFit]) -> pd.DataFrame:
    """Per-sample values for the fit method: central differences at lag ``m`` and the exact
    discrete rate ``omega = arccos((y[k+m] + y[k-m]) / (2 y[k])) / (m dt)``.

    ``samples`` is sorted by track, then time. ``dy_dt`` is the central difference at that lag
    and ``d2y_dt2 = -omega2 * y``, the second derivative of the sinusoid through the three
    samples; rows near a track's ends have NaN.
    """
    table = samples.loc[:, ["track", "frame", "time_s", "offset_px"]].reset_index(drop=True)
    tracks = table["track"].to_numpy()
    times = table["time_s"].to_numpy(dtype=float)
    offsets = table["offset_px"].to_numpy(dtype=float)
    n_all = len(table)
    dy = np.full(n_all, np.nan)
    omega2 = np.full(n_all, np.nan)
    for part in _track_slices(tracks):
        time_s, offset = times[part], offsets[part]
        n = len(offset)
        if n < 3:
            continue
        fit = fits.get(int(tracks[part.start]), _FAILED)
        lag = local_lag(fit.omega_rad_s * float(np.median(np.diff(time_s))), n)
        if n <= 2 * lag:
            continue
        k = np.arange(lag, n - lag)
        step_s = (time_s[k + lag] - time_s[k - lag]) / 2.0
        with np.errstate(divide="ignore", invalid="ignore"):
            cosine = (offset[k + lag] + offset[k - lag]) / (2.0 * offset[k])
            rate = np.arccos(np.clip(cosine, -1.0, 1.0)) / step_s
            # cos > 1 means the point curves away from the axis: a negative omega^2.
            rate2 = np.where(cosine > 1.0, -(np.arccosh(np.maximum(cosine, 1.0)) / step_s) ** 2, rate**2)
        dy[part.start + k] = (offset[k + lag] - offset[k - lag]) / (2.0 * step_s)
        omega2[part.start + k] = rate2
    table["dy_dt"] = dy
    table["d2y_dt2"] = -omega2 * offsets
    table["omega2"] = omega2
    table["omega_rad_s"] = np.sqrt(np.where(omega2 > 0, omega2, np.nan))
    return table


def fit_tracks(samples: pd.DataFrame) -> dict[int, TrackFit]:
    """Fit every track of ``samples`` (sorted by track then time; columns ``track, time_s,
    offset_px``); keyed by track."""
    tracks = samples["track"].to_numpy()
    times = samples["time_s"].to_numpy(dtype=float)
    offsets = samples["offset_px"].to_numpy(dtype=float)
    return {int(tracks[part.start]): fit_track(times[part], offsets[part]) for part in _track_slices(tracks)}
