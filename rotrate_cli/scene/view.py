"""The view, from the tracks' paths at the measured rate: how far the axis leans out of the image
plane (0 a side view, the paper's; 90 a frontal view, the axis pointing at the camera) and where
the turning centre lies in the image.

Every point of a body turning about a fixed axis moves on the image of a circle: at a known rate
``w`` its path is ``p(t) = c + A cos(wt) + B sin(wt)``, linear in ``c, A, B`` and so well set even
on a short arc. The ellipse's width over its length is the sine of the axis's elevation; its
centre ``c`` lies on the axis's image (for a flat disk, every centre is the spindle's foot). Only
tracks that follow such a path closely and move well beyond their misfit speak: on real footage
most tracks are reflections that stand still, points sliding along grooves or rims, or the
background, and those say nothing of the view (on the record clip 141 of 45,215 tracks pass; on
the bicycle wheel, whose rim and tyre look the same after any turn, none does, and the view is
then reported unknown rather than guessed).

Through a pinhole the image of a circle's centre is not the ellipse's centre: the centre found
is good to the lens's effect over the radius (18 px on the record clip, seen close).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rotrate_cli.fitting.stats import weighted_median
from rotrate_cli.runtime.lazy import pandas as pd

#: Tracks that speak for the view: at least this many samples, turning through at least this
#: much (rad) at the measured rate, fitting their ellipse within this misfit (px) and moving at
#: least MOTION_RATIO times that misfit.
MIN_SAMPLES = 8
MIN_TURN_RAD = 1.0
MAX_MISFIT_PX = 1.5
MOTION_RATIO = 8.0
#: The misfit below which a track is taken as fitting that well (video's own noise, px).
MIN_MISFIT_PX = 0.25
#: Paths whose centres lie farther apart than this many times their size (the median path's
#: long semi-axis) do not tell one view: on the bicycle wheel the tracks that pass are points
#: sliding a few pixels along the rim, whose centres lie 60 px apart, and read as a side view
#: of a thin rod. (A rigid body's paths are as large as its points are far from the axis.)
MAX_SPREAD = 4.0
#: Seen from the side (the paths flat, under SIDE_DEG of elevation), a body's paths are centred
#: on the axis's image, one line across their long axes: centres farther from that line than
#: LINE_SPREAD times the paths' size (the median distance) are no body's turn. On the bicycle
#: wheel the only tracks that pass are on the hands holding its axle, shaken at the wheel's
#: rate: flat paths 12 px long whose centres lie 6 px (0.5 of that) from any one line, read as
#: a side view of a frontal wheel. Rendered side views, through lenses up to 25 degrees
#: across, hold their centres within 0.01-0.05 of their paths' size.
SIDE_DEG = 20.0
LINE_SPREAD = 0.25
#: Fewer passing tracks than this leave the view unknown.
MIN_TRACKS = 10
#: Tracks kept for the view when the rest of the tracks table is let go: the longest, each
#: thinned to at most this many samples (a 30-minute clip's tracks need not stay in memory).
KEEP_TRACKS = 1000
KEEP_SAMPLES = 32


@dataclass(frozen=True)
class View:
    """The view found from the tracks' paths (see the module's notes).

    Attributes:
        elevation_deg: the axis's elevation out of the image plane: 0 side, 90 frontal (through a
            lens found from the tracks, the lens fit's: see :func:`rotrate_cli.stages.view_at_rate.view_at_rate`).
        centre_px: the turning centre in the image (the median of the paths' centres), (x, y).
        centre_spread_px: the paths' centres' median distance from it: how well it is set.
        tracks: the tracks that spoke.
        path_px: their median path's long semi-axis (the paths' typical radius in the image).
        across_deg: the image direction of the paths' long axes (degrees from the image x axis,
            y down): across the axis's image.
    """

    elevation_deg: float
    centre_px: tuple[float, float]
    centre_spread_px: float
    tracks: int
    path_px: float
    across_deg: float

    @property
    def name(self) -> str:
        """``side`` (under 20 degrees), ``frontal`` (over 70) or ``oblique``."""
        if self.elevation_deg < 20.0:
            return "side"
        return "frontal" if self.elevation_deg > 70.0 else "oblique"


def keep_for_view(tracks: pd.DataFrame) -> pd.DataFrame:
    """The part of a tracks table (``track, time_s, x_px, y_px`` sorted by track then time)
    that :func:`view_from_paths` needs: the longest :data:`KEEP_TRACKS` tracks of at least
    :data:`MIN_SAMPLES` samples, each thinned evenly to at most :data:`KEEP_SAMPLES`."""
    track = tracks["track"].to_numpy()
    if len(track) == 0:
        return tracks[["track", "time_s", "x_px", "y_px"]].iloc[:0]
    starts = np.flatnonzero(np.r_[True, track[1:] != track[:-1]])
    counts = np.diff(np.r_[starts, len(track)])
    long_enough = np.flatnonzero(counts >= MIN_SAMPLES)
    chosen = long_enough[np.argsort(-counts[long_enough], kind="stable")[:KEEP_TRACKS]]
    return tracks[["track", "time_s", "x_px", "y_px"]].iloc[_evenly(starts, counts, np.sort(chosen))].reset_index(
        drop=True)


def _evenly(starts: np.ndarray, counts: np.ndarray, chosen: np.ndarray) -> np.ndarray:
    """The rows of the ``chosen`` tracks, each thinned evenly to at most :data:`KEEP_SAMPLES`:
    ``linspace(first, last, samples)`` rounded, for all tracks at once (a loop over a thousand
    tracks took 4% of a short clip's analysis). The steps are at least one row, so no row
    repeats."""
    if len(chosen) == 0:
        return np.zeros(0, np.int64)
    first, count = starts[chosen].astype(np.float64), counts[chosen]
    samples = np.minimum(count, KEEP_SAMPLES)
    step = np.where(samples > 1, (count - 1) / np.maximum(samples - 1, 1), 0.0)
    owner = np.repeat(np.arange(len(chosen)), samples)
    within = np.arange(int(samples.sum())) - np.repeat(np.cumsum(samples) - samples, samples)
    rows = within * step[owner] + first[owner]  # numpy's linspace: index * step + start
    last = np.cumsum(samples) - 1
    rows[last] = first + count - 1  # and its end point exactly
    return rows.round().astype(np.int64)


@dataclass(frozen=True)
class Ellipses:
    """Every track's path fitted at one rate: ``c + A cos(wt) + B sin(wt)`` per coordinate
    (``coef``: tracks x (1, cos, sin) x (x, y), zero where not ``usable``: too few samples, too
    little of a turn, or a singular fit), with each track's rms misfit, turn, the motion seen
    (the larger of its x and y ranges) and its sample count."""

    coef: np.ndarray  # tracks x (1, cos, sin) x (x, y)
    misfit_px: np.ndarray
    usable: np.ndarray
    turn_rad: np.ndarray
    seen_px: np.ndarray
    counts: np.ndarray


def fit_ellipses(tracks: pd.DataFrame, omega: float, min_turn_rad: float = MIN_TURN_RAD) -> Ellipses:
    """Each track's path at the rate ``omega`` (see :class:`Ellipses`), by linear least squares;
    ``tracks``: ``track, time_s, x_px, y_px`` sorted by track then time."""
    track = tracks["track"].to_numpy()
    starts = np.flatnonzero(np.r_[True, track[1:] != track[:-1]])
    counts = np.diff(np.r_[starts, len(track)])
    time_s = tracks["time_s"].to_numpy(dtype=np.float64)
    turn = omega * (time_s[starts + counts - 1] - time_s[starts])
    centred = time_s - np.repeat(np.add.reduceat(time_s, starts) / counts, counts)
    c, s = np.cos(omega * centred), np.sin(omega * centred)
    columns = (np.ones_like(c), c, s)
    normal = np.empty((len(starts), 3, 3))
    for i in range(3):
        for j in range(i, 3):
            normal[:, i, j] = normal[:, j, i] = np.add.reduceat(columns[i] * columns[j], starts)
    xy = tracks[["x_px", "y_px"]].to_numpy(dtype=np.float64)
    right = np.stack([np.stack([np.add.reduceat(col * xy[:, k], starts) for col in columns], axis=1)
                      for k in range(2)], axis=2)
    usable = (counts >= MIN_SAMPLES) & (turn >= min_turn_rad)
    usable &= np.abs(np.linalg.det(normal)) > 1e-9 * np.maximum(counts, 1) ** 3
    coef = np.zeros((len(starts), 3, 2))
    if usable.any():
        coef[usable] = np.linalg.solve(normal[usable], right[usable])
    fitted = sum(np.repeat(coef[:, k, :], counts, axis=0) * columns[k][:, None] for k in range(3))
    misfit = np.sqrt(np.add.reduceat(((xy - fitted) ** 2).sum(axis=1), starts) / counts)
    # the motion seen, not the fitted ellipse's size: on a short arc a still point's ellipse can
    # be large and cancel its own centre
    seen = np.maximum(np.maximum.reduceat(xy[:, 0], starts) - np.minimum.reduceat(xy[:, 0], starts),
                      np.maximum.reduceat(xy[:, 1], starts) - np.minimum.reduceat(xy[:, 1], starts))
    return Ellipses(coef, misfit, usable, turn, seen, counts)


def _passing(fit: Ellipses) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Which tracks follow a turning path closely (see the module's notes), and every track's
    path's long and short semi-axes and long axis's direction (radians)."""
    a, b = fit.coef[:, 1, :], fit.coef[:, 2, :]
    shape = a[:, :, None] * a[:, None, :] + b[:, :, None] * b[:, None, :]
    values, vectors = np.linalg.eigh(shape)
    values = np.sqrt(np.clip(values, 0.0, None))
    major, minor = values[:, 1], values[:, 0]
    direction = np.arctan2(vectors[:, 1, 1], vectors[:, 0, 1])
    passing = fit.usable & (fit.misfit_px <= MAX_MISFIT_PX)
    passing &= fit.seen_px >= MOTION_RATIO * np.maximum(fit.misfit_px, MIN_MISFIT_PX)
    # and an ellipse no larger than the arc shows (a chord of 2 r sin(turn / 2)), within a margin
    passing &= major <= 2.0 * fit.seen_px / np.sin(np.clip(fit.turn_rad, 1e-3, math.pi) / 2.0)
    return passing, major, minor, direction


def view_from_paths(tracks: pd.DataFrame, omega_rad_s: float) -> View | None:
    """The view at the rate ``omega_rad_s`` (its sign does not matter) from ``tracks``
    (``track, time_s, x_px, y_px`` sorted by track then time); None when fewer than
    :data:`MIN_TRACKS` tracks follow a turning path at that rate."""
    omega = abs(omega_rad_s)
    if not (math.isfinite(omega) and omega > 0) or tracks.empty:
        return None
    fit = fit_ellipses(tracks, omega)
    passing, major, minor, direction = _passing(fit)
    if int(passing.sum()) < MIN_TRACKS:
        return None
    width = minor[passing] / np.maximum(major[passing], 1e-300)
    # a longer arc sets its ellipse better, and a larger one its centre: a small path may be a
    # slight wobble anywhere, a large one is the body turning
    weight = np.minimum(fit.turn_rad[passing], 2 * math.pi) * major[passing]
    elevation = math.degrees(math.asin(min(1.0, weighted_median(width, weight))))
    centres = fit.coef[passing, 0, :]
    centre = (weighted_median(centres[:, 0], weight), weighted_median(centres[:, 1], weight))
    spread = float(np.median(np.hypot(centres[:, 0] - centre[0], centres[:, 1] - centre[1])))
    size = weighted_median(major[passing], weight)
    if spread > MAX_SPREAD * size:
        return None
    doubled = 2.0 * direction[passing]  # a direction has no sign: average the doubled angles
    across = 0.5 * math.atan2(float(weight @ np.sin(doubled)), float(weight @ np.cos(doubled)))
    if elevation < SIDE_DEG:
        along = centres[:, 0] * math.cos(across) + centres[:, 1] * math.sin(across)  # across the axis's image
        if float(np.median(np.abs(along - weighted_median(along, weight)))) > LINE_SPREAD * size:
            return None
    return View(elevation, centre, spread, int(passing.sum()), size, math.degrees(across))


#: The paths' rate is sought within this fraction of the first rate, on a grid this fine.
PATHS_SEARCH = 0.15
PATHS_STEP = 0.0025
#: Paths smaller than this fraction of the view's typical path are left out of the paths' rate.
SMALL_PATH = 0.25


def rate_from_paths(tracks: pd.DataFrame, omega_rad_s: float) -> float:
    """The rate (unsigned, rad/s) at which the tracks that follow a turning path at
    ``omega_rad_s`` (and tell a view) are best explained in both image coordinates as images of
    circles seen from the view's elevation: each track with its own centre, radius and phase
    (unlike the offsets across one image direction, this does not assume the paths' centres
    line up across it); NaN when too few tracks follow such a path.

    Free ellipses would not do: on a short arc an ellipse of another rate fits as well (0.4%
    off on exact paths with 0.2 px of noise); a circle seen from a known elevation cannot
    bend so. Each track's misfit is capped (at :data:`MAX_MISFIT_PX`), and the minimum on a
    grid of :data:`PATHS_STEP` is refined by a parabola. On rendered boxes and cylinders seen
    from 30 and 60 degrees above (orthographic, a half turn), the offsets across the axis read
    2-2.5% low.
    """
    rate = abs(omega_rad_s)
    for _ in range(PATHS_ROUNDS):  # the view is read at the rate, and the rate in the view
        found = _rate_in_view(tracks, rate)
        if not math.isfinite(found):
            return math.nan
        settled = abs(found / rate - 1.0) < PATHS_STEP / 10
        rate = found
        if settled:
            break
    return rate


#: Rounds of reading the view at the rate found and the rate in that view.
PATHS_ROUNDS = 4


def _rate_in_view(tracks: pd.DataFrame, omega: float) -> float:
    """One round of :func:`rate_from_paths`: the view at ``omega``, and the best rate in it."""
    if not (math.isfinite(omega) and omega > 0) or tracks.empty:
        return math.nan
    view = view_from_paths(tracks, omega)
    if view is None:
        return math.nan  # the paths that pass do not tell one view: they are no body's turn
    passing, major, _, _ = _passing(fit_ellipses(tracks, omega))
    # small paths say little of the rate: points near the axis, and slides along a rim
    passing &= major >= SMALL_PATH * view.path_px
    track = tracks["track"].to_numpy()
    starts = np.flatnonzero(np.r_[True, track[1:] != track[:-1]])
    chosen = tracks[np.isin(track, track[starts[passing]])]
    circles = _Circles(chosen, view)
    grid = omega * (1.0 + np.arange(-PATHS_SEARCH, PATHS_SEARCH + PATHS_STEP / 2, PATHS_STEP))
    costs = np.array([circles.cost(rate) for rate in grid])
    best = int(np.argmin(costs))
    if best in (0, len(grid) - 1):
        return math.nan  # no minimum within reach: the paths do not say
    left, middle, right = costs[best - 1:best + 2]
    curvature = left - 2 * middle + right
    shift = 0.5 * (left - right) / curvature if curvature > 0 else 0.0
    return float(grid[best] + shift * (grid[1] - grid[0]))


class _Circles:
    """Tracks as images of circles seen from a view's elevation: in the frame of the paths'
    long axis (``u``) and the axis's image (``v``), ``u = cu + a cos - b sin`` and
    ``v = cv + sin(elevation) (a sin + b cos)``, linear in each track's ``cu, cv, a, b``."""

    def __init__(self, tracks: pd.DataFrame, view: View) -> None:
        track = tracks["track"].to_numpy()
        self.starts = np.flatnonzero(np.r_[True, track[1:] != track[:-1]])
        self.counts = np.diff(np.r_[self.starts, len(track)])
        time_s = tracks["time_s"].to_numpy(dtype=np.float64)
        self.time_s = time_s - np.repeat(np.add.reduceat(time_s, self.starts) / self.counts, self.counts)
        across = math.radians(view.across_deg)
        x, y = tracks["x_px"].to_numpy(dtype=np.float64), tracks["y_px"].to_numpy(dtype=np.float64)
        self.u = x * math.cos(across) + y * math.sin(across)
        self.v = -x * math.sin(across) + y * math.cos(across)
        self.squash = math.sin(math.radians(view.elevation_deg))

    def cost(self, rate: float) -> float:
        """The capped misfit at ``rate``, in the better of the two senses of turning (the
        rate is unsigned here, and the sense flips the short axis's sign)."""
        return min(self._cost(rate, self.squash), self._cost(rate, -self.squash))

    def _cost(self, rate: float, k: float) -> float:
        c, s = np.cos(rate * self.time_s), np.sin(rate * self.time_s)
        zero, one = np.zeros_like(c), np.ones_like(c)
        # columns (cu, cv, a, b) for the u rows, then for the v rows
        u_cols = (one, zero, c, -s)
        v_cols = (zero, one, k * s, k * c)
        starts = self.starts
        normal = np.empty((len(starts), 4, 4))
        for i in range(4):
            for j in range(i, 4):
                total = np.add.reduceat(u_cols[i] * u_cols[j] + v_cols[i] * v_cols[j], starts)
                normal[:, i, j] = normal[:, j, i] = total
        right = np.stack([np.add.reduceat(u_cols[i] * self.u + v_cols[i] * self.v, starts) for i in range(4)], axis=1)
        coef = np.linalg.solve(normal + 1e-9 * np.eye(4), right[:, :, None])[:, :, 0]
        each = np.repeat(coef, self.counts, axis=0)
        fitted_u = sum(each[:, i] * u_cols[i] for i in range(4))
        fitted_v = sum(each[:, i] * v_cols[i] for i in range(4))
        misfit2 = np.add.reduceat((self.u - fitted_u) ** 2 + (self.v - fitted_v) ** 2, starts) / self.counts
        return float((np.minimum(misfit2, MAX_MISFIT_PX ** 2) * self.counts).sum())

