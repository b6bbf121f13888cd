"""The camera's focal length (and elevation) from the tracks themselves: ``--fov auto``.

Orthographic offsets alone say little about perspective: a nearer or farther camera changes the
shape of each track's horizontal motion only at second order, and on partial arcs that is
confounded with the rate (a misfit-driven search put a 25-degree lens at 40 degrees). The
vertical motion says it at first order. Seen through a pinhole, a point's image row is
``f Y / Z``: as the point turns towards the camera its depth ``Z`` shrinks and its row moves
away from the principal point, by its height over the distance, in step with its nearness. A
track near the top of the object bobs up as it passes in front, one near the bottom bobs down;
orthographically neither moves. So the rows' motion, against each track's height in the image,
measures ``1 / f``.

The model is the whole rigid motion. In pixel units at the axis's depth (the camera at
distance ``f`` from the axis point ``A``, which projects to the fixation point), each track is
a point at height ``Y`` along the axis direction ``u`` and at ``(a, b)`` in the plane of turning:

    P(t) = A + Y u + e1 (a cos wt - b sin wt) + e2 (a sin wt + b cos wt),
    image offset from the principal point = P_xy / (1 + g P_z'),

with ``g = 1 / f`` (0 is orthographic, so the fit passes smoothly through it), ``P_z'`` the
depth relative to the axis point, ``e1`` the image direction in which offsets are measured, and
``u`` and ``e2`` leaning by the camera's elevation ``eps``. The shared unknowns are ``g``,
``eps`` and ``w``; each track has ``Y, a, b``. They are fitted to both image coordinates of
every sample by sparse nonlinear least squares (a soft-L1 loss, then the worst-fitting tracks
dropped and the fit repeated: a track that slid along the object shows as vertical misfit).
The principal point is taken at the image centre.
"""

from __future__ import annotations

import math
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from rotrate_cli.errors import InputError
from rotrate_cli.runtime.lazy import pandas as pd
from rotrate_cli.scene.axis import unit_offset
from rotrate_cli.scene.patches import PLACING_THREADS, place_again
from rotrate_cli.tracking.keyframes import Keyframes

#: Tracks and samples per track the fit uses: the longest tracks, evenly thinned. The shared
#: unknowns are three; more data than this narrows them little and costs time.
MAX_TRACKS = 160
MAX_SAMPLES_PER_TRACK = 24
#: A track must turn through this much (rad) to say anything about its ellipse.
MIN_TURN_RAD = 0.3
#: The fit needs at least this many tracks; a track placed again on the kept frames needs at
#: least MIN_PLACED of its samples to have matched.
MIN_TRACKS = 8
MIN_PLACED = 6
#: ... and at least this share of the tracks must have matched, or the tracker's positions are
#: fitted. On the accuracy suite's lenses 90-99% of the tracks matched; on real stills far apart
#: (the dinosaur's first 20-30 photographs, 10 degrees apart) 10-22%, where the tracker's
#: positions are as good.
PLACED_SHARE = 0.5
#: Tracks placed again (the longest): their misfit is a fifth of the tracker's positions', so
#: fewer do (on the accuracy suite's lenses, 80 tracks found them within 0.4 degrees of 160), and
#: each costs about 3 ms (placed on :data:`rotrate_cli.scene.patches.PLACING_THREADS` threads).
MAX_PLACED_TRACKS = 96
#: Samples whose offset across the line of sight exceeds this fraction of their radius (turned
#: more than 55 degrees from facing the camera) are left out after the first fit.
FACE_ON_LATERAL = 0.82
#: Unknowns shared by all tracks: inverse focal length, elevation, rate, the axis's angle, and the
#: axis point's shift across the axis.
SHARED = 5
#: Focal lengths longer than this many image widths (a field of view under 8.2 degrees) are
#: reported as orthographic: the trackers' own small biases look like that much perspective (an
#: orthographic rendered sphere came out at 4.6 degrees, which moved its omega by -1.8%), and a
#: lens that long changes omega by little more.
ORTHOGRAPHIC_WIDTHS = 7.0
#: A first fit that ends at the orthographic bound (an inverse focal length under AT_BOUND, per
#: pixel) may have stopped in a local minimum: the fit is started again from a lens this wide, and
#: the better of the two kept. A cylinder filling a portrait frame, 40 degrees across and seen from
#: 15 degrees above, ended there (misfit cost 10,300) and read +49% within [+45%, +54%], good;
#: from 45 degrees it found 41.2 (cost 4,300) and reads -0.7%, weak and covering.
WIDE_START_FOV_DEG = 45.0
AT_BOUND = 1e-9
#: Seen from at least this far above or below (degrees, and this many standard errors of the
#: elevation), the way the paths go round their ellipses tells the sense of turning. On 133 renders
#: of bench-random whose lens was sought, the elevations found from 15, 30 and 60 degrees above were
#: all 13.9 degrees or more, and the sense so told right on all 80; side views came out within 0.5.
SENSE_ELEVATION_DEG = 5.0
SENSE_SE = 5.0


