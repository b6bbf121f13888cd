"""The whole job in one call: :func:`analyze` for a video, :func:`analyze_tracks` for tracks.

A composition of the stages of :mod:`rotrate_cli.stages`, top to bottom, in the order that
package lists them: tracks, period, geometry (camera, fits), checks, verdict, the view at the
reported rate, and omega(t)'s windows.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field, replace
from functools import cached_property
from pathlib import Path

import numpy as np

from rotrate_cli.config import AnalysisConfig, check_config
from rotrate_cli.errors import InputError, NoResultError
from rotrate_cli.fitting.camera import Camera
from rotrate_cli.fitting.orbits import TurningGroup, turning_groups
from rotrate_cli.fitting.outliers import FEATURE_COLUMNS, Combined, RejectionConfig
from rotrate_cli.fitting.segment import Body
from rotrate_cli.fitting.series import rate_series, window_centres
from rotrate_cli.runtime.lazy import pandas as pd
from rotrate_cli.runtime.memory import release_free_memory
from rotrate_cli.runtime.pools import pipeline_threads
from rotrate_cli.scene.focal import FocalEstimate
from rotrate_cli.scene.picture_angle import PictureAngle
from rotrate_cli.scene.plane_turn import keep_for_plane
from rotrate_cli.scene.reasons import against_rate, name_rejections, on_plane, track_places
from rotrate_cli.scene.sense import not_side_view, sense_of_turning
from rotrate_cli.scene.turning import PictureTurning, picture_turning
from rotrate_cli.scene.view import View, keep_for_view, view_from_paths
from rotrate_cli.stages.angle import angle_windows, picture_angle
from rotrate_cli.stages.bodies import another_body_seen, measure_bodies
from rotrate_cli.stages.camera import lens_from, method_name
from rotrate_cli.stages.checks import Checked, check_rate
from rotrate_cli.stages.fits import (
    RateResult,
    decided_sense,
    no_result_message,
    rates_from_offsets,
    running_measure,
    sample_rates,
    sample_spacing,
    thin,
    with_sense,
)
from rotrate_cli.stages.geometry import Geometry, locate, measure
from rotrate_cli.stages.period import Period, Thumbnails, find_period
from rotrate_cli.stages.roll import roll_note, sway_note, turned_back_positions, unsteady_camera_period, zoom_note
from rotrate_cli.stages.tracks import NO_BACKGROUND_NOTE, Footage, NothingTracked, ProgressCallback, read_footage
from rotrate_cli.stages.verdict import Verdict, judge, turns_between
from rotrate_cli.stages.view_at_rate import view_at_rate
from rotrate_cli.stages.windows import judged_series
from rotrate_cli.tracking.steady import CameraPath, Shake

__all__ = ["Analysis", "AnalysisConfig", "ProgressCallback", "analyze", "analyze_tracks", "rates_from_offsets",
           "thin"]

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
        direction: ``ccw``, ``cw`` or ``unknown``: seen from the top end of the axis, or as the
            picture shows it (``direction_in_picture``).
        tracks_total, tracks_used: tracks found, and tracks that went into the result.
        features: one row per track (see :data:`rotrate_cli.fitting.outliers.FEATURE_COLUMNS`).
        offsets: one row per track per sample: ``track, frame, time_s, offset_px``.
        rejection: the thresholds the verdicts used.
        warnings: things the user should know that did not stop the run.
        position_unit: the unit of positions and offsets (``px`` for videos).
        axis_angle_deg: the axis's angle in the image (0 vertical, positive: top end right).
        axis_found: True when the fixation point was found from the tracks.
        axis_angle_found: True when the angle was found from the tracks.
        axis_angle_from: how it was found (``motion``, ``paths`` or ``lens``, with the lens found
            from the tracks; see ``AnalysisConfig.angle_from``).
        elevation_deg: the camera's elevation found from the paths (``paths``) or with the
            focal length (``find_focal``); NaN otherwise.
        focal: with ``find_focal``, what the tracks said about the camera; None otherwise.
        series: omega(t) over a sliding window (see :mod:`rotrate_cli.fitting.series`), or None.
        bodies: with ``segment``, every rigid body measured, the headline one (most tracks)
            first; None otherwise.
        tracks: with ``keep_tracks``, the positions ``frame, time_s, track, x_px, y_px`` on
            the frames as they are (a shaken camera's too)
            (tracks numbered as the features); None otherwise.
        verdict: how the reported rate was judged from the tracks and the clip's repetition,
            and its quality (``good``/``weak``; see :mod:`rotrate_cli.stages.verdict`).
        period: the clip's repetition (:mod:`rotrate_cli.stages.period`), or None where none was seen.
        clock: where the frame times came from (``container``, ``fps``, ``exif``, ``times file``;
            ``tracks`` for given tracks).
        camera_from: the camera model used: ``orthographic`` (the paper's), ``given`` (``--fov``
            or ``--focal-px``), ``exif`` (the photographs' lens) or ``found`` (``--fov auto``).
        view: the view read from the tracks' paths at the reported rate (the axis's elevation
            out of the image plane, the turning centre; :mod:`rotrate_cli.scene.view`), or None where
            too few tracks follow a turning path to tell.
        camera: the pinhole model the tracks' rates were measured through, or None
            (orthographic).
        shake: a hand-held camera's shake, taken out of the tracks (:mod:`rotrate_cli.tracking.steady`);
            None where none showed.
        camera_path: that camera's path, frame by frame (the fixation is where it stood at the first
            frame); None where none showed.
        direction_in_picture: True when the sense of turning is the one the tracks go round the
            fixation in the picture (a view from above or face on: :mod:`rotrate_cli.scene.sense`).
        camera_turn_deg_s: the camera's own turn, degrees a second (anticlockwise as the picture
            shows it), measured and taken out before the rate: from the picture around a turning
            plane (:mod:`rotrate_cli.scene.backdrop`) or the roll the return needed taken out; 0
            where none was. The view is then not read from the tracks' paths, which carry it.
        other_body: another body seen turning at another rate about another axis
            (:func:`rotrate_cli.stages.bodies.another_body_seen`), or None.

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
    camera: Camera | None = None
    shake: Shake | None = None
    camera_path: CameraPath | None = None
    direction_in_picture: bool = False
    camera_turn_deg_s: float = 0.0
    other_body: TurningGroup | None = None

    @property
    def quality(self) -> str:
        """``good``, or ``weak`` when the evidence is weak (see :mod:`rotrate_cli.stages.verdict`)."""
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
    as the run moves on to each later stage (the axis, the fits, their checks, the verdict: each
    can take a while on a long clip).

    Raises:
        InputError: bad source or options.
        NoResultError: the video was read but no track gave a trustworthy rate.
    """
    check_config(config)
    try:
        with pipeline_threads():
            return _analyze(source, config, progress, stage)
    except NoResultError as error:
        if (config.every or 1) > 1 and " short" in str(error):
            raise NoResultError(f"{error}; `every={config.every}` keeps one frame in {config.every}, which leaves "
                                "these tracks too few samples to fit: try a smaller `every`") from error
        if config.tracker_kind == "csrt" and not config.points_px:
            raise NoResultError(f"{error}; CSRT loses points that jump far between frames (stills taken "
                                "far apart, fast turns): the default `tracker_kind='auto'` follows those") from error
        raise


