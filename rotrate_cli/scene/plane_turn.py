"""A turning plane's angle from its tracks, through any view: the homography between two frames of
a plane turning about its own axis is a rotation seen through that view (``Q R Q^-1``), so its
eigenvalues are the rotation's, ``1`` and ``exp(+-i theta)``, whatever the camera's tilt, lens or
where the axis lies (in the frame or out of it). The angle turned between two frames is read from
the trace of their homography (scaled to determinant 1: ``1 + 2 cos theta``), its sense from how
the points turn about its fixed point (the axis's point), and the rate is fitted to the angles of
many pairs of frames.

Where the picture's own turning is measured through a view found from the picture
(:mod:`rotrate_cli.scene.picture_angle`), a view that is not known well turns the picture
unevenly; here no view is needed at all. A real photograph laid on a disc tilted 45 degrees before
a 50-degree lens, its axis below the frame, a third of a turn: its tracks' one-point fits read
+39%, the picture's turning through the view it found +15%; this reads +0.3%. It needs tracks that
stay on the plane (a printed or textured face); a record's grooves and a wheel's thin spokes give
too few, and there the picture's turning answers. A face that is not the turning plane (a box's
side, turning about an axis that lies in it) has a line of fixed points, so real eigenvalues: its
pairs are left out.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import cv2
import numpy as np

from rotrate_cli.fitting.stats import student_t_975
from rotrate_cli.runtime.lazy import pandas as pd
from rotrate_cli.scene.disc import DiscView, PlaneMap
from rotrate_cli.scene.patches import place_tracks
from rotrate_cli.scene.picture_angle import PictureAngle
from rotrate_cli.tracking.keyframes import Keyframes

#: Tracks that move less than this (px, the extent of their path) are the still picture's.
MOVING_PX = 3.0
#: At most this many frames are kept (evenly over the clip), and pairs this many frames apart
#: (in the frames kept) compared.
MOST_FRAMES = 96
LAGS = (1, 2, 3, 4, 6, 8, 12, 16, 24, 32, 48, 64)
#: Pairs compared at most per lag past the first (evenly over the clip), tracks per pair, and RANSAC's rounds.
MOST_PER_LAG = 24
MOST_POINTS = 300
RANSAC_ROUNDS = 300
#: A pair needs this many tracks in both frames, and this share of them on its homography
#: (RANSAC, within :data:`ON_PLANE_PX`).
MIN_COMMON = 12
MIN_ON_PLANE = 0.3
ON_PLANE_PX = 1.0
#: A homography (scaled to determinant 1) is a turn where its real eigenvalue and the modulus of
#: its complex ones lie within this of 1.
ROTATION_LIKE = 0.05
#: Pairs whose span turns more than this (degrees) are left out: the trace tells an angle up to
#: half a turn, and nothing of which way past it.
LONGEST_DEG = 150.0
#: The pairs' fixed points (the axis's point) must lie within this share of the tracks' reach of
#: their median, this share of them at least: a face turning about a line in it (a box's side)
#: fixes no point, and its pairs' noise puts one anywhere (300-2000 px apart on a box's side).
ONE_AXIS = 0.1
ONE_AXIS_SHARE = 0.7
#: Fewer pairs than this, or a turn smaller than this (degrees), tell no rate; the pairs must turn
#: the same way, all but this share.
MIN_PAIRS = 6
MIN_TURNED_DEG = 15.0
AGAINST_SHARE = 0.1
#: The interval: the rate's jackknife over this many stretches of the clip (pairs touching one
#: left out at a time), at least what reading the angle to :data:`READ_TO_DEG` over the turn seen
#: allows: the tracks placed again (:func:`plane_angle`) read the renders' turns to about this
#: (a plane turning half a turn behind a bar across it, 0.09 degrees over the turn; 0.03-0.08
#: elsewhere), where their jackknife said less.
STRETCHES = 8
READ_TO_DEG = 0.1
#: A rate whose interval's half is wider than this fraction of it is no measurement.
LOOSEST = 0.5
#: Samples placed again (:func:`plane_angle`), at most: each costs about 0.2 ms of a core. Beyond
#: it, every track at fewer frames: a smoothly textured disc's 600 tracks at every third frame read
#: +0.01% within +-0.15%, its 200 longest at every frame +0.36% within +-0.3% (missing); the
#: renders of real photographs alike either way.
PLACED_SAMPLES = 6000


def keep_for_plane(tracks: pd.DataFrame, among: np.ndarray | None = None) -> pd.DataFrame:
    """The part of a tracks table (``frame, time_s, track, x_px, y_px``) that :func:`plane_angle`
    needs: the moving tracks (:data:`MOVING_PX`) at :data:`MOST_FRAMES` frames at most, evenly
    over the clip; chosen ``among`` these frames (the tracker's images kept, on which they are
    placed again: :func:`plane_angle`) where at least :data:`MIN_PAIRS` of them were tracked."""
    columns = ["frame", "time_s", "track", "x_px", "y_px"]
    if len(tracks) == 0:
        return tracks[columns].iloc[:0]
    places = tracks.groupby("track", sort=False)[["x_px", "y_px"]]
    extent = places.max() - places.min()
    moving = extent.index[np.hypot(extent["x_px"], extent["y_px"]) >= MOVING_PX]
    frames = np.unique(tracks["frame"].to_numpy())
    if among is not None and np.isin(frames, among).sum() > MIN_PAIRS:
        frames = frames[np.isin(frames, among)]
    if len(frames) > MOST_FRAMES:
        frames = frames[np.unique(np.linspace(0, len(frames) - 1, MOST_FRAMES).round().astype(int))]
    kept = tracks["track"].isin(moving) & tracks["frame"].isin(frames)
    return tracks.loc[kept, columns].reset_index(drop=True)


def plane_angle(samples: pd.DataFrame, keyframes: Keyframes | None = None,
                steady: Callable[[pd.DataFrame], pd.DataFrame] | None = None) -> PictureAngle | None:
    """The plane's turning angle and rate from its tracks (:func:`keep_for_plane`; see the
    module's notes); None where too few pairs of frames show a plane turning.

    With ``keyframes`` (the tracker's images), the tracks are placed again on those images by
    matching each one's first patch, affinely warped (:func:`rotrate_cli.scene.patches.place_tracks`,
    up to :data:`PLACED_SAMPLES` samples), and the plane is read from them where they show it; from
    the tracker's own positions where they do not. Lucas-Kanade follows a window by its translation
    alone; on a turning picture each step misses by the turn times the offset of the window's
    texture from its centre, and the tracks slide. On 17 renders of real photographs turning face
    on and tilted 45-75 degrees, the axis in the frame and out of it, 0.15-0.6 of a turn
    (2026-11-28), the tracker's positions read the plane -18% to +0.07% (median -1.4%), intervals
    up to +-15%, 10 of 17 covering; placed again, -0.16% to +0.44% (median -0.02%), all covering.

    ``steady``: the positions as a still camera would have seen them, where the camera moved
    (:meth:`rotrate_cli.scene.backdrop.BackdropPath.steady`)."""
    placed = placed_for_plane(samples, keyframes)
    return plane_from(samples, placed, steady)


def placed_for_plane(samples: pd.DataFrame, keyframes: Keyframes | None) -> pd.DataFrame | None:
    """The plane's tracks placed again on ``keyframes`` (:func:`plane_angle`); None without them."""
    if keyframes is None or len(keyframes) == 0 or len(samples) == 0:
        return None
    return place_tracks(keyframes, samples, PLACED_SAMPLES)