@dataclass(frozen=True)
class FocalEstimate:
    """What the tracks say about the camera (see the module's notes).

    Attributes:
        focal_px: the focal length in pixels; ``inf`` when the view is indistinguishable from
            orthographic (the inverse focal length is not clearly above zero).
        fov_deg: the horizontal field of view that focal length gives on this frame width.
        inverse_focal: ``1 / focal_px`` as fitted (may be slightly negative on an orthographic
            view), and ``inverse_focal_se`` its standard error.
        elevation_deg: how far the camera looks down on the axis (negative: up at it).
        tracks: tracks in the final fit.
        rms_px: root-mean-square misfit of those tracks' positions, pixels.
        axis_angle_deg: the axis's angle in the image the fit found.
        fixation_px: the axis point the fit found: the given one moved across the axis.
        sense: +1 anticlockwise seen from the axis's top end, -1 clockwise, as the paths go round
            their ellipses seen from above or below (which a lens found tells); NaN where the
            view is too near a side view, or no lens was found, to say.
    """

    focal_px: float
    fov_deg: float
    inverse_focal: float
    inverse_focal_se: float
    elevation_deg: float
    tracks: int
    rms_px: float
    axis_angle_deg: float = math.nan
    fixation_px: tuple[float, float] = (math.nan, math.nan)
    sense: float = math.nan


def parse_fov(text: str | None, where: str = "`fov_deg`") -> tuple[float | None, bool]:
    """``--fov``'s value as ``(degrees or None, find the focal length)``: degrees (given),
    ``auto`` or not given (found from the tracks: ``(None, True)``), ``ortho`` (the paper's
    orthographic camera, forced: ``(None, False)``).

    Raises:
        InputError: anything else.
    """
    if text is None or text.strip().lower() == "auto":
        return None, True
    if text.strip().lower() in ("ortho", "orthographic"):
        return None, False
    try:
        return float(text), False
    except ValueError:
        raise InputError(f"{where}: the field of view must be degrees, auto or ortho; got {text!r}") from None


def _placed(tracks: pd.DataFrame, omega_rad_s: float,
            keyframes: Keyframes) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """The longest tracks that turn through MIN_TURN_RAD, each as (time, x, y) thinned evenly
    over the frames kept in ``keyframes`` and placed again there by matching its first patch
    (:mod:`rotrate_cli.scene.patches`); a track left with fewer than MIN_PLACED matched samples is
    dropped."""
    candidates = _longest(tracks[keyframes.has(tracks["frame"].to_numpy())], omega_rad_s, MAX_PLACED_TRACKS)

    def place(candidate: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]) -> tuple[np.ndarray, ...] | None:
        time_s, frame, x, y = candidate
        x, y = place_again(keyframes, frame, x, y)
        good = np.isfinite(x)
        return (time_s[good], x[good], y[good]) if good.sum() >= MIN_PLACED else None

    # OpenCV lets go of the interpreter while it matches: two tracks at once use both cores
    with ThreadPoolExecutor(max_workers=PLACING_THREADS) as pool:
        placed = [track for track in pool.map(place, candidates) if track is not None]
    # where most tracks' patches do not match, the picture changes in ways an affine warp does not
    # follow (stills far apart, glossy or jagged surfaces): the few that match are no better
    return placed if len(placed) >= PLACED_SHARE * len(candidates) else []


