"""The whole job in one call: :func:`analyze` for a video, :func:`analyze_tracks` for tracks.

A composition of stages, top to bottom: decode (a background thread, reduced grey frames, with a
thumbnail of each) -> tracks (:mod:`rotrate_cli.tracking`) -> the clip's repetition
(:mod:`rotrate_cli.period`) -> geometry: camera, axis angle, fixation (:mod:`rotrate_cli.geometry`)
-> fits (:mod:`rotrate_cli.fits`) -> the judged estimate (:mod:`rotrate_cli.verdict`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from functools import cached_property
from pathlib import Path

import numpy as np

from rotrate_cli import axis as axes
from rotrate_cli.chosen import follow_points
from rotrate_cli.config import AnalysisConfig, check_config
from rotrate_cli.csrt import CsrtTracker, csrt_settings
from rotrate_cli.decode import FrameSource, prefetch
from rotrate_cli.errors import InputError, NoResultError
from rotrate_cli.fits import (
    RateResult,
    no_result_message,
    rate_change,
    rates_from_offsets,
    sample_rates,
    thin,
)
from rotrate_cli.focal import FocalEstimate
from rotrate_cli.geometry import (
    MIN_TRACKS_FOR_ANGLE,
    across,
    find_focal,
    fixation_doubt,
    measure_body,
    method_name,
    path_shape,
    prepare_body,
    with_lens_doubt,
)
from rotrate_cli.lazy import pandas as pd
from rotrate_cli.memory import release_free_memory
from rotrate_cli.outliers import (
    FEATURE_COLUMNS,
    Combined,
    RejectionConfig,
)
from rotrate_cli.period import Period, Thumbnails, find_period
from rotrate_cli.reasons import name_rejections, track_places
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
from rotrate_cli.view import View, keep_for_view, rate_from_paths, view_from_paths

#: Progress callback: (frames done, frames expected or None).
ProgressCallback = Callable[[int, int | None], None]
StageCallback = Callable[[str], None]


DIRECTIONS = ("ccw", "cw", "unknown")


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
        view: the view read from the tracks' paths at the reported rate (the axis's elevation
            out of the image plane, the turning centre; :mod:`rotrate_cli.view`), or None where
            too few tracks follow a turning path to tell.

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
    view: View | None = None

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


def analyze(source: str | Path, config: AnalysisConfig, progress: ProgressCallback | None = None,
            stage: StageCallback | None = None) -> Analysis:
    """Measure the rotation rate of the object in a video or image sequence.

    ``progress(frames_done, frames_expected)`` is called as frames are tracked; ``stage(text)``
    when the run moves on from tracking to the fits (which take a while on long clips).

    Raises:
        InputError: bad source or options.
        NoResultError: the video was read but no track gave a trustworthy rate.
    """
    check_config(config)
    try:
        return _analyze(source, config, progress, stage)
    except NoResultError as error:
        if (config.every or 1) > 1 and " short" in str(error):
            raise NoResultError(f"{error}; --every {config.every} keeps one frame in {config.every}, which leaves "
                                "these tracks too few samples to fit: try a smaller --every") from error
        if config.tracker_kind == "csrt" and not config.points_px:
            raise NoResultError(f"{error}; CSRT loses points that jump far between frames (stills taken "
                                "far apart, fast turns): the default --tracker klt follows those") from error
        raise


def _analyze(source: str | Path, config: AnalysisConfig, progress: ProgressCallback | None,
             stage: StageCallback | None = None) -> Analysis:
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
    if config.axis_angle_deg is not None and across(config.axis_angle_deg):
        tracker = _turned(tracker)
    thumbnails = Thumbnails()
    run = _track(video, config, tracker, progress, thumbnails)
    count = run.frames
    if count == 0:
        raise InputError(f"no frame of {source} lies between --start and --end")
    if count < 3:
        raise InputError(f"{source} has only {count} frame(s) to analyse; rotation needs at least 3")
    if run.tracks.empty and thumbnails.lifeless_fraction() >= LIFELESS and video.use_ffmpeg():
        # OpenCV's trouble with interlaced streams: black frames, or one frozen garbled picture;
        # it strikes some openings of a file and not others, so it is caught here too
        thumbnails.clear()
        run = _track(video, config, tracker, progress, thumbnails)
        count = run.frames
    if run.tracks.empty:
        hint = ("if the video shows motion, it is probably interlaced (camcorder, broadcast, DV), which this OpenCV "
                "cannot decode: deinterlace it (ffmpeg -i IN -vf yadif OUT.mp4) or pip install 'rotrate[ffmpeg]'")
        if thumbnails.black_fraction() >= LIFELESS:
            raise InputError(f"the frames of {source} decode black: {hint}")
        if thumbnails.lifeless_fraction() >= LIFELESS:
            raise NoResultError(f"no point could be tracked: the picture does not change from frame to frame; {hint}")
        raise NoResultError(no_result_message(pd.DataFrame(columns=["reason"])))
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
        if across(angle):
            # the motion runs up and down the image: track again with the window turned to suit it
            thumbnails.clear()
            run = _track(video, config, _turned(tracker), progress, thumbnails)
            if run.tracks.empty:
                raise NoResultError(no_result_message(pd.DataFrame(columns=["reason"])))
            everything = _by_track(run.tracks)
            angle = axes.motion_angle_deg(everything)
        angle = angle if math.isfinite(angle) else 0.0
        if config.angle_from == "paths":
            shape = path_shape(everything, angle)
            if shape is None:
                warnings_early.append("too few tracks turned far enough to read the axis from their paths: "
                                      "it is found from the motion")
                angle_source = "motion"
            else:
                angle, elevation_found = shape.angle_deg, shape.elevation_deg
                if config.elevation_deg is None:
                    config = replace(config, elevation_deg=elevation_found)
    if stage is not None:
        stage("fitting the tracks")
    # the decoder may have learnt something while it read (a stream OpenCV decodes black)
    warnings_early += [warning for warning in video.warnings if warning not in warnings_early]
    warnings = list(run.notes) + warnings_early
    if assumed_vertical:
        warnings.append("too few tracks to find the axis's angle: taken as vertical (give --axis-angle DEG)")
    if config.start_s == 0 and config.end_s is None:
        short = video.shortfall(count, run.last_time_s)
        if short is not None:
            warnings.append(short)

    duration_s = run.last_time_s - run.first_time_s
    del run
    size_px = (info.width_px, info.height_px)
    context = {"source": str(source), "fps": info.fps, "frames": count, "duration_s": duration_s,
               "rejection": config.rejection, "axis_angle_deg": float(angle),
               "axis_found": config.fixation_px is None,
               "axis_angle_found": config.axis_angle_deg is None and not assumed_vertical,
               "axis_angle_from": angle_source, "elevation_deg": elevation_found, "clock": info.clock,
               "camera_from": camera_from}
    if config.every is None:
        config = replace(config, every=_sample_spacing(everything, angle, config.method))
    if config.segment:
        return _segmented(everything, angle, config, size_px, warnings, context)
    kept = None
    if config.keep_tracks:  # for pictures of the measurement (an overlay): numbered as the features
        kept = everything[["frame", "time_s", "track", "x_px", "y_px"]].assign(track=everything["track"] + 1)
    period = _repetition(thumbnails, config, info.clock_resolution_s)
    thumbnails.clear()
    view_tracks = keep_for_view(everything)  # the view is read at the rate reported, once it is known
    places = track_places(everything)  # where each track lies: to name why the rejected were
    try:
        body = prepare_body(everything, angle, config)
    except NoResultError:
        if period is None:
            raise
        return _with_view(_repetition_only(period, config, warnings, kept, context), view_tracks, config, size_px)
    focal = None
    # the lens is sought only where the tracks' rate is what is reported: a clip that repeats is
    # measured by its repetition, which needs no model of the camera (and the search costs
    # seconds on a 720p clip)
    if (config.find_focal and camera_from == "orthographic" and config.method == "fit" and not config.points_px
            and period is None):
        config, focal = find_focal(everything, body, angle, config, size_px)
        if focal is not None:
            context["camera_from"] = "found"
            if math.isfinite(focal.focal_px):
                context["elevation_deg"] = focal.elevation_deg
    del everything  # the offsets hold what is needed: a long clip's positions need not stay
    release_free_memory()
    fixation, result, camera = measure_body(body, angle, config, size_px, steady=period is not None)
    del body
    result = replace(result, features=name_rejections(result.features, places, fixation, angle,
                                                      result.combined.omega_rad_s, result.offsets))
    if focal is not None and math.isfinite(focal.focal_px) and result.combined.tracks_used > 0:
        result = with_lens_doubt(result, focal, fixation, angle, config, size_px)
    if result.combined.tracks_used == 0 and period is not None:
        return _with_view(_repetition_only(period, config, warnings, kept, context, result), view_tracks, config,
                          size_px)
    doubts: tuple[str, ...] = ()
    if config.fixation_px is not None and period is None:  # the repetition's rate needs no axis
        doubt = fixation_doubt(result, camera, fixation, angle, config, size_px)
        doubts = () if doubt is None else (doubt,)
    change = rate_change(result, config, camera) if period is None else None
    if change is not None:
        doubts += (change,)
    series = None
    if config.window_s is not None and config.window_s > duration_s:
        raise InputError(f"--window {config.window_s:g} s is longer than the {duration_s:.2f} s analysed; give a "
                         "window shorter than the clip (a few seconds, about a quarter turn or more)")
    if config.window_s is not None:
        series = rate_series(result.offsets, config.window_s,
                             lambda part: rates_from_offsets(part, config.method, config.rejection, camera).combined)
    if period is None and result.combined.tracks_used > 0:
        result, note = _with_paths_rate(result, view_tracks)
        warnings += [note] if note else []
    analysis = _result(result, fixation_px=(float(fixation[0]), float(fixation[1])),
                       method=method_name(config, camera), warnings=tuple(warnings), series=series, tracks=kept,
                       focal=focal, period=period, doubts=doubts, **context)
    return _with_view(analysis, view_tracks, config, size_px)


def _with_paths_rate(result: RateResult, view_tracks: pd.DataFrame) -> tuple[RateResult, str | None]:
    """Seen obliquely or face on, the result with its interval widened to hold the rate of the
    tracks' paths in both image coordinates (:func:`rotrate_cli.view.rate_from_paths`), and a
    note saying so; as it was in a side view, or where the two agree. The offsets across one
    image direction assume the paths' centres line up across it, which an axis leaning towards
    the camera breaks (rendered box from 60 degrees above: -2.5%, interval [-4.7%, -0.3%]; its
    paths: +0.6%)."""
    combined = result.combined
    view = view_from_paths(view_tracks, combined.omega_rad_s)
    if view is None or view.name == "side":
        return result, None
    paths = rate_from_paths(view_tracks, combined.omega_rad_s) * (1.0 if combined.omega_rad_s >= 0 else -1.0)
    if not math.isfinite(paths) or combined.omega_low_rad_s <= paths <= combined.omega_high_rad_s:
        return result, None
    widened = Combined(combined.omega_rad_s, min(combined.omega_low_rad_s, paths),
                       max(combined.omega_high_rad_s, paths), combined.tracks_used)
    note = (f"seen {view.name} ({view.elevation_deg:.0f} deg), the tracks' paths fitted in both image coordinates "
            f"give {paths:.4g} rad/s, outside the offsets' interval: the interval is widened to hold it")
    return replace(result, combined=widened), note


def _with_view(analysis: Analysis, view_tracks: pd.DataFrame, config: AnalysisConfig,
               size_px: tuple[int, int]) -> Analysis:
    """The analysis with the view read from the tracks' paths at its reported rate
    (:mod:`rotrate_cli.view`). Where the rate is the clip's repetition and the fixation was to
    be found, the found fixation is the paths' turning centre: the tracks' own axis search
    assumes a side view (on the record clip it put the spindle 380 px off; the paths' centre is
    25 px off, and 37 px off where the picture is cropped to leave the spindle outside it)."""
    view = view_from_paths(view_tracks, analysis.omega_rad_s)
    if view is None:
        return analysis
    changes: dict[str, object] = {"view": view}
    if math.isnan(analysis.elevation_deg):
        changes["elevation_deg"] = view.elevation_deg
    if config.fixation_px is None and analysis.rate_from == "repetition":
        changes["fixation_px"] = view.centre_px
        x, y = view.centre_px
        if not (0 <= x <= size_px[0] - 1 and 0 <= y <= size_px[1] - 1):
            changes["warnings"] = (*analysis.warnings, f"the axis found, ({x:.0f}, {y:.0f}), lies outside the "
                                   f"{size_px[0]}x{size_px[1]} frame")
    return replace(analysis, **changes)


#: A run whose frames are this often black, or the same as the one before pixel for pixel, got
#: nothing from its decoder (see :meth:`rotrate_cli.period.Thumbnails.lifeless_fraction`).
LIFELESS = 0.5


#: The paper's method differentiates positions this far apart in angle (its 16 frames at 30 fps
#: of a car turning at 0.327 rad/s): closer, its second differences are noise (+201% at --every 1).
PAPER_SPACING_RAD = 1.0 / 6.0


def _sample_spacing(everything: pd.DataFrame, angle_deg: float, method: str) -> int:
    """``--every`` when not given: 1 for the fit method; for the paper's, the frames that make
    :data:`PAPER_SPACING_RAD` at a first rate from the tracks (the recurrence), at least 1."""
    if method != "paper":
        return 1
    omega = axes.rate_from_recurrence(everything, axes.offsets_along(everything, (0.0, 0.0), angle_deg))
    times = everything.drop_duplicates("frame")["time_s"].to_numpy()
    step_s = float(np.median(np.diff(np.sort(times)))) if len(times) > 1 else math.nan
    if not (math.isfinite(omega) and omega > 0 and math.isfinite(step_s) and step_s > 0):
        return 1
    return max(1, round(PAPER_SPACING_RAD / (omega * step_s)))


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
            fixation, result, camera = measure_body(prepare_body(part, angle, config), angle, config, size_px)
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
    return _result(result, fixation_px=(float(fixation[0]), float(fixation[1])), method=method_name(config, camera),
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


def _result(rates_result: RateResult, period: Period | None = None, doubts: tuple[str, ...] = (),
            **context: object) -> Analysis:
    """The Analysis of a rate result, the clip's repetition (if any) and their context: the
    reported rate is judged from both (:func:`rotrate_cli.verdict.judge`), with ``doubts`` about
    the tracks' rate. NoResultError when neither gave a rate."""
    combined = rates_result.combined
    if combined.tracks_used == 0 and period is None:
        raise NoResultError(no_result_message(rates_result.features))
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
    every: int | None = 1,
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
    every = 1 if every is None else every  # given tracks are taken as sampled
    check_config(AnalysisConfig(fixation_px=(fixation, 0.0), fps=fps, every=every, method=method))
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
