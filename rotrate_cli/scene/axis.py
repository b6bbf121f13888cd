"""The rotation axis in the image, found from the tracks: its direction and its position.

Direction. Under orthographic projection every point of a body spinning about an axis moves
along a line perpendicular to the axis's image (under perspective, along a flat ellipse), so the
dominant direction of all frame-to-frame displacements is the direction in which offsets are
measured, and the axis is perpendicular to it. Seen from above, points move on ellipses instead,
and the steps' direction leans with which part of each ellipse was seen; :func:`path_shape`
fits each track's ellipse at a known rate and takes their long axes (and, from their width, the
camera's elevation). Angles follow :func:`unit_offset`: 0 is a vertical axis, positive leans the
axis's top end to the right (a camera rolled anticlockwise).

Position. The paper's appendix: with the axis at an unknown offset ``o`` along that direction,
every point obeys ``s'' = -omega^2 (s - o)``. Its exact discrete form at a lag of ``m`` frames,
``s[k+m] + s[k-m] = kappa s[k] + beta`` with ``kappa = 2 cos(omega m dt)`` and
``beta = (2 - kappa) o``, is linear, so one robust regression over the triples of all tracks
gives ``o`` without knowing omega. Once omega is known, ``o`` is refined by the joint least
squares of all tracks, each ``s = o + A cos(wt) + B sin(wt)`` with its own ``A, B`` and one
shared ``o`` (closed form).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rotrate_cli.fitting.camera import Camera
from rotrate_cli.fitting.estimators import solve_two_columns
from rotrate_cli.fitting.ragged import Ragged
from rotrate_cli.fitting.stats import weighted_median
from rotrate_cli.runtime.lazy import pandas as pd
from rotrate_cli.scene.view import fit_ellipses

#: Triples needed for a regression at one lag, and the largest rotation per lag used (rad):
#: beyond it the regression's slope saturates.
_MIN_TRIPLES = 30
_MAX_TURN_RAD = 1.2
#: At most this many triples (evenly spread) enter each lag's regression: its two coefficients
#: are settled long before, and a long clip has millions.
_MAX_TRIPLES = 20_000
#: A lag whose triples are fewer than this share of the first lag's comes from the few tracks
#: that last longest, not from the body: on a 720p cylinder the 121 triples at a lag of 32 frames
#: (0.2% of the first lag's, all on one side of the axis) put the axis 100 px off, and the joint
#: refinement stopped 10 px short of it (omega -5%).
_MIN_TRIPLE_SHARE = 0.05
#: The lag used is the longest whose standard error is within this factor of the smallest (see
#: :func:`_recurrence`).
_SE_WITHIN = 2.0


@dataclass(frozen=True)
class Axis:
    """The rotation axis's image.

    Attributes:
        angle_deg: 0 vertical; positive leans the top end right (see the module docstring).
        fixation_px: a point on the axis (x, y in pixels): where the tracked points' mid-height
            meets it when found, or the point the user gave.
        found: True when estimated from the tracks, False when given.
    """

    angle_deg: float
    fixation_px: tuple[float, float]
    found: bool = True


def unit_offset(angle_deg: float) -> tuple[float, float]:
    """The image direction (x, y with y down) in which offsets from an axis at ``angle_deg``
    are measured: to the right for a vertical axis, downwards for ``angle_deg = 90``."""
    angle = math.radians(angle_deg)
    return math.cos(angle), math.sin(angle)


def offsets_along(tracks: pd.DataFrame, fixation_px: tuple[float, float], angle_deg: float) -> np.ndarray:
    """Each sample's signed distance from the axis, perpendicular to it, in pixels."""
    ux, uy = unit_offset(angle_deg)
    # in place: a long clip's positions are large, and this runs on all of them
    offset = tracks["x_px"].to_numpy(dtype=np.float64, copy=True)
    offset -= fixation_px[0]
    offset *= ux
    if uy != 0.0:
        across = tracks["y_px"].to_numpy(dtype=np.float64, copy=True)
        across -= fixation_px[1]
        across *= uy
        offset += across
    return offset