def plane_from(samples: pd.DataFrame, placed: pd.DataFrame | None,
               steady: Callable[[pd.DataFrame], pd.DataFrame] | None = None) -> PictureAngle | None:
    """:func:`plane_angle` from the tracks ``placed`` again (:func:`placed_for_plane`) where they
    show a plane, else from the tracker's ``samples``."""
    as_seen = steady if steady is not None else (lambda positions: positions)
    if placed is not None and len(placed) > 0:
        reading = _plane_angle(as_seen(placed))
        if reading is not None:
            # (fewer samples, and quicker: a finely textured disc's 650 tracks took 3-5 s, placed 1.2 s)
            return replace(reading, plane_placed=True)
    return _plane_angle(as_seen(samples))


def _plane_angle(samples: pd.DataFrame) -> PictureAngle | None:
    """:func:`plane_angle` from these positions."""
    if len(samples) == 0:
        return None
    pairs = _pairs(samples)
    if len(pairs) < MIN_PAIRS:
        return None
    centres = np.array([pair.centre_px for pair in pairs])
    middle = np.median(centres, axis=0)
    reach = float(np.max(np.ptp(samples[["x_px", "y_px"]].to_numpy(np.float64), axis=0)))
    near = np.hypot(*(centres - middle).T) <= ONE_AXIS * reach
    if near.mean() < ONE_AXIS_SHARE:
        return None  # no one axis: fixed points all over (a face turning about a line in it)
    pairs = [pair for pair, kept in zip(pairs, near, strict=True) if kept]
    if len(pairs) < MIN_PAIRS:
        return None
    first = np.array([pair.first for pair in pairs])
    second = np.array([pair.second for pair in pairs])
    spans = np.array([pair.span_s for pair in pairs])
    line = _horizon(pairs, np.zeros(2))
    angles = _angles(pairs, line)
    signs = np.sign(angles)
    sense = 1 if np.sum(signs > 0) >= np.sum(signs < 0) else -1
    if np.mean(signs != sense) > AGAINST_SHARE:
        return None  # the pairs do not agree which way it turns
    rate = _rate(spans, angles)
    frames = np.unique(np.r_[first, second])
    times = samples.groupby("frame")["time_s"].first()
    chained = _chained(frames, first, second, angles)
    turned = float(np.ptp(chained))
    if not math.isfinite(rate) or turned < MIN_TURNED_DEG:
        return None
    error, stretches = _jackknife(pairs, frames, line)
    half = max(student_t_975(stretches - 1) * error, READ_TO_DEG * abs(rate) / turned)
    if not half < LOOSEST * abs(rate):
        return None
    omega = math.radians(abs(rate))
    plane_map = _plane_map(pairs, line, samples)
    view = DiscView((float(np.median(centres[near, 0])), float(np.median(centres[near, 1]))), 0.0, 0.0, math.inf)
    on_plane = tuple(int(track) for track in np.unique(np.concatenate([pair.tracks for pair in pairs])))
    return PictureAngle(omega, max(0.0, omega - math.radians(half)), omega + math.radians(half), sense,
                        times.loc[frames].to_numpy(np.float64), chained - chained[0], turned, 1.0, view,
                        plane=True, plane_map=plane_map, plane_tracks=on_plane)