def _longest(tracks: pd.DataFrame, omega_rad_s: float,
             most: int = MAX_TRACKS) -> list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
    """The ``most`` longest tracks that turn through MIN_TURN_RAD, each as (time, frame, x, y)
    thinned evenly."""
    track = tracks["track"].to_numpy()
    starts = np.flatnonzero(np.r_[True, track[1:] != track[:-1]])
    ends = np.r_[starts[1:], len(track)]
    time_s = tracks["time_s"].to_numpy(dtype=np.float64)
    frame = tracks["frame"].to_numpy() if "frame" in tracks else np.zeros(len(track), np.int64)
    x, y = tracks["x_px"].to_numpy(dtype=np.float64), tracks["y_px"].to_numpy(dtype=np.float64)
    span = time_s[ends - 1] - time_s[starts]
    order = np.argsort(-span, kind="stable")
    chosen = []
    for i in order[:most]:
        if abs(omega_rad_s) * span[i] < MIN_TURN_RAD or ends[i] - starts[i] < 6:
            break
        rows = np.unique(np.linspace(starts[i], ends[i] - 1, MAX_SAMPLES_PER_TRACK).round().astype(int))
        chosen.append((time_s[rows], frame[rows], x[rows], y[rows]))
    return chosen


@dataclass(frozen=True)
class _Posed:
    """The model's samples under one set of unknowns: each sample's height, cos and sin of its
    turn, in-plane coordinates, the frame ``(e1, up, e2)``, its point, whether its depth is free
    (not held at the nearest allowed), the depth, and its image (relative to the principal point)."""

    height: np.ndarray
    cos: np.ndarray
    sin: np.ndarray
    along1: np.ndarray
    along2: np.ndarray
    frame: tuple[np.ndarray, np.ndarray, np.ndarray]
    point: np.ndarray
    free: np.ndarray
    depth: np.ndarray
    image: np.ndarray