def _step_scatter(tracks: pd.DataFrame) -> np.ndarray | None:
    """The 2x2 scatter of the tracks' frame-to-frame steps; None when nothing moves."""
    same = (tracks["track"].to_numpy()[1:] == tracks["track"].to_numpy()[:-1])
    dx = np.diff(tracks["x_px"].to_numpy(dtype=np.float64))[same]
    dy = np.diff(tracks["y_px"].to_numpy(dtype=np.float64))[same]
    if len(dx) == 0 or not (np.abs(dx).sum() + np.abs(dy).sum()) > 0:
        return None
    return np.array([[dx @ dx, dx @ dy], [dx @ dy, dy @ dy]])


def steps_spread(tracks: pd.DataFrame) -> float:
    """How far the tracks' steps spread across their main direction: the ratio of the steps'
    scatter across it to that along it (NaN when nothing moves). Seen from the side, points
    swing to and fro along one line (near 0); seen from an elevation ``e``, around ellipses
    whose width is ``sin e`` of their length: up to ``sin(e)^2``, less where the tracks cover
    only the front of their ellipses (measured: 0.002 on the side-view bench clip, 0.13-0.17 on
    renders and the dinosaur from 25-27 degrees above, 0.45 from 45)."""
    scatter = _step_scatter(tracks)
    if scatter is None:
        return math.nan
    values = np.linalg.eigvalsh(scatter)
    return float(values[0] / values[1]) if values[1] > 0 else math.nan


def motion_angle_deg(tracks: pd.DataFrame) -> float:
    """The axis angle implied by the tracks' motion (NaN when nothing moves).

    ``tracks``: ``track, frame, x_px, y_px``, sorted by track then frame. The principal
    direction of the frame-to-frame displacements is the offset direction.
    """
    scatter = _step_scatter(tracks)
    if scatter is None:
        return math.nan
    values, vectors = np.linalg.eigh(scatter)
    mx, my = vectors[:, int(np.argmax(values))]
    angle = math.degrees(math.atan2(my, mx))
    # the offset direction is defined up to its sign: fold into (-90, 90]
    if angle <= -90:
        angle += 180
    elif angle > 90:
        angle -= 180
    return angle


def _triples(track: np.ndarray, frame: np.ndarray, position: np.ndarray, lag: int) -> tuple[np.ndarray, np.ndarray]:
    """``(s[k], s[k+lag] + s[k-lag])`` for every sample with both neighbours ``lag`` frames away
    on the same track (rows sorted by track then frame, one row per frame)."""
    n = len(position)
    if n <= 2 * lag:
        return np.empty(0), np.empty(0)
    centre = np.arange(lag, n - lag)
    ok = (track[centre - lag] == track[centre]) & (track[centre + lag] == track[centre]) \
        & (frame[centre + lag] - frame[centre] == lag) & (frame[centre] - frame[centre - lag] == lag)
    centre = centre[ok]
    return position[centre], position[centre + lag] + position[centre - lag]


def _robust_line(x: np.ndarray, y: np.ndarray) -> tuple[float, float, np.ndarray]:
    """Slope and intercept of ``y = kappa x + beta`` by Huber-weighted least squares, and their
    2x2 covariance (the residuals' robust scale squared over the weighted normal matrix)."""
    weight = np.ones_like(x)
    kappa = beta = math.nan
    scale = 0.0
    design = np.column_stack([x, np.ones_like(x)])
    for _ in range(6):
        weighted = design * weight[:, None]
        solution, *_ = np.linalg.lstsq(weighted, y * weight, rcond=None)
        kappa, beta = float(solution[0]), float(solution[1])
        residual = y - kappa * x - beta
        scale = 1.4826 * float(np.median(np.abs(residual - np.median(residual)))) + 1e-12
        weight = np.sqrt(np.minimum(1.0, 1.5 * scale / np.maximum(np.abs(residual), 1e-12)))
    weighted = design * weight[:, None]
    normal = weighted.T @ weighted
    covariance = scale ** 2 * np.linalg.pinv(normal)
    return kappa, beta, covariance


