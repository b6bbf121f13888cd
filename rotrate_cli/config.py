"""The options of one analysis (:class:`AnalysisConfig`) and their checks."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from rotrate_cli.errors import SettingError
from rotrate_cli.fitting import estimators
from rotrate_cli.fitting.outliers import (
    RejectionConfig,
)
from rotrate_cli.tracking.chosen import TRACKERS
from rotrate_cli.tracking.klt import (
    TrackerConfig,
)

#: The trackers a measurement can use (``auto``: chosen by the source, see :class:`AnalysisConfig`).
TRACKER_KINDS = ("auto", *TRACKERS, "matched")

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
            of all the steps, :func:`rotrate_cli.scene.axis.motion_angle_deg`), ``paths`` (the long
            axis of each track's elliptical path, :func:`rotrate_cli.scene.axis.path_shape`:
            right when the camera looks down on the object, where ``motion`` leans), or
            ``auto`` (the default): ``paths`` where the steps show the camera looking down
            (:func:`rotrate_cli.stages.geometry.axis_angle`), ``motion`` otherwise.
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
            in both image directions (:mod:`rotrate_cli.scene.focal`; the default, ``--fov auto``)
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
            features 1..n, instead of finding corners (see :mod:`rotrate_cli.tracking.chosen`).
        tracker_kind: ``auto`` (the default: ``klt`` for videos, ``matched`` for image
            sequences), ``klt`` (pyramidal Lucas-Kanade), ``csrt`` (OpenCV's CSRT: for chosen
            points, or for 30 automatic corners placed to sub-pixel, see :mod:`rotrate_cli.tracking.csrt`;
            about 5x slower than ``klt``, and for videos, not stills far apart) or ``matched``
            (SIFT features matched from frame to frame, for photographs far apart on the turn:
            :mod:`rotrate_cli.tracking.matched`).
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
    tracker_kind: str = "auto"
    times_s: tuple[float, ...] | None = None


def check_config(config: AnalysisConfig) -> None:
    if config.method not in estimators.METHODS:
        raise SettingError(f"`method` must be one of {', '.join(estimators.METHODS)}; got {config.method!r}", "method")
    if config.every is not None and config.every < 1:
        raise SettingError("`every` must be a whole number of frames, 1 or more", "every")
    if config.start_s < 0 or not math.isfinite(config.start_s):
        raise SettingError("`start_s` must be 0 seconds or later", "start_s")
    if config.end_s is not None and not config.end_s > config.start_s:
        raise SettingError("`end_s` must be later than `start_s`", "end_s")
    if config.fov_deg is not None and config.focal_px is not None:
        raise SettingError("give either `fov_deg` or `focal_px`, not both", "fov_deg")
    if config.fov_deg is not None and not 0 < config.fov_deg < 170:
        raise SettingError("`fov_deg` must be a horizontal field of view between 0 and 170 degrees", "fov_deg")
    if config.focal_px is not None and not (config.focal_px > 0 and math.isfinite(config.focal_px)):
        raise SettingError("`focal_px` must be a positive focal length in pixels", "focal_px")
    if config.window_s is not None and not (math.isfinite(config.window_s) and config.window_s > 0):
        raise SettingError("`window_s` must be a positive number of seconds", "window_s")
    if config.axis_angle_deg is not None and not (math.isfinite(config.axis_angle_deg)
                                                   and -180 <= config.axis_angle_deg <= 180):
        raise SettingError("`axis_angle_deg` takes degrees between -180 and 180 (0: a vertical axis)", "axis_angle_deg")
    if config.angle_from not in ANGLE_SOURCES:
        raise SettingError(f"`angle_from` must be one of {', '.join(ANGLE_SOURCES)}; got {config.angle_from!r}",
                           "angle_from")
    if config.angle_from == "paths" and config.axis_angle_deg is not None:
        raise SettingError("give either `axis_angle_deg` or `angle_from='paths'`, not both", "axis_angle_deg")
    if config.angle_from == "paths" and config.segment:
        raise SettingError("`angle_from='paths'` fits one rate to all paths; it cannot be combined with `segment`",
                           "angle_from")
    if config.elevation_deg is not None:
        if not (math.isfinite(config.elevation_deg) and -80 <= config.elevation_deg <= 80):
            raise SettingError("`elevation_deg` must be between -80 and 80 degrees", "elevation_deg")
        if config.fov_deg is None and config.focal_px is None and not config.find_focal:
            raise SettingError("`elevation_deg` is for the pinhole model: drop `find_focal=False`, or give "
                               "`fov_deg` or `focal_px`",
                               "elevation_deg")
    if config.direction not in (None, *DIRECTIONS):
        raise SettingError(f"`direction` must be one of {', '.join(DIRECTIONS)}; got {config.direction!r}", "direction")
    if config.tracker_kind not in TRACKER_KINDS:
        raise SettingError(f"`tracker_kind` must be one of {', '.join(TRACKER_KINDS)}; got {config.tracker_kind!r}",
                           "tracker_kind")
    if config.points_px and config.tracker_kind not in (*TRACKERS, "auto"):
        raise SettingError(f"chosen points are followed by {' or '.join(TRACKERS)}, not {config.tracker_kind!r}",
                           "tracker_kind")
    if config.segment and config.fixation_px is not None:
        raise SettingError("`segment` finds each body's axis itself; drop `fixation_px` (or use `fixation_px=None`)",
                           "segment")
    if config.segment and config.window_s is not None:
        raise SettingError("`window_s` follows one body; it cannot be combined with `segment`", "window_s")
    if config.method == "paper" and (config.fov_deg is not None or config.focal_px is not None):
        raise SettingError("`method='paper'` is orthographic, as in the paper; drop `fov_deg`/`focal_px` or "
                           "use `method='fit'`",
                           "method")