@dataclass(frozen=True)
class _Pair:
    """Two frames whose tracks show a plane turning: the frames, the time between them (s), the
    tracks on the plane in each (px, RANSAC's inliers) and the homography's fixed point (px)."""

    first: int
    second: int
    span_s: float
    before: np.ndarray
    after: np.ndarray
    centre_px: np.ndarray
    tracks: np.ndarray  # the tracks on the plane (their numbers), as ``before`` and ``after``


def _pairs(samples: pd.DataFrame) -> list[_Pair]:
    """The pairs of frames whose tracks show a plane turning (see the module's notes)."""
    by_frame = {int(frame): group.set_index("track")[["x_px", "y_px"]] for frame, group in samples.groupby("frame")}
    times = samples.groupby("frame")["time_s"].first()
    frames = sorted(by_frame)
    found: list[_Pair] = []
    for lag in LAGS:
        firsts = range(len(frames) - lag)
        if lag > 1 and len(firsts) > MOST_PER_LAG:  # (every step: the chain of angles runs through them)
            firsts = np.unique(np.linspace(0, len(frames) - lag - 1, MOST_PER_LAG).round().astype(int))
        for index in firsts:
            frame, other = frames[index], frames[index + lag]
            common = by_frame[frame].index.intersection(by_frame[other].index)
            if len(common) < MIN_COMMON:
                continue
            if len(common) > MOST_POINTS:
                common = common[np.unique(np.linspace(0, len(common) - 1, MOST_POINTS).round().astype(int))]
            before = by_frame[frame].loc[common].to_numpy(np.float64)
            after = by_frame[other].loc[common].to_numpy(np.float64)
            turn = _turn(before, after)
            if turn is not None and abs(turn[0]) <= LONGEST_DEG:
                on = turn[2]
                found.append(_Pair(frame, other, float(times[other] - times[frame]), before[on], after[on], turn[1],
                                   common.to_numpy()[on]))
    return found