class _Model:
    """The rigid-turn pinhole model over a fixed set of tracks (see the module's notes)."""

    def __init__(self, chosen: list[tuple[np.ndarray, np.ndarray, np.ndarray]], centre_px: np.ndarray,
                 axis_px: np.ndarray, angle_deg: float) -> None:
        self.counts = np.array([len(t) for t, _, _ in chosen])
        self.owner = np.repeat(np.arange(len(chosen)), self.counts)
        time_s = np.concatenate([t for t, _, _ in chosen])
        self.time_s = time_s - time_s.mean()
        # positions relative to the principal point
        self.observed = np.stack([np.concatenate([x for _, x, _ in chosen]),
                                  np.concatenate([y for _, _, y in chosen])], axis=1) - centre_px
        self.centre_px = centre_px
        self.axis_px = axis_px  # the axis point, relative to the principal point
        self.angle_rad = math.radians(angle_deg)

    @staticmethod
    def frame(elevation_rad: float, angle_rad: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The image direction ``e1`` in which offsets are measured, the axis direction ``u``
        (its top end) and the in-plane direction ``e2``, for an elevation and an image angle."""
        ux, uy = unit_offset(math.degrees(angle_rad))
        e1 = np.array([ux, uy, 0.0])
        up = np.array([math.cos(elevation_rad) * uy, -math.cos(elevation_rad) * ux, -math.sin(elevation_rad)])
        return e1, up, np.cross(up, e1)

    def _posed(self, params: np.ndarray) -> _Posed:
        """Every sample's point and its image under ``params`` (for :meth:`predict` and
        :meth:`jacobian`)."""
        g, elevation, omega, angle, across = params[:SHARED]
        per_track = params[SHARED:].reshape(-1, 3)[self.owner]
        height, a, b = per_track[:, 0], per_track[:, 1], per_track[:, 2]
        e1, up, e2 = self.frame(elevation, angle)
        c, s = np.cos(omega * self.time_s), np.sin(omega * self.time_s)
        along1, along2 = a * c - b * s, a * s + b * c
        point = height[:, None] * up + along1[:, None] * e1 + along2[:, None] * e2
        raw_depth = 1.0 + g * point[:, 2]
        free = raw_depth > 0.05  # nearer than that (a fit's wild trial) the depth is held
        depth = np.where(free, raw_depth, 0.05)
        image = (self.axis_px + across * e1[:2] + point[:, :2]) / depth[:, None]
        return _Posed(height, c, s, along1, along2, (e1, up, e2), point, free, depth, image)

    def predict(self, params: np.ndarray) -> np.ndarray:
        return self._posed(params).image

    def lateral_fraction(self, params: np.ndarray) -> np.ndarray:
        """Each sample's offset across the line of sight as a fraction of its radius: |sin| of
        its angle from facing the camera (1 at the object's outline)."""
        omega = params[2]
        per_track = params[SHARED:].reshape(-1, 3)[self.owner]
        a, b = per_track[:, 1], per_track[:, 2]
        c, s = np.cos(omega * self.time_s), np.sin(omega * self.time_s)
        return np.abs(a * c - b * s) / np.maximum(np.hypot(a, b), 1e-9)

    def residuals(self, params: np.ndarray) -> np.ndarray:
        return (self.predict(params) - self.observed).ravel()

    def jacobian(self, params: np.ndarray):  # a scipy.sparse.csr_matrix
        """The residuals' derivatives, worked out (each sample's two rows depend on the shared
        unknowns and its own track's three only). Finite differences of :meth:`residuals` took
        nine evaluations of the model a step and most of the fit's time."""
        from scipy.sparse import csr_matrix  # scipy is imported only when the focal length is sought

        g, elevation, _, _, across = params[:SHARED]
        posed = self._posed(params)
        height, c, s, along1, along2 = posed.height, posed.cos, posed.sin, posed.along1, posed.along2
        e1, up, e2 = posed.frame
        point, free, depth, out = posed.point, posed.free, posed.depth, posed.image
        # the frame's derivatives by the elevation and by the angle (e1 = (cos, sin, 0) of the angle)
        up_elevation = np.array([-math.sin(elevation) * e1[1], math.sin(elevation) * e1[0], -math.cos(elevation)])
        e1_angle = np.array([-e1[1], e1[0], 0.0])
        up_angle = np.array([math.cos(elevation) * e1_angle[1], -math.cos(elevation) * e1_angle[0], 0.0])
        e2_elevation = np.cross(up_elevation, e1)
        e2_angle = np.cross(up_angle, e1) + np.cross(up, e1_angle)
        time_s = self.time_s

        def column(d_point: np.ndarray, d_numerator_extra: np.ndarray | None = None,
                   d_depth_g: np.ndarray | None = None) -> np.ndarray:
            """d(out)/d(unknown), n x 2, from the point's derivative (n x 3 or 3)."""
            d_point = np.broadcast_to(d_point, point.shape)
            d_depth = g * d_point[:, 2] if d_depth_g is None else d_depth_g
            d_numerator = d_point[:, :2] if d_numerator_extra is None else d_point[:, :2] + d_numerator_extra
            return (d_numerator - out * np.where(free, d_depth, 0.0)[:, None]) / depth[:, None]

        zero3 = np.zeros(3)
        shared = [
            column(zero3, d_depth_g=point[:, 2]),  # g
            column(height[:, None] * up_elevation + along2[:, None] * e2_elevation),  # elevation
            column(time_s[:, None] * (-along2[:, None] * e1 + along1[:, None] * e2)),  # omega
            column(height[:, None] * up_angle + along1[:, None] * e1_angle + along2[:, None] * e2_angle,
                   across * e1_angle[:2]),  # angle
            column(zero3, np.broadcast_to(e1[:2], out.shape)),  # across
        ]
        own = [
            column(up),  # height
            column(c[:, None] * e1 + s[:, None] * e2),  # a
            column(-s[:, None] * e1 + c[:, None] * e2),  # b
        ]
        samples = len(self.owner)
        rows = np.arange(2 * samples)
        shared_values = np.stack([d.ravel() for d in shared], axis=1)  # 2n x SHARED
        own_values = np.stack([d.ravel() for d in own], axis=1)  # 2n x 3
        own_columns = SHARED + 3 * np.repeat(self.owner, 2)[:, None] + np.arange(3)
        all_rows = np.repeat(rows, SHARED + 3)
        all_columns = np.concatenate([np.broadcast_to(np.arange(SHARED), (2 * samples, SHARED)), own_columns],
                                     axis=1).ravel()
        values = np.concatenate([shared_values, own_values], axis=1).ravel()
        return csr_matrix((values, (all_rows, all_columns)), shape=(2 * samples, SHARED + 3 * len(self.counts)))

    def linear_start(self, elevation: float, omega: float) -> np.ndarray:
        """Per-track ``Y, a, b`` by linear least squares with ``g = 0`` (orthographic)."""
        e1, up, e2 = self.frame(elevation, self.angle_rad)
        c, s = np.cos(omega * self.time_s), np.sin(omega * self.time_s)
        centred = self.observed - self.axis_px
        start = np.zeros((len(self.counts), 3))
        bounds = np.r_[0, np.cumsum(self.counts)]
        for k in range(len(self.counts)):
            rows = slice(bounds[k], bounds[k + 1])
            # columns: Y -> up_xy; a -> e1 c + e2 s; b -> -e1 s + e2 c (xy parts)
            design = np.stack([
                np.broadcast_to(up[:2], (rows.stop - rows.start, 2)),
                c[rows, None] * e1[:2] + s[rows, None] * e2[:2],
                -s[rows, None] * e1[:2] + c[rows, None] * e2[:2],
            ], axis=2).reshape(-1, 3)
            start[k] = np.linalg.lstsq(design, centred[rows].ravel(), rcond=None)[0]
        return start.ravel()


def estimate_focal(tracks: pd.DataFrame, fixation_px: tuple[float, float], angle_deg: float,
                   omega_rad_s: float, size_px: tuple[int, int], elevation_deg: float = 0.0,
                   keyframes: Keyframes | None = None) -> FocalEstimate | None:
    """The focal length and elevation that best explain the tracks' rigid turning (see the
    module's notes); None when too few tracks turn far enough.

    ``tracks``: ``track, time_s, x_px, y_px`` sorted by track then time, on one body;
    ``omega_rad_s``: a first rate (its sign is free here); ``elevation_deg``: a first guess.
    With perspective seen, the sense of turning and so the sign of the elevation are told
    (positive: the camera looks down); on an orthographic view the sign is not. ``keyframes``:
    the tracker's images kept, on which the samples are placed again (:func:`_placed`); where
    too few match well enough to fit, the tracker's own positions are fitted.
    """
    if keyframes is not None and len(keyframes):
        found = _estimate(_placed(tracks, omega_rad_s, keyframes), fixation_px, angle_deg, omega_rad_s,
                          size_px, elevation_deg)
        if found is not None:
            return found
    chosen = [(time_s, x, y) for time_s, _, x, y in _longest(tracks, omega_rad_s)]
    return _estimate(chosen, fixation_px, angle_deg, omega_rad_s, size_px, elevation_deg)


def _estimate(chosen: list[tuple[np.ndarray, np.ndarray, np.ndarray]], fixation_px: tuple[float, float],
              angle_deg: float, omega_rad_s: float, size_px: tuple[int, int],
              elevation_deg: float) -> FocalEstimate | None:
    """:func:`estimate_focal` on the tracks chosen, each as (time, x, y)."""
    if len(chosen) < MIN_TRACKS:
        return None
    width_px, height_px = size_px
    centre = np.array([width_px / 2.0 - 0.5, height_px / 2.0 - 0.5])
    model = _Model(chosen, centre, np.asarray(fixation_px, dtype=np.float64) - centre, angle_deg)
    turning = _sense(model, math.radians(elevation_deg), abs(omega_rad_s))
    best = None
    for inverse_focal in (0.0, math.tan(math.radians(WIDE_START_FOV_DEG) / 2.0) / (width_px / 2.0)):
        if best is not None and best.x[0] > AT_BOUND:
            break  # the fit from the orthographic start found a lens: no second start
        for sign in (1.0, -1.0):  # orthographically, (elevation, omega) and (-elevation, -omega) agree
            elevation = math.radians(elevation_deg) * sign
            omega = abs(omega_rad_s) * sign * turning
            start = np.r_[inverse_focal, elevation, omega, model.angle_rad, 0.0, model.linear_start(elevation, omega)]
            fit = _fit(model, start, "soft_l1")
            if best is None or fit.cost < best.cost:
                best = fit
    assert best is not None
    # keep to the parts of each turn seen face on: near the object's outline a surface is seen
    # edge on, and the tracker's window there slides along it (on a rendered cylinder through a
    # 40-degree lens, the tracks that ran into the outline bobbed half as much as they should
    # have, and put the focal length 27% long)
    lateral = model.lateral_fraction(best.x)
    chosen, kept_tracks = _trim(chosen, lateral <= FACE_ON_LATERAL, model.owner)
    if len(chosen) < MIN_TRACKS:
        return None
    params = np.r_[best.x[:SHARED], best.x[SHARED:].reshape(-1, 3)[kept_tracks].ravel()]
    model = _Model(chosen, centre, model.axis_px, angle_deg)
    best = _fit(model, params, "soft_l1")
    # drop the tracks that fit worst (slid along the surface, or off the body) and fit again
    misfit = np.sqrt(np.bincount(model.owner, (best.fun.reshape(-1, 2) ** 2).sum(axis=1)) / model.counts)
    keep = misfit <= max(3.0 * float(np.median(misfit)), 0.5)
    if keep.sum() < len(chosen) and keep.sum() >= MIN_TRACKS:
        chosen = [track for track, kept in zip(chosen, keep, strict=True) if kept]
        params = np.r_[best.x[:SHARED], best.x[SHARED:].reshape(-1, 3)[keep].ravel()]
        model = _Model(chosen, centre, model.axis_px, angle_deg)
        best = _fit(model, params, "linear")
    residual = best.fun
    dof = max(len(residual) - len(best.x), 1)
    sigma2 = float(residual @ residual) / dof
    se = _shared_standard_errors(best.jac, np.repeat(model.owner, 2), sigma2)
    g, elevation = float(best.x[0]), math.degrees(float(best.x[1]))
    g_se = se[0]
    focal = 1.0 / g if g > 0 and g > 2.0 * g_se and 1.0 / g < ORTHOGRAPHIC_WIDTHS * width_px else math.inf
    fov = 2.0 * math.degrees(math.atan((width_px / 2.0) / focal)) if math.isfinite(focal) else 0.0
    angle = float(best.x[3])
    # the sense of turning: the direction the paths go round their ellipses, with the camera's
    # elevation's sign (which a lens tells: the nearer half looks larger)
    sense = math.nan
    if math.isfinite(focal) and abs(elevation) >= SENSE_ELEVATION_DEG and abs(best.x[1]) >= SENSE_SE * se[1]:
        sense = float(np.sign(best.x[2]) * np.sign(best.x[1]))
    e1 = model.frame(float(best.x[1]), angle)[0]
    fixation = (float(fixation_px[0] + best.x[4] * e1[0]), float(fixation_px[1] + best.x[4] * e1[1]))
    return FocalEstimate(focal, fov, g, g_se, elevation, len(chosen),
                         math.sqrt(float(residual @ residual) / len(residual)), math.degrees(angle), fixation, sense)


def _sense(model: _Model, elevation: float, omega: float) -> float:
    """+1 or -1: the sign of omega, with the elevation positive, under which the orthographic
    model fits the tracks better. Seen from above, a turn one way and the other trace the same
    ellipses in opposite directions; the pair with both signs flipped fits orthographically alike
    (a view from below turning the other way), so the fits start from both members of the better
    class only."""
    costs = []
    for sign in (1.0, -1.0):
        start = np.r_[0.0, elevation, sign * omega, model.angle_rad, 0.0, model.linear_start(elevation, sign * omega)]
        residual = model.residuals(start)
        costs.append(float(residual @ residual))
    return 1.0 if costs[0] <= costs[1] else -1.0


def _trim(chosen: list[tuple[np.ndarray, np.ndarray, np.ndarray]], keep: np.ndarray,
          owner: np.ndarray) -> tuple[list[tuple[np.ndarray, np.ndarray, np.ndarray]], np.ndarray]:
    """The tracks with only their ``keep`` samples, those left with at least 6; and which
    tracks those are."""
    bounds = np.r_[0, np.cumsum(np.bincount(owner, minlength=len(chosen)))]
    trimmed, kept = [], np.zeros(len(chosen), bool)
    for k, (time_s, x, y) in enumerate(chosen):
        mask = keep[bounds[k]:bounds[k + 1]]
        if mask.sum() >= 6:
            trimmed.append((time_s[mask], x[mask], y[mask]))
            kept[k] = True
    return trimmed, kept


def _fit(model: _Model, params: np.ndarray, loss: str):
    """One sparse least-squares fit of ``model`` from ``params``; the inverse focal length is
    bounded below by 0, nothing else is bounded. ``loss``: ``soft_l1`` (1 px scale) or ``linear``."""
    from scipy.optimize import least_squares  # imported here: it weighs on every run's start otherwise

    lower = np.full(len(params), -np.inf)
    lower[0] = 0.0
    return least_squares(model.residuals, params, jac=model.jacobian, bounds=(lower, np.inf),
                         loss=loss, f_scale=1.0, x_scale="jac", max_nfev=60)


def _shared_standard_errors(jacobian, owner: np.ndarray, sigma2: float) -> np.ndarray:
    """Standard errors of the three shared unknowns, with the per-track unknowns eliminated
    (Schur complement, track by track): ``owner`` gives each residual's track."""
    jacobian = jacobian.tocsr() if hasattr(jacobian, "tocsr") else np.asarray(jacobian)
    shared = (np.asarray(jacobian[:, :SHARED].todense()) if hasattr(jacobian, "todense")
              else jacobian[:, :SHARED])
    reduced = shared.T @ shared
    bounds = np.r_[0, np.flatnonzero(np.diff(owner)) + 1, len(owner)]
    for k in range(len(bounds) - 1):
        rows = slice(bounds[k], bounds[k + 1])
        block = jacobian[rows, SHARED + 3 * k:SHARED + 3 + 3 * k]
        b = np.asarray(block.todense()) if hasattr(block, "todense") else block
        s = shared[rows]
        normal_ll = b.T @ b
        cross = s.T @ b
        try:
            reduced -= cross @ np.linalg.solve(normal_ll, cross.T)
        except np.linalg.LinAlgError:
            continue
    try:
        covariance = np.linalg.inv(reduced) * sigma2
    except np.linalg.LinAlgError:
        return np.full(SHARED, math.inf)
    return np.sqrt(np.clip(np.diag(covariance), 0.0, None))
