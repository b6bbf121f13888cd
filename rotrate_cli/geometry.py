"""The geometry stage: the camera (given, from EXIF, or found from the tracks), the axis's angle
and the fixation point (given, or found and refined from the tracks), for one body; and the checks
of a given fixation against the axis the tracks show."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from rotrate_cli import axis as axes
from rotrate_cli import rates
from rotrate_cli.config import AnalysisConfig
from rotrate_cli.errors import NoResultError
from rotrate_cli.fits import JOINT_MIN_TRACKS, RateResult, changes, half_rates, rates_from_offsets, thin
from rotrate_cli.focal import ORTHOGRAPHIC_WIDTHS, FocalEstimate, estimate_focal
from rotrate_cli.lazy import pandas as pd
from rotrate_cli.memory import release_free_memory
from rotrate_cli.outliers import (
    Combined,
)

#: Fewer tracks than this do not find the axis's angle from their motion: it is taken as vertical.
MIN_TRACKS_FOR_ANGLE = 10


#: The found lens's inverse focal length is good to about this fraction on rendered solids, more
#: than its standard error says (the tracker's small slides near the outline bias it): found
#: 13.3, 25.0, 28.3 and 26.8 degrees for 15, 25, 30 and 20 (a sphere: -2.0% in omega, with an
#: interval of +-0.8% from the standard error alone).
LENS_FLOOR = 0.35


#: A found axis about which the tracks' interval is this many times narrower than about a given
#: fixation shows the given one to be off by more than the measurement resolves.
SHARPER = 1.5


def camera_model(config: AnalysisConfig, size_px: tuple[int, int], fixation_px: tuple[float, float],
            angle_deg: float) -> rates.Camera | None:
    """The pinhole camera (principal point at the image centre), offsets along ``angle_deg``."""
    if config.focal_px is None and config.fov_deg is None:
        return None
    width_px, height_px = size_px
    focal_px = config.focal_px if config.focal_px is not None else rates.focal_px_from_fov(config.fov_deg or 0.0,
                                                                                           width_px)
    ux, uy = axes.unit_offset(angle_deg)
    axis_px = (fixation_px[0] - (width_px / 2.0 - 0.5)) * ux + (fixation_px[1] - (height_px / 2.0 - 0.5)) * uy
    depth_scale = math.cos(math.radians(config.elevation_deg or 0.0))
    return rates.Camera(focal_px, axis_px / focal_px, depth_scale)


def with_lens_doubt(result: RateResult, focal: FocalEstimate, fixation: tuple[float, float], angle_deg: float,
                     config: AnalysisConfig, size_px: tuple[int, int]) -> RateResult:
    """The result with its interval widened to hold the rates measured through the lenses at the
    ends of the found lens's 95% interval (its inverse focal length +-1.96 standard errors, and
    at least +-:data:`LENS_FLOOR` of it; 0 is orthographic)."""
    rates_at_ends = []
    half = max(1.96 * focal.inverse_focal_se, LENS_FLOOR * focal.inverse_focal)
    lower = focal.inverse_focal - half
    if lower < 1.0 / (ORTHOGRAPHIC_WIDTHS * size_px[0]):
        lower = 0.0  # within its uncertainty of a lens called orthographic: the paper's model is as likely
    for inverse in (lower, focal.inverse_focal + half):
        lens = replace(config, focal_px=1.0 / inverse if inverse > 0 else None,
                       fov_deg=None if inverse > 0 else config.fov_deg)
        camera = camera_model(lens, size_px, fixation, angle_deg)
        rates_at_ends.append(rates_from_offsets(result.offsets, config.method, config.rejection, camera)
                             .combined.omega_rad_s)
    combined = result.combined
    low = float(np.nanmin([combined.omega_low_rad_s, *rates_at_ends]))
    high = float(np.nanmax([combined.omega_high_rad_s, *rates_at_ends]))
    return replace(result, combined=Combined(combined.omega_rad_s, low, high, combined.tracks_used))


def find_focal(everything: pd.DataFrame, body: PreparedBody, angle: float, config: AnalysisConfig,
                size_px: tuple[int, int]) -> tuple[AnalysisConfig, FocalEstimate | None]:
    """The focal length (and elevation) from the tracks, put into the configuration as if
    given; orthographic when no perspective shows, or when too few tracks turn far enough to
    tell (the estimate is then None)."""
    omega = axes.rate_from_recurrence(everything, axes.offsets_along(everything, body.fixation_px, angle))
    estimate = None
    if math.isfinite(omega) and omega > 0:
        estimate = estimate_focal(everything, body.fixation_px, angle, omega, size_px,
                                  config.elevation_deg if config.elevation_deg is not None else 0.0)
    if estimate is None or not math.isfinite(estimate.focal_px):
        return config, estimate
    elevation = config.elevation_deg if config.elevation_deg is not None else estimate.elevation_deg
    return replace(config, focal_px=estimate.focal_px, elevation_deg=elevation), estimate


def method_name(config: AnalysisConfig, camera: rates.Camera | None) -> str:
    return config.method if camera is None else f"{config.method}+pinhole(f={camera.focal_px:.1f}px)"


@dataclass(frozen=True)
class PreparedBody:
    """One body's tracks reduced to what the rate stages need (see :func:`prepare_body`).

    Attributes:
        fixation_px: the fixation point (given, or found from the tracks).
        base: ``track, frame, time_s`` per sample (tracks numbered from 1).
        offsets_px: each sample's offset from ``fixation_px``.
        positions: ``x_px, y_px`` per sample while the fixation may still be refined, else None.
    """

    fixation_px: tuple[float, float]
    base: pd.DataFrame
    offsets_px: np.ndarray
    positions: pd.DataFrame | None


def prepare_body(everything: pd.DataFrame, angle: float, config: AnalysisConfig) -> PreparedBody:
    """The fixation point (given, or found from the tracks) and the offsets from it of one
    body's tracks (``frame, time_s, track, x_px, y_px`` sorted by track then frame). The caller
    can drop the tracks table afterwards: nothing here refers to it.

    Raises:
        NoResultError: the axis cannot be found from the tracks.
    """
    if config.fixation_px is None:
        found = axes.axis_offset_from_recurrence(everything, axes.offsets_along(everything, (0.0, 0.0), angle))
        if not math.isfinite(found):
            raise NoResultError("could not find the rotation axis from the motion (too little of a turn); "
                                "give --fixation X,Y")
        fixation = axes.point_on_axis(found, angle, everything)
    else:
        fixation = (float(config.fixation_px[0]), float(config.fixation_px[1]))
    tracks = thin(everything, config.every)
    base = pd.DataFrame({
        "track": tracks["track"].to_numpy() + 1,  # features are numbered from 1, as in the paper
        "frame": tracks["frame"].to_numpy(),
        "time_s": tracks["time_s"].to_numpy(),
    }, copy=False)
    # positions are kept only while the fixation may still move: keep the peak low
    positions = tracks[["x_px", "y_px"]] if config.fixation_px is None else None
    return PreparedBody(fixation, base, axes.offsets_along(tracks, fixation, angle), positions)


def measure_body(
    body: PreparedBody, angle: float, config: AnalysisConfig, size_px: tuple[int, int], steady: bool = False
) -> tuple[tuple[float, float], RateResult, rates.Camera | None]:
    """The rates of one prepared body, with its fixation refined when it was found. ``steady``:
    the rate is known not to change (the clip repeats itself), so a spin-up is not looked for
    (it costs two more fits: 0.4 s of the record clip's 45,000 tracks)."""
    fixation = body.fixation_px

    def measure(point: tuple[float, float]) -> tuple[RateResult, rates.Camera | None]:
        moved = body.positions is not None and point != fixation
        offset = axes.offsets_along(body.positions, point, angle) if moved else body.offsets_px
        offsets = body.base.assign(offset_px=offset)
        camera = camera_model(config, size_px, point, angle)
        return rates_from_offsets(offsets, config.method, config.rejection, camera), camera

    result, camera = measure(fixation)
    release_free_memory()
    if config.fixation_px is None and config.method == "fit":
        # the axis is refined even where the clip's repetition gives the rate: the sense of
        # turning is the tracks' (without it, one EPFL car's sense came out wrong)
        fixation, result, camera = _refine_fixation(result, camera, fixation, angle, measure)
        change = None if steady else half_rates(result, config, camera)
        if change is not None and changes(result.combined, *change):
            # a spinning-up body: one rate for all tracks misplaces the axis; the turn's angle
            # as it speeds up (from the halves' rates) does not. Once: measuring the halves again
            # about the moved axis and moving it again diverged (rendered cylinder 2.7 -> 19 px)
            fixation, result, camera = _refine_fixation(result, camera, fixation, angle, measure, spin_up=change)
    return fixation, result, camera


def fixation_doubt(result: RateResult, camera: rates.Camera | None, fixation: tuple[float, float],
                    angle_deg: float, config: AnalysisConfig, size_px: tuple[int, int]) -> str | None:
    """A given fixation checked against the axis the inlier tracks turn about (the shared-axis
    least squares at the measured rate, :func:`rotrate_cli.axis.refine_axis_offset`): a line
    naming the found axis point when measuring about it moves the rate outside the interval
    measured about the given one, or narrows the interval :data:`SHARPER` times (what the
    measurement can resolve); None otherwise."""
    features = result.features
    inlier = features["inlier"].to_numpy(dtype=bool)
    if config.method != "fit" or config.points_px or inlier.sum() < JOINT_MIN_TRACKS:
        return None
    offsets, omega = _inliers_and_rate(result, camera)
    shift = axes.refine_axis_offset(offsets, omega, camera)
    if not math.isfinite(shift) or abs(shift) < 2.0:
        return None
    ux, uy = axes.unit_offset(angle_deg)
    found = (fixation[0] + shift * ux, fixation[1] + shift * uy)
    moved = offsets.assign(offset_px=offsets["offset_px"].to_numpy() - shift)  # the inliers: memory
    again = rates_from_offsets(moved, config.method, config.rejection, camera_model(config, size_px, found, angle_deg))
    rate, combined = again.combined.omega_rad_s, result.combined
    width = combined.omega_high_rad_s - combined.omega_low_rad_s
    width_found = again.combined.omega_high_rad_s - again.combined.omega_low_rad_s
    # resolved: about the found axis the rate moves outside the given one's interval, or the
    # tracks agree markedly better (a 10 px error on the sample box: interval 0.098 -> 0.006)
    if not math.isfinite(rate) or (combined.omega_low_rad_s <= rate <= combined.omega_high_rad_s
                                   and not width > SHARPER * width_found):
        return None
    return (f"the tracks turn about an axis through ({found[0]:.1f}, {found[1]:.1f}), {abs(shift):.0f} px from the "
            f"given fixation; measured about it the rate is {rate:.4g} rad/s: check --fixation, or use "
            "--fixation auto")


def across(angle_deg: float) -> bool:
    """True when an axis at ``angle_deg`` is nearer horizontal than vertical in the image."""
    return math.isfinite(angle_deg) and abs(angle_deg) > 45.0


def path_shape(everything: pd.DataFrame, angle: float) -> axes.PathShape | None:
    """The axis angle and camera elevation from the shape of the tracks' elliptical paths (see
    :func:`rotrate_cli.axis.path_shape`), at a first rate from the recurrence along the
    direction of motion ``angle``, twice (on the dinosaur photographs: -4.0 degrees from the
    motion, then -1.7, then -1.4; their axis leans -1.2); None when either cannot be had."""
    shape = None
    for _ in range(2):  # the rate along a better direction is better, and so the next direction
        omega = axes.rate_from_recurrence(everything, axes.offsets_along(everything, (0.0, 0.0), angle))
        found = axes.path_shape(everything, omega, min_tracks=MIN_TRACKS_FOR_ANGLE)
        if found is None:
            break
        shape = found
        angle = found.angle_deg
    return shape


def _refine_fixation(
    result: RateResult, camera: rates.Camera | None, fixation: tuple[float, float], angle_deg: float,
    measure: Callable[[tuple[float, float]], tuple[RateResult, rates.Camera | None]],
    spin_up: tuple[Combined, Combined, float, float] | None = None,
) -> tuple[tuple[float, float], RateResult, rates.Camera | None]:
    """Move a found fixation point to the shared-axis least squares of the inlier tracks at the
    measured rate (with ``spin_up``, the halves' rates and middle times: a rate changing
    steadily), with the pinhole model when there is a ``camera``, and measure again (twice at
    most: it converges in one step when omega is well determined)."""
    ux, uy = axes.unit_offset(angle_deg)
    for _ in range(2):
        offsets, omega = _inliers_and_rate(result, camera)
        if spin_up is not None:  # the rate at the halves' middles, changing steadily between them
            early, late, early_s, late_s = spin_up
            sense = omega / result.combined.omega_rad_s if result.combined.omega_rad_s else 1.0
            alpha = (late.omega_rad_s - early.omega_rad_s) / (late_s - early_s)
            shift = axes.refine_axis_offset(offsets, early.omega_rad_s * sense, camera, alpha * sense, early_s)
        else:
            shift = axes.refine_axis_offset(offsets, omega, camera)
        if not math.isfinite(shift) or abs(shift) < 0.02:
            break
        fixation = (fixation[0] + shift * ux, fixation[1] + shift * uy)
        result, camera = measure(fixation)
    return fixation, result, camera


def _inliers_and_rate(result: RateResult, camera: rates.Camera | None) -> tuple[pd.DataFrame, float]:
    """The inlier tracks' offsets and the combined rate, signed as the fits' sense where a pinhole
    ``camera`` tells it (the axis refinement's model is signed there), positive otherwise."""
    features = result.features
    inlier = features["inlier"].to_numpy(dtype=bool)
    offsets = result.offsets[result.offsets["track"].isin(features.loc[inlier, "track"])]
    omega = result.combined.omega_rad_s
    if camera is not None:
        senses = features.loc[inlier, "sense"].to_numpy(dtype=float)
        omega *= (float(np.sign(np.nansum(senses))) if np.isfinite(senses).any() else 0.0) or 1.0
    return offsets, omega