def _turn(before: np.ndarray, after: np.ndarray) -> tuple[float, np.ndarray, np.ndarray] | None:
    """The angle (degrees, signed), fixed point and points on the plane (a mask) of the homography
    that takes ``before`` to ``after``, or None where it is no turn of a plane (too few points on
    it, or not rotation-like)."""
    homography, mask = cv2.findHomography(before, after, cv2.RANSAC, ON_PLANE_PX, maxIters=RANSAC_ROUNDS,
                                          confidence=0.99)
    if homography is None or mask is None:
        return None
    on = mask.ravel().astype(bool)
    if on.sum() < max(8, MIN_ON_PLANE * len(before)):
        return None
    refitted, _ = cv2.findHomography(before[on], after[on], 0)  # least squares on the plane's points
    homography = refitted if refitted is not None else homography
    determinant = float(np.linalg.det(homography))
    if determinant <= 0:
        return None  # a mirror: no turn
    scaled = homography / np.cbrt(determinant)
    values, vectors = np.linalg.eig(scaled)
    real = int(np.argmin(np.abs(values.imag)))
    others = [values[i] for i in range(3) if i != real]
    if (abs(values[real].imag) > 1e-12 or min(abs(v.imag) for v in others) <= 1e-12
            or abs(values[real].real - 1.0) > ROTATION_LIKE or any(abs(abs(v) - 1.0) > ROTATION_LIKE for v in others)):
        return None  # real eigenvalues: a line of fixed points (a plane turning about an axis in it)
    fixed = vectors[:, real].real
    if abs(fixed[2]) < 1e-12:
        return None
    centre = fixed[:2] / fixed[2]
    theta = math.degrees(math.acos(max(-1.0, min(1.0, (float(np.trace(scaled).real) - 1.0) / 2.0))))
    u, v = before[on] - centre, after[on] - centre
    turning = float(np.sum(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]))
    # (the picture's y runs down: a turn clockwise as shown has a positive cross product)
    return (-theta if turning > 0 else theta), centre, on


#: The plane's horizon (the picture of its line at infinity, ``a x + b y + 1 = 0``) is sought in
#: these units (per px), and a point on the plane must lie this far (in ``a x + b y + 1``) on the
#: near side of it.
HORIZON_UNIT = 1e-3
NEAR_SIDE = 0.05


def _affines(stacked: _Stacked, line: np.ndarray) -> tuple[float, np.ndarray] | None:
    """Each pair's affine map (3 x 2, least squares) between its points seen from above the plane
    (the picture taken through ``line``'s horizon to infinity: ``x / (a x + b y + 1)``), each point
    weighted by its nearness squared so that residuals count nearly in the picture's px, and the
    sum of the squared distances (px) from the points to where the maps put them back in the
    picture; None where a point lies past the horizon. All pairs at once. (Summed in the picture
    taken through the horizon, the residuals shrink as a horizon brought nearer shrinks the
    picture: a disc seen face on, 0.3 px of noise, was read through a horizon 40000 px off and
    +0.25%.)"""
    near_before = stacked.before @ line + 1.0
    near_after = stacked.after @ line + 1.0
    if near_before.min() < NEAR_SIDE or near_after.min() < NEAR_SIDE:
        return None
    flat_before = stacked.before / near_before[:, None]
    flat_after = stacked.after / near_after[:, None]
    weight = near_after ** 2
    design = np.c_[flat_before, np.ones(len(flat_before))]
    groups = len(stacked.starts)

    starts = stacked.starts

    def summed(values: np.ndarray) -> np.ndarray:  # per pair, of each column
        return np.add.reduceat(values * weight[:, None], starts, axis=0)

    products = summed(np.einsum("ni,nj->nij", design, design).reshape(-1, 9)).reshape(groups, 3, 3)
    crossed = summed(np.einsum("ni,nj->nij", design, flat_after).reshape(-1, 6)).reshape(groups, 3, 2)
    try:
        solutions = np.linalg.solve(products, crossed)
    except np.linalg.LinAlgError:
        return None
    mapped = np.einsum("ni,nij->nj", design, solutions[stacked.owner])
    back = 1.0 - mapped @ line
    if back.min() < NEAR_SIDE:
        return None
    return float(np.sum((mapped / back[:, None] - stacked.after) ** 2)), solutions


@dataclass(frozen=True)
class _Stacked:
    """The pairs' points, one pair's after the other's, where each pair's start, and whose each is
    (stacked once for a search over the horizon: its every step maps them all)."""

    before: np.ndarray
    after: np.ndarray
    starts: np.ndarray
    owner: np.ndarray


