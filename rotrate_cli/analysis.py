"""The whole job in one call: :func:`analyze` for a video, :func:`analyze_tracks` for tracks.

video -> decode (background thread, reduced grey) -> KLT tracks -> offsets from the fixation
point -> per-track rates -> outlier rejection -> combined omega with a 95% interval.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from functools import cached_property
from pathlib import Path

import numpy as np
import pandas as pd

from rotrate_cli import axis as axes
from rotrate_cli import rates
from rotrate_cli.chosen import TRACKERS, follow_points
from rotrate_cli.csrt import CsrtTracker, csrt_settings
from rotrate_cli.decode import FrameSource, prefetch
from rotrate_cli.errors import InputError, NoResultError
from rotrate_cli.focal import ORTHOGRAPHIC_WIDTHS, FocalEstimate, estimate_focal
from rotrate_cli.joint import joint_fit
from rotrate_cli.memory import release_free_memory
from rotrate_cli.outliers import (
    FEATURE_COLUMNS,
    Combined,
    RejectionConfig,
    combine,
    combine_plain,
    flag_samples,
    judge_fits,
    judge_paper,
)
from rotrate_cli.period import Period, Thumbnails, find_period
from rotrate_cli.segment import Body, segment_tracks, unresolved
from rotrate_cli.series import rate_series
from rotrate_cli.tracking import (
    VIDEO_BLUR_SIGMA_PX,
    TrackerConfig,
    TrackingRun,
    track_frames,
    tracking_image,
    tracking_scale,
)
from rotrate_cli.verdict import Verdict, judge

#: Progress callback: (frames done, frames expected or None).
ProgressCallback = Callable[[int, int | None], None]

DIRECTIONS = ("ccw", "cw", "unknown")

#: How the axis's angle is found when not given (see ``AnalysisConfig.angle_from``).
ANGLE_SOURCES = ("motion", "paths")

#: Below this many inlier tracks the summary is the random-effects mean of per-track rates
#: rather than the joint fit: the joint fit's gain (no small-track bias) needs many tracks, its
#: jackknife interval needs enough of them to see their spread, and with a handful one track's
#: model error would steer it (the paper's two hand-tracked features: 0.309 joint, 0.334 mean).
JOINT_MIN_TRACKS = 10

#: Fewer tracks than this do not find the axis's angle from their motion: it is taken as vertical.
MIN_TRACKS_FOR_ANGLE = 10

#: Halves of a clip whose rates lie outside each other's intervals and this fraction apart show
#: a changing rate.
CHANGE_FRACTION = 0.02

#: The found lens's inverse focal length is good to about this fraction on rendered solids, more
#: than its standard error says (the tracker's small slides near the outline bias it): found
#: 13.3, 25.0, 28.3 and 26.8 degrees for 15, 25, 30 and 20 (a sphere: -2.0% in omega, with an
#: interval of +-0.8% from the standard error alone).
LENS_FLOOR = 0.35

#: A found axis about which the tracks' interval is this many times narrower than about a given
#: fixation shows the given one to be off by more than the measurement resolves.
SHARPER = 1.5

#: Degrees of freedom given to the typical track noise when moderating each track's own.
PRIOR_DOF = 10.0


@dataclass(frozen=True)
class AnalysisConfig:
    """Options of one analysis.

    Attributes:
        fixation_px: the fixation point (x = column, y = row) on the rotation axis, in pixels;
            None to find the axis from the tracks.
        axis_angle_deg: the axis's angle in the image (0 vertical, positive: top end leaning
            right); None to find it (see ``angle_from``).
        angle_from: how the angle is found when not given: ``motion`` (the principal direction
            of all the steps, :func:`rotrate_cli.axis.motion_angle_deg`) or ``paths`` (the long
            axis of each track's elliptical path, :func:`rotrate_cli.axis.path_shape`:
            right when the camera looks down on the object, where ``motion`` leans).
        elevation_deg: how far the camera looks down on the object, degrees, for the pinhole
            model (``fov_deg``/``focal_px``); None: level, or found from the paths with
            ``angle_from="paths"``.
        fps: frame-rate override in frames per second (required for image sequences).
        start_s, end_s: the time span to analyse, in seconds (``end_s`` None: to the end).
        every: use every N-th frame's positions for the rates (tracking still sees every frame).
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
    angle_from: str = "motion"
    elevation_deg: float | None = None
    start_s: float = 0.0
    end_s: float | None = None
    every: int = 1
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


