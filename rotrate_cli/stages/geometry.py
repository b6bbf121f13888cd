"""The geometry stage: camera, axis and view of one body, as one typed result (:class:`Geometry`).

In two steps, so that the caller can let a long clip's tracks table go between them:

1. :func:`locate`: the axis's angle (given, from the tracks' motion or from their paths' shape),
   the camera (:mod:`rotrate_cli.stages.camera`: given, EXIF, found or orthographic) and a first
   fixation point (given, or found from the tracks' recurrence); the body's offsets from it.
2. :func:`measure`: the body's rates (:mod:`rotrate_cli.stages.fits`) with a found fixation refined
   to the shared axis the inlier tracks turn about (with the turn speeding up where the rate
   changes). A given fixation is checked against it by the checks stage
   (:func:`rotrate_cli.stages.checks.fixation_doubt`).

The view at the reported rate is read after the verdict (:mod:`rotrate_cli.stages.view_at_rate`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from rotrate_cli.config import AnalysisConfig
from rotrate_cli.errors import NoResultError
from rotrate_cli.fitting.camera import Camera
from rotrate_cli.fitting.outliers import Combined
from rotrate_cli.runtime.lazy import pandas as pd
from rotrate_cli.runtime.memory import release_free_memory
from rotrate_cli.scene import axis as axes
from rotrate_cli.scene.view import View
from rotrate_cli.stages.camera import Lens, camera_at, find_lens, lens_from
from rotrate_cli.stages.fits import (
    SENSES,
    RateResult,
    changes,
    decided_sense,
    half_rates,
    rates_from_offsets,
    rejoined,
    thin,
    told_sense,
    with_sense,
)
from rotrate_cli.stages.tracks import MIN_TRACKS_FOR_ANGLE
from rotrate_cli.tracking.keyframes import Keyframes
from rotrate_cli.video.frames import VideoInfo

#: An axis moved for a spin-up is kept only where at least this fraction of the inlier tracks
#: still agree about it. Halves of a short clip can differ by their own bias: a steady cylinder
#: turned 34 degrees through a 60-degree lens read 0.28 and 0.21 rad/s (truth 0.2), and the move
#: took the axis 148 px off, outside the body, keeping 95 of 241 tracks (-18%, the sense
#: reversed). Real spin-ups (rendered box and cylinder, 0.35 + 0.12 t rad/s) keep 83% and 100%.
SPIN_UP_KEEPS = 0.5

#: Seen from this many degrees above (or below) or more, as the tracks' paths tell it, the default
#: reads the axis's angle from the paths rather than from their motion (``angle_from="auto"``).
LOOKS_DOWN_DEG = 15.0
#: The paths are read where the steps spread across their main direction by this much or more
#: (:func:`rotrate_cli.scene.axis.steps_spread`): about ``sin(elevation)^2`` where tracks cover whole
#: near halves, less where they cover short arcs near the front (0.028 and 0.046 on such tracks
#: seen from 15 and 20 degrees above, 0.13 on a render from 25). Side views spread 0.002-0.004
#: (the 720p bench clip, an EPFL car), the EPFL cars from a few degrees above up to 0.053.
LOOKS_DOWN_SPREAD = 0.03

#: How the axis's angle was had (``Geometry.angle_from``): given (``--axis-angle``), from the
#: tracks' motion or their paths' shape, with the lens found from the tracks (:mod:`rotrate_cli.scene.focal`),
#: or assumed vertical (too few tracks to tell).
ANGLE_FROM = ("given", "motion", "paths", "lens", "assumed")


@dataclass(frozen=True)
class AxisSpread:
    """How well a found axis is placed across itself, and what that does to the rate.

    Attributes:
        se_px: the standard error of the axis point across the axis, pixels
            (:func:`rotrate_cli.scene.axis.axis_offset_se`: from how the inlier tracks disagree).
        rate_per_px: how much the rate moves when the axis point moves one pixel across the
            axis, rad/s per px (measured, about the point moved by a standard error).
        coupling: how much the axis's place follows the rate, times how much the rate follows
            the axis's place: the shared-axis least squares' move per rad/s of the rate (px per
            rad/s) times ``rate_per_px``. The two are found together, each from the other (see
            :func:`_refine_fixation`), so an error in either comes back through the other: the
            rate's error is ``1 / (1 - coupling)`` times what the axis's placement and the
            tracks' scatter give alone (:attr:`gain`). Near 0 where the tracks' paths pin the
            axis whatever the rate (a turn or more), towards 1 on short arcs, where a rate a
            little off and an axis a little aside fit the same paths.
    """

    se_px: float
    rate_per_px: float
    coupling: float = 0.0

    @property
    def rate_se_rad_s(self) -> float:
        """The rate's standard error from the axis's placement alone."""
        return abs(self.rate_per_px) * self.se_px

    @property
    def gain(self) -> float:
        """What the coupling of the axis's place and the rate multiplies the rate's error by:
        ``1 / (1 - coupling)``, at least 1 and at most :data:`MAX_COUPLING_GAIN` (at a coupling
        of 1 or more the two are not told apart by the tracks at all, and the linear reading
        of their errors no longer holds)."""
        if not (math.isfinite(self.coupling) and self.coupling > 0):
            return 1.0
        return 1.0 / max(1.0 - self.coupling, 1.0 / MAX_COUPLING_GAIN)


@dataclass(frozen=True)
class Geometry:
    """Camera, axis and view of one body.

    Attributes:
        axis_angle_deg: the axis's angle in the image (0 vertical, positive: top end right).
        angle_from: how it was had (see :data:`ANGLE_FROM`).
        fixation_px: a point on the axis (x, y), pixels; it may lie outside the frame.
        fixation_found: True when it was found from the tracks rather than given.
        lens: the camera model (:class:`rotrate_cli.stages.camera.Lens`) and where it came from.
        elevation_deg: the camera's elevation as the tracks tell it (the paths' shape, or the
            found lens); NaN where they were not asked.
        view: the view read from the tracks' paths at the reported rate (the axis's elevation
            out of the image plane, 0 side to 90 frontal; the turning centre); None until
            :func:`rotrate_cli.stages.view_at_rate.view_at_rate`, and where too few tracks follow a
            turning path to tell.
        notes: what the user should know about how these were found.
        axis_spread: how well a found fixation is placed across the axis and what that does to
            the tracks' rate (:func:`measure`); None where it was given, or the rate is the clip's
            repetition (which needs no axis).
        halves: the rates of the clip's halves measured about the found fixation, by
            :func:`rotrate_cli.stages.fits.half_rates` (:func:`measure` asks them whether the
            rate changes: the checks need not measure them again); None where not measured.
    """

    axis_angle_deg: float
    angle_from: str
    fixation_px: tuple[float, float]
    fixation_found: bool
    lens: Lens
    elevation_deg: float = math.nan
    view: View | None = None
    notes: tuple[str, ...] = ()
    axis_spread: AxisSpread | None = None
    halves: tuple[Combined, Combined, float, float] | None = None

    def camera(self, size_px: tuple[int, int]) -> Camera | None:
        """The pinhole camera about the fixation point, or None (orthographic)."""
        return camera_at(self.lens, size_px, self.fixation_px, self.axis_angle_deg)


@dataclass(frozen=True)
class PreparedBody:
    """One body's tracks reduced to what the rate stages need (see :func:`locate`).

    Attributes:
        base: ``track, frame, time_s`` per sample (tracks numbered from 1).
        offsets_px: each sample's offset from the first fixation point.
        positions: ``x_px, y_px`` per sample while the fixation may still be refined, else None.
    """

    base: pd.DataFrame
    offsets_px: np.ndarray
    positions: pd.DataFrame | None

    def offsets(self, offset_px: np.ndarray) -> pd.DataFrame:
        """``track, frame, time_s, offset_px`` per sample, over the base's own arrays: not a
        copy of them, as ``base.assign`` would make (4 MB on the 32-s 720p bench clip)."""
        columns = {name: self.base[name].to_numpy() for name in self.base.columns}
        return pd.DataFrame(dict(columns, offset_px=offset_px), copy=False)


def axis_angle(tracks: pd.DataFrame, motion_angle_deg: float,
               config: AnalysisConfig) -> tuple[float, str, float, tuple[str, ...]]:
    """The axis's angle, how it was had, the camera's elevation where the paths' shape tells it
    (NaN otherwise), and notes."""
    if config.axis_angle_deg is not None:
        return float(config.axis_angle_deg), "given", math.nan, ()
    if not math.isfinite(motion_angle_deg):  # a few points' wobble says little about the axis
        return 0.0, "assumed", math.nan, ("too few tracks to find the axis's angle: taken as vertical "
                                          "(give `axis_angle_deg`)",)
    if config.angle_from == "paths":
        shape = path_shape(tracks, motion_angle_deg)
        if shape is not None:
            return shape.angle_deg, "paths", shape.elevation_deg, ()
        return motion_angle_deg, "motion", math.nan, ("too few tracks turned far enough to read the axis from "
                                                      "their paths: it is found from the motion",)
    if config.angle_from == "auto" and not config.segment and looks_down(tracks):
        shape = path_shape(tracks, motion_angle_deg)
        if shape is not None and shape.elevation_deg >= LOOKS_DOWN_DEG:
            return shape.angle_deg, "paths", shape.elevation_deg, ()
    return motion_angle_deg, "motion", math.nan, ()


def looks_down(tracks: pd.DataFrame) -> bool:
    """True when the tracks' steps spread across their main direction as they do seen from
    above (:data:`LOOKS_DOWN_SPREAD`). There the principal direction of the steps leans (the
    tracks cover the near halves of their ellipses, unevenly): on renders from 45 and 70 degrees
    above, by 3.7 and 18 degrees, against 1.0 and 10 from the paths; on the dinosaur photographs
    -4.0 against the paths' -1.4 (its axis: -1.18). Seen from the side the paths add nothing and
    cost time (0.06 s on the 720p bench clip), so they are read only here."""
    spread = axes.steps_spread(tracks)
    return math.isfinite(spread) and spread >= LOOKS_DOWN_SPREAD


def locate(tracks: pd.DataFrame, motion_angle_deg: float, config: AnalysisConfig, info: VideoInfo,
           seek_lens: bool | Callable[[], bool], keyframes: Keyframes | None = None) -> tuple[Geometry, PreparedBody]:
    """Step 1 (see the module's notes). ``tracks``: ``frame, time_s, track, x_px, y_px`` of one
    body, sorted by track then frame; the caller may let them go afterwards. ``seek_lens``: find
    the lens from the tracks where none is given or read (it costs seconds at 720p, and a rate
    from the clip's repetition needs no camera), or a function that says so, asked once the axis
    is found (a caller may work the answer out meanwhile); ``keyframes``: the tracker's images
    kept, on which the lens's fit places its samples again.

    Raises:
        NoResultError: the axis cannot be found from the tracks.
    """
    angle, angle_from, elevation, notes = axis_angle(tracks, motion_angle_deg, config)
    lens = lens_from(config, info)  # its elevation given, or NaN
    paths_elevation = elevation if angle_from == "paths" else math.nan
    fixation = _first_fixation(tracks, angle, config)
    size_px = (info.width_px, info.height_px)
    if (lens.source == "orthographic" and config.find_focal and config.method == "fit" and not config.points_px
            and (seek_lens() if callable(seek_lens) else seek_lens)):
        # the paths' elevation reads their ellipses as seen from far away: it only starts the lens's
        # fit, which finds the elevation with the perspective
        lens = find_lens(tracks, fixation, angle, lens, size_px, paths_elevation, keyframes)
        if lens.estimate is not None and math.isfinite(lens.estimate.focal_px):
            elevation = lens.estimate.elevation_deg
            if config.axis_angle_deg is None and config.angle_from == "auto":
                # the lens's fit reads the axis's angle with the perspective (seen from 60 degrees
                # above through 35-65 degree lenses, renders' paths leaned 7 and 5 degrees, the
                # lens's fit 0.2 and 0.0)
                angle, angle_from = lens.estimate.axis_angle_deg, "lens"
    if not math.isfinite(lens.elevation_deg):
        lens = replace(lens, elevation_deg=paths_elevation)
    geometry = Geometry(angle, angle_from, fixation, config.fixation_px is None, lens, elevation, notes=notes)
    return geometry, prepare_body(tracks, angle, fixation, config)


def _first_fixation(tracks: pd.DataFrame, angle: float, config: AnalysisConfig) -> tuple[float, float]:
    if config.fixation_px is not None:
        return float(config.fixation_px[0]), float(config.fixation_px[1])
    found = axes.axis_offset_from_recurrence(tracks, axes.offsets_along(tracks, (0.0, 0.0), angle))
    if not math.isfinite(found):
        raise NoResultError("could not find the rotation axis from the motion (too little of a turn); "
                            "give `fixation_px` (X,Y)")
    return axes.point_on_axis(found, angle, tracks)


def prepare_body(tracks: pd.DataFrame, angle: float, fixation: tuple[float, float],
                 config: AnalysisConfig) -> PreparedBody:
    """The offsets from ``fixation`` of one body's tracks (``frame, time_s, track, x_px, y_px``
    sorted by track then frame), thinned to ``config.every``. Nothing here refers to ``tracks``
    afterwards."""
    thinned = thin(tracks, config.every or 1)
    base = pd.DataFrame({
        "track": thinned["track"].to_numpy() + 1,  # features are numbered from 1, as in the paper
        "frame": thinned["frame"].to_numpy(),
        "time_s": thinned["time_s"].to_numpy(),
    }, copy=False)
    # positions are kept only while the fixation may still move: keep the peak low
    positions = thinned[["x_px", "y_px"]] if config.fixation_px is None else None
    return PreparedBody(base, axes.offsets_along(thinned, fixation, angle), positions)


def measure(body: PreparedBody, geometry: Geometry, config: AnalysisConfig, size_px: tuple[int, int],
            steady: bool | Callable[[], bool] = False) -> tuple[Geometry, RateResult]:
    """Step 2: the body's rates, with a found fixation refined (see the module's notes).
    ``steady``: the rate is known not to change (the clip repeats itself), so a spin-up is not
    looked for (it costs two more fits: 0.4 s of the record clip's 45,000 tracks); a callable is
    asked only after the first fit, and only where a found fixation is refined (the clip's
    repetition, worked out in another thread, is not waited for before)."""
    first = geometry.fixation_px
    angle = geometry.axis_angle_deg

    sense = 0  # the sense of rotation, once the first fit has told it

    def offsets_at(point: tuple[float, float]) -> pd.DataFrame:
        moved = body.positions is not None and point != first
        return body.offsets(axes.offsets_along(body.positions, point, angle) if moved else body.offsets_px)

    def measured(point: tuple[float, float]) -> tuple[RateResult, Camera | None]:
        offset = offsets_at(point)
        camera = camera_at(geometry.lens, size_px, point, angle)
        # about a point moved by a pixel or so the body turns the same way: the sense the first fit
        # decided is not asked again (each fit in both senses is two of all the tracks' fits)
        result = rates_from_offsets(offset, config.method, config.rejection, with_sense(camera, sense))
        return result, camera

    result, camera = measured(first)
    sense = decided_sense(result)
    release_free_memory()
    fixation = first
    refine = geometry.fixation_found and config.method == "fit"
    known_steady = refine and (steady() if callable(steady) else steady)  # asked here, once, after the first fit
    if refine:
        # the axis is refined even where the clip's repetition gives the rate: the sense of
        # turning is the tracks' (without it, one EPFL car's sense came out wrong)
        # where the clip's repetition gives the rate, the axis gives only the sense of turning and
        # the view: two moves (the second a secant one) come within a pixel (the record clip: 0.6
        # px), and each further one costs a fit of all its tracks (45,000 on the record clip)
        fixation, result, camera = _refine_fixation(result, camera, fixation, angle, measured,
                                                    steps=STEADY_REFINE_STEPS if known_steady else REFINE_STEPS)
        change = None if known_steady else half_rates(result, config.method, config.rejection, camera)
        halves = change
        if change is not None and changes(result.combined, *change):
            # a spinning-up body: one rate for all tracks misplaces the axis; the turn's angle
            # as it speeds up (from the halves' rates) does not. Once: measuring the halves again
            # about the moved axis and moving it again diverged (rendered cylinder 2.7 -> 19 px)
            moved = _refine_fixation(result, camera, fixation, angle, measured, spin_up=change)
            if moved[1].combined.tracks_used >= SPIN_UP_KEEPS * result.combined.tracks_used:
                fixation, result, camera = moved
                halves = None  # measured about the axis before it moved
    spread = None
    if refine and not known_steady:
        measured_result = result

        def rate_at(point: tuple[float, float]) -> float:
            camera_there = camera_at(geometry.lens, size_px, point, angle)
            return rejoined(measured_result, offsets_at(point), config.rejection, camera_there)

        spread = _axis_spread(result, camera, fixation, angle, rate_at)
    else:
        halves = None
    return replace(geometry, fixation_px=(float(fixation[0]), float(fixation[1])), axis_spread=spread,
                   halves=halves), result


#: The found axis point is moved by its standard error, and at least this much (px), to measure
#: the rate's sensitivity to it.
SPREAD_STEP_PX = 0.5
#: The rate is moved by this fraction either way to measure how the axis's place follows it
#: (:attr:`AxisSpread.coupling`).
COUPLING_STEP = 0.01
#: The most the coupling of the axis's place and the rate widens the interval by (a coupling of
#: 0.9 or more: see :attr:`AxisSpread.gain`).
MAX_COUPLING_GAIN = 10.0
#: A found fixation is refined until it moves less than this (px)...
REFINE_TOLERANCE_PX = 0.02
#: ...or it has been measured this many times (:func:`_refine_fixation`).
REFINE_STEPS = 5
#: ...or, where the clip's repetition gives the rate, this many.
STEADY_REFINE_STEPS = 2


def _axis_spread(
    result: RateResult, camera: Camera | None, fixation: tuple[float, float], angle_deg: float,
    rate_at: Callable[[tuple[float, float]], float],
) -> AxisSpread | None:
    """How well the found ``fixation`` is placed across the axis (the inlier tracks' shared-axis
    least squares, its jackknife standard error over tracks) and the rate's change per pixel
    across it, measured about the point moved by that much (``rate_at``: the same tracks' rate
    about a point); None where either cannot be had (see
    :func:`rotrate_cli.stages.checks.with_axis_doubt`)."""
    offsets, omega, placing = inliers_and_rate(result, camera)
    se_px = axes.axis_offset_se(offsets, omega, placing)
    if not (math.isfinite(se_px) and math.isfinite(result.combined.omega_rad_s)):
        return None
    step = max(se_px, SPREAD_STEP_PX)
    ux, uy = axes.unit_offset(angle_deg)
    moved = rate_at((fixation[0] + step * ux, fixation[1] + step * uy))
    if not math.isfinite(moved):
        return None
    rate_per_px = (moved - result.combined.omega_rad_s) / step
    # the axis's place as the rate moves (a relative step either way of the signed rate the
    # axis is placed with, which is the reported rate times a constant sign)
    higher = axes.refine_axis_offset(offsets, omega * (1.0 + COUPLING_STEP), placing)
    lower = axes.refine_axis_offset(offsets, omega * (1.0 - COUPLING_STEP), placing)
    px_per_rate = (higher - lower) / (2.0 * COUPLING_STEP * result.combined.omega_rad_s)
    coupling = rate_per_px * px_per_rate
    return AxisSpread(se_px, rate_per_px, coupling if math.isfinite(coupling) else 0.0)


def path_shape(tracks: pd.DataFrame, angle: float) -> axes.PathShape | None:
    """The axis angle and camera elevation from the shape of the tracks' elliptical paths (see
    :func:`rotrate_cli.scene.axis.path_shape`), at a first rate from the recurrence along the
    direction of motion ``angle``, twice (on the dinosaur photographs: -4.0 degrees from the
    motion, then -1.7, then -1.4; their axis leans -1.2); None when either cannot be had."""
    shape = None
    for _ in range(2):  # the rate along a better direction is better, and so the next direction
        omega = axes.rate_from_recurrence(tracks, axes.offsets_along(tracks, (0.0, 0.0), angle))
        found = axes.path_shape(tracks, omega, min_tracks=MIN_TRACKS_FOR_ANGLE)
        if found is None:
            break
        shape = found
        angle = found.angle_deg
    return shape


def _refine_fixation(
    result: RateResult, camera: Camera | None, fixation: tuple[float, float], angle_deg: float,
    measured: Callable[[tuple[float, float]], tuple[RateResult, Camera | None]],
    spin_up: tuple[Combined, Combined, float, float] | None = None, steps: int = REFINE_STEPS,
) -> tuple[tuple[float, float], RateResult, Camera | None]:
    """Move a found fixation point to the shared-axis least squares of the inlier tracks at the
    measured rate (with ``spin_up``, the halves' rates and middle times: a rate changing
    steadily), with the pinhole model when there is a ``camera``, and measure again, until the
    point and the rate measured about it agree (the move under :data:`REFINE_TOLERANCE_PX`), in
    ``steps`` measurements at most.

    The point and the rate are each found from the other. Where the tracks' paths pin the axis
    whatever the rate (a turn or more), one move settles it. On a short arc they trade off (see
    :attr:`AxisSpread.coupling`): each move goes only part of the way, the next a like part of
    what is left, and so on. So from the second move on, the move is to where the last two say
    it ends (the root of the line through the moves found at the last two points; a secant
    step), at most :data:`MAX_COUPLING_GAIN` times the move found. Two plain moves stopped short:
    the EPFL cars' parts of a turn (five cars, 30 to 70 photographs from every 15th) kept most of
    their first axis's error, and 5 of the 15 results called good missed the truth by 2-6%
    (one car's 15th to 64th photographs: +5.6% within [+4.4%, +7.0%], its axis 7 px aside).
    Settled, that one reads -0.55%, and of the tracks' results called good none missed it (with
    the interval's gain for the coupling: :func:`rotrate_cli.stages.checks.with_axis_doubt`)."""
    ux, uy = axes.unit_offset(angle_deg)
    along = 0.0  # how far the point has moved along the offset direction
    last: tuple[float, float] | None = None  # the last point's place along it and the move found there
    for _ in range(steps):
        offsets, omega, placing = inliers_and_rate(result, camera)
        if spin_up is not None:  # the rate at the halves' middles, changing steadily between them
            early, late, early_s, late_s = spin_up
            sense = omega / result.combined.omega_rad_s if result.combined.omega_rad_s else 1.0
            alpha = (late.omega_rad_s - early.omega_rad_s) / (late_s - early_s)
            shift = axes.refine_axis_offset(offsets, early.omega_rad_s * sense, placing, alpha * sense, early_s)
        else:
            shift = axes.refine_axis_offset(offsets, omega, placing)
        if not math.isfinite(shift) or abs(shift) < REFINE_TOLERANCE_PX:
            break
        step = shift
        if last is not None and along != last[0]:
            # the move shrinks linearly as the point nears where the moves end: -1 < slope < 0
            # where each plain move goes part of the way (slope -1: all of it)
            slope = (shift - last[1]) / (along - last[0])
            if slope < 0:
                step = shift / max(-slope, 1.0 / MAX_COUPLING_GAIN)
        last = (along, shift)
        along += step
        fixation = (fixation[0] + step * ux, fixation[1] + step * uy)
        result, camera = measured(fixation)
    return fixation, result, camera


def inliers_and_rate(result: RateResult, camera: Camera | None
                      ) -> tuple[pd.DataFrame, float, Camera | None]:
    """The inlier tracks' offsets, the combined rate, and the camera to place the axis with.

    Through a pinhole ``camera`` the rate is signed as the sense of rotation (the axis
    refinement's model is signed there): the fits', else the view's, else the one the near
    side's travel shows (``result.direction``); positive otherwise. Where none tells it, the
    axis is placed orthographically: the pinhole model in the wrong sense puts it far off (the
    first 30 photographs of EPFL car 02, turning clockwise, fitted anticlockwise: 104 px to the
    wrong side of the axis, then 2,900 px and the rate 56% low; orthographically 12 px towards
    it, and the other sense 26 px)."""
    features = result.features
    inlier = features["inlier"].to_numpy(dtype=bool)
    offsets = result.offsets[result.offsets["track"].isin(features.loc[inlier, "track"])]
    omega = result.combined.omega_rad_s
    if camera is not None:
        told = told_sense(features.loc[inlier, "sense"].to_numpy(dtype=float))
        if told is not None:
            omega *= float(told) or 1.0
        elif camera.sense:
            omega *= float(camera.sense)
        elif result.direction in SENSES:  # as the near side's travel shows it (see fits.rates_from_offsets)
            omega *= float(SENSES[result.direction])
        else:
            camera = None
    return offsets, omega, camera
