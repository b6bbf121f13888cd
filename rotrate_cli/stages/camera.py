"""The camera of the geometry stage: the lens given (``--fov``/``--focal-px``), read from the
photographs' EXIF, found from the tracks (:mod:`rotrate_cli.scene.focal`, ``--fov auto``, the default)
or orthographic (``--fov ortho``, the paper's model); and the pinhole model the fits use about a
fixation point (:func:`camera_at`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from rotrate_cli.config import AnalysisConfig
from rotrate_cli.fitting.camera import Camera, focal_px_from_fov
from rotrate_cli.fitting.outliers import RejectionConfig
from rotrate_cli.runtime.lazy import pandas as pd
from rotrate_cli.scene import axis as axes
from rotrate_cli.scene.focal import FocalEstimate, estimate_focal
from rotrate_cli.stages.fits import rates_from_offsets
from rotrate_cli.tracking.keyframes import Keyframes
from rotrate_cli.video.frames import VideoInfo

#: Where the tracks cannot tell the lens, the interval holds the rates through any lens from the
#: orthographic camera to one this wide (a phone's main camera is 65-75 degrees across; the EPFL
#: cars' 64). A box turned 2.4 rad in 3 s through a 60-degree lens, its halves' rates apart:
#: orthographic +13.2% within [+2.1%, +24.2%], weak, the truth outside.
WIDEST_FOV_DEG = 70.0

#: Where the camera model came from (``Lens.source``).
CAMERA_SOURCES = ("orthographic", "given", "exif", "found")


@dataclass(frozen=True)
class Lens:
    """The camera model of a measurement.

    Attributes:
        focal_px: the focal length in pixels; None for the orthographic camera.
        elevation_deg: how far the camera looks down on the axis, degrees (0: level; the fits'
            pinhole model uses it); NaN where nothing says.
        source: ``orthographic`` (the paper's), ``given`` (``--fov``/``--focal-px``), ``exif``
            (the photographs' lens) or ``found`` (from the tracks).
        estimate: what the tracks said about the camera where it was sought; None otherwise.
        unsettled: the lens was sought and the tracks could not tell it (too few turned far
            enough, or the rate changed): the orthographic camera stands in for an unknown one.
        told_sense: +1 anticlockwise, -1 clockwise seen from the axis's top end where the user
            said it (``--direction``); 0 otherwise.
    """

    focal_px: float | None
    elevation_deg: float = math.nan
    source: str = "orthographic"
    estimate: FocalEstimate | None = None
    unsettled: bool = False
    told_sense: int = 0


def lens_from(config: AnalysisConfig, info: VideoInfo) -> Lens:
    """The lens given in the options, else the photographs' own (EXIF), else orthographic (to be
    found from the tracks where ``config.find_focal``); with the sense of turning the user gave."""
    elevation = config.elevation_deg if config.elevation_deg is not None else math.nan
    told = {"ccw": 1, "cw": -1}.get(config.direction or "", 0)
    if config.focal_px is not None:
        return Lens(config.focal_px, elevation, "given", told_sense=told)
    if config.fov_deg is not None:
        return Lens(focal_px_from_fov(config.fov_deg, info.width_px), elevation, "given", told_sense=told)
    if info.focal_px is not None and config.find_focal and config.method == "fit":
        return Lens(info.focal_px, elevation, "exif", told_sense=told)
    return Lens(None, elevation, "orthographic", told_sense=told)


def camera_at(lens: Lens, size_px: tuple[int, int], fixation_px: tuple[float, float],
              angle_deg: float) -> Camera | None:
    """The pinhole camera (principal point at the image centre) with offsets measured along
    ``angle_deg`` from ``fixation_px``; None for the orthographic camera."""
    if lens.focal_px is None:
        return None
    width_px, height_px = size_px
    ux, uy = axes.unit_offset(angle_deg)
    axis_px = (fixation_px[0] - (width_px / 2.0 - 0.5)) * ux + (fixation_px[1] - (height_px / 2.0 - 0.5)) * uy
    elevation = lens.elevation_deg if math.isfinite(lens.elevation_deg) else 0.0
    told = lens.estimate.sense if lens.source == "found" and lens.estimate is not None else math.nan
    if lens.told_sense:  # the user's word stands over the view's
        told = float(lens.told_sense)
    return Camera(lens.focal_px, axis_px / lens.focal_px, math.cos(math.radians(elevation)),
                        int(told) if math.isfinite(told) else 0)


def find_lens(tracks: pd.DataFrame, fixation_px: tuple[float, float], angle_deg: float, lens: Lens,
              size_px: tuple[int, int], elevation_guess_deg: float = math.nan,
              keyframes: Keyframes | None = None) -> Lens:
    """The focal length (and elevation, unless given) found from the tracks, at a first rate from
    their recurrence; orthographic when no perspective shows, and ``unsettled`` (``estimate``
    None) when too few tracks turn far enough to tell, or the clip's halves turn at different
    rates both through the orthographic camera and through the lens found (a rate that changes:
    a lens's model holds one steady rate). ``keyframes``: the tracker's images kept, on which
    the lens fit's samples are placed again (:mod:`rotrate_cli.scene.patches`)."""
    offsets = axes.offsets_along(tracks, fixation_px, angle_deg)
    omega = axes.rate_from_recurrence(tracks, offsets)
    if not (math.isfinite(omega) and omega > 0):
        return replace(lens, unsettled=True)
    changing = _changing(tracks, offsets)
    elevation = next((value for value in (lens.elevation_deg, elevation_guess_deg) if math.isfinite(value)), 0.0)
    estimate = estimate_focal(tracks, fixation_px, angle_deg, omega, size_px, elevation, keyframes)
    if estimate is None or (changing and not math.isfinite(estimate.focal_px)):
        return replace(lens, unsettled=True)
    if not math.isfinite(estimate.focal_px):
        return replace(lens, estimate=estimate, source="found")
    if not math.isfinite(lens.elevation_deg):
        elevation = estimate.elevation_deg
    found = Lens(estimate.focal_px, elevation, "found", estimate, told_sense=lens.told_sense)
    if changing and not _steady_through(found, tracks, offsets, fixation_px, angle_deg, size_px):
        return replace(lens, unsettled=True)
    return found


#: Halves of the clip whose first rates (the recurrence's) differ by more than this fraction turn
#: at a changing rate, which the lens's model (one steady rate) cannot hold: it takes the change
#: for perspective (the spin-up sample, 0.3 + 0.15 t rad/s through an orthographic camera, found
#: an 11-degree lens whenever its tracks changed a little).
STEADY_FRACTION = 0.1
#: The halves' rates are read from at most about this many samples (whole tracks).
CHANGE_SAMPLES = 200_000


def _whole_tracks_evenly(tracks: pd.DataFrame, offsets: np.ndarray) -> tuple[pd.DataFrame, np.ndarray]:
    """At most about :data:`CHANGE_SAMPLES` samples, whole tracks chosen evenly by number: no
    copy of a long clip's table."""
    if len(tracks) <= CHANGE_SAMPLES:
        return tracks, offsets
    chosen = tracks["track"].to_numpy() % math.ceil(len(tracks) / CHANGE_SAMPLES) == 0
    return tracks[chosen], offsets[chosen]


def _steady_through(lens: Lens, tracks: pd.DataFrame, offsets: np.ndarray, fixation_px: tuple[float, float],
                    angle_deg: float, size_px: tuple[int, int]) -> bool:
    """True when the clip's halves, measured through ``lens``, turn at one rate (within
    :data:`STEADY_FRACTION`): the halves' apparent rates differed because of the lens, not the
    body. A wide lens makes a short clip's halves differ: a box turned 2.4 rad in 3 s through a
    60-degree lens read 0.90 and 1.00 rad/s orthographically, 0.804 and 0.797 through the 58.6
    degrees found; a spin-up's halves (box_spinup.mp4) differ through any lens."""
    tracks, offsets = _whole_tracks_evenly(tracks, offsets)
    table = pd.DataFrame({"track": tracks["track"].to_numpy(), "frame": tracks["frame"].to_numpy(),
                          "time_s": tracks["time_s"].to_numpy(), "offset_px": offsets})
    times = table["time_s"].to_numpy()
    middle = 0.5 * (float(times.min()) + float(times.max()))
    camera = camera_at(lens, size_px, fixation_px, angle_deg)
    rates_ = []
    for part in (times <= middle, times > middle):
        try:
            rates_.append(rates_from_offsets(table[part], "fit", RejectionConfig(), camera).combined.omega_rad_s)
        except (ValueError, IndexError):
            return False
    if not all(math.isfinite(rate) and rate > 0 for rate in rates_):
        return False
    return abs(rates_[1] / rates_[0] - 1.0) <= STEADY_FRACTION


def _changing(tracks: pd.DataFrame, offsets: np.ndarray) -> bool:
    """True when the clip's halves turn at clearly different rates (see :data:`STEADY_FRACTION`)."""
    tracks, offsets = _whole_tracks_evenly(tracks, offsets)
    frame = tracks["frame"].to_numpy()
    early = frame <= np.median(frame)
    rates = [axes.rate_from_recurrence(tracks[part], offsets[part]) for part in (early, ~early)]
    if not all(math.isfinite(rate) and rate > 0 for rate in rates):
        return False
    return abs(rates[1] / rates[0] - 1.0) > STEADY_FRACTION


def method_name(method: str, camera: Camera | None) -> str:
    """The estimator's name as reported: ``fit``, ``paper``, or ``fit+pinhole(f=...px)``."""
    return method if camera is None else f"{method}+pinhole(f={camera.focal_px:.1f}px)"
