"""Several rigid bodies in one scene: tracks grouped by their own rate and axis.

The paper notes that points of another body give another omega, so omega can segment a scene.
Every point of one body shares two numbers: the rate and the axis. Each track gets both on its
own from the exact recurrence of its positions along the offset direction (see
:mod:`rotrate_cli.scene.axis`): at a lag of ``m`` frames, ``s[k+m] + s[k-m] = kappa s[k] + beta``,
with ``kappa = 2 cos(omega m dt)`` and ``beta = (2 - kappa) o``; a straight-line fit per track
gives ``omega`` and the axis position ``o``, no model of the body needed.

The tracks are then grouped by mode seeking in (log rate, axis) space: the track with the most
neighbours within :data:`RATE_TOLERANCE` and the axis tolerance seeds a body, whose centre is the
median of those neighbours; every track near the centre joins it, and the search repeats on the
rest while a group of at least :data:`MIN_BODY_TRACKS` is left. Each body is then measured on
its own by the usual pipeline (axis found, joint fit, interval).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rotrate_cli.fitting.joint import track_misfits
from rotrate_cli.runtime.lazy import pandas as pd

#: Lags (frames) at which each track's recurrence is fitted; the longest one that turns the
#: track by at most :data:`_MAX_TURN_RAD` and leaves :data:`_MIN_TRIPLES` triples is used.
_LAGS = (1, 2, 4, 8, 16, 32)
_MAX_TURN_RAD = 1.2
_MIN_TRIPLES = 5
#: Tracks of one body lie within this relative rate (in log) and this fraction of the frame's
#: extent across the axis of the group's centre.
RATE_TOLERANCE = 0.12
AXIS_TOLERANCE_FRACTION = 0.03
#: A candidate group joins an earlier body when that body's rate and axis explain its tracks
#: with at most this multiple of the summed squared misfit of the group's own. Measured on the
#: two-body sample: fringes of a body score 0.4-1.6, the other body 900 and more.
MERGE_RATIO = 4.0
#: Groups whose rates and axes both lie within this many tolerances of each other are one body
#: (the per-track estimates cannot resolve closer ones; perspective alone spreads one body's
#: tracks that far when ``--fov`` is not given).
RESOLUTION = 2.0
#: A track joins the body that fits it best only when that misfit is at most this fraction of
#: the next body's.
AMBIGUITY = 0.25
#: The fewest tracks that make a body, and the most bodies reported.
MIN_BODY_TRACKS = 10
MAX_BODIES = 8
#: Candidates tried as the seed of a body (a subset for very many tracks: the cost is quadratic).
_MAX_SEEDS = 1500


@dataclass(frozen=True)
class Body:
    """One rigid body of a segmented scene.

    Attributes:
        omega_rad_s, omega_low_rad_s, omega_high_rad_s: its rate and 95% interval, rad/s.
        axis_px: a point on its axis (x, y pixels).
        direction: ``ccw``, ``cw`` or ``unknown`` (seen from the top end of its axis).
        tracks_used, tracks_total: its tracks that went into the rate, and all it was given.
    """

    omega_rad_s: float
    omega_low_rad_s: float
    omega_high_rad_s: float
    axis_px: tuple[float, float]
    direction: str
    tracks_used: int
    tracks_total: int


def track_motion(tracks: pd.DataFrame, position: np.ndarray) -> pd.DataFrame:
    """Each track's own rate and axis position.

    Args:
        tracks: ``track, frame, time_s`` sorted by track then frame.
        position: each row's position along the offset direction (pixels).

    Returns:
        One row per track that the recurrence could fit: ``track, omega_rad_s, axis_px``
        (``axis_px`` in the units of ``position``), ``lag`` (frames) and ``triples``.
    """
    track = tracks["track"].to_numpy()
    frame = tracks["frame"].to_numpy()
    time_s = tracks["time_s"].to_numpy(dtype=float)
    ids, code = np.unique(track, return_inverse=True)
    k = len(ids)
    best_omega = np.full(k, np.nan)
    best_axis = np.full(k, np.nan)
    best_lag = np.zeros(k, dtype=int)
    best_count = np.zeros(k, dtype=int)
    n = len(track)
    for lag in _LAGS:
        if n <= 2 * lag:
            break
        centre = np.arange(lag, n - lag)
        ok = (track[centre - lag] == track[centre]) & (track[centre + lag] == track[centre]) \
            & (frame[centre + lag] - frame[centre] == lag) & (frame[centre] - frame[centre - lag] == lag)
        centre = centre[ok]
        if len(centre) == 0:
            break
        x = position[centre]
        y = position[centre + lag] + position[centre - lag]
        step_s = (time_s[centre + lag] - time_s[centre - lag]) / 2.0
        c = code[centre]
        count = np.bincount(c, minlength=k).astype(float)
        with np.errstate(divide="ignore", invalid="ignore"):
            mean_x = np.bincount(c, x, k) / count
            mean_y = np.bincount(c, y, k) / count
            mean_step = np.bincount(c, step_s, k) / count
            dx = x - mean_x[c]
            sxx = np.bincount(c, dx * dx, k)
            sxy = np.bincount(c, dx * (y - mean_y[c]), k)
            kappa = sxy / sxx
            beta = mean_y - kappa * mean_x
            turn = np.arccos(np.clip(kappa / 2.0, -1.0, 1.0))
            omega = turn / mean_step
            axis = beta / (2.0 - kappa)
        usable = (count >= _MIN_TRIPLES) & (sxx > 0) & (np.abs(kappa) < 2.0) & (turn <= _MAX_TURN_RAD) \
            & np.isfinite(omega) & (omega > 0) & np.isfinite(axis)
        # a longer lag turns further between samples: the same noise weighs less
        best_omega = np.where(usable, omega, best_omega)
        best_axis = np.where(usable, axis, best_axis)
        best_lag = np.where(usable, lag, best_lag)
        best_count = np.where(usable, count, best_count)
    found = np.isfinite(best_omega)
    return pd.DataFrame({
        "track": ids[found], "omega_rad_s": best_omega[found], "axis_px": best_axis[found],
        "lag": best_lag[found], "triples": best_count[found],
    })


def segment_tracks(tracks: pd.DataFrame, position: np.ndarray, extent_px: float) -> list[np.ndarray]:
    """Track ids grouped into rigid bodies, largest first.

    Args:
        tracks: ``track, frame, time_s`` sorted by track then frame.
        position: each row's position along the offset direction (pixels).
        extent_px: the frame's extent across the axis, which scales the axis tolerance.

    Candidate groups come from mode seeking on each track's own estimates (see the module
    docstring). A candidate joins an earlier body when their rates and axes are within
    :data:`RESOLUTION` tolerances of each other, or when that body explains its tracks nearly as
    well as its own centre does (summed misfit within :data:`MERGE_RATIO`): such a group is a
    fringe of the body (tracks near an outline, short arcs), not a body of its own.

    Then every track, whether or not its own estimate was usable, goes to the body whose rate
    and axis fit its whole path best, provided that fit is clearly better than any other body's
    (misfit at most :data:`AMBIGUITY` times the next); the others are left out.
    """
    motion = track_motion(tracks, position)
    track = tracks["track"].to_numpy()
    samples = pd.DataFrame({"track": track, "time_s": tracks["time_s"].to_numpy()}, copy=False)

    def misfits(rate_rad_s: float, axis_px: float) -> np.ndarray:
        """Per track (in id order) misfit of its path about ``axis_px`` at ``rate_rad_s``."""
        return track_misfits(samples.assign(offset_px=position - axis_px), rate_rad_s)

    ids = np.unique(track)
    centres: list[tuple[float, float]] = []
    for group in _modes(motion, extent_px):
        rows = motion[motion["track"].isin(group)]
        rate, axis = float(rows["omega_rad_s"].median()), float(rows["axis_px"].median())
        members = np.isin(ids, group)
        own = float(misfits(rate, axis)[members].sum())
        fringe = any(
            unresolved(rate, axis, r, a, extent_px) or float(misfits(r, a)[members].sum()) <= MERGE_RATIO * own
            for r, a in centres
        )
        if not fringe:
            centres.append((rate, axis))
    if not centres:
        return []
    if len(centres) == 1:
        return [ids] if len(motion) >= MIN_BODY_TRACKS else []
    table = np.column_stack([misfits(r, a) for r, a in centres])
    order = np.sort(table, axis=1)
    best = np.argmin(table, axis=1)
    clear = order[:, 0] <= AMBIGUITY * order[:, 1]
    groups = [ids[clear & (best == b)] for b in range(len(centres))]
    return sorted((g for g in groups if len(g) >= MIN_BODY_TRACKS), key=len, reverse=True)


def unresolved(rate_a: float, axis_a_px: float, rate_b: float, axis_b_px: float, extent_px: float) -> bool:
    """True when two bodies' rates and axis positions (along the offset direction) both lie within
    :data:`RESOLUTION` tolerances of each other: they cannot be told apart, so they are one."""
    return (abs(np.log(rate_a / rate_b)) <= RESOLUTION * RATE_TOLERANCE
            and abs(axis_a_px - axis_b_px) <= RESOLUTION * AXIS_TOLERANCE_FRACTION * extent_px)


def _modes(motion: pd.DataFrame, extent_px: float) -> list[np.ndarray]:
    """Candidate groups of track ids by mode seeking in (log rate, axis), in the order found."""
    rate = np.log(motion["omega_rad_s"].to_numpy()) / RATE_TOLERANCE
    axis = motion["axis_px"].to_numpy() / (AXIS_TOLERANCE_FRACTION * extent_px)
    ids = motion["track"].to_numpy()
    left = np.ones(len(ids), dtype=bool)
    bodies: list[np.ndarray] = []
    rng = np.random.default_rng(0)  # deterministic subset of seeds
    while len(bodies) < MAX_BODIES and left.sum() >= MIN_BODY_TRACKS:
        pool = np.flatnonzero(left)
        seeds = pool if len(pool) <= _MAX_SEEDS else np.sort(rng.choice(pool, _MAX_SEEDS, replace=False))
        near = (np.abs(rate[seeds, None] - rate[None, pool]) <= 1.0) \
            & (np.abs(axis[seeds, None] - axis[None, pool]) <= 1.0)
        counts = near.sum(1)
        best = int(np.argmax(counts))
        if counts[best] < MIN_BODY_TRACKS:
            break
        members = pool[near[best]]
        centre_rate, centre_axis = float(np.median(rate[members])), float(np.median(axis[members]))
        joined = pool[(np.abs(rate[pool] - centre_rate) <= 1.0) & (np.abs(axis[pool] - centre_axis) <= 1.0)]
        if len(joined) < MIN_BODY_TRACKS:
            break
        bodies.append(ids[joined])
        left[joined] = False
    return bodies