@dataclass(frozen=True)
class _Lag:
    """One lag's regression of the recurrence: ``s[k+lag] + s[k-lag] = kappa s[k] + beta``."""

    lag: int
    kappa: float
    beta: float
    covariance: np.ndarray  # of (kappa, beta)

    @property
    def offset(self) -> float:
        return self.beta / (2.0 - self.kappa)

    def offset_se(self) -> float:
        """The axis offset's standard error, ``beta / (2 - kappa)`` by the delta method."""
        gradient = np.array([self.offset, 1.0]) / (2.0 - self.kappa)
        return math.sqrt(max(0.0, float(gradient @ self.covariance @ gradient)))

    def rate_per_frame(self) -> float:
        return math.acos(min(1.0, max(-1.0, self.kappa / 2.0))) / self.lag

    def rate_relative_se(self) -> float:
        """The rate's standard error over the rate (``kappa = 2 cos(omega lag)``)."""
        turn = self.rate_per_frame() * self.lag
        return math.sqrt(max(0.0, float(self.covariance[0, 0]))) / (2.0 * math.sin(turn) * turn)


def _recurrence(tracks: pd.DataFrame, position: np.ndarray, wanted: str) -> _Lag | None:
    """The lag of the discrete recurrence pooled over all tracks that measures the ``wanted``
    quantity (``"offset"`` or ``"rate"``): the longest whose standard error is within
    :data:`_SE_WITHIN` times the smallest; None when the motion is too small to tell.

    Longer lags turn more per lag, so their slope tells more, and through a lens they are the
    least biased (the recurrence is exact for a sinusoid only: a box through a 75 degree lens
    read the axis 43-48 px off at the first three lags, 20 px at the fourth). But only the
    tracks that last longest reach them, and a few tracks that are not the body's can make up
    a long lag: on a real car's glossy paint, the hall's reflections barely move and last
    longest. The first 70 photographs of EPFL car 02 read the axis within 20 px and the rate
    within 8% at the first three lags (standard errors 4-9 px), 900 px off at a third of the rate
    at the fourth (1,500 px), and 150 px off at the fifth (200 px), which was used: the rate
    came out 53% low. A lag whose tracks disagree among themselves, or barely turn, measures
    little, and its standard error says so."""
    track = tracks["track"].to_numpy()
    frame = tracks["frame"].to_numpy()
    found: list[tuple[_Lag, float]] = []
    lag = 1
    first_count = 0
    while True:
        x, y = _triples(track, frame, position, lag)
        first_count = first_count or len(x)
        if len(x) < max(_MIN_TRIPLES, _MIN_TRIPLE_SHARE * first_count):
            break
        if len(x) > _MAX_TRIPLES:
            step = len(x) / _MAX_TRIPLES
            pick = (np.arange(_MAX_TRIPLES) * step).astype(np.int64)
            x, y = x[pick], y[pick]
        kappa, beta, covariance = _robust_line(x, y)
        if not (2 * math.cos(_MAX_TURN_RAD) < kappa < 2.0):
            if kappa <= 2 * math.cos(_MAX_TURN_RAD):
                break  # turned too far per lag: longer lags only get worse
            lag *= 2
            continue
        regression = _Lag(lag, kappa, beta, covariance)
        se = regression.offset_se() if wanted == "offset" else regression.rate_relative_se()
        found.append((regression, se if math.isfinite(se) else math.inf))
        lag *= 2
    if not found:
        return None
    least = min(se for _, se in found)
    return [regression for regression, se in found if se <= _SE_WITHIN * least][-1]


def axis_offset_from_recurrence(tracks: pd.DataFrame, position: np.ndarray) -> float:
    """The axis's position along the offset direction (same units as ``position``), from the
    discrete recurrence pooled over all tracks; NaN when the motion is too small to tell.

    ``tracks`` gives ``track`` and ``frame`` per row (sorted by track then frame); ``position``
    is each row's coordinate along the offset direction.
    """
    found = _recurrence(tracks, position, "offset")
    return math.nan if found is None else found.offset


def rate_from_recurrence(tracks: pd.DataFrame, position: np.ndarray) -> float:
    """A first estimate of the rotation rate (rad/s, magnitude) from the same recurrence:
    ``kappa = 2 cos(omega lag dt)``; NaN when the motion is too small to tell. ``tracks`` also
    needs ``time_s`` (the frame interval is the median over consecutive samples)."""
    found = _recurrence(tracks, position, "rate")
    if found is None:
        return math.nan
    track = tracks["track"].to_numpy()
    same = track[1:] == track[:-1]
    steps = np.diff(tracks["frame"].to_numpy())[same]
    seconds = np.diff(tracks["time_s"].to_numpy(dtype=np.float64))[same]
    usable = steps > 0
    if not usable.any():
        return math.nan
    frame_s = float(np.median(seconds[usable] / steps[usable]))
    return found.rate_per_frame() / frame_s if frame_s > 0 else math.nan