#: Matched features' tracks (photographs far apart) are fitted from this many samples.
MATCHED_MIN_SAMPLES = 5


def _analyze(source: str | Path, config: AnalysisConfig, progress: ProgressCallback | None,
             stage: StageCallback | None) -> Analysis:
    try:
        footage = read_footage(source, config, progress)
    except NothingTracked as error:
        # no point followed (a blurred disc, thin spokes): the picture's own turning may still tell
        if config.method != "fit" or config.points_px or config.segment:
            raise
        if stage is not None:
            stage("measuring the picture's turning")
        try:
            return _repetition_only(error.footage, None, config, None, None)
        except NoResultError:
            # (a record tilted 65 degrees, a third of a turn at 9 degrees a frame: nothing followed,
            # and "check that the object moves and has texture" alone misled)
            raise NoResultError(f"{error}; the picture's own turning, measured without tracks, told no rate "
                                "either") from None
    if footage.matched and config.rejection == RejectionConfig():
        # features matched photograph to photograph: short tracks, sampled sparsely on the turn,
        # are fitted from 5 samples (as given tracks are, :func:`analyze_tracks`): the dinosaur's
        # first 9, 14 and 18 photographs read -0.7%, -1.1% and -0.4% from 6, within 1% from 5
        config = replace(config, rejection=replace(config.rejection, min_samples=MATCHED_MIN_SAMPLES))
    if stage is not None:
        stage("placing the axis and the lens")
    if config.window_s is not None and config.window_s > footage.duration_s:
        raise InputError(f"`window_s={config.window_s:g}` s is longer than the {footage.duration_s:.2f} s analysed; "
                         "give a window shorter than the clip (a few seconds, about a quarter turn or more)")
    tracks = footage.tracks
    if config.every is None:
        config = replace(config, every=sample_spacing(tracks, _angle_guess(footage, config), config.method))
    size_px = (footage.info.width_px, footage.info.height_px)
    if config.segment:
        return _segmented(footage, config)
    # the tracks' orbits, while the tracks are held: where another body turns, whichever measurement rates one
    groups = turning_groups(tracks, size_px)
    with ThreadPoolExecutor(max_workers=1, thread_name_prefix="rotrate-repetition") as pool:
        # the clip's repetition (from the thumbnails alone) is worked out beside the axis's search
        # and the first fit, on the core that decoding left idle: it is first wanted where the
        # lens is chosen, else where a found axis is moved (the first fit does not wait for it)
        repetition = pool.submit(_repetition, footage.thumbnails, footage.info.clock_resolution_s, config,
                                 footage.background_unseen)
        kept = _kept_tracks(tracks, footage.camera) if config.keep_tracks else None
        view_tracks = keep_for_view(tracks)  # the view is read at the rate reported, once it is known
        places = track_places(tracks)  # where each track lies: to name why the rejected were
        try:
            # a rate from the repetition needs no lens
            geometry, body = locate(tracks, footage.motion_angle_deg, config, footage.info,
                                    seek_lens=lambda: repetition.result() is None, keyframes=footage.keyframes)
        except NoResultError:
            if repetition.result() is None and config.method != "fit":
                raise
            return _heeding(groups, config, _repetition_only(footage, repetition.result(), config, kept,
                                                             view_tracks))
        # the lens is found: of the tracker's images, those the plane's turning places its tracks on stay
        plane_tracks = keep_for_plane(tracks, footage.keyframes.indices())
        footage.keyframes.keep_only(plane_tracks["frame"].unique())
        footage = replace(footage, tracks=tracks.iloc[:0], plane_tracks=plane_tracks)
        del tracks  # the offsets hold what is needed: a long clip's positions need not stay
        release_free_memory()
        if stage is not None:
            stage("fitting the tracks")
        geometry, result = measure(body, geometry, config, size_px, steady=lambda: repetition.result() is not None)
        period = repetition.result()
    del body
    result = replace(result, features=name_rejections(result.features, places, geometry.fixation_px,
                                                      geometry.axis_angle_deg, result.combined.omega_rad_s,
                                                      result.offsets))
    if stage is not None:
        stage("checking the rate")
    checked = check_rate(result, geometry, config, size_px, view_tracks, repeating=period is not None,
                         clock_resolution_s=footage.info.clock_resolution_s, fps=footage.info.fps)
    if checked.result.combined.tracks_used == 0 and (period is not None or config.method == "fit"):
        footage.thumbnails.clear()
        return _heeding(groups, config, _repetition_only(footage, period, config, kept, view_tracks, checked.result,
                                                         geometry))
    series = None
    if config.window_s is not None:
        series = rate_series(checked.result.offsets, config.window_s,
                             running_measure(config.method, config.rejection,
                                             with_sense(geometry.camera(size_px), decided_sense(checked.result))))
    if stage is not None:
        stage("weighing the tracks, the return and the picture's turning")
    try:
        return _heeding(groups, config, _result(footage, config, geometry, checked, period, view_tracks,
                                                series=series, tracks=kept))
    finally:
        footage.thumbnails.clear()
        footage.keyframes.clear()


