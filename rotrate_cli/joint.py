"""One rate for the whole body: a joint least-squares fit that shares omega across tracks.

A rigid body has one rate, so the summary omega is the value that minimises the summed
(noise-weighted) squared misfit of *all* inlier tracks at once, each track keeping its own
amplitude and phase. The amplitudes enter linearly, so for a trial omega each track's best
misfit is a small linear least-squares problem; the summed misfit is profiled over omega on a
grid, refined, and its minimum located by a parabola.

Why not average the per-track rates? Short or noisy tracks give per-track rates whose own
standard errors shrink as the rate estimate grows (``se(omega) ~ se(omega^2) / 2 omega``), so an
inverse-variance mean leans high; and a track whose noise flattened its curvature may give no
rate at all and silently drop out. The profiled misfit has neither bias: its expected noise
part does not depend on omega.

The 95% interval comes from the delete-one-track jackknife of the same minimisation, which
sees the spread between tracks (tracking errors, residual model error) rather than trusting
the per-sample noise model alone. Errors that tracks of one kind share (points that slide near
the outline, long-lived points that drift) cancel in that jackknife; so the tracks are also
split into :data:`GROUPS` groups by the angle they span and, separately, by their distance from
the axis, and the delete-one-group jackknife of each split widens the interval where the
groups disagree. Measured on the accuracy suite (``make bench-accuracy``), that is what brings
the coverage of the truth from about half the clips to the nominal rate.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pandas as pd
from scipy.special import stdtrit

from rotrate_cli.outliers import Combined
from rotrate_cli.rates import Camera, padded_tracks, two_column_fit

#: Grid points per refinement pass, and the number of passes.
_GRID_POINTS = 41
_PASSES = 3
#: Tracks per block when evaluating misfits (bounds the temporaries' memory).
_CHUNK_TRACKS = 256
#: Groups per split for the grouped jackknife, and the fewest tracks per group it needs.
GROUPS = 5
_MIN_PER_GROUP = 3


def _misfits(
    time_s: np.ndarray, offset: np.ndarray, weight: np.ndarray, omega_rad_s: float, camera: Camera | None
) -> np.ndarray:
    """Each padded track's least squared misfit (in the offsets' units squared) at one rate.

    Orthographic: ``offset = A cos(wt) + B sin(wt)``. Pinhole (normalised coordinates ``x``,
    see :func:`rotrate_cli.rates._pinhole`): ``x (1 - Z) = axis_n + L`` is linear in ``A, B``;
    solved once unweighted, then again with weights ``1 / (1 - Z)^2`` so that the misfit is
    the geometric one.
    """
    c, s_ = np.cos(omega_rad_s * time_s), np.sin(omega_rad_s * time_s)
    if camera is None:
        target, first, second = offset, c, s_
    else:
        x = offset / camera.focal_px + camera.axis_n
        target, first, second = x - camera.axis_n, c - x * s_, s_ + x * c
    w = weight
    for _ in range(1 if camera is None else 2):
        a, b = two_column_fit(first * w, second * w, target * w)
        if camera is not None:
            depth = -a[:, None] * s_ + b[:, None] * c
            w = weight / np.maximum(np.abs(1.0 - depth), 1e-3)
    residual = (target - a[:, None] * first - b[:, None] * second) * w
    scale = 1.0 if camera is None else camera.focal_px
    return (residual**2).sum(1) * scale**2


def _parabola_minimum(grid: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Per row of ``values`` (rows x grid), the grid minimum refined by a parabola through it
    and its neighbours; NaN where the minimum lies on the grid's edge."""
    index = np.argmin(values, axis=1)
    inside = (index > 0) & (index < len(grid) - 1)
    i = np.clip(index, 1, len(grid) - 2)
    rows = np.arange(len(values))
    left, middle, right = values[rows, i - 1], values[rows, i], values[rows, i + 1]
    curvature = left - 2.0 * middle + right
    with np.errstate(divide="ignore", invalid="ignore"):
        shift = np.where(curvature > 0, 0.5 * (left - right) / curvature, 0.0)
    step = grid[1] - grid[0]
    return np.where(inside, grid[i] + np.clip(shift, -1.0, 1.0) * step, np.nan)