@dataclass(frozen=True)
class PathShape:
    """What the shapes of the tracks' elliptical paths say about the camera (see :func:`path_shape`).

    Attributes:
        angle_deg: the axis's angle in the image (as :func:`motion_angle_deg`).
        elevation_deg: how far the camera looks down on (or up at) the object, degrees (0 for a
            level camera): the arcsine of the paths' width over their length. Its sign is not
            told.
        tracks: the tracks that turned enough to say.
    """

    angle_deg: float
    elevation_deg: float
    tracks: int


def path_shape(tracks: pd.DataFrame, omega_rad_s: float, min_turn_rad: float = 0.3,
               min_tracks: int = 10) -> PathShape | None:
    """The axis angle (and the camera's elevation) from the shape of the tracks' paths at a
    known rate; None when fewer than ``min_tracks`` tracks turn through ``min_turn_rad`` or more.

    A point turning about the axis moves on an ellipse, ``p(t) = c + A cos(wt) + B sin(wt)``,
    whose long axis is perpendicular to the axis's image whatever the camera's elevation (the
    short axis, along the axis, is the radius times the sine of the elevation). With ``w``
    known each track's ``c, A, B`` are linear least squares; the long axis is the principal
    direction of ``A A^T + B B^T``, and the angle is the median over tracks, weighted by how
    much longer than wide each path is. Unlike the principal direction of all the steps
    (:func:`motion_angle_deg`), it does not depend on which part of each ellipse was seen: seen
    from above, the tracks cover the near half of their ellipses, and unevenly, which leaned
    that direction by 3 degrees on a rendered box seen from 25 degrees above, 10 on a cylinder
    from 30, and 2.8 on the dinosaur photographs (their axis leans 1.2 degrees; this gives 1.4).

    ``tracks``: ``track, time_s, x_px, y_px``, sorted by track then time.
    """
    if not (math.isfinite(omega_rad_s) and omega_rad_s > 0):
        return None
    fit = fit_ellipses(tracks, omega_rad_s, min_turn_rad)
    usable = fit.usable
    if int(usable.sum()) < min_tracks:
        return None
    coef = fit.coef[usable]  # tracks x (1, cos, sin) x (x, y)
    a, b = coef[:, 1, :], coef[:, 2, :]
    shape = a[:, :, None] * a[:, None, :] + b[:, :, None] * b[:, None, :]
    values, vectors = np.linalg.eigh(shape)
    major = vectors[:, :, 1]
    weight = values[:, 1] - values[:, 0]
    angle = np.degrees(np.arctan2(major[:, 1], major[:, 0]))
    angle = (angle + 90.0) % 180.0 - 90.0  # the long axis has no sign: fold into [-90, 90)
    # a median on the circle of directions: centre the folding on the weighted mean direction
    doubled = np.radians(2 * angle)
    centre = math.degrees(math.atan2(float(weight @ np.sin(doubled)), float(weight @ np.cos(doubled)))) / 2
    angle = (angle - centre + 90.0) % 180.0 - 90.0 + centre
    median = weighted_median(angle, weight)
    median = (median + 90.0) % 180.0 - 90.0
    width = np.sqrt(np.clip(values[:, 0], 0.0, None) / np.maximum(values[:, 1], 1e-300))
    elevation = math.degrees(math.asin(min(1.0, weighted_median(width, weight))))
    return PathShape(median, elevation, int(usable.sum()))



def refine_axis_offset(samples: pd.DataFrame, omega_rad_s: float, camera: Camera | None = None,
                       alpha_rad_s2: float = 0.0, t0_s: float = 0.0) -> float:
    """The shared axis offset that, with each track's own amplitude and phase, best explains
    ``samples`` (``track, time_s, offset_px`` sorted by track then time) turning at
    ``omega_rad_s`` at time ``t0_s`` and speeding up by ``alpha_rad_s2`` (0: steady): the
    correction to add to the fixation's position along the offset direction.

    Per track, with ``P`` the projection on its two columns, the least squares of
    ``offset - o ~ a first + b second`` over a shared ``o`` is
    ``o = sum 1.(I - P) offset / sum 1.(I - P) 1``. Orthographic, the columns are
    ``cos(wt), sin(wt)``. With a pinhole ``camera`` (offsets from the fixation the camera was
    made for; ``omega_rad_s`` signed, as the fits' sense), the model
    ``x (1 - k Z) = axis_n + L`` in normalised coordinates (see :func:`rotrate_cli.fitting.estimators._pinhole`)
    is ``offset / f - o / f = a (c - k x s) + b (s + k x c)``: linear in ``a, b, o`` again, with
    columns that depend on the data but not on ``o``.
    """
    numerators, denominators, scale = _axis_terms(samples, omega_rad_s, camera, alpha_rad_s2, t0_s)
    denominator = float(denominators.sum())
    if denominator <= 0:
        return math.nan
    return scale * float(numerators.sum()) / denominator