def _heeding(groups: tuple[TurningGroup, ...], config: AnalysisConfig, analysis: Analysis) -> Analysis:
    """``analysis`` told of another body turning in the picture (:func:`rotrate_cli.stages.bodies.another_body_seen`),
    and weak for it where its axis was found, not given."""
    seen = another_body_seen(groups, analysis.omega_rad_s, analysis.fixation_px, config.fixation_px is not None)
    if seen is None or analysis.verdict is None:
        return analysis
    verdict = analysis.verdict
    warnings = tuple(warning for warning in analysis.warnings if not warning.startswith("weak evidence: "))
    if seen.weak_because:
        verdict = replace(verdict, quality="weak", weak_because=(*verdict.weak_because, seen.weak_because))
    warnings += (seen.note,)
    if verdict.quality == "weak":
        warnings += ("weak evidence: " + "; ".join(verdict.weak_because),)
    return replace(analysis, verdict=verdict, warnings=warnings, other_body=seen.group)


def _picture_turning(footage: Footage, geometry: Geometry, view_tracks: pd.DataFrame | None,
                     period: Period) -> PictureTurning | None:
    """The picture's own turning among the rates the return allows (:mod:`rotrate_cli.scene.turning`),
    about the centre and through the ellipse of the tracks' paths at the return's rate where they
    tell them (a tilted disc), else about the fixation, face on; None in a side view."""
    rate = period.omega_rad_s()[0]
    view = view_from_paths(view_tracks, rate) if view_tracks is not None else None
    if view_tracks is None or not not_side_view(view, view_tracks):
        return None  # seen from the side the picture does not turn: a test of its turning says nothing
    roll = (footage.pairs.roll_deg_s, footage.pairs.roll_start_s)
    if view is None:
        return picture_turning(footage.pairs.pairs, geometry.fixation_px, footage.info.width_px, rate, roll=roll)
    ellipse = (view.across_deg, math.sin(math.radians(view.elevation_deg)))
    return picture_turning(footage.pairs.pairs, view.centre_px, footage.info.width_px, rate, ellipse, roll)