def _stacked(pairs: list[_Pair], backwards: bool = False) -> _Stacked:
    """The pairs' points stacked (``backwards``: each pair's later frame's first)."""
    sizes = np.array([len(pair.before) for pair in pairs])
    before = np.concatenate([pair.after if backwards else pair.before for pair in pairs])
    after = np.concatenate([pair.before if backwards else pair.after for pair in pairs])
    return _Stacked(before, after, np.r_[0, np.cumsum(sizes)[:-1]], np.repeat(np.arange(len(pairs)), sizes))


def _horizon(pairs: list[_Pair], start: np.ndarray, step: float = 0.3, budget: int = 150) -> np.ndarray:
    """The plane's horizon (``a, b``, per px) through which every pair's map is most nearly
    affine: one line for the whole clip (a homography fitted to each pair alone reads its angle
    through its own horizon, noise and all: a disc tilted 72 degrees read -6.8% so, -0.2% through
    one horizon)."""
    from scipy.optimize import minimize  # a well-kept simplex search; imported where used (start-up)

    stacked = _stacked(pairs)

    def cost(x: np.ndarray) -> float:
        fitted = _affines(stacked, x * HORIZON_UNIT)
        return fitted[0] if fitted is not None else math.inf

    simplex = [start, start + np.array([step, 0.0]), start + np.array([0.0, step])]
    found = minimize(cost, start, method="Nelder-Mead",
                     options={"initial_simplex": simplex, "xatol": 1e-3, "fatol": 1e-9, "maxfev": budget})
    return (found.x if math.isfinite(found.fun) else start) * HORIZON_UNIT


def _angles(pairs: list[_Pair], line: np.ndarray) -> np.ndarray:
    """Each pair's angle (degrees, signed: anticlockwise as the picture shows it positive) through
    the plane's horizon ``line``: its affine map, a turn seen through one affine view, taken back
    through that view (:func:`_metric`) to a turn, whose angle is read with its sign (a cosine
    read from the map's trace holds its noise as a turn: a disc seen face on turning 1.7 degrees
    a frame, 0.15 px of noise, read +0.08% so). The mean of the map fitted each way: a
    least-squares map is pulled by the noise of the points it maps from."""
    forward = _affines(_stacked(pairs), line)
    backward = _affines(_stacked(pairs, backwards=True), line)
    if forward is None or backward is None:
        return np.full(len(pairs), np.nan)
    metric = _metric(forward[1])
    if metric is None:
        return np.full(len(pairs), np.nan)
    return 0.5 * (_angle_of(forward[1], metric) - _angle_of(backward[1], metric))


def _metric(solutions: np.ndarray) -> np.ndarray | None:
    """The affine view (2 x 2: a circle's radius to the picture taken through the horizon) that
    makes every map (3 x 2) a turn: one ellipse ``x^T M x = 1`` is every map's own
    (``L^T M L = M`` for each linear part ``L``, least squares); None where none fits."""
    linear = np.transpose(solutions[:, :2, :], (0, 2, 1))
    determinant = np.linalg.det(linear)
    linear = linear[determinant > 0] / np.sqrt(determinant[determinant > 0])[:, None, None]
    if len(linear) < 2:
        return None
    rows = []
    for basis in (np.array([[1.0, 0.0], [0.0, 0.0]]), np.array([[0.0, 1.0], [1.0, 0.0]]),
                  np.array([[0.0, 0.0], [0.0, 1.0]])):
        moved = np.transpose(linear, (0, 2, 1)) @ basis @ linear - basis
        rows.append(np.stack([moved[:, 0, 0], moved[:, 0, 1], moved[:, 1, 1]], axis=1).ravel())
    m1, m2, m3 = np.linalg.svd(np.stack(rows, axis=1))[2][-1]
    form = np.array([[m1, m2], [m2, m3]])
    form = -form if form[0, 0] < 0 else form
    if np.linalg.eigvalsh(form).min() <= 0:
        return None
    return np.linalg.cholesky(np.linalg.inv(form))  # metric @ metric.T = form^-1


def _angle_of(solutions: np.ndarray, metric: np.ndarray) -> np.ndarray:
    """The angle (degrees, signed) of each affine map (3 x 2) taken back through ``metric`` to a
    turn; NaN for a mirror."""
    linear = np.transpose(solutions[:, :2, :], (0, 2, 1))
    turn = np.linalg.solve(metric, linear) @ metric
    sine, cosine = turn[:, 1, 0] - turn[:, 0, 1], turn[:, 0, 0] + turn[:, 1, 1]
    # (the picture's y runs down: a positive sine turns clockwise as shown)
    return np.where(np.linalg.det(linear) > 0, -np.degrees(np.arctan2(sine, cosine)), np.nan)