@dataclass(frozen=True)
class Analysis:
    """The result of one analysis.

    Attributes:
        source: the input as given.
        fps: the frame rate used, frames per second.
        frames: frames analysed.
        duration_s: time from the first to the last analysed frame, seconds.
        fixation_px: the fixation point (x, y); y is NaN where only x is known (track files).
        method: the estimator used.
        omega_rad_s, omega_low_rad_s, omega_high_rad_s: combined rate and its 95% interval, rad/s.
        direction: ``ccw``, ``cw`` or ``unknown`` (seen from the top end of the axis).
        tracks_total, tracks_used: tracks found, and tracks that went into the result.
        features: one row per track (see :data:`rotrate_cli.outliers.FEATURE_COLUMNS`).
        offsets: one row per track per sample: ``track, frame, time_s, offset_px``.
        rejection: the thresholds the verdicts used.
        warnings: things the user should know that did not stop the run.
        position_unit: the unit of positions and offsets (``px`` for videos).
        axis_angle_deg: the axis's angle in the image (0 vertical, positive: top end right).
        axis_found: True when the fixation point was found from the tracks.
        axis_angle_found: True when the angle was found from the tracks.
        axis_angle_from: how it was found (``motion`` or ``paths``; see ``AnalysisConfig.angle_from``).
        elevation_deg: the camera's elevation found from the paths (``paths``) or with the
            focal length (``find_focal``); NaN otherwise.
        focal: with ``find_focal``, what the tracks said about the camera; None otherwise.
        series: omega(t) over a sliding window (see :mod:`rotrate_cli.series`), or None.
        bodies: with ``segment``, every rigid body measured, the headline one (most tracks)
            first; None otherwise.
        tracks: with ``keep_tracks``, the positions ``frame, time_s, track, x_px, y_px``
            (tracks numbered as the features); None otherwise.
        verdict: how the reported rate was judged from the tracks and the clip's repetition,
            and its quality (``good``/``weak``; see :mod:`rotrate_cli.verdict`).
        period: the clip's repetition (:mod:`rotrate_cli.period`), or None where none was seen.
        clock: where the frame times came from (``container``, ``fps``, ``exif``, ``times file``;
            ``tracks`` for given tracks).
        camera_from: the camera model used: ``orthographic`` (the paper's), ``given`` (``--fov``
            or ``--focal-px``), ``exif`` (the photographs' lens) or ``found`` (``--fov auto``).

    ``samples`` (per-sample derivatives and rates, Table I) is computed when first asked for:
    a long clip's table is large, and most reports do not need it.
    """

    source: str
    fps: float
    frames: int
    duration_s: float
    fixation_px: tuple[float, float]
    method: str
    omega_rad_s: float
    omega_low_rad_s: float
    omega_high_rad_s: float
    direction: str
    tracks_total: int
    tracks_used: int
    features: pd.DataFrame
    offsets: pd.DataFrame
    rejection: RejectionConfig = field(default_factory=RejectionConfig)
    warnings: tuple[str, ...] = ()
    position_unit: str = "px"
    axis_angle_deg: float = 0.0
    axis_found: bool = False
    axis_angle_found: bool = False
    axis_angle_from: str = "motion"
    elevation_deg: float = math.nan
    focal: FocalEstimate | None = None
    series: pd.DataFrame | None = None
    bodies: tuple[Body, ...] | None = None
    tracks: pd.DataFrame | None = None
    verdict: Verdict | None = None
    period: Period | None = None
    clock: str = "container"
    camera_from: str = "orthographic"

    @property
    def quality(self) -> str:
        """``good``, or ``weak`` when the evidence is weak (see :mod:`rotrate_cli.verdict`)."""
        return self.verdict.quality if self.verdict is not None else "good"

    @property
    def rate_from(self) -> str:
        """What the reported rate comes from: ``tracks`` or ``repetition``."""
        return self.verdict.rate_from if self.verdict is not None else "tracks"

    @property
    def rpm(self) -> float:
        """The combined rate in revolutions per minute."""
        return self.omega_rad_s * 60.0 / (2.0 * math.pi)

    @cached_property
    def samples(self) -> pd.DataFrame:
        """One row per track per sample: ``track, frame, time_s, offset_px, dy_dt, d2y_dt2,
        omega2, omega_rad_s, inlier, reason`` (the paper's Table I columns)."""
        return sample_rates(self.offsets, self.features, self.method, self.rejection)


@dataclass(frozen=True)
class RateResult:
    """What the rate stages produce from a table of offsets."""

    offsets: pd.DataFrame
    features: pd.DataFrame
    combined: Combined
    direction: str