def _angle_guess(footage: Footage, config: AnalysisConfig) -> float:
    """The axis's angle before the geometry stage: for the paper's sample spacing."""
    if config.axis_angle_deg is not None:
        return config.axis_angle_deg
    return footage.motion_angle_deg if math.isfinite(footage.motion_angle_deg) else 0.0


def _kept_tracks(tracks: pd.DataFrame, camera: CameraPath | None = None) -> pd.DataFrame:
    """The positions for pictures of the measurement (an overlay), numbered as the features, where
    the camera saw them (a shaken camera's own frames)."""
    kept = tracks[["frame", "time_s", "track", "x_px", "y_px"]].assign(track=tracks["track"] + 1)
    return kept if camera is None else camera.seen(kept)


def _repetition(thumbnails: Thumbnails, clock_resolution_s: float, config: AnalysisConfig,
                background_unseen: bool = False) -> Period | None:
    """The clip's repetition (:mod:`rotrate_cli.stages.period`) where it can stand for the body's turn:
    the fit method on automatic points (chosen points and the paper's method are measured as
    they are; several bodies do not repeat as one). Given the thumbnails alone, not the footage,
    so that the tracks can be let go of while it runs. Where none is found and no still
    background shows the camera's motion (``background_unseen``), it is sought with a steady
    roll of the camera taken out, or allowing the camera a sway (:mod:`rotrate_cli.stages.roll`)."""
    if config.method != "fit" or config.points_px or config.segment:
        return None
    found = find_period(thumbnails.times_s, thumbnails.images, clock_resolution_s)
    if background_unseen and thumbnails.shape is not None:
        found = unsteady_camera_period(thumbnails.times_s, thumbnails.images, thumbnails.shape, clock_resolution_s,
                                       found)
    return found


