"""The tracks stage: from a source to its tracked points (:func:`read_footage`).

Opens the source, checks the options that depend on its frames (the region of interest, a
fixation outside the picture), decodes it in a background thread and tracks it, keeping a
thumbnail of each frame for the clip's repetition (:mod:`rotrate_cli.stages.period`). Tracks again where
the first pass says it should: through FFmpeg where OpenCV decoded lifeless frames (interlaced
streams), and with the tracking window turned a quarter where the points move up and down the
image. The direction of that motion is this stage's by-product: the geometry stage starts from it.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable, Iterator
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from rotrate_cli.config import AnalysisConfig
from rotrate_cli.errors import InputError, NoResultError
from rotrate_cli.runtime.lazy import pandas as pd
from rotrate_cli.runtime.memory import release_free_memory
from rotrate_cli.scene import axis as axes
from rotrate_cli.scene.turning import FramePairs
from rotrate_cli.stages.fits import no_result_message
from rotrate_cli.stages.period import Thumbnails
from rotrate_cli.tracking.chosen import follow_points
from rotrate_cli.tracking.csrt import CsrtTracker, csrt_settings
from rotrate_cli.tracking.keyframes import Keyframes
from rotrate_cli.tracking.klt import (
    VIDEO_BLUR_SIGMA_PX,
    TrackerConfig,
    TrackingRun,
    track_frames,
    tracking_image,
    tracking_scale,
)
from rotrate_cli.tracking.matched import match_frames
from rotrate_cli.tracking.steady import CameraPath, Shake, find_shake, still_background
from rotrate_cli.video.decode import FrameSource, prefetch
from rotrate_cli.video.frames import Frame, VideoInfo
from rotrate_cli.video.shots import longest_shot

#: Progress callback: (frames done, frames expected or None).
ProgressCallback = Callable[[int, int | None], None]

#: A run whose frames are this often black, or the same as the one before pixel for pixel, got
#: nothing from its decoder (see :meth:`rotrate_cli.stages.period.Thumbnails.lifeless_fraction`).
LIFELESS = 0.5

#: The tracker's settings that None leaves to the source (see :class:`rotrate_cli.tracking.klt.TrackerConfig`).
BY_SOURCE = ("retry_lost", "predict_new", "laid_along_rows", "steady_light")

#: Fewer tracks than this do not find the axis's angle from their motion: it is taken as vertical.
MIN_TRACKS_FOR_ANGLE = 10

_INTERLACED_HINT = ("if the video shows motion, it is probably interlaced (camcorder, broadcast, DV), which this "
                    "OpenCV cannot decode: deinterlace it (ffmpeg -i IN -vf yadif OUT.mp4), or reinstall "
                    "imageio-ffmpeg (a dependency) or put an ffmpeg on the PATH")


@dataclass(frozen=True)
class Footage:
    """What the tracks stage hands on.

    Attributes:
        info: the source's size, clock and lens (:class:`rotrate_cli.video.decode.VideoInfo`).
        tracks: ``frame, time_s, track, x_px, y_px`` sorted by track then frame (tracks from 0).
        thumbnails: a small grey picture of each frame, for the clip's repetition.
        keyframes: some of the tracker's own images, evenly over the clip, for the lens's fit.
        pairs: some pairs of consecutive frames, evenly over the clip, for the picture's own
            turning (:mod:`rotrate_cli.scene.turning`).
        frames: frames analysed.
        duration_s: time from the first to the last analysed frame, seconds.
        motion_angle_deg: the axis's angle in the image as the tracks' motion shows it (the
            principal direction of all their steps, :func:`rotrate_cli.scene.axis.motion_angle_deg`);
            the given ``--axis-angle`` where there is one; NaN where too few tracks
            (:data:`MIN_TRACKS_FOR_ANGLE`) tell.
        warnings: what the user should know from decoding and tracking.
        shake: the hand-held camera's shake taken out of the tracks (:mod:`rotrate_cli.tracking.steady`);
            None where none showed. ``camera``: its motion, to draw the tracks on its frames.
        matched: the tracks are features matched from photograph to photograph
            (:mod:`rotrate_cli.tracking.matched`): short, and sampled sparsely on the turn.
        plane_tracks: the moving tracks at some frames, kept for the plane's turning
            (:func:`rotrate_cli.scene.plane_turn.keep_for_plane`) once ``tracks`` are let go; None
            while ``tracks`` are held.
        background_unseen: the whole picture moves, its rim too, and nothing in it stays still: a
            camera that rolled would look the same (:data:`NO_BACKGROUND_NOTE`).
    """

    info: VideoInfo
    tracks: pd.DataFrame
    thumbnails: Thumbnails
    keyframes: Keyframes
    pairs: FramePairs
    frames: int
    duration_s: float
    motion_angle_deg: float
    warnings: tuple[str, ...] = ()
    shake: Shake | None = None
    camera: CameraPath | None = None
    matched: bool = False
    plane_tracks: pd.DataFrame | None = None
    background_unseen: bool = False


class NothingTracked(NoResultError):
    """Nothing could be tracked; ``footage`` holds what decoding kept all the same (its tracks
    empty), for a measurement that needs no track (the picture's own turning)."""

    def __init__(self, message: str, footage: Footage) -> None:
        super().__init__(message)
        self.footage = footage


def read_footage(source: str | Path, config: AnalysisConfig, progress: ProgressCallback | None = None) -> Footage:
    """Decode and track ``source`` between ``config.start_s`` and ``config.end_s``.

    Raises:
        InputError: the source cannot be read, has too few frames, or an option does not fit it.
        NothingTracked: nothing could be tracked.
    """
    video = FrameSource(source, fps=config.fps,
                        times_s=None if config.times_s is None else np.asarray(config.times_s, dtype=np.float64))
    info = video.info
    warnings = list(video.warnings) + _check_against_frames(config, info)
    tracker = config.tracker
    if config.axis_angle_deg is not None and across(config.axis_angle_deg):
        tracker = turned(tracker)
    thumbnails = Thumbnails()
    scale = tracking_scale((info.width_px, info.height_px), tracker)
    keyframes = Keyframes(scale)
    pairs = FramePairs()
    run = _track(video, config, tracker, progress, thumbnails, keyframes, pairs)
    if run.frames == 0:
        raise InputError(f"no frame of {source} lies between `start_s` and `end_s`")
    if run.frames < 3:
        raise InputError(f"{source} has only {run.frames} frame(s) to analyse; rotation needs at least 3")
    if run.tracks.empty and thumbnails.lifeless_fraction() >= LIFELESS and video.use_ffmpeg():
        # OpenCV's trouble with interlaced streams: black frames, or one frozen garbled picture;
        # it strikes some openings of a file and not others, so it is caught here too
        run = _track(video, config, tracker, progress, thumbnails, keyframes, pairs)
    try:
        _check_tracked(run, thumbnails, source)
    except NoResultError as error:
        raise NothingTracked(str(error), Footage(info, run.tracks, thumbnails, keyframes, pairs, run.frames,
                                                 run.last_time_s - run.first_time_s, math.nan,
                                                 tuple(warnings))) from None
    shot = None if config.points_px else longest_shot(thumbnails.times_s, thumbnails.images, thumbnails.levels,
                                                      tuple(video.damaged_s))
    skip_s: tuple[tuple[float, float], ...] = ()
    if shot is not None:
        # the clip cuts: tracks do not cross a cut, and the repetition is another scene's too;
        # frames garbled after a damaged spot are left out
        last = shot.last == len(thumbnails.times_s) - 1  # to the clip's end (thumbnails stop at a long clip's)
        config = replace(config, start_s=shot.start_s, end_s=config.end_s if last else shot.end_s)
        skip_s = shot.skipped_s
        run = _track(video, config, tracker, progress, thumbnails, keyframes, pairs, skip_s=skip_s)
        _check_tracked(run, thumbnails, source)
    tracks = by_track(run.tracks)
    release_free_memory()  # the tracker's store and the frames' buffers are gone
    shaken = None if config.points_px else find_shake(tracks, run.frames, 1.0 / scale, (info.width_px, info.height_px))
    if shaken is not None and shaken[1].smooth and not _rim_moves(thumbnails):
        # a smooth turn of the whole picture whose rim stands still: a face-on disc turning before
        # a still background, not a camera that rolls (a rendered checkered disc read -9%)
        shaken = None
    if shaken is not None:
        # a hand-held camera: track again knowing its motion, so that the still background is let
        # go of as on a tripod and the points go to the body; the positions as a still camera saw them
        run = _track(video, config, tracker, progress, thumbnails, keyframes, pairs, shaken[0], skip_s)
        tracks = shaken[0].steady(by_track(run.tracks))
    angle = config.axis_angle_deg if config.axis_angle_deg is not None else math.nan
    if config.axis_angle_deg is None and tracks["track"].nunique() >= MIN_TRACKS_FOR_ANGLE:
        angle = axes.motion_angle_deg(tracks)
        if across(angle):
            # the motion runs up and down the image: track again with the window turned to suit it
            camera = None if shaken is None else shaken[0]
            run = _track(video, config, turned(tracker), progress, thumbnails, keyframes, pairs, camera, skip_s)
            if run.tracks.empty:
                raise NoResultError(no_result_message(pd.DataFrame(columns=["reason"])))
            tracks = by_track(run.tracks) if camera is None else camera.steady(by_track(run.tracks))
            angle = axes.motion_angle_deg(tracks)
        angle = angle if math.isfinite(angle) else 0.0
    # the decoder may have learnt something while it read (a stream OpenCV decodes black)
    warnings += [warning for warning in video.warnings if warning not in warnings]
    notes = list(run.notes) + warnings + ([] if shot is None else [shot.note])
    shake, camera = (None, None) if shaken is None else (shaken[1], shaken[0])
    keyframes.camera = camera
    background_unseen = False
    if shake is not None:
        notes.append(_shake_note(shake))
    elif (not config.points_px and not still_background(tracks, run.frames, 1.0 / scale)
          and _rim_moves(thumbnails)):
        # all the picture moves, its rim too, and nothing in it stays still: a camera that turned
        # would look the same (the record close-up rolled 3 degrees a second read -49%)
        notes.append(NO_BACKGROUND_NOTE)
        background_unseen = True
    if config.start_s == 0 and config.end_s is None:
        short = video.shortfall(run.frames, run.last_time_s)
        if short is not None:
            notes.append(short)
    return Footage(info, tracks, thumbnails, keyframes, pairs, run.frames, run.last_time_s - run.first_time_s,
                   float(angle), tuple(notes), shake, camera, matched_tracks(config, info),
                   background_unseen=background_unseen)


#: Said where nothing in the picture stays still to tell the camera's own motion.
NO_BACKGROUND_NOTE = ("no still background is seen to tell the camera's own motion: the result assumes a "
                      "still camera (one that turns turns the whole picture with it)")
#: A camera's own turn over the clip is named where it reaches this many degrees.
MATERIAL_ROLL_DEG = 1.0


def _shake_note(shake: Shake) -> str:
    """What the camera's own motion was, and that it is taken out."""
    moved = "moved smoothly" if shake.smooth else "shook"
    turn = ""
    if abs(shake.turned_deg) >= MATERIAL_ROLL_DEG:
        sense = "anticlockwise" if shake.turned_deg > 0 else "clockwise"
        rate = f", {abs(shake.turn_deg_s):.2g} degrees a second" if math.isfinite(shake.turn_deg_s) else ""
        turn = f" and turned {abs(shake.turned_deg):.1f} degrees {sense} as the picture shows it{rate}"
    return (f"the camera {moved} ({shake.rms_px:.1f} px rms, at most {shake.largest_px:.1f} px{turn}): the frames and "
            f"tracks are measured as a still camera would see them, from {shake.background_tracks} still background "
            "tracks")


#: The picture's rim: this share of its width and height on every side (of the thumbnails).
RIM_SHARE = 0.1
#: A rim that moves: it differs from the clip's first frame, at this quantile of the frames, by
#: this many times its typical change from one frame to the next, and by this many grey levels at
#: least. Between the first and last frames alone, a camera that wobbled about where it started
#: and ended near it was taken for a still one (a tilted clock filmed so read +199%, weak, from a
#: return of its swaying picture).
RIM_QUANTILE = 0.9
RIM_MOVES = 3.0
RIM_LEVELS = 2.0


#: A camera that turns moves its picture's rim on every side: at least this many of its four
#: sides must move. A textured disc turning face on before a still floor, reaching the picture's
#: foot, moved the rim on that side alone, and its turn was taken for the camera's (98.7 degrees,
#: the floor read as turning the other way, the disc's axis put 120 px off).
RIM_SIDES = 3


def _rim_moves(thumbnails: Thumbnails) -> bool:
    """True where the picture's rim changes over the clip (a camera that turns moves all of its
    picture, the rim on every side), more than from one frame to the next (its noise)."""
    images = thumbnails.images
    if len(images) < 3 or thumbnails.shape is None:
        return True  # nothing to tell by: as found
    height, width = thumbnails.shape
    grid = images.reshape(len(images), height, width).astype(np.float32)
    dy, dx = max(1, int(RIM_SHARE * height)), max(1, int(RIM_SHARE * width))
    sides = (grid[:, :dy, :], grid[:, height - dy:, :], grid[:, :, :dx], grid[:, :, width - dx:])
    return sum(_side_moves(side.reshape(len(images), -1)) for side in sides) >= RIM_SIDES


def _side_moves(values: np.ndarray) -> bool:
    """True where a side of the rim (``values``: frames x pixels) strays from the first frame's
    more than from one frame to the next: all but the farthest tenth of the frames (a camera that
    wobbles about where it started strays all through, and may end near it)."""
    over_clip = float(np.quantile(np.mean(np.abs(values[1:] - values[0]), axis=1), RIM_QUANTILE))
    step = float(np.median(np.mean(np.abs(np.diff(values, axis=0)), axis=1)))
    return over_clip > max(RIM_MOVES * step, RIM_LEVELS)


def matched_tracks(config: AnalysisConfig, info: VideoInfo) -> bool:
    """True where the tracks are features matched from frame to frame (``tracker_kind``
    ``matched``, or ``auto`` on an image sequence without chosen points)."""
    return not config.points_px and (config.tracker_kind == "matched"
                                     or (config.tracker_kind == "auto" and info.is_image_sequence))


def _steadied_for(frames: Iterator[Frame], camera: CameraPath, scale: float,
                  taps: Callable[[Iterator[Frame]], Iterator[Frame]]) -> Iterator[Frame]:
    """``frames`` as they came, once ``taps`` (which yield each frame they are given, in order)
    have seen them as a still camera would have (:meth:`CameraPath.steady_image`)."""
    waiting: deque[Frame] = deque()
    first: list[np.ndarray] = []

    def steadied() -> Iterator[Frame]:
        for frame in frames:
            waiting.append(frame)
            if not first:
                first.append(frame.image)
            yield Frame(frame.index, frame.time_s, camera.steady_image(frame.image, frame.index, scale, first[0]))
    for _ in taps(steadied()):
        yield waiting.popleft()


def _check_against_frames(config: AnalysisConfig, info: VideoInfo) -> list[str]:
    """Options that must fit the frames: an error for a region outside them, a warning for a
    fixation outside them."""
    notes = []
    if config.fixation_px is not None:
        fx, fy = config.fixation_px
        if not (math.isfinite(fx) and math.isfinite(fy)):
            raise InputError("`fixation_px` must be two numbers X,Y in pixels, or auto")
        if not (0 <= fx <= info.width_px - 1 and 0 <= fy <= info.height_px - 1):
            # a record player's spindle seen close up lies outside the picture: measured, but said
            notes.append(f"the fixation ({fx:g}, {fy:g}) lies outside the {info.width_px}x{info.height_px} "
                         "frame; check it, or use `fixation_px=None`")
    roi = config.tracker.roi
    if roi is not None and (
        roi.width_px <= 0 or roi.height_px <= 0 or roi.x_px < 0 or roi.y_px < 0
        or roi.x_px + roi.width_px > info.width_px or roi.y_px + roi.height_px > info.height_px
    ):
        raise InputError(f"`roi` must be X,Y,W,H inside the {info.width_px}x{info.height_px} frame")
    return notes


def _check_tracked(run: TrackingRun, thumbnails: Thumbnails, source: str | Path) -> None:
    """Nothing tracked: say why, as far as the frames tell."""
    if not run.tracks.empty:
        return
    if thumbnails.black_fraction() >= LIFELESS:
        raise InputError(f"the frames of {source} decode black: {_INTERLACED_HINT}")
    if thumbnails.lifeless_fraction() >= LIFELESS:
        raise NoResultError("no point could be tracked: the picture does not change from frame to frame; "
                            + _INTERLACED_HINT)
    raise NoResultError(no_result_message(pd.DataFrame(columns=["reason"])))


def across(angle_deg: float) -> bool:
    """True when an axis at ``angle_deg`` is nearer horizontal than vertical in the image."""
    return math.isfinite(angle_deg) and abs(angle_deg) > 45.0


def by_track(tracks: pd.DataFrame) -> pd.DataFrame:
    """``tracks`` sorted by track then frame (the tracker hands them over so: then as they are)."""
    track, frame = tracks["track"].to_numpy(), tracks["frame"].to_numpy()
    step = np.diff(track)
    if ((step > 0) | ((step == 0) & (np.diff(frame) > 0))).all():
        return tracks
    return tracks.sort_values(["track", "frame"], kind="stable").reset_index(drop=True)


def turned(tracker: TrackerConfig) -> TrackerConfig:
    """The tracker with its window turned a quarter: narrow across the motion again (see
    :class:`rotrate_cli.tracking.klt.TrackerConfig`) when points move up and down the image."""
    return replace(tracker, win_width_px=tracker.win_height_px, win_height_px=tracker.win_width_px)


def _track(video: FrameSource, config: AnalysisConfig, tracker: TrackerConfig,
           progress: ProgressCallback | None, thumbnails: Thumbnails, keyframes: Keyframes, pairs: FramePairs,
           camera: CameraPath | None = None, skip_s: tuple[tuple[float, float], ...] = ()) -> TrackingRun:
    """Decode (in a background thread) and track the frames of ``video`` between start and end,
    keeping a thumbnail of each in ``thumbnails`` and some of the tracker's images in
    ``keyframes`` (both emptied first: a run again replaces the last); ``camera``: its own motion,
    where known; ``skip_s``: stretches of frames left out (first and last time, seconds: those a
    damaged spot garbled, :class:`rotrate_cli.video.shots.Shot`)."""
    info = video.info
    scale = tracking_scale((info.width_px, info.height_px), tracker)
    blur = tracker.blur_sigma_px
    if blur is None:
        blur = 0.0 if info.is_image_sequence else VIDEO_BLUR_SIGMA_PX
    # the tracker's choices left open (None) are made by source: on for videos, off for stills
    tracker = replace(tracker, **{name: not info.is_image_sequence for name in BY_SOURCE
                                  if getattr(tracker, name) is None})
    thumbnails.steady_light = not info.is_image_sequence
    # the luma table is known once the stream has read (and checked) its first frame
    frames = video.frames(config.start_s, config.end_s, grey=True, map_luma=False,
                          transform=lambda image: tracking_image(image, scale, blur, video.luma_levels()))
    if skip_s:
        frames = (frame for frame in frames
                  if not any(first - 1e-9 <= frame.time_s <= last + 1e-9 for first, last in skip_s))
    expected = info.frame_count
    notify = None if progress is None else (lambda done, _time_s: progress(done, expected))
    size_px = (info.width_px, info.height_px)
    thumbnails.clear()
    pairs.clear()
    # thumbnails and frame pairs made in the decoding thread: off the tracker's path; from the
    # frames as a still camera would have seen them where the camera's motion is known (the
    # tracker takes it out of its own points)
    def taps(stream: Iterator[Frame]) -> Iterator[Frame]:
        return pairs.tap(thumbnails.tap(stream))
    stream = prefetch(taps(frames) if camera is None else _steadied_for(frames, camera, scale, taps))
    keyframes.clear()
    kind = config.tracker_kind
    if config.points_px:
        return follow_points(stream, size_px, list(config.points_px), "klt" if kind == "auto" else kind, tracker,
                             notify)
    stream = keyframes.tap(stream)
    if matched_tracks(config, info):
        return match_frames(stream, scale, notify)
    if kind == "csrt":
        return track_frames(stream, size_px, csrt_settings(tracker), notify, kind=CsrtTracker, camera=camera)
    return track_frames(stream, size_px, tracker, notify, camera=camera)
