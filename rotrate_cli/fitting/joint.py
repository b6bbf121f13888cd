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
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from rotrate_cli.fitting.camera import Camera
from rotrate_cli.fitting.estimators import solve_two_columns
from rotrate_cli.fitting.outliers import Combined
from rotrate_cli.fitting.ragged import Ragged
from rotrate_cli.fitting.stats import student_t_975
from rotrate_cli.runtime.lazy import pandas as pd

#: Grid points of the search for the minimum, and the relative grid step at which it stops.
_SEARCH_POINTS = 13
_SEARCH_STEP = 0.02
#: The grid on which every track's misfit is kept for the jackknives: relative half-width and
#: points; and the wider one used when leaving tracks out moves the minimum off it.
_GRID = (0.06, 25)
_WIDE_GRID = (0.3, 61)
#: Relative steps of the parabola polishing the summed misfit's minimum.
_POLISH_STEPS = (1e-3, 2e-4)
#: Samples per block when evaluating misfits (bounds the temporaries' memory), and blocks worked
#: on at once.
_BLOCK_SAMPLES = 1 << 14
_THREADS = 2
#: Groups per split for the grouped jackknife, and the fewest tracks per group it needs.
GROUPS = 5
_MIN_PER_GROUP = 3


@dataclass(frozen=True)
class _Block:
    """A block of tracks with what its misfits need at every trial rate, made once: the target
    (offsets, or through a pinhole their normalised image positions) and, through a pinhole, the
    positions that scale the depth term."""

    tracks: Ragged
    target: np.ndarray
    x: np.ndarray | None

    @classmethod
    def of(cls, block: Ragged, camera: Camera | None) -> _Block:
        if camera is None:
            return cls(block, block.offset, None)
        target = block.offset / camera.focal_px
        return cls(block, target, (target + camera.axis_n) * camera.depth_scale)