def _result(footage: Footage, config: AnalysisConfig, geometry: Geometry, checked: Checked, period: Period | None,
            view_tracks: pd.DataFrame | None, notes: tuple[str, ...] = (), **extra: object) -> Analysis:
    """The Analysis: the reported rate judged from the checked tracks' rate and the clip's
    repetition (:func:`rotrate_cli.stages.verdict.judge`), and the view read at it. NoResultError when
    neither gave a rate."""
    result = checked.result
    combined = result.combined
    tracks_rate = combined if combined.tracks_used > 0 else None
    if period is not None and period.roll_deg_s:
        # the camera rolled (the picture came back only with that taken out): the picture's
        # turning is read with it taken out too, about an axis that then stays put, and so are
        # the tracks' paths that tell its view
        if view_tracks is not None:
            view_tracks = turned_back_positions(view_tracks, period.roll_deg_s, footage.pairs.start_s,
                                                (footage.info.width_px, footage.info.height_px))
        footage = replace(footage, pairs=footage.pairs.turned_back(period.roll_deg_s))
    if period is not None and (period.roll_deg_s or period.sway_deg or period.zoom_share):
        # the tracks, followed in the rolling, swaying or zooming picture with nothing still to take
        # the camera's motion out of them, are no evidence of the count of returns a turn (the rolled
        # record's first 12 s: three tracks on its sliding label told 2, and the result was half
        # the truth, its interval missing)
        tracks_rate = None
    measured: dict[str, PictureAngle | None] = {}

    def measured_angle() -> PictureAngle | None:  # once, for the verdict and omega(t)
        if "angle" not in measured:
            measured["angle"] = picture_angle(footage, geometry, view_tracks, tracks_rate)
        return measured["angle"]

    angle: PictureAngle | None | Callable[[], PictureAngle | None] = measured_angle
    if combined.tracks_used == 0 and period is None:
        # no track and no return: the picture's own turning alone, where it tells a rate
        angle = picture_angle(footage, geometry, view_tracks, None) if config.method == "fit" else None
        if angle is None and result.features.empty and config.method == "fit":
            # points were followed, but too few or too briefly to place the axis (a record tilted 65
            # degrees, a third of a turn at 9 degrees a frame): not "no point could be tracked"
            raise NoResultError("too few points were followed long enough to place the axis, and the picture's own "
                                "turning told no rate; try a longer clip, or `roi` around the object")
        if angle is None:
            raise NoResultError(no_result_message(result.features))
        measured["angle"] = angle
    if period is not None:
        period = turns_between(period, tracks_rate, combined.tracks_used)
    verdict = judge(tracks_rate, period, combined.tracks_used, checked.doubts,
                    turning=lambda: _picture_turning(footage, geometry, view_tracks, period), angle=angle)
    if period is not None and verdict.turns_spanned > 1:  # the return found spans several turns
        period = period.over(verdict.turns_spanned * period.turns_between)
    if verdict.rate_from == "turning" and measured.get("angle") is not None:
        # the axis the rate was measured about: the picture's turning's, not the tracks'
        geometry = replace(geometry, fixation_px=measured["angle"].view.centre_px)  # type: ignore[union-attr]
    features, tracks_used = result.features, combined.tracks_used
    reading = measured.get("angle")
    if verdict.rate_from == "turning" and verdict.plane and reading is not None:
        # the tracks on the plane stand behind its rate, whatever their one-point fits read
        features = on_plane(features, reading.plane_tracks, verdict.omega_rad_s)
        tracks_used = int(features["inlier"].sum())
    elif verdict.rate_from in ("repetition", "turning"):  # the tracks shown as used are those that agree with it
        features = against_rate(features, verdict.omega_rad_s)
        tracks_used = int(features["inlier"].sum())
    if isinstance(extra.get("series"), pd.DataFrame):
        extra["series"] = judged_series(extra["series"], verdict, footage.thumbnails,  # type: ignore[arg-type]
                                        footage.info.clock_resolution_s, config.window_s or 0.0,
                                        angle_windows(footage, measured_angle),
                                        roll_deg_s=period.roll_deg_s if period is not None else 0.0,
                                        sway_deg=period.sway_deg if period is not None else 0.0,
                                        zoom_share=period.zoom_share if period is not None else 0.0)
    footage.pairs.clear()
    size_px = (footage.info.width_px, footage.info.height_px)
    direction, in_picture = result.direction, False
    if view_tracks is not None:
        geometry = view_at_rate(geometry, view_tracks, verdict.omega_rad_s, verdict.rate_from, size_px)
        direction, in_picture = sense_of_turning(direction, geometry.view, view_tracks, geometry.fixation_px,
                                                 verdict.omega_rad_s)
    if verdict.rate_from == "turning" and verdict.plane and reading is not None:
        # the tracks' plane tells its sense as the picture shows it, through any view (its paths
        # about the axis tell none where the view read at the rate is near the side: a disc tilted
        # 60 degrees, its axis below the frame, read clockwise from the side-view rule, turning anticlockwise)
        direction, in_picture = ("ccw" if reading.sense > 0 else "cw"), True
    checks = checked.notes
    if verdict.rate_from == "turning" and (checks or checked.doubts):
        # the tracks' own checks and doubts are of a rate not reported
        checks = (f"the tracks' own rate ({combined.omega_rad_s:.4g} rad/s) is not the one reported; "
                  f"{len(checks) + len(checked.doubts)} check(s) of it are left out",)
    warnings = footage.warnings + geometry.notes + notes + checks + verdict.notes
    if (period is not None and (period.roll_deg_s or period.sway_deg or period.zoom_share)
            and verdict.rate_from == "repetition"):
        # the picture came back once the camera's roll was taken out (or its sway or zoom allowed):
        # that is what is said of the camera, rather than that nothing tells its motion
        said = (sway_note(period) if period.sway_deg else zoom_note(period) if period.zoom_share
                else roll_note(period.roll_deg_s))
        warnings = tuple(said if warning == NO_BACKGROUND_NOTE else warning for warning in warnings)
    camera_turn = period.roll_deg_s if period is not None and verdict.rate_from == "repetition" else 0.0
    if verdict.rate_from == "turning" and reading is not None and reading.camera_turn_deg_s:
        # the picture around the turning plane told the camera's own motion, taken out of its tracks
        warnings = tuple(warning for warning in warnings if warning != NO_BACKGROUND_NOTE)
        camera_turn = reading.camera_turn_deg_s
    if camera_turn:
        # the tracks' paths carry the camera's turn: a view read from them is not the body's (a
        # face-on disc under a camera rolling 3 degrees a second read "oblique, 69 degrees")
        geometry = replace(geometry, view=None)
    if verdict.quality == "weak":
        warnings += ("weak evidence: " + "; ".join(verdict.weak_because),)
    camera = geometry.camera(size_px)
    measured_by: dict[str, object] = {"method": method_name(config.method, camera), "focal": geometry.lens.estimate,
                                      "camera": camera}
    measured_by.update(extra)  # the repetition alone: no camera measured anything
    return Analysis(
        source=footage.info.source, fps=footage.info.fps, frames=footage.frames, duration_s=footage.duration_s,
        fixation_px=geometry.fixation_px,
        omega_rad_s=verdict.omega_rad_s, omega_low_rad_s=verdict.omega_low_rad_s,
        omega_high_rad_s=verdict.omega_high_rad_s, direction=direction, direction_in_picture=in_picture,
        tracks_total=int(len(result.features)), tracks_used=tracks_used, features=features,
        offsets=result.offsets, rejection=config.rejection, warnings=warnings,
        axis_angle_deg=float(geometry.axis_angle_deg), axis_found=geometry.fixation_found,
        axis_angle_found=geometry.angle_from in ("motion", "paths", "lens"),
        axis_angle_from=(geometry.angle_from if geometry.angle_from in ("motion", "paths", "lens")
                         else config.angle_from),
        elevation_deg=geometry.elevation_deg, verdict=verdict, period=period, clock=footage.info.clock,
        camera_from=geometry.lens.source, view=geometry.view, shake=footage.shake, camera_path=footage.camera,
        camera_turn_deg_s=float(camera_turn),
        **measured_by,  # type: ignore[arg-type]
    )