def _plane_map(pairs: list[_Pair], line: np.ndarray, samples: pd.DataFrame) -> PlaneMap | None:
    """The plane's picture as the pairs tell it (:class:`rotrate_cli.scene.disc.PlaneMap`): through
    the horizon ``line``, each pair's affine map is a turn seen through one affine view, so one
    ellipse (``x^T M x = 1``, ``L^T M L = M`` for every map's linear part ``L``) is every map's own,
    and the axis's point is their fixed point. None where no such ellipse fits."""
    fitted = _affines(_stacked(pairs), line)
    if fitted is None:
        return None
    fixed = []
    for solution in fitted[1]:
        linear, shift = solution[:2].T, solution[2]
        if np.linalg.det(linear) <= 0:
            continue
        try:
            fixed.append(np.linalg.solve(np.eye(2) - linear, shift))
        except np.linalg.LinAlgError:
            continue
    metric = _metric(fitted[1])
    if len(fixed) < MIN_PAIRS or metric is None:
        return None
    centre = np.median(np.array(fixed), axis=0)
    points = samples[["x_px", "y_px"]].to_numpy(np.float64)
    near = points @ line + 1.0
    flat = points[near > NEAR_SIDE] / near[near > NEAR_SIDE, None]
    radii = np.linalg.norm(np.linalg.solve(metric, (flat - centre).T), axis=0)
    if len(radii) == 0:
        return None
    return PlaneMap((float(line[0]), float(line[1])), (float(centre[0]), float(centre[1])),
                    ((float(metric[0, 0]), float(metric[0, 1])), (float(metric[1, 0]), float(metric[1, 1]))),
                    float(np.quantile(radii, 0.98)))


def _rate(spans: np.ndarray, angles: np.ndarray) -> float:
    """The rate (degrees a second) of the pairs' angles over their spans: a line through the origin."""
    known = np.isfinite(angles)
    total = float(np.sum(spans[known] ** 2))
    return float(np.sum(spans[known] * angles[known])) / total if total > 0 else math.nan


def _jackknife(pairs: list[_Pair], frames: np.ndarray, line: np.ndarray) -> tuple[float, int]:
    """The rate's standard error (degrees a second) and the stretches it was found from: a
    jackknife over :data:`STRETCHES` stretches of the clip, the pairs touching one left out at a
    time and the horizon sought again (pairs sharing frames share their errors, which a fit's
    residuals do not show, and the horizon is uncertain too)."""
    first = np.array([pair.first for pair in pairs])
    second = np.array([pair.second for pair in pairs])
    rates = []
    for stretch in np.array_split(frames, min(STRETCHES, len(frames))):
        low, high = stretch[0], stretch[-1]
        kept = ~(((first >= low) & (first <= high)) | ((second >= low) & (second <= high)))
        if kept.sum() >= MIN_PAIRS // 2:
            chosen = [pair for pair, keep in zip(pairs, kept, strict=True) if keep]
            horizon = _horizon(chosen, line / HORIZON_UNIT, step=0.05, budget=50)
            spans = np.array([pair.span_s for pair in chosen])
            rates.append(_rate(spans, _angles(chosen, horizon)))
    values = np.array(rates)
    values = values[np.isfinite(values)]
    count = len(values)
    if count < 3:
        return math.inf, max(count, 2)
    return math.sqrt((count - 1) / count * float(np.sum((values - values.mean()) ** 2))), count


def _chained(frames: np.ndarray, first: np.ndarray, second: np.ndarray, angles: np.ndarray) -> np.ndarray:
    """Each frame's angle (degrees, from the first frame's), the least-squares fit of the pairs'
    angles as differences (frames no pair joins to the first lie on the line of the rest)."""
    index = {int(frame): i for i, frame in enumerate(frames)}
    known = np.isfinite(angles)
    design = np.zeros((int(known.sum()) + 1, len(frames)))
    for row, (a, b) in enumerate(zip(first[known], second[known], strict=True)):
        design[row, index[int(a)]], design[row, index[int(b)]] = -1.0, 1.0
    design[-1, 0] = 1.0  # the first frame's angle is 0
    return np.linalg.lstsq(design, np.r_[angles[known], 0.0], rcond=None)[0]