def axis_offset_se(samples: pd.DataFrame, omega_rad_s: float, camera: Camera | None = None) -> float:
    """The standard error (px) of :func:`refine_axis_offset`'s shared offset, from how the tracks
    disagree about it: the offset is a ratio of sums over tracks, and its variance is the
    jackknife one over tracks (each left out in turn), which holds whatever each track's own
    misfit (a window sliding on a real surface, a perspective the model leaves out) rather than
    assuming the samples' errors independent, and weighs the tracks that carry most of the
    offset as they deserve. NaN with fewer than 3 tracks."""
    numerators, denominators, scale = _axis_terms(samples, omega_rad_s, camera, 0.0, 0.0)
    count = len(numerators)
    total_n, total_d = float(numerators.sum()), float(denominators.sum())
    rest = total_d - denominators
    if count < 3 or total_d <= 0 or (rest <= 0).any():
        return math.nan
    left_out = (total_n - numerators) / rest
    return scale * math.sqrt((count - 1) / count * float(((left_out - left_out.mean()) ** 2).sum()))


def _axis_terms(samples: pd.DataFrame, omega_rad_s: float, camera: Camera | None, alpha_rad_s2: float,
                t0_s: float) -> tuple[np.ndarray, np.ndarray, float]:
    """Per track, ``1.(I - P) offset`` and ``1.(I - P) 1`` of :func:`refine_axis_offset`'s
    closed form (offsets divided by the returned scale: the focal length with a pinhole camera,
    else 1); empty arrays where there is nothing to fit."""
    tracks = Ragged.from_samples(samples)
    if len(tracks) == 0 or not (math.isfinite(omega_rad_s) and math.isfinite(alpha_rad_s2)):
        return np.empty(0), np.empty(0), 1.0
    # a steady rate, or one changing steadily (a spin-up): the turn's angle at each time
    elapsed = tracks.times_s - t0_s
    angle = omega_rad_s * elapsed + 0.5 * alpha_rad_s2 * elapsed ** 2
    c, s_ = np.cos(angle)[tracks.time_index], np.sin(angle)[tracks.time_index]
    y = tracks.offset
    scale = 1.0
    if camera is not None:
        scale = camera.focal_px
        y = y / scale
        x = (y + camera.axis_n) * camera.depth_scale
        c, s_ = c - x * s_, s_ + x * c
    sums = tracks.sums
    cc, ss, cs, sum_c, sum_s = sums(c * c), sums(s_ * s_), sums(c * s_), sums(c), sums(s_)

    def unexplained_dot_one(sum_v: np.ndarray, sum_cv: np.ndarray, sum_sv: np.ndarray) -> np.ndarray:
        """Per track, ``1.(I - P) v`` from the sums of ``v``, ``c v`` and ``s v``."""
        a, b = solve_two_columns(cc, ss, cs, sum_cv, sum_sv)
        return sum_v - a * sum_c - b * sum_s

    denominators = unexplained_dot_one(tracks.counts.astype(float), sum_c, sum_s)
    numerators = unexplained_dot_one(sums(y), sums(c * y), sums(s_ * y))
    return np.asarray(numerators, dtype=np.float64), np.asarray(denominators, dtype=np.float64), scale


def point_on_axis(offset_px: float, angle_deg: float, tracks: pd.DataFrame) -> tuple[float, float]:
    """The point of the axis at ``offset_px`` (along the offset direction from the image origin)
    level with the tracked points' median position along the axis."""
    ux, uy = unit_offset(angle_deg)
    along = float(np.median(-tracks["x_px"].to_numpy() * uy + tracks["y_px"].to_numpy() * ux))
    return offset_px * ux - along * uy, offset_px * uy + along * ux