def _repetition_only(footage: Footage, period: Period | None, config: AnalysisConfig, kept: pd.DataFrame | None,
                     view_tracks: pd.DataFrame | None, result: RateResult | None = None,
                     geometry: Geometry | None = None) -> Analysis:
    """The Analysis when no track gave a rate but the clip repeats: the rate is the repetition's,
    the sense of turning unknown, and the fixation the one given (else found from the paths'
    centre by the view, where they tell one). Where the clip does not repeat either (under a
    turn), the picture's own turning alone (NoResultError where it tells no rate)."""
    features = result.features if result is not None else pd.DataFrame(columns=list(FEATURE_COLUMNS))
    offsets = result.offsets if result is not None else pd.DataFrame(
        {"track": pd.Series(dtype=int), "frame": pd.Series(dtype=int), "time_s": pd.Series(dtype=float),
         "offset_px": pd.Series(dtype=float)})
    empty = RateResult(offsets, features, Combined(math.nan, math.nan, math.nan, 0), "unknown")
    fixation = config.fixation_px if config.fixation_px is not None else (math.nan, math.nan)
    if geometry is None:  # the axis was not found: as far as the tracks went
        geometry = Geometry(_angle_guess(footage, config), "given" if config.axis_angle_deg is not None else "motion",
                            (math.nan, math.nan), config.fixation_px is None, lens_from(config, footage.info))
    geometry = replace(geometry, fixation_px=(float(fixation[0]), float(fixation[1])))
    hint = ("; CSRT loses points that jump far between frames (stills taken far apart, fast turns): the default "
            "`tracker_kind='auto'` follows those") if config.tracker_kind == "csrt" else ""
    source = "the clip's repetition" if period is not None else "the picture's turning"
    note = f"no track gave a rate: the rate is {source} alone, and the sense of turning is unknown{hint}"
    # omega(t)'s windows, with no track's rate in them: the picture's turning rates each it can
    # (the return's windows are not sought again here: weak where the turning does not rate them)
    series = None
    kept_frames = footage.pairs.angle_frames.frames
    if config.window_s is not None and kept_frames:
        centres = window_centres(kept_frames[0][1], kept_frames[-1][1], config.window_s)
        series = pd.DataFrame({"time_s": centres, "omega_rad_s": math.nan, "omega_low_rad_s": math.nan,
                               "omega_high_rad_s": math.nan, "tracks_used": 0})
    return _result(footage, config, geometry, Checked(empty), period, view_tracks, notes=(note,),
                   method=config.method, focal=None, camera=None, series=series, tracks=kept)