def _block_misfits(block: Ragged | _Block, cos_t: np.ndarray, sin_t: np.ndarray, camera: Camera | None) -> np.ndarray:
    """Each track's least squared misfit (in the offsets' units squared) at one rate, given the
    rate's ``cos``/``sin`` at the distinct sample times.

    Orthographic: ``offset = A cos(wt) + B sin(wt)``. Pinhole (normalised coordinates ``x``,
    see :func:`rotrate_cli.fitting.estimators._pinhole`): ``x (1 - k Z) = axis_n + L`` is linear in ``A, B``;
    solved once unweighted, then again with weights ``1 / (1 - Z)^2`` so that the misfit is
    the geometric one. Times need no centring: shifting them turns the two columns into
    combinations of each other, which leaves the misfit unchanged.
    """
    prepared = block if isinstance(block, _Block) else _Block.of(block, camera)
    block = prepared.tracks
    c, s_ = cos_t[block.time_index], sin_t[block.time_index]
    sums = block.sums
    target = prepared.target
    if prepared.x is None:
        first, second = c, s_
    else:
        x = prepared.x
        first, second = c - x * s_, s_ + x * c

    def solve(weight2: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        wf, ws = first * weight2, second * weight2
        b1, b2 = sums(wf * target), sums(ws * target)
        a, b = solve_two_columns(sums(wf * first), sums(ws * second), sums(wf * second), b1, b2)
        return a, b, b1, b2

    weight2: np.ndarray | float = 1.0
    a, b, b1, b2 = solve(weight2)
    if camera is not None:
        depth = (-block.spread(a) * s_ + block.spread(b) * c) * camera.depth_scale
        weight2 = 1.0 / np.maximum(np.abs(1.0 - depth), 1e-3) ** 2
        a, b, b1, b2 = solve(weight2)
    misfit = np.maximum(sums(target * target * weight2) - a * b1 - b * b2, 0.0)
    return misfit if camera is None else misfit * camera.focal_px**2


def track_misfits(samples: pd.DataFrame, omega_rad_s: float, camera: Camera | None = None) -> np.ndarray:
    """Each track's least squared misfit at ``omega_rad_s`` (offsets' units squared), in the
    order of track ids; ``samples`` as for :func:`joint_fit`."""
    tracks = Ragged.from_samples(samples)
    angle = omega_rad_s * tracks.times_s
    cos_t, sin_t = np.cos(angle), np.sin(angle)
    out = np.empty(len(tracks))
    for part, block in tracks.blocks(_BLOCK_SAMPLES):
        out[part] = _block_misfits(block, cos_t, sin_t, camera)
    return out


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


def _relative_grid(omega: float, half_width_and_points: tuple[float, int]) -> np.ndarray:
    half_width, points = half_width_and_points
    return np.linspace(omega * (1 - half_width), omega * (1 + half_width), points)


def joint_fit(
    samples: pd.DataFrame,
    noise: dict[int, float],
    omega_guess_rad_s: float,
    span: float = 0.2,
    camera: Camera | None = None,
    sense: float = 1.0,
) -> Combined:
    """The rate shared by the tracks of ``samples`` (columns ``track, time_s, offset_px``,
    sorted by track then time) that ``noise`` lists.

    Args:
        samples: the tracks' offsets (other tracks may be present: only those in ``noise`` count).
        noise: each track's noise standard deviation (the offsets' units); tracks weigh
            ``1 / noise^2``.
        omega_guess_rad_s: where to centre the search (for example the mean of per-track rates).
        span: the search covers ``omega_guess * (1 +- span)`` (and moves on when the minimum
            sits on its edge).
        camera: a pinhole camera for perspective fits, or None for orthographic.
        sense: with a camera, +1 for anticlockwise rotation, -1 for clockwise.

    Returns:
        The joint rate and its interval; NaN throughout when no minimum could be found.
    """
    tracks = Ragged.from_samples(samples, np.fromiter(noise, dtype=np.int64, count=len(noise)))
    k = len(tracks)
    failed = Combined(math.nan, math.nan, math.nan, k)
    if k == 0 or not math.isfinite(omega_guess_rad_s) or omega_guess_rad_s <= 0:
        return failed
    weights = np.array([1.0 / max(noise[int(i)], 1e-6) ** 2 for i in tracks.ids])
    signed = 1.0 if camera is None or sense >= 0 else -1.0

    blocks = [(part, _Block.of(block, camera)) for part, block in tracks.blocks(_BLOCK_SAMPLES)]

    def misfits(grid: np.ndarray) -> np.ndarray:
        out = np.empty((k, len(grid)))
        angle = signed * grid[:, None] * tracks.times_s[None, :]
        cos_t, sin_t = np.cos(angle), np.sin(angle)

        def fill(part_and_block: tuple[slice, _Block]) -> None:
            part, block = part_and_block
            for j in range(len(grid)):
                out[part, j] = _block_misfits(block, cos_t[j], sin_t[j], camera)

        if len(blocks) == 1:
            fill(blocks[0])
        else:
            list(pool.map(fill, blocks))
        return out

    # numpy lets go of the interpreter in its array loops: two blocks at once use both cores
    with ThreadPoolExecutor(max_workers=_THREADS) as pool:
        return _joint_fit(tracks, weights, misfits, omega_guess_rad_s, span, failed)


def _joint_fit(tracks: Ragged, weights: np.ndarray, misfits: Callable[[np.ndarray], np.ndarray],
               omega_guess_rad_s: float, span: float, failed: Combined) -> Combined:
    """:func:`joint_fit` once its tracks' ``misfits`` at a grid of trial rates can be had."""
    k = len(tracks)
    rough = _locate(misfits, weights, omega_guess_rad_s, span)
    if not math.isfinite(rough):
        return failed
    def weighted_misfits(grid: np.ndarray) -> np.ndarray:
        out = misfits(grid)
        out *= weights[:, None]  # in place: a long clip's tracks x grid is megabytes
        return out

    grid = _relative_grid(rough, _GRID)
    weighted = weighted_misfits(grid)
    omega = float(_parabola_minimum(grid, weighted.sum(0)[None, :])[0])
    if not math.isfinite(omega):
        return failed
    omega = _polish(lambda trial: float((weights @ misfits(trial))[0]), omega)
    if k == 1:
        # one track: the curvature of its misfit, scaled by its own residual variance
        return _single(grid, weighted[0], omega, float(tracks.counts[0]))
    leave_one_out = _leave_one_out(grid, weighted)
    if not np.isfinite(leave_one_out).all():
        # a track whose removal moves the minimum off the grid: a wider one
        grid = _relative_grid(omega, _WIDE_GRID)
        del weighted
        weighted = weighted_misfits(grid)
        leave_one_out = _leave_one_out(grid, weighted)
    finite = leave_one_out[np.isfinite(leave_one_out)]
    if len(finite) < 2:
        return Combined(omega, math.nan, math.nan, k)
    half = _jackknife_half_width(finite)
    if k >= GROUPS * _MIN_PER_GROUP:
        duration_s = np.empty(k)
        distance = np.empty(k)
        for part, block in tracks.blocks(_BLOCK_SAMPLES):
            time_s = block.time_s
            duration_s[part] = np.maximum.reduceat(time_s, block.starts) - np.minimum.reduceat(time_s, block.starts)
            distance[part] = block.sums(np.abs(block.offset)) / block.counts
        arc = np.abs(omega) * duration_s
        groups = [np.array_split(np.argsort(key, kind="stable"), GROUPS) for key in (arc, distance)]
        for wider in (False, True):
            if wider:
                grid = _relative_grid(omega, _WIDE_GRID)
                del weighted
                weighted = weighted_misfits(grid)
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
    return student_t_975(m - 1) * se


#: Tracks per chunk of the delete-one-track minima (bounds their temporaries' memory).
_CHUNK_TRACKS = 1024


def _leave_one_out(grid: np.ndarray, weighted: np.ndarray) -> np.ndarray:
    """The joint minimum with each track (row of ``weighted``) left out in turn (NaN where off
    ``grid``), a chunk of tracks at a time rather than as one more tracks x grid array."""
    total = weighted.sum(0)[None, :]
    return np.concatenate([_parabola_minimum(grid, total - weighted[start:start + _CHUNK_TRACKS])
                           for start in range(0, len(weighted), _CHUNK_TRACKS)])


def _delete_one_group(grid: np.ndarray, weighted: np.ndarray, groups: list[np.ndarray]) -> np.ndarray:
    """The joint minimum with each group of tracks left out in turn (NaN where off ``grid``)."""
    total = weighted.sum(0)
    return _parabola_minimum(grid, np.array([total - weighted[g].sum(0) for g in groups]))


def _locate(
    misfits: Callable[[np.ndarray], np.ndarray], weights: np.ndarray, guess: float, span: float
) -> float:
    """Roughly (to a few percent) where ``weights @ misfits(omega)`` is least: a grid over
    ``guess * (1 +- span)`` that moves while the minimum sits on its edge and zooms in until its
    step is fine enough; NaN when it finds none."""
    low, high = guess * max(1.0 - span, 0.05), guess * (1.0 + span)
    floor = guess * 0.05
    last = _SEARCH_POINTS - 1
    for _ in range(12):
        grid = np.linspace(low, high, _SEARCH_POINTS)
        total = weights @ misfits(grid)
        best = int(np.argmin(total))
        step = grid[1] - grid[0]
        if best == 0 and low > floor:
            low, high = max(low - (high - low), floor), low + 2 * step
        elif best == last:
            low, high = high - 2 * step, high + (high - low)
        elif best == 0:
            return math.nan  # the minimum runs down to (nearly) no rotation
        elif step / grid[best] > _SEARCH_STEP:
            low, high = grid[best - 1], grid[best + 1]
        else:
            return float(grid[best])
    return math.nan


def _polish(total: Callable[[np.ndarray], float], omega: float) -> float:
    """The minimum of ``total`` near ``omega``, by parabolas through ever closer neighbours."""
    for relative in _POLISH_STEPS:
        step = omega * relative
        left, middle, right = (total(np.array([omega + d * step])) for d in (-1.0, 0.0, 1.0))
        curvature = left - 2.0 * middle + right
        if curvature > 0:
            omega += float(np.clip(0.5 * (left - right) / curvature, -2.0, 2.0)) * step
    return omega


def _single(grid: np.ndarray, total: np.ndarray, omega: float, samples: float) -> Combined:
    i = int(np.clip(np.argmin(total), 1, len(grid) - 2))
    step = grid[1] - grid[0]
    curvature = (total[i - 1] - 2 * total[i] + total[i + 1]) / step**2
    residual_variance = float(total[i]) / max(samples - 3.0, 1.0)
    if curvature <= 0:
        return Combined(omega, math.nan, math.nan, 1)
    se = math.sqrt(2.0 * max(residual_variance, 1e-12) / curvature)
    half = student_t_975(max(samples - 3.0, 1.0)) * se
    return Combined(omega, max(omega - half, 0.0), omega + half, 1)
