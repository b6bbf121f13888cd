"""The options of one analysis (:class:`AnalysisConfig`) and their checks."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from rotrate_cli import rates
from rotrate_cli.chosen import TRACKERS
from rotrate_cli.errors import InputError
from rotrate_cli.outliers import (
    RejectionConfig,
)
from rotrate_cli.tracking import (
    TrackerConfig,
)

#: How the axis's angle is found when not given (see ``AnalysisConfig.angle_from``).
ANGLE_SOURCES = ("auto", "motion", "paths")
#: The ways round an object can be told to turn (``--direction``), seen from the axis's top end.
DIRECTIONS = ("ccw", "cw")


@dataclass(frozen=True)
class AnalysisConfig:
    """Options of one analysis.

    Attributes:
        fixation_px: the fixation point (x = column, y = row) on the rotation axis, in pixels;
            None to find the axis from the tracks.
        axis_angle_deg: the axis's angle in the image (0 vertical, positive: top end leaning
            right); None to find it (see ``angle_from``).
        angle_from: how the angle is found when not given: ``motion`` (the principal direction
            of all the steps, :func:`rotrate_cli.axis.motion_angle_deg`), ``paths`` (the long
            axis of each track's elliptical path, :func:`rotrate_cli.axis.path_shape`:
            right when the camera looks down on the object, where ``motion`` leans), or
            ``auto`` (the default): ``paths`` where the steps show the camera looking down
            (:func:`rotrate_cli.geometry.axis_angle`), ``motion`` otherwise.
        elevation_deg: how far the camera looks down on the object, degrees, for the pinhole
            model (``fov_deg``/``focal_px``); None: level, or found from the paths where the
            angle comes from them.
        direction: ``ccw`` or ``cw``, seen from the top end of the axis (as the report's
            ``direction`` reads), where the user knows which way the object turns; None: the
            tracks tell it where they can. Through a lens the two ways fit different rates, and
            the tracks of a short turn seen level cannot always tell them apart.
        fps: frame-rate override in frames per second (required for image sequences).
        start_s, end_s: the time span to analyse, in seconds (``end_s`` None: to the end).
        every: use every N-th frame's positions for the rates (tracking still sees every frame);
            None: 1 for the fit method, and for the paper's method the paper's spacing, about a
            sixth of a radian between samples (its 16 frames at 30 fps), from a first rate.
        method: ``fit`` (ours) or ``paper`` (the reference paper's backward differences).
        fov_deg: the camera's horizontal field of view, degrees, for the pinhole model; None
            (and no ``focal_px``) treats the view as orthographic, as the paper does.
        focal_px: the focal length in pixels, instead of ``fov_deg``.
        find_focal: find the focal length (and the camera's elevation) from the tracks' motion
            in both image directions (:mod:`rotrate_cli.focal`; the default, ``--fov auto``)
            where no lens is given (``fov_deg``/``focal_px``, or the photographs' EXIF); a view
            with no measurable perspective stays orthographic. False (``--fov ortho``): the
            paper's orthographic camera. Not for ``segment``, chosen points or the paper's method.
        tracker: tracking settings.
        rejection: outlier-rejection thresholds.
        window_s: also measure omega(t) over a sliding window this long (None: not).
        segment: group the tracks into rigid bodies by rate and axis and measure each (the
            axis of each is found; ``fixation_px`` must be None).
        keep_tracks: keep the tracked positions in the result (``Analysis.tracks``), for
            pictures of the measurement; they cost memory in proportion to the clip.
        points_px: follow only these points (x, y pixels in the first analysed frame), as
            features 1..n, instead of finding corners (see :mod:`rotrate_cli.chosen`).
        tracker_kind: ``klt`` (pyramidal Lucas-Kanade) or ``csrt`` (OpenCV's CSRT: for chosen
            points, or for 30 automatic corners placed to sub-pixel, see :mod:`rotrate_cli.csrt`;
            about 5x slower than ``klt``, and for videos, not stills far apart).
        times_s: one time per frame, seconds (``--times``), instead of the source's clock.
    """

    fixation_px: tuple[float, float] | None
    fps: float | None = None
    axis_angle_deg: float | None = None
    angle_from: str = "auto"
    elevation_deg: float | None = None
    direction: str | None = None
    start_s: float = 0.0
    end_s: float | None = None
    every: int | None = 1
    method: str = "fit"
    fov_deg: float | None = None
    focal_px: float | None = None
    find_focal: bool = True
    tracker: TrackerConfig = field(default_factory=TrackerConfig)
    rejection: RejectionConfig = field(default_factory=RejectionConfig)
    window_s: float | None = None
    segment: bool = False
    keep_tracks: bool = False
    points_px: tuple[tuple[float, float], ...] = ()
    tracker_kind: str = "klt"
    times_s: tuple[float, ...] | None = None


def check_config(config: AnalysisConfig) -> None:
    if config.method not in rates.METHODS:
        raise InputError(f"unknown method {config.method!r}; use one of {', '.join(rates.METHODS)}")
    if config.every is not None and config.every < 1:
        raise InputError("--every must be a whole number of frames, 1 or more")
    if config.start_s < 0 or not math.isfinite(config.start_s):
        raise InputError("--start must be 0 seconds or later")
    if config.end_s is not None and not config.end_s > config.start_s:
        raise InputError("--end must be later than --start")
    if config.fov_deg is not None and config.focal_px is not None:
        raise InputError("give either --fov or --focal-px, not both")
    if config.fov_deg is not None and not 0 < config.fov_deg < 170:
        raise InputError("--fov must be a horizontal field of view between 0 and 170 degrees")
    if config.focal_px is not None and not (config.focal_px > 0 and math.isfinite(config.focal_px)):
        raise InputError("--focal-px must be a positive focal length in pixels")
    if config.window_s is not None and not (math.isfinite(config.window_s) and config.window_s > 0):
        raise InputError("--window must be a positive number of seconds")
    if config.axis_angle_deg is not None and not (math.isfinite(config.axis_angle_deg)
                                                   and -180 <= config.axis_angle_deg <= 180):
        raise InputError("--axis-angle takes degrees between -180 and 180 (0: a vertical axis)")
    if config.angle_from not in ANGLE_SOURCES:
        raise InputError(f"--angle-from must be one of {', '.join(ANGLE_SOURCES)}; got {config.angle_from!r}")
    if config.angle_from == "paths" and config.axis_angle_deg is not None:
        raise InputError("give either --axis-angle or --angle-from paths, not both")
    if config.angle_from == "paths" and config.segment:
        raise InputError("--angle-from paths fits one rate to all paths; it cannot be combined with --segment")
    if config.elevation_deg is not None:
        if not (math.isfinite(config.elevation_deg) and -80 <= config.elevation_deg <= 80):
            raise InputError("--elevation must be between -80 and 80 degrees")
        if config.fov_deg is None and config.focal_px is None and not config.find_focal:
            raise InputError("--elevation is for the pinhole model: drop --fov ortho, or give --fov or --focal-px")
    if config.direction not in (None, *DIRECTIONS):
        raise InputError(f"--direction must be one of {', '.join(DIRECTIONS)}; got {config.direction!r}")
    if config.tracker_kind not in TRACKERS:
        raise InputError(f"--tracker must be one of {', '.join(TRACKERS)}; got {config.tracker_kind!r}")
    if config.segment and config.fixation_px is not None:
        raise InputError("--segment finds each body's axis itself; drop --fixation (or use --fixation auto)")
    if config.segment and config.window_s is not None:
        raise InputError("--window follows one body; it cannot be combined with --segment")
    if config.method == "paper" and (config.fov_deg is not None or config.focal_px is not None):
        raise InputError("--method paper is orthographic, as in the paper; drop --fov/--focal-px or use --method fit")