def _segmented(footage: Footage, config: AnalysisConfig) -> Analysis:
    """Group the tracks into rigid bodies (:mod:`rotrate_cli.stages.bodies`) and measure each; the
    largest measured body is the analysis's headline result, all are in ``bodies``."""
    found = measure_bodies(footage.tracks, footage.motion_angle_deg, config, footage.info)
    return _result(footage, config, found.geometry, Checked(found.result), None, None, notes=found.notes,
                   series=None, bodies=found.bodies)


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
        raise InputError("`fixation` must be a number (the axis position in the tracks' units)")
    table = tracks.copy()
    given_fps = fps is not None
    if fps is not None:
        if not (fps > 0 and math.isfinite(fps)):
            raise InputError("`fps` must be a positive number of frames per second")
        table["time_s"] = table["frame"] / fps
    elif table["time_s"].isna().any():
        raise InputError("the tracks have no time_s column; pass `fps`")
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
    combined = result.combined
    if combined.tracks_used == 0:
        raise NoResultError(no_result_message(result.features))
    verdict = judge(combined, None, combined.tracks_used)
    weak = ("weak evidence: " + "; ".join(verdict.weak_because),) if verdict.quality == "weak" else ()
    return Analysis(
        source=source, fps=float(fps), frames=int(table["frame"].nunique()),
        duration_s=float(table["time_s"].max() - table["time_s"].min()), fixation_px=(float(fixation), math.nan),
        method=method, omega_rad_s=verdict.omega_rad_s, omega_low_rad_s=verdict.omega_low_rad_s,
        omega_high_rad_s=verdict.omega_high_rad_s, direction=result.direction,
        tracks_total=int(len(result.features)), tracks_used=combined.tracks_used, features=result.features,
        offsets=result.offsets, rejection=rules, warnings=verdict.notes + weak, position_unit=position_unit,
        verdict=verdict, clock="fps" if given_fps else "tracks")