def joint_fit(
    samples: pd.DataFrame,
    noise: dict[int, float],
    omega_guess_rad_s: float,
    span: float = 0.2,
    camera: Camera | None = None,
    sense: float = 1.0,
) -> Combined:
    """The rate shared by the tracks of ``samples`` (columns ``track, time_s, offset_px``,
    sorted by track then time).

    Args:
        samples: the inlier tracks' offsets.
        noise: each track's noise standard deviation (the offsets' units); tracks weigh
            ``1 / noise^2``.
        omega_guess_rad_s: where to centre the search (for example the mean of per-track rates).
        span: the search covers ``omega_guess * (1 +- span)`` (and is widened when the minimum
            sits on its edge).
        camera: a pinhole camera for perspective fits, or None for orthographic.
        sense: with a camera, +1 for anticlockwise rotation, -1 for clockwise.

    Returns:
        The joint rate and its interval; NaN throughout when no minimum could be found.
    """
    time_s, offset, mask, ids = padded_tracks(samples)
    k = len(ids)
    failed = Combined(math.nan, math.nan, math.nan, k)
    if k == 0 or not math.isfinite(omega_guess_rad_s) or omega_guess_rad_s <= 0:
        return failed
    weight = mask.astype(float)
    n = weight.sum(1)
    centre_s = (time_s * weight).sum(1) / n
    time_s = (time_s - centre_s[:, None]) * weight
    offset = offset * weight
    inverse_variance = np.array([1.0 / max(noise.get(int(i), 1.0), 1e-6) ** 2 for i in ids])

    def misfits(grid: np.ndarray) -> np.ndarray:
        # in chunks of tracks: the temporaries stay the same size however long the clip
        signed = 1.0 if camera is None or sense >= 0 else -1.0
        out = np.empty((k, len(grid)))
        for start in range(0, k, _CHUNK_TRACKS):
            part = slice(start, start + _CHUNK_TRACKS)
            for j, w in enumerate(grid):
                out[part, j] = _misfits(time_s[part], offset[part], weight[part], signed * w, camera)
        return out

    # fixed effects: every track weighted by its own noise
    found = _search(misfits, inverse_variance, omega_guess_rad_s, span)
    if found is None:
        return failed
    grid, curves, omega = found
    if k == 1:
        # one track: the curvature of its misfit, scaled by its own residual variance
        return _single(grid, curves[0] * inverse_variance[0], omega, float(n[0]))
    weights = inverse_variance
    weighted = curves * weights[:, None]
    leave_one_out = _parabola_minimum(grid, weighted.sum(0)[None, :] - weighted)
    if not np.isfinite(leave_one_out).all():
        # a track whose removal moves the minimum off the fine grid: a wider grid
        grid = np.linspace(omega * 0.8, omega * 1.2, 4 * _GRID_POINTS + 1)
        weighted = misfits(grid) * weights[:, None]
        leave_one_out = _parabola_minimum(grid, weighted.sum(0)[None, :] - weighted)
    finite = leave_one_out[np.isfinite(leave_one_out)]
    if len(finite) < 2:
        return Combined(omega, math.nan, math.nan, k)
    half = _jackknife_half_width(finite)
    if k >= GROUPS * _MIN_PER_GROUP:
        arc = np.abs(omega) * (time_s.max(1) - time_s.min(1))
        distance = np.abs(offset).sum(1) / n
        groups = [np.array_split(np.argsort(key, kind="stable"), GROUPS) for key in (arc, distance)]
        for relative, points in ((0.06, 25), (0.3, 61)):
            grid = np.linspace(omega * (1 - relative), omega * (1 + relative), points)
            weighted = misfits(grid) * weights[:, None]
            estimates = [_delete_one_group(grid, weighted, split) for split in groups]
            if all(np.isfinite(e).all() for e in estimates):
                half = max(half, *(_jackknife_half_width(e) for e in estimates))
                break
        else:  # a group on its own pulls the rate more than 30% away: no trustworthy interval
            half = max(half, omega)
    return Combined(omega, max(omega - half, 0.0), omega + half, k)


def _jackknife_half_width(estimates: np.ndarray) -> float:
    """Half-width of the 95% t-interval from delete-one estimates."""
    m = len(estimates)
    se = math.sqrt((m - 1) / m * float(((estimates - estimates.mean()) ** 2).sum()))
    return float(stdtrit(m - 1, 0.975)) * se


def _delete_one_group(grid: np.ndarray, weighted: np.ndarray, groups: list[np.ndarray]) -> np.ndarray:
    """The joint minimum with each group of tracks left out in turn (NaN where off ``grid``)."""
    total = weighted.sum(0)
    return _parabola_minimum(grid, np.array([total - weighted[g].sum(0) for g in groups]))


def _search(
    misfits: Callable[[np.ndarray], np.ndarray], weights: np.ndarray, guess: float, span: float
) -> tuple[np.ndarray, np.ndarray, float] | None:
    """Minimise ``weights @ misfits(omega)``: grid, zoom in, parabola. Returns the last grid,
    the tracks' misfits on it and the minimum, or None."""
    low, high = guess * max(1.0 - span, 0.05), guess * (1.0 + span)
    floor = guess * 0.05
    for _ in range(_PASSES + 6):
        grid = np.linspace(low, high, _GRID_POINTS)
        curves = misfits(grid)
        total = weights @ curves
        best = int(np.argmin(total))
        step = grid[1] - grid[0]
        if best == 0 and low > floor:
            low, high = max(low - (high - low), floor), low + 2 * step
        elif best == _GRID_POINTS - 1:
            low, high = high - 2 * step, high + (high - low)
        elif step / grid[best] > 2e-4:
            low, high = grid[best] - 3 * step, grid[best] + 3 * step
        else:
            break
    omega = float(_parabola_minimum(grid, total[None, :])[0])
    return (grid, curves, omega) if math.isfinite(omega) else None


def _single(grid: np.ndarray, total: np.ndarray, omega: float, samples: float) -> Combined:
    i = int(np.clip(np.argmin(total), 1, len(grid) - 2))
    step = grid[1] - grid[0]
    curvature = (total[i - 1] - 2 * total[i] + total[i + 1]) / step**2
    residual_variance = float(total[i]) / max(samples - 3.0, 1.0)
    if curvature <= 0:
        return Combined(omega, math.nan, math.nan, 1)
    se = math.sqrt(2.0 * max(residual_variance, 1e-12) / curvature)
    half = float(stdtrit(max(samples - 3.0, 1.0), 0.975)) * se
    return Combined(omega, max(omega - half, 0.0), omega + half, 1)