def _camera(config: AnalysisConfig, size_px: tuple[int, int], fixation_px: tuple[float, float],
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


def _check_config(config: AnalysisConfig) -> None:
    if config.method not in rates.METHODS:
        raise InputError(f"unknown method {config.method!r}; use one of {', '.join(rates.METHODS)}")
    if config.every < 1:
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
    if config.tracker_kind not in TRACKERS:
        raise InputError(f"--tracker must be one of {', '.join(TRACKERS)}; got {config.tracker_kind!r}")
    if config.segment and config.fixation_px is not None:
        raise InputError("--segment finds each body's axis itself; drop --fixation (or use --fixation auto)")
    if config.segment and config.window_s is not None:
        raise InputError("--window follows one body; it cannot be combined with --segment")
    if config.method == "paper" and (config.fov_deg is not None or config.focal_px is not None):
        raise InputError("--method paper is orthographic, as in the paper; drop --fov/--focal-px or use --method fit")


def thin(tracks: pd.DataFrame, every: int) -> pd.DataFrame:
    """Every ``every``-th frame's rows, counted from the first frame (the paper's sampling)."""
    if every == 1 or tracks.empty:
        return tracks
    first = int(tracks["frame"].min())
    return tracks[(tracks["frame"] - first) % every == 0]


def _direction(offsets: pd.DataFrame, features: pd.DataFrame) -> str:
    """Sense of rotation, given only on a clear majority of the inlier tracks.

    With a pinhole camera each track's fit says which sense explains it (near points move
    faster). Otherwise: the net horizontal travel. An opaque object shows its near side, whose
    points cross in front of the axis: moving right means anticlockwise seen from above.
    Far-side points (a transparent object, a turntable's top seen from above) travel the other
    way, hence the majority rule.
    """
    inliers = features[features["inlier"]]
    used = set(inliers["track"].astype(int))
    if len(used) < 5:
        return "unknown"
    senses = inliers["sense"].dropna().to_numpy()
    if len(senses) >= 5:
        vote = float(senses.mean())
        return "ccw" if vote >= 0.6 else "cw" if vote <= -0.6 else "unknown"
    # offsets are sorted by track then time: a track's first and last rows bound its slice
    tracks = offsets["track"].to_numpy()
    values = offsets["offset_px"].to_numpy()
    starts = np.flatnonzero(np.r_[True, tracks[1:] != tracks[:-1]])
    ends = np.r_[starts[1:], len(tracks)] - 1
    keep = np.array([int(t) in used for t in tracks[starts]], dtype=bool)
    travel = values[ends[keep]] - values[starts[keep]]
    total = float(np.abs(travel).sum())
    if total <= 0:
        return "unknown"
    balance = float(travel.sum()) / total
    if balance >= 0.7:
        return "ccw"
    if balance <= -0.7:
        return "cw"
    return "unknown"


def sample_rates(
    offsets: pd.DataFrame, features: pd.DataFrame, method: str, rejection: RejectionConfig
) -> pd.DataFrame:
    """Per-sample derivatives, rates and verdicts for offsets already judged per track."""
    if method == "paper":
        return judge_paper(rates.paper_samples(offsets))[0]
    rate = dict(zip(features["track"].astype(int), features["omega_rad_s"], strict=True))
    return flag_samples(rates.fit_samples(offsets, rate), features, rejection)


def _sorted_by_track_and_time(offsets: pd.DataFrame) -> bool:
    track_step = np.diff(offsets["track"].to_numpy())
    time_step = np.diff(offsets["time_s"].to_numpy())
    return bool(((track_step > 0) | ((track_step == 0) & (time_step > 0))).all())


def rates_from_offsets(
    offsets: pd.DataFrame, method: str, rejection: RejectionConfig, camera: rates.Camera | None = None
) -> RateResult:
    """Per-track rates and verdicts, and the combined rate.

    ``offsets`` has columns ``track, frame, time_s, offset_px``, one row per sample; ``camera``
    (fit method only) switches from orthographic to pinhole projection.
    """
    if not _sorted_by_track_and_time(offsets):
        offsets = offsets.sort_values(["track", "time_s"], kind="stable").reset_index(drop=True)
    if method == "paper":
        _, features = judge_paper(rates.paper_samples(offsets))
        combined = combine_plain(features.loc[features["inlier"], "omega_rad_s"].to_numpy())
    else:
        features = judge_fits(offsets, rates.fit_tracks(offsets, rejection.min_samples, camera), rejection)
        release_free_memory()  # the per-track fits' padded batches are gone
        used = features[features["inlier"]]
        combined = combine(used["omega_rad_s"].to_numpy(), used["omega_se_rad_s"].to_numpy())
        combined = _joint(offsets, used, combined, rejection, camera)
    return RateResult(offsets, features, combined, _direction(offsets, features))


def _joint(
    offsets: pd.DataFrame, used: pd.DataFrame, pooled: Combined, rejection: RejectionConfig, camera: rates.Camera | None
) -> Combined:
    """The joint fit of the inlier tracks (see :mod:`rotrate_cli.joint`), started from the
    pooled per-track rates; the pooled result stands where the joint fit finds no minimum, and
    for fewer than :data:`JOINT_MIN_TRACKS` tracks."""
    if len(used) < JOINT_MIN_TRACKS or not math.isfinite(pooled.omega_rad_s):
        return pooled
    # Each track's noise from its own residuals, moderated towards the tracks' typical noise
    # (a few degrees of freedom say little on their own; the tracker is the same for all).
    samples = used["samples"].to_numpy(dtype=float)
    dof = np.maximum(samples - 3, 1)
    variance = used["rms_residual"].to_numpy() ** 2 * samples / dof
    typical = float(np.median(variance))
    noise_px = np.maximum(np.sqrt((dof * variance + PRIOR_DOF * typical) / (dof + PRIOR_DOF)),
                          max(rejection.residual_floor, 1e-9))
    senses = used["sense"].to_numpy(dtype=float)
    sense = float(np.sign(np.nansum(senses))) if np.isfinite(senses).any() else 1.0
    spread = (pooled.omega_high_rad_s - pooled.omega_low_rad_s) / pooled.omega_rad_s
    joint = joint_fit(offsets, dict(zip(used["track"], noise_px, strict=True)),
                      pooled.omega_rad_s, span=float(np.clip(2 * spread, 0.02, 0.5)) if math.isfinite(spread) else 0.2,
                      camera=camera, sense=sense or 1.0)
    if not math.isfinite(joint.omega_rad_s):
        return pooled
    # The jackknife sees scatter between tracks but not a bias they share (tracking drift,
    # projection error); where the two weightings disagree, that disagreement is such a bias,
    # so the interval spans both estimators' intervals.
    low = np.nanmin([joint.omega_low_rad_s, pooled.omega_low_rad_s, pooled.omega_rad_s])
    high = np.nanmax([joint.omega_high_rad_s, pooled.omega_high_rad_s, pooled.omega_rad_s])
    return Combined(joint.omega_rad_s, float(low), float(high), joint.tracks_used)


def _no_result_message(features: pd.DataFrame) -> str:
    if features.empty:
        return "no point could be tracked; check that the object moves and has texture, or pass --roi"
    counts = Counter(features["reason"])
    detail = ", ".join(f"{n} {why}" for why, n in counts.most_common())
    return (f"no track gave a trustworthy rate ({detail}); "
            "try a longer clip, --roi around the object, or check --fixation")


def analyze(source: str | Path, config: AnalysisConfig, progress: ProgressCallback | None = None) -> Analysis:
    """Measure the rotation rate of the object in a video or image sequence.

    Raises:
        InputError: bad source or options.
        NoResultError: the video was read but no track gave a trustworthy rate.
    """
    _check_config(config)
    try:
        return _analyze(source, config, progress)
    except NoResultError as error:
        if config.every > 1 and " short" in str(error):
            raise NoResultError(f"{error}; --every {config.every} keeps one frame in {config.every}, which leaves "
                                "these tracks too few samples to fit: try a smaller --every") from error
        if config.tracker_kind == "csrt" and not config.points_px:
            raise NoResultError(f"{error}; CSRT loses points that jump far between frames (stills taken "
                                "far apart, fast turns): the default --tracker klt follows those") from error
        raise


def _analyze(source: str | Path, config: AnalysisConfig, progress: ProgressCallback | None) -> Analysis:
    video = FrameSource(source, fps=config.fps,
                        times_s=None if config.times_s is None else np.asarray(config.times_s, dtype=np.float64))
    info = video.info
    warnings_early: list[str] = list(video.warnings)
    camera_from = "given" if config.fov_deg is not None or config.focal_px is not None else "orthographic"
    if camera_from == "orthographic" and info.focal_px is not None and config.find_focal and config.method == "fit":
        config = replace(config, focal_px=info.focal_px)  # the photographs' own lens
        camera_from = "exif"
    if config.fixation_px is not None:
        fx, fy = config.fixation_px
        if not (math.isfinite(fx) and math.isfinite(fy)):
            raise InputError("--fixation must be two numbers X,Y in pixels, or auto")
        if not (0 <= fx <= info.width_px - 1 and 0 <= fy <= info.height_px - 1):
            # a record player's spindle seen close up lies outside the picture: measured, but said
            warnings_early.append(f"the fixation ({fx:g}, {fy:g}) lies outside the {info.width_px}x{info.height_px} "
                                  "frame; check it, or use --fixation auto")
    roi = config.tracker.roi
    if roi is not None and (
        roi.width_px <= 0 or roi.height_px <= 0 or roi.x_px < 0 or roi.y_px < 0
        or roi.x_px + roi.width_px > info.width_px or roi.y_px + roi.height_px > info.height_px
    ):
        raise InputError(f"--roi must be X,Y,W,H inside the {info.width_px}x{info.height_px} frame")

    tracker = config.tracker
    if config.axis_angle_deg is not None and _across(config.axis_angle_deg):
        tracker = _turned(tracker)
    thumbnails = Thumbnails()
    run = _track(video, config, tracker, progress, thumbnails)
    count = run.frames
    if count == 0:
        raise InputError(f"no frame of {source} lies between --start and --end")
    if count < 3:
        raise InputError(f"{source} has only {count} frame(s) to analyse; rotation needs at least 3")
    if run.tracks.empty:
        raise NoResultError(_no_result_message(pd.DataFrame(columns=["reason"])))
    everything = _by_track(run.tracks)
    release_free_memory()  # the tracker's store and the frames' buffers are gone
    angle = config.axis_angle_deg
    assumed_vertical = False
    elevation_found = math.nan
    angle_source = config.angle_from
    if angle is None and everything["track"].nunique() < MIN_TRACKS_FOR_ANGLE:
        angle, assumed_vertical = 0.0, True  # a few points' wobble says little about the axis
    if angle is None:
        angle = axes.motion_angle_deg(everything)
        if _across(angle):
            # the motion runs up and down the image: track again with the window turned to suit it
            thumbnails.clear()
            run = _track(video, config, _turned(tracker), progress, thumbnails)
            if run.tracks.empty:
                raise NoResultError(_no_result_message(pd.DataFrame(columns=["reason"])))
            everything = _by_track(run.tracks)
            angle = axes.motion_angle_deg(everything)
        angle = angle if math.isfinite(angle) else 0.0
        if config.angle_from == "paths":
            shape = _path_shape(everything, angle)
            if shape is None:
                warnings_early.append("too few tracks turned far enough to read the axis from their paths: "
                                      "it is found from the motion")
                angle_source = "motion"
            else:
                angle, elevation_found = shape.angle_deg, shape.elevation_deg
                if config.elevation_deg is None:
                    config = replace(config, elevation_deg=elevation_found)
    expected = info.frame_count
    warnings = list(run.notes) + warnings_early
    if assumed_vertical:
        warnings.append("too few tracks to find the axis's angle: taken as vertical (give --axis-angle DEG)")
    if expected and config.start_s == 0 and config.end_s is None and count < expected - 1:
        warnings.append(f"decoded {count} of the {expected} frames the file announces; it may be cut off")

    duration_s = run.last_time_s - run.first_time_s
    del run
    size_px = (info.width_px, info.height_px)
    context = {"source": str(source), "fps": info.fps, "frames": count, "duration_s": duration_s,
               "rejection": config.rejection, "axis_angle_deg": float(angle),
               "axis_found": config.fixation_px is None,
               "axis_angle_found": config.axis_angle_deg is None and not assumed_vertical,
               "axis_angle_from": angle_source, "elevation_deg": elevation_found, "clock": info.clock,
               "camera_from": camera_from}
    if config.segment:
        return _segmented(everything, angle, config, size_px, warnings, context)
    kept = None
    if config.keep_tracks:  # for pictures of the measurement (an overlay): numbered as the features
        kept = everything[["frame", "time_s", "track", "x_px", "y_px"]].assign(track=everything["track"] + 1)
    period = _repetition(thumbnails, config, info.clock_resolution_s)
    thumbnails.clear()
    try:
        body = _prepare_body(everything, angle, config)
    except NoResultError:
        if period is None:
            raise
        return _repetition_only(period, config, warnings, kept, context)
    focal = None
    # the lens is sought only where the tracks' rate is what is reported: a clip that repeats is
    # measured by its repetition, which needs no model of the camera (and the search costs
    # seconds on a 720p clip)
    if (config.find_focal and camera_from == "orthographic" and config.method == "fit" and not config.points_px
            and period is None):
        config, focal = _find_focal(everything, body, angle, config, size_px)
        if focal is not None:
            context["camera_from"] = "found"
            if math.isfinite(focal.focal_px):
                context["elevation_deg"] = focal.elevation_deg
    del everything  # the offsets hold what is needed: a long clip's positions need not stay
    release_free_memory()
    fixation, result, camera = _measure_body(body, angle, config, size_px)
    del body
    if focal is not None and math.isfinite(focal.focal_px) and result.combined.tracks_used > 0:
        result = _with_lens_doubt(result, focal, fixation, angle, config, size_px)
    if result.combined.tracks_used == 0 and period is not None:
        return _repetition_only(period, config, warnings, kept, context, result)
    doubts: tuple[str, ...] = ()
    if config.fixation_px is not None and period is None:  # the repetition's rate needs no axis
        doubt = _fixation_doubt(result, camera, fixation, angle, config, size_px)
        doubts = () if doubt is None else (doubt,)
    change = _rate_change(result, config, camera) if period is None else None
    if change is not None:
        doubts += (change,)
    series = None
    if config.window_s is not None:
        series = rate_series(result.offsets, config.window_s,
                             lambda part: rates_from_offsets(part, config.method, config.rejection, camera).combined)
    return _result(result, fixation_px=(float(fixation[0]), float(fixation[1])), method=_method_name(config, camera),
                   warnings=tuple(warnings), series=series, tracks=kept, focal=focal, period=period, doubts=doubts,
                   **context)


def _repetition(thumbnails: Thumbnails, config: AnalysisConfig, clock_resolution_s: float) -> Period | None:
    """The clip's repetition (:mod:`rotrate_cli.period`) where it can stand for the body's turn:
    the fit method on automatic points (chosen points and the paper's method are measured as
    they are; several bodies do not repeat as one)."""
    if config.method != "fit" or config.points_px or config.segment:
        return None
    return find_period(thumbnails.times_s, thumbnails.images, clock_resolution_s)


def _repetition_only(period: Period, config: AnalysisConfig, warnings: list[str], kept: pd.DataFrame | None,
                     context: dict[str, object], result: RateResult | None = None) -> Analysis:
    """The Analysis when no track gave a rate but the clip repeats: the rate is the repetition's,
    the sense of turning unknown."""
    features = result.features if result is not None else pd.DataFrame(columns=list(FEATURE_COLUMNS))
    offsets = result.offsets if result is not None else pd.DataFrame(
        {"track": pd.Series(dtype=int), "frame": pd.Series(dtype=int), "time_s": pd.Series(dtype=float),
         "offset_px": pd.Series(dtype=float)})
    empty = RateResult(offsets, features, Combined(math.nan, math.nan, math.nan, 0), "unknown")
    fixation = config.fixation_px if config.fixation_px is not None else (math.nan, math.nan)
    hint = ("; CSRT loses points that jump far between frames (stills taken far apart, fast turns): the default "
            "--tracker klt follows those") if config.tracker_kind == "csrt" else ""
    notes = [*warnings, "no track gave a rate: the rate is the clip's repetition alone, and the sense of turning "
             f"is unknown{hint}"]
    return _result(empty, fixation_px=(float(fixation[0]), float(fixation[1])), method=config.method,
                   warnings=tuple(notes), series=None, tracks=kept, focal=None, period=period, **context)


def _with_lens_doubt(result: RateResult, focal: FocalEstimate, fixation: tuple[float, float], angle_deg: float,
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
        camera = _camera(lens, size_px, fixation, angle_deg)
        rates_at_ends.append(rates_from_offsets(result.offsets, config.method, config.rejection, camera)
                             .combined.omega_rad_s)
    combined = result.combined
    low = float(np.nanmin([combined.omega_low_rad_s, *rates_at_ends]))
    high = float(np.nanmax([combined.omega_high_rad_s, *rates_at_ends]))
    return replace(result, combined=Combined(combined.omega_rad_s, low, high, combined.tracks_used))


def _find_focal(everything: pd.DataFrame, body: _Prepared, angle: float, config: AnalysisConfig,
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


def running_rate(analysis: Analysis, step_s: float | None = None) -> pd.DataFrame:
    """The rate as it would have been measured up to each time: ``time_s, omega_rad_s,
    omega_low_rad_s, omega_high_rad_s, tracks_used`` every ``step_s`` (default: a twentieth of
    the clip, at least half a second), from the analysis's own offsets and rules. NaN until
    enough of a turn has been seen."""
    offsets = analysis.offsets
    times = offsets["time_s"].to_numpy()
    first, last = float(times.min()), float(times.max())
    step = step_s if step_s is not None else max(0.5, (last - first) / 20.0)
    rows = []
    method = "paper" if analysis.method == "paper" else "fit"
    for end in np.arange(first + step, last + step / 2, step):
        part = offsets[times <= end]
        try:
            combined = rates_from_offsets(part, method, analysis.rejection).combined
        except (ValueError, IndexError):
            combined = Combined(math.nan, math.nan, math.nan, 0)
        rows.append((float(min(end, last)), combined.omega_rad_s, combined.omega_low_rad_s,
                     combined.omega_high_rad_s, combined.tracks_used))
    return pd.DataFrame(rows, columns=["time_s", "omega_rad_s", "omega_low_rad_s", "omega_high_rad_s",
                                       "tracks_used"])


def _method_name(config: AnalysisConfig, camera: rates.Camera | None) -> str:
    return config.method if camera is None else f"{config.method}+pinhole(f={camera.focal_px:.1f}px)"


@dataclass(frozen=True)
class _Prepared:
    """One body's tracks reduced to what the rate stages need (see :func:`_prepare_body`).

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


def _prepare_body(everything: pd.DataFrame, angle: float, config: AnalysisConfig) -> _Prepared:
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
    return _Prepared(fixation, base, axes.offsets_along(tracks, fixation, angle), positions)


def _measure_body(
    body: _Prepared, angle: float, config: AnalysisConfig, size_px: tuple[int, int]
) -> tuple[tuple[float, float], RateResult, rates.Camera | None]:
    """The rates of one prepared body, with its fixation refined when it was found."""
    fixation = body.fixation_px

    def measure(point: tuple[float, float]) -> tuple[RateResult, rates.Camera | None]:
        moved = body.positions is not None and point != fixation
        offset = axes.offsets_along(body.positions, point, angle) if moved else body.offsets_px
        offsets = body.base.assign(offset_px=offset)
        camera = _camera(config, size_px, point, angle)
        return rates_from_offsets(offsets, config.method, config.rejection, camera), camera

    result, camera = measure(fixation)
    release_free_memory()
    if config.fixation_px is None and config.method == "fit":
        fixation, result, camera = _refine_fixation(result, camera, fixation, angle, measure)
        change = _halves(result, config, camera)
        if change is not None and _changes(result.combined, *change):
            # a spinning-up body: one rate for all tracks misplaces the axis; the turn's angle
            # as it speeds up (from the halves' rates) does not. Once: measuring the halves again
            # about the moved axis and moving it again diverged (rendered cylinder 2.7 -> 19 px)
            fixation, result, camera = _refine_fixation(result, camera, fixation, angle, measure, spin_up=change)
    return fixation, result, camera


def _halves(result: RateResult, config: AnalysisConfig,
            camera: rates.Camera | None) -> tuple[Combined, Combined, float, float] | None:
    """The rates of the clip's first and second halves (same tracks, same rules) and the middle
    time of each; None where a half gives no rate."""
    if config.method != "fit" or result.combined.tracks_used < JOINT_MIN_TRACKS:
        return None
    times = result.offsets["time_s"].to_numpy()
    first, last = float(times.min()), float(times.max())
    middle = 0.5 * (first + last)
    halves = []
    for part in (times <= middle, times > middle):
        try:
            halves.append(rates_from_offsets(result.offsets[part], config.method, config.rejection, camera).combined)
        except (ValueError, IndexError):
            return None
    if not all(h.tracks_used > 0 and math.isfinite(h.omega_rad_s) for h in halves):
        return None
    return halves[0], halves[1], 0.5 * (first + middle), 0.5 * (middle + last)


def _changes(whole: Combined, early: Combined, late: Combined, *_: float) -> bool:
    """True when the halves' rates lie outside each other's intervals and more than
    :data:`CHANGE_FRACTION` of the whole's rate apart."""
    separate = late.omega_low_rad_s > early.omega_high_rad_s or early.omega_low_rad_s > late.omega_high_rad_s
    return separate and abs(late.omega_rad_s - early.omega_rad_s) > CHANGE_FRACTION * whole.omega_rad_s


def _rate_change(result: RateResult, config: AnalysisConfig, camera: rates.Camera | None) -> str | None:
    """A line saying the rate changes over the clip (see :func:`_changes`); None otherwise."""
    halves = _halves(result, config, camera)
    if halves is None or not _changes(result.combined, *halves):
        return None
    early, late = halves[0], halves[1]
    return (f"the rate changes over the clip: {early.omega_rad_s:.4g} rad/s in its first half, {late.omega_rad_s:.4g} "
            "in its second; the result is an average: see omega(t) with --window SECONDS")


def _fixation_doubt(result: RateResult, camera: rates.Camera | None, fixation: tuple[float, float],
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
    offsets = result.offsets[result.offsets["track"].isin(features.loc[inlier, "track"])]
    omega = result.combined.omega_rad_s
    if camera is not None:
        senses = features.loc[inlier, "sense"].to_numpy(dtype=float)
        omega *= (float(np.sign(np.nansum(senses))) if np.isfinite(senses).any() else 0.0) or 1.0
    shift = axes.refine_axis_offset(offsets, omega, camera)
    if not math.isfinite(shift) or abs(shift) < 2.0:
        return None
    ux, uy = axes.unit_offset(angle_deg)
    found = (fixation[0] + shift * ux, fixation[1] + shift * uy)
    moved = offsets.assign(offset_px=offsets["offset_px"].to_numpy() - shift)  # the inliers: memory
    again = rates_from_offsets(moved, config.method, config.rejection, _camera(config, size_px, found, angle_deg))
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


def _segmented(
    everything: pd.DataFrame, angle: float, config: AnalysisConfig, size_px: tuple[int, int],
    warnings: list[str], context: dict[str, object],
) -> Analysis:
    """Group the tracks into rigid bodies (:mod:`rotrate_cli.segment`) and measure each; the
    largest measured body is the analysis's headline result, all are in ``bodies``."""
    ux, uy = axes.unit_offset(angle)
    extent_px = abs(size_px[0] * ux) + abs(size_px[1] * uy)
    groups = segment_tracks(everything, axes.offsets_along(everything, (0.0, 0.0), angle), extent_px)
    track = everything["track"].to_numpy()
    measured = []
    for ids in groups:
        part = everything[np.isin(track, ids)].reset_index(drop=True)
        try:
            fixation, result, camera = _measure_body(_prepare_body(part, angle, config), angle, config, size_px)
        except NoResultError:
            continue
        if result.combined.tracks_used > 0:
            measured.append((fixation, result, camera, len(ids)))
    if not measured:
        raise NoResultError(f"no rigid body could be measured ({len(groups)} group(s) of tracks found); "
                            "try a longer clip or --roi around one object")
    skipped = len(groups) - len(measured)
    if skipped:
        warnings.append(f"{skipped} group(s) of tracks gave no trustworthy rate and are not reported")
    measured, folded = _distinct_bodies(measured, ux, uy, extent_px)
    if folded:
        warnings.append(f"{folded} smaller group(s) of tracks measured like a larger body (rate and axis within "
                        "the resolution) and are not reported as bodies of their own")
    bodies = tuple(
        Body(r.combined.omega_rad_s, r.combined.omega_low_rad_s, r.combined.omega_high_rad_s,
             (float(f[0]), float(f[1])), r.direction, r.combined.tracks_used, total)
        for f, r, _, total in measured
    )
    fixation, result, camera, _ = measured[0]
    return _result(result, fixation_px=(float(fixation[0]), float(fixation[1])), method=_method_name(config, camera),
                   warnings=tuple(warnings), series=None, bodies=bodies, **context)


def _distinct_bodies(measured: list, ux: float, uy: float, extent_px: float) -> tuple[list, int]:
    """The measured bodies (largest group first) without those whose measured rate and axis lie
    within the resolution of a larger one (:func:`rotrate_cli.segment.unresolved`), and how
    many were left out. Grouping works on each track's own rough estimates; a group of
    mis-tracks along an outline can look apart there and measure like the body it borders:
    seen on a 32 s 720p cylinder, 57 rim tracks (1% of them) measured 1.27 rad/s about an axis 8
    px from the body's 1.57."""
    kept: list = []
    for entry in measured:
        fixation, result = entry[0], entry[1]
        axis_px = fixation[0] * ux + fixation[1] * uy
        if not any(unresolved(result.combined.omega_rad_s, axis_px, other[1].combined.omega_rad_s,
                              other[0][0] * ux + other[0][1] * uy, extent_px) for other in kept):
            kept.append(entry)
    return kept, len(measured) - len(kept)


def _by_track(tracks: pd.DataFrame) -> pd.DataFrame:
    """``tracks`` sorted by track then frame (the tracker hands them over so: then as they are)."""
    track, frame = tracks["track"].to_numpy(), tracks["frame"].to_numpy()
    step = np.diff(track)
    if ((step > 0) | ((step == 0) & (np.diff(frame) > 0))).all():
        return tracks
    return tracks.sort_values(["track", "frame"], kind="stable").reset_index(drop=True)


def _across(angle_deg: float) -> bool:
    """True when an axis at ``angle_deg`` is nearer horizontal than vertical in the image."""
    return math.isfinite(angle_deg) and abs(angle_deg) > 45.0


def _path_shape(everything: pd.DataFrame, angle: float) -> axes.PathShape | None:
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


def _turned(tracker: TrackerConfig) -> TrackerConfig:
    """The tracker with its window turned a quarter: narrow across the motion again (see
    :class:`rotrate_cli.tracking.TrackerConfig`) when points move up and down the image."""
    return replace(tracker, win_width_px=tracker.win_height_px, win_height_px=tracker.win_width_px)


def _track(video: FrameSource, config: AnalysisConfig, tracker: TrackerConfig,
           progress: ProgressCallback | None, thumbnails: Thumbnails) -> TrackingRun:
    """Decode (in a background thread) and track the frames of ``video`` between start and end,
    keeping a thumbnail of each in ``thumbnails`` (for the repetition, :mod:`rotrate_cli.period`)."""
    info = video.info
    scale = tracking_scale(info.width_px, tracker)
    blur = tracker.blur_sigma_px
    if blur is None:
        blur = 0.0 if info.is_image_sequence else VIDEO_BLUR_SIGMA_PX
    # the luma table is known once the stream has read (and checked) its first frame
    frames = video.frames(config.start_s, config.end_s, grey=True, map_luma=False,
                          transform=lambda image: tracking_image(image, scale, blur, video.luma_levels()))
    expected = info.frame_count
    notify = None if progress is None else (lambda done, _time_s: progress(done, expected))
    size_px = (info.width_px, info.height_px)
    stream = thumbnails.tap(prefetch(frames))
    if config.points_px:
        return follow_points(stream, size_px, list(config.points_px), config.tracker_kind, tracker, notify)
    if config.tracker_kind == "csrt":
        return track_frames(stream, size_px, csrt_settings(tracker), notify, kind=CsrtTracker)
    return track_frames(stream, size_px, tracker, notify)


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
        inlier = result.features["inlier"]
        used = result.features.loc[inlier, "track"]
        offsets = result.offsets[result.offsets["track"].isin(used)]
        omega = result.combined.omega_rad_s
        if camera is not None:  # the pinhole model tells the sense: the rate is signed there
            senses = result.features.loc[inlier, "sense"].to_numpy(dtype=float)
            omega *= (float(np.sign(np.nansum(senses))) if np.isfinite(senses).any() else 0.0) or 1.0
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


def _result(rates_result: RateResult, period: Period | None = None, doubts: tuple[str, ...] = (),
            **context: object) -> Analysis:
    """The Analysis of a rate result, the clip's repetition (if any) and their context: the
    reported rate is judged from both (:func:`rotrate_cli.verdict.judge`), with ``doubts`` about
    the tracks' rate. NoResultError when neither gave a rate."""
    combined = rates_result.combined
    if combined.tracks_used == 0 and period is None:
        raise NoResultError(_no_result_message(rates_result.features))
    verdict = judge(combined if combined.tracks_used > 0 else None, period, combined.tracks_used, doubts)
    warnings = tuple(context.pop("warnings", ()))  # type: ignore[arg-type]
    warnings += verdict.notes
    if verdict.quality == "weak":
        warnings += ("weak evidence: " + "; ".join(verdict.weak_because),)
    return Analysis(
        omega_rad_s=verdict.omega_rad_s,
        omega_low_rad_s=verdict.omega_low_rad_s,
        omega_high_rad_s=verdict.omega_high_rad_s,
        direction=rates_result.direction,
        tracks_total=int(len(rates_result.features)),
        tracks_used=combined.tracks_used,
        features=rates_result.features,
        offsets=rates_result.offsets,
        warnings=warnings,
        verdict=verdict,
        period=period,
        **context,  # type: ignore[arg-type]
    )


def _rate_from_times(table: pd.DataFrame) -> float:
    """Frames per second implied by a tracks table's ``frame`` and ``time_s`` columns (NaN if unknown)."""
    pairs = table.drop_duplicates("frame").sort_values("frame")
    frame_steps = np.diff(pairs["frame"].to_numpy())
    time_steps = np.diff(pairs["time_s"].to_numpy())
    if len(frame_steps) == 0 or not (time_steps > 0).all():
        return math.nan
    return float(np.median(frame_steps / time_steps))


def analyze_tracks(
    tracks: pd.DataFrame,
    fixation: float,
    *,
    source: str = "tracks",
    fps: float | None = None,
    every: int = 1,
    method: str = "fit",
    rejection: RejectionConfig | None = None,
    position_unit: str = "units",
) -> Analysis:
    """Measure the rotation rate from given tracks (``track, frame, time_s, position``).

    ``fixation`` is the axis position in the positions' units. Times are ``frame / fps`` when
    ``fps`` is given, else the ``time_s`` column.

    Raises:
        InputError: no usable times, or bad options.
        NoResultError: no track gave a trustworthy rate.
    """
    _check_config(AnalysisConfig(fixation_px=(fixation, 0.0), fps=fps, every=every, method=method))
    if not math.isfinite(fixation):
        raise InputError("--fixation must be a number (the axis position in the tracks' units)")
    table = tracks.copy()
    given_fps = fps is not None
    if fps is not None:
        if not (fps > 0 and math.isfinite(fps)):
            raise InputError("--fps must be a positive number of frames per second")
        table["time_s"] = table["frame"] / fps
    elif table["time_s"].isna().any():
        raise InputError("the tracks have no time_s column; pass --fps")
    else:
        fps = _rate_from_times(table)
    if table.groupby("track")["time_s"].apply(lambda t: bool((np.diff(t.to_numpy()) <= 0).any())).any():
        raise InputError("times must increase along each track")
    offsets = thin(table, every).assign(offset_px=lambda t: t["position"] - fixation)
    # Given tracks are taken at their word: no tracker-jitter floor, and 5 samples (the fewest
    # that leave the three-parameter fit two degrees of freedom) are a track; published tracks
    # are often sparse keyframes (the dinosaur's: most span 5-7 views 10 degrees apart).
    rules = rejection if rejection is not None else RejectionConfig(min_samples=5, min_range=0.0, residual_floor=0.0,
                                                                                min_motion_ratio=0.0)
    result = rates_from_offsets(offsets[["track", "frame", "time_s", "offset_px"]], method, rules)
    return _result(result, source=source, fps=float(fps), frames=int(table["frame"].nunique()),
                   duration_s=float(table["time_s"].max() - table["time_s"].min()),
                   fixation_px=(float(fixation), math.nan), method=method, rejection=rules,
                   position_unit=position_unit, clock="fps" if given_fps else "tracks")
