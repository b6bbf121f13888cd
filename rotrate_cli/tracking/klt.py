"""Multi-point tracking: Shi-Tomasi corners followed by pyramidal Lucas-Kanade optical flow.

Each frame is scaled to a grey image whose longer side is ``TrackerConfig.track_size_px`` at most
(and ``track_min_size_px`` at least: small frames are enlarged) (done in
the decode thread by :func:`tracking_image`), then every live point is tracked forward and back
again; a point whose round trip misses its start by more than ``fb_max_error_px`` is dropped
(it turned out of view, was occluded, or slid). New corners are seeded every few frames where
the image has changed (so the static background is not seeded) and away from live points.
Points that stay put for ``static_window_s`` are dropped and their place is not seeded again.

The result is a tidy DataFrame ``frame, time_s, track, x_px, y_px`` in full-resolution pixels,
where ``x_px`` is the image column and ``y_px`` the image row.
"""

from __future__ import annotations

import math
import statistics
from collections import deque
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass

import cv2
import numpy as np

from rotrate_cli.runtime.lazy import pandas as pd
from rotrate_cli.tracking.steady import CameraPath
from rotrate_cli.video.frames import Frame
from rotrate_cli.video.light import SteadyLight

KNOWN_LEVELS = 0
#: Where at least this fraction of the points followed from their predicted steps are lost in one
#: frame, and :data:`JOLT_TIMES` the fraction usual in the last :data:`JOLT_FRAMES` frames, the
#: camera jolted, and they are sought again over the full pyramid. Measured (fraction lost a
#: frame, median and 99th percentile): the 720p bench clip 0.02 and 0.05, the bicycle wheel 0 and
#: 0.33, the record 0.24 and 0.46; a rendered box whose picture shook by 5 px 0.04 and 0.93.
JOLT_LOST = 0.25
JOLT_TIMES = 2.0
JOLT_FRAMES = 31
#: ... or, at :data:`JOLT_LOST` or more, where the recent searches found this fraction of their
#: points again (their median): a hand that trembles jolts the picture every frame, and the usual
#: fraction lost rises with it (a clock filmed in the hand, 2 px of tremor a frame: a third of
#: the points lost each frame, 99% found again; tracks 3 frames long at the median, the camera
#: not found, the rate 8 times the truth and its interval missing; now -0.47%, `make
#: bench-clock`'s in-hand-tremor-10s). The record's grooves: 1% found again, the bicycle wheel's 1%.
RECOVERING = 0.8
#: Lucas-Kanade stopping rule (iterations, last step in px) of the forward pass, which gives the
#: positions. Stopping at a 0.03 px step rather than 0.01 costs nothing measurable (accuracy suite:
#: median 0.12% either way, largest error 0.69% either way; dinosaur unchanged) and saves a fifth
#: of the Lucas-Kanade time.
FORWARD_CRITERIA = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 30, 0.03)
#: The backward pass only checks the round trip against ``fb_max_error_px`` (0.3 px): a step of
#: 0.03 px is ten times finer than that, and stops 15% sooner than the forward rule.
BACKWARD_CRITERIA = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 10, 0.03)

#: A new point's first step is predicted from the steps of the known points around it, where at
#: least :data:`NEIGHBOURS_NEEDED` of its :data:`NEIGHBOURS` nearest lie within
#: :data:`NEIGHBOUR_RADIUS_PX` (tracking pixels) and one affine field of steps (a turn's, seen
#: near enough) explains theirs within :data:`NEIGHBOUR_RMS_PX`: such a point is then followed
#: at the base level like a known one, not searched for over the whole pyramid (four levels,
#: each as dear as the base). On the real record clip, whose 45,000 new points took two thirds
#: of its Lucas-Kanade time, 41% of them are predicted so, and as many of those are kept as
#: the full search keeps (7,295 against 7,279; 97% of the points both keep end within 0.05 px
#: of each other); a radius of 30 px predicts 13%, 120 px 53% with neighbours' misfits three
#: times larger and fewer kept.
NEIGHBOURS = 8
NEIGHBOURS_NEEDED = 4
NEIGHBOUR_RADIUS_PX = 60.0
NEIGHBOUR_RMS_PX = 1.0

#: The activity map compares a frame with the last one seeded from (``reseed_every`` before) and
#: with the one ``activity_s`` before; where the first shows under this share of the pixels the
#: second does, the turn is slow, and both count. Frames a few apart show 0.6-0.95 of it on the
#: accuracy suite's renders and the real record (a body's pixels change at either lag), 0.1-0.5 on
#: the real wheel (its holder sways), 0.03-0.09 on a box turning at 0.05 rad/s and none at 0.03.
#: At most :data:`MAX_REFERENCES` earlier frames are kept (120 frames/s, seeding every 4th: 30 a
#: second).
SLOW_SHARE = 0.2
MAX_REFERENCES = 64


#: The blur applied to video frames before tracking when the configuration leaves it open.
VIDEO_BLUR_SIGMA_PX = 1.0
TRACK_COLUMNS = ("frame", "time_s", "track", "x_px", "y_px")


@dataclass(frozen=True)
class Roi:
    """A region of interest in full-resolution pixels: left, top, width, height."""

    x_px: int
    y_px: int
    width_px: int
    height_px: int


@dataclass(frozen=True)
class TrackerConfig:
    """Settings of the KLT tracker. Distances are in tracking-image pixels unless named ``_full``.

    Attributes:
        max_points: the most points tracked at once.
        track_size_px: frames whose longer side is longer than this are reduced (area-averaged)
            before tracking: a 1280x720 frame to 640x360, and one held upright, 720x1280, to
            360x640 alike (by its width, it was tracked at 640x1138, and the record clip turned a
            quarter took 5.7 s against 2.8).
        track_min_size_px: frames whose longer side is shorter than this are enlarged (by the
            smallest whole factor that reaches it, bilinearly) before tracking. The tracker's
            sizes are in its image's pixels: its window is 21 px long, and it seeds only where that
            window lies wholly on moving pixels. On the bicycle wheel halved to 256x192 that left
            24 corners in the whole clip and "no point could be tracked"; enlarged twice, it reads
            as the whole-size clip does.
        quality_level: Shi-Tomasi corner quality, relative to the best corner in the frame.
        min_distance_px: the least spacing between seeded corners.
        win_width_px, win_height_px: the Lucas-Kanade window. It is narrow across the motion on
            purpose: on a curved surface the image velocity varies nonlinearly across the window,
            and a translational tracker then follows the window-averaged velocity, which lags the
            true one (Jensen's inequality) by an amount that grows with the window's width
            squared. A 15-px-wide window drifted 0.7 px/s and biased omega by +3% on a rendered
            cylinder; 5 px wide, 0.06 px/s and +0.3%. Tall windows keep enough texture.
        blur_sigma_px: Gaussian blur of the tracking image (its pixels); None chooses by source
            (:data:`VIDEO_BLUR_SIGMA_PX` for videos, none for image sequences). A light blur keeps
            the narrow window from locking onto static codec blocks and sensor noise: on the
            accuracy suite sigma 1 took a JPEG-quality-20 clip from -0.82% to -0.34% and a
            perspective sphere from +0.66% to +0.36%, and left clean clips within 0.05%. Image
            sequences are stills taken one by one, often far apart (the dinosaur's are 10 degrees
            apart), where detail matters more for the large steps: there it moved the estimate
            from +0.15% to +1.7% (within its own interval, but the wrong way).
        pyramid_levels: pyramid levels above the base image (each halves the size).
        steady_light: a frame brighter or darker than the last few by more than
            :data:`rotrate_cli.video.light.FLICKER_GAIN` is brought to their brightness (lights
            flickering with the mains); None chooses by source: videos, not image sequences (stills exposed one by
            one differ for their own reasons: on the EPFL cars it moved the rates by up to 0.3%
            and their parts by up to 9%).
        retry_lost: a point lost from its predicted step searches the full pyramid once more;
            None chooses by source: videos, whose hand-held cameras jolt (a rendered box whose
            picture shook by 5 px broke into 6,900 tracks of a few frames each, 520 with it),
            and not image sequences, stills of a turntable from a tripod whose irregular steps
            it follows no better (on the EPFL cars' parts it made 5 of 15 good results weak and
            moved two of them by 2-17%).
        predict_new: a new point's first step is predicted from its known neighbours' where they
            agree (:func:`neighbour_steps`), and followed at the base level, not searched for over
            the whole pyramid; None chooses by source: videos, whose frames come evenly (on the
            real record clip it takes a sixth off the Lucas-Kanade time with the same result),
            and not image sequences, stills taken at the hand's pace, where a neighbour's last
            step says less (on the EPFL cars' first 50 photographs of seq18 it moved the rate
            from -2.4% to -5.5%, outside its interval).
        laid_along_rows: a window taller than wide (the default 5x21) is run on the transposed
            frames, laid along their rows as 21x5: OpenCV's Lucas-Kanade goes along a window's
            rows in vector steps and does the rest of each row a pixel at a time, so the same sums
            in another order cost a third less (300 points, 0.47 -> 0.32 ms a frame). None chooses
            by source: videos, and not image sequences, whose tracks on stills taken far apart turn
            on the sums' rounding (on the EPFL cars' 52 parts of a turn, the other order alone
            moved single weak parts by up to 30 points, the median error from 3.7% to 5.2%, and
            made one good part weak), and which are few frames, where the time is small.
        fb_max_error_px: the largest forward-backward round-trip error a point may have.
        reseed_every: seed new corners every this many frames.
        motion_threshold: grey-level change (0-255) that marks a pixel as moving, between a
            frame and the last one seeded from (``reseed_every`` before), and where the turn is
            slow also the one ``activity_s`` before (:data:`SLOW_SHARE`).
        activity_s: a pixel counts as moving for this long after it last changed.
        max_static_fraction: a point whose window holds more than this fraction of static
            pixels is on the object's outline (or off the object) and is dropped.
        static_window_s, static_range_px: a point that moves less than ``static_range_px``
            over ``static_window_s`` seconds is background and is dropped.
        roi: seed only inside this region (full-resolution pixels); None for the whole frame.
    """

    max_points: int = 300
    track_size_px: int = 640
    track_min_size_px: int = 320
    quality_level: float = 0.01
    min_distance_px: float = 6.0
    win_width_px: int = 5
    win_height_px: int = 21
    blur_sigma_px: float | None = None
    pyramid_levels: int = 3
    retry_lost: bool | None = None
    steady_light: bool | None = None
    predict_new: bool | None = None
    laid_along_rows: bool | None = None
    fb_max_error_px: float = 0.3
    reseed_every: int = 4
    motion_threshold: float = 6.0
    activity_s: float = 1.0
    max_static_fraction: float = 0.25
    static_window_s: float = 1.0
    static_range_px: float = 0.4
    roi: Roi | None = None


def tracking_scale(size_px: tuple[int, int], config: TrackerConfig) -> float:
    """The factor by which frames of this size (width, height) are scaled for tracking: under 1
    where they are reduced, a whole number over 1 where they are enlarged (see
    :class:`TrackerConfig`)."""
    side = max(1, *size_px)
    if side < config.track_min_size_px:
        return float(math.ceil(config.track_min_size_px / side))
    return min(1.0, config.track_size_px / float(side))


def tracking_image(
    image: np.ndarray, scale: float, blur_sigma_px: float = 0.0, levels: np.ndarray | None = None
) -> np.ndarray:
    """Grey, scaled (see :func:`tracking_scale`; and lightly blurred) copy of a BGR or grey frame,
    as the tracker wants it.
    Cheap enough for the decode thread. ``levels`` (a 256-entry table, see
    :meth:`rotrate_cli.video.decode.FrameSource.luma_levels`) maps a decoder's luma to grey; applied
    after the reduction, on fewer pixels (the reduction and blur are linear, so the order does
    not matter beyond rounding)."""
    grey = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY) if image.ndim == 3 else image
    if scale < 1.0:
        grey = _reduce(grey, scale)
    elif scale > 1.0:
        grey = cv2.resize(grey, None, fx=scale, fy=scale, interpolation=cv2.INTER_LINEAR)
    if blur_sigma_px > 0:
        grey = cv2.GaussianBlur(grey, (0, 0), blur_sigma_px)
    if levels is not None:
        grey = cv2.LUT(grey, levels)
    return grey


def _reduce(grey: np.ndarray, scale: float) -> np.ndarray:
    """``grey`` reduced by ``scale`` with an area average (``cv2.INTER_AREA``, as ``cv2.resize``
    with ``fx=fy=scale`` gives it). OpenCV's area reduction is fast for halving only, so where
    the frame divides into whole blocks of ``n`` pixels a side: ``n = 3`` (1920x1080 to 640x360)
    comes from a 3x3 box filter sampled at the blocks' centres (the same pixels, 0.21 against
    0.65 ms of processor time a frame, measured), and an even ``n`` of 4 or more is halved first
    (an average of averages: within one grey level of the direct one, from the rounding in
    between; 3840x2160 in 0.70 against 2.2 ms, 2560x1440 in 0.14 against 0.90). Other sizes
    are OpenCV's own reduction (halving where blocks do not divide evenly would weigh the pixels
    a block's edge cuts as one, a slight distortion)."""
    height, width = grey.shape[:2]
    blocks = round(1.0 / scale)
    if abs(1.0 / scale - blocks) > 1e-9 or width % blocks or height % blocks:
        return cv2.resize(grey, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)
    while blocks >= 4 and blocks % 2 == 0:
        width, height, blocks = width // 2, height // 2, blocks // 2
        grey = cv2.resize(grey, (width, height), interpolation=cv2.INTER_AREA)
    if blocks == 3:
        box = cv2.boxFilter(grey, -1, (3, 3), normalize=True, borderType=cv2.BORDER_REPLICATE)
        return np.ascontiguousarray(box[1::3, 1::3])
    return cv2.resize(grey, (width // blocks, height // blocks), interpolation=cv2.INTER_AREA)


#: Samples per block of the tracker's store (see :class:`_Tracks`).
_BLOCK_SAMPLES = 1 << 15
#: Samples the tracker's store holds at most (24 bytes each in the tracks table, and a few times
#: that in the fits): past it, every other track is let go, and from then on (see
#: :meth:`_Tracks._thin`). Four minutes of 300 points at 30 frames/s; a 10-minute 640x480 clip
#: peaked at 767 MB with every track kept.
MAX_STORED_SAMPLES = 1_500_000


class _Tracks:
    """Append-only store of tracked positions, compact (16 bytes a sample: id, frame slot, and
    float32 x, y) and in large blocks rather than one small array per frame: a finished block
    is freed as soon as it has been copied into the table, and large blocks go back to the
    operating system when freed, where many small arrays would stay in the process's heap. So
    at the end of a long clip the store and the table it becomes are not both resident."""

    def __init__(self, max_samples: int = MAX_STORED_SAMPLES) -> None:
        self.frame_index: list[int] = []
        self.frame_time_s: list[float] = []
        self._blocks: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []  # ids, frame slots, points
        self._fill = _BLOCK_SAMPLES  # samples used in the last block (full: start a new one)
        self._max = max_samples
        self._stored = 0
        #: only tracks whose id is a multiple of this are kept (doubled each time the store fills)
        self.keep_every = 1

    def add(self, frame: int, time_s: float, ids: np.ndarray, points: np.ndarray) -> None:
        if self.keep_every > 1:
            kept = ids % self.keep_every == 0
            ids, points = ids[kept], points[kept]
        if len(ids) == 0:
            return
        slot = len(self.frame_index)
        self.frame_index.append(frame)
        self.frame_time_s.append(time_s)
        self._append(ids, np.full(len(ids), slot, np.int32), points)
        if self._stored > self._max:
            self._thin()

    def _append(self, ids: np.ndarray, slots: np.ndarray, points: np.ndarray) -> None:
        start = 0
        while start < len(ids):
            if self._fill == _BLOCK_SAMPLES:
                self._blocks.append((np.empty(_BLOCK_SAMPLES, np.int32), np.empty(_BLOCK_SAMPLES, np.int32),
                                     np.empty((_BLOCK_SAMPLES, 2), np.float32)))
                self._fill = 0
            block_ids, block_slots, block_points = self._blocks[-1]
            take = min(len(ids) - start, _BLOCK_SAMPLES - self._fill)
            end = self._fill + take
            block_ids[self._fill:end] = ids[start:start + take]
            block_slots[self._fill:end] = slots[start:start + take]
            block_points[self._fill:end] = points[start:start + take]
            self._fill = end
            start += take
        self._stored += len(ids)

    def _thin(self) -> None:
        """Keep every other track of those kept so far (by id: evenly over the clip), and from now
        on: a long clip's store, and all that is computed from it, stays bounded."""
        self.keep_every *= 2
        blocks, filled = self._blocks, [self._filled(i) for i in range(len(self._blocks))]
        self._blocks, self._fill, self._stored = [], _BLOCK_SAMPLES, 0
        for (ids, slots, points), count in zip(blocks, filled, strict=True):
            kept = ids[:count] % self.keep_every == 0
            self._append(ids[:count][kept], slots[:count][kept], points[:count][kept])

    def _filled(self, index: int) -> int:
        return self._fill if index == len(self._blocks) - 1 else _BLOCK_SAMPLES

    def frame(self, scale: float) -> pd.DataFrame:
        """The positions as a tidy table sorted by track then frame, in full-resolution pixels,
        emptying the store as it goes.

        Positions stay float32 (the tracker's own precision, ~1e-3 px) to keep long clips small.
        Rows are placed by a counting sort on the track id (samples are stored frame by frame,
        and a frame's ids are distinct), straight into the finished columns: no global sort and
        no concatenated copy of the store.
        """
        if not self._blocks:
            return pd.DataFrame({
                "frame": pd.Series(dtype="int32"), "time_s": pd.Series(dtype="float64"),
                "track": pd.Series(dtype="int32"), "x_px": pd.Series(dtype="float32"),
                "y_px": pd.Series(dtype="float32"),
            })
        tracks = 1 + max(int(ids[:self._filled(i)].max()) for i, (ids, _, _) in enumerate(self._blocks))
        per_track = np.zeros(tracks, dtype=np.int64)
        for i, (ids, _, _) in enumerate(self._blocks):
            per_track += np.bincount(ids[:self._filled(i)], minlength=tracks)
        total = int(per_track.sum())
        next_row = np.concatenate([[0], np.cumsum(per_track)[:-1]])
        frame_index = np.asarray(self.frame_index, dtype=np.int32)
        frame_time_s = np.asarray(self.frame_time_s, dtype=np.float64)
        frame = np.empty(total, np.int32)
        time_s = np.empty(total, np.float64)
        x_px = np.empty(total, np.float32)
        y_px = np.empty(total, np.float32)
        inverse = np.float32(1.0 / scale)
        count = len(self._blocks)
        for i in range(count):
            ids, slots, points = self._blocks[0]
            filled = _BLOCK_SAMPLES if i < count - 1 else self._fill
            ids, slots, points = ids[:filled], slots[:filled], points[:filled]
            # within a block, one frame's samples are consecutive and their ids distinct
            edges = np.flatnonzero(np.diff(slots)) + 1
            for part in np.split(np.arange(filled), edges):
                rows = next_row[ids[part]]
                next_row[ids[part]] += 1
                frame[rows] = frame_index[slots[part[0]]]
                time_s[rows] = frame_time_s[slots[part[0]]]
                x_px[rows] = points[part, 0] * inverse
                y_px[rows] = points[part, 1] * inverse
            del ids, slots, points
            self._blocks.pop(0)  # freed here: its memory goes back before the next is read
        self._fill = _BLOCK_SAMPLES
        self.frame_index.clear()
        self.frame_time_s.clear()
        track = np.repeat(np.arange(tracks, dtype=np.int32), per_track)
        return pd.DataFrame({"frame": frame, "time_s": time_s, "track": track, "x_px": x_px, "y_px": y_px},
                            copy=False)  # pandas copies dict input by default: twice the memory of a long clip


class CornerTracker:
    """Follows many corners through a stream of reduced grey frames: seeds corners on the moving
    object, drops points that stay put or reach the outline, and stores the positions. How a
    point moves from one frame to the next is the subclass's :meth:`_move` (Lucas-Kanade in
    :class:`KltTracker`, CSRT in :class:`rotrate_cli.tracking.csrt.CsrtTracker`).

    Feed frames in order with :meth:`update`, then read :meth:`tracks`.
    """

    def __init__(self, frame_size_px: tuple[int, int], config: TrackerConfig) -> None:
        width_px, height_px = frame_size_px
        self.config = config
        self.scale = tracking_scale(frame_size_px, config)
        self._size = (max(1, round(width_px * self.scale)), max(1, round(height_px * self.scale)))
        self._seed_mask = np.full((self._size[1], self._size[0]), 255, np.uint8)
        if config.roi is not None:
            roi = config.roi
            self._seed_mask[:] = 0
            x0, y0 = int(roi.x_px * self.scale), int(roi.y_px * self.scale)
            x1 = int(np.ceil((roi.x_px + roi.width_px) * self.scale))
            y1 = int(np.ceil((roi.y_px + roi.height_px) * self.scale))
            self._seed_mask[y0:y1, x0:x1] = 255
        self._static_mask = np.full_like(self._seed_mask, 255)
        self._store = _Tracks()
        self._prev: np.ndarray | None = None
        # the frames compared with (box-blurred) for the activity map, with their times and indices:
        # the last one, and back to activity_s ago
        self._references: deque[tuple[np.ndarray, float, int]] = deque(maxlen=MAX_REFERENCES)
        self._last_change = np.full(self._seed_mask.shape, -np.inf, np.float32)  # when each pixel last changed, s
        self._now = np.empty_like(self._last_change)  # the frame's time in every pixel, to copy in
        self._points = np.empty((0, 2), np.float32)
        self._ids = np.empty(0, np.int32)
        self._velocity = np.empty((0, 2), np.float32)  # last displacement per frame, for prediction
        self._anchor = np.empty((0, 2), np.float32)  # where each point stood static_window_s ago
        self._anchor_time = np.empty(0, np.float64)
        self._next_id = 0
        self._count = 0
        #: the camera's own motion (a hand-held camera's shake), where known: points that stand
        #: still against it are the background, and pixels change only where the picture does
        self.camera: CameraPath | None = None
        self._lost: deque[float] = deque(maxlen=JOLT_FRAMES)  # fraction of followed points lost, recent frames
        self._recovered: deque[float] = deque(maxlen=JOLT_FRAMES)  # fraction found again, recent searches
        self._frame_index = 0
        self._light = SteadyLight()  # flickering light taken out (videos)

    def update(self, frame_index: int, time_s: float, grey: np.ndarray) -> None:
        """Track the live points into this frame, drop the bad ones, and seed new ones."""
        self._frame_index = frame_index
        if self.config.steady_light:
            grey = self._light.steadied(grey)
        if self._prev is not None and len(self._points):
            self._advance(grey)
            self._drop_static(time_s, frame_index)
        if self._count % self.config.reseed_every == 0:
            moving = self._update_activity(grey, time_s, frame_index)
            if moving is not None:
                self._drop_outline(moving)
                self._seed(grey, time_s, moving)
        self._store.add(frame_index, time_s, self._ids, self._points)
        self._prev = grey
        self._count += 1

    def _move(self, grey: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Where each live point went in ``grey`` (n x 2, tracking-image pixels) and whether it was
        followed (n booleans). ``self._prev`` is the previous frame; ``self._velocity`` each
        point's last step."""
        raise NotImplementedError

    def _seeded(self, grey: np.ndarray, corners: np.ndarray, ids: np.ndarray) -> np.ndarray:
        """Called with the corners about to be followed from ``grey``; returns which to keep."""
        return np.ones(len(corners), bool)

    def _advance(self, grey: np.ndarray) -> None:
        moved, keep = self._move(grey)
        width, height = self._size
        keep = (
            keep
            & (moved[:, 0] >= 0)
            & (moved[:, 1] >= 0)
            & (moved[:, 0] <= width - 1)
            & (moved[:, 1] <= height - 1)
        )
        self._velocity = (moved - self._points)[keep]
        self._points = moved[keep]
        self._ids = self._ids[keep]
        self._anchor = self._anchor[keep]
        self._anchor_time = self._anchor_time[keep]

    def _held(self, points: np.ndarray, frame_index: int) -> np.ndarray:
        """``points`` (tracking pixels) where a camera held still would have seen them."""
        if self.camera is None:
            return points
        frames = np.full(len(points), frame_index)
        x, y = self.camera.undo(frames, points[:, 0] / self.scale, points[:, 1] / self.scale)
        return (np.stack([x, y], axis=1) * self.scale).astype(np.float32)

    def _drop_static(self, time_s: float, frame_index: int = 0) -> None:
        due = time_s - self._anchor_time >= self.config.static_window_s
        if not due.any():
            return
        range_px = np.linalg.norm(self._held(self._points, frame_index) - self._anchor, axis=1) / self.scale
        static = due & (range_px < self.config.static_range_px)
        for x, y in self._points[static]:
            cv2.circle(self._static_mask, (int(round(x)), int(round(y))), int(self.config.min_distance_px), 0, -1)
        # Points that moved start a new window from where they are now.
        moving_due = due & ~static
        self._anchor[moving_due] = self._held(self._points[moving_due], frame_index)
        self._anchor_time[moving_due] = time_s
        keep = ~static
        self._points, self._ids, self._velocity = self._points[keep], self._ids[keep], self._velocity[keep]
        self._anchor, self._anchor_time = self._anchor[keep], self._anchor_time[keep]

    def _update_activity(self, grey: np.ndarray, time_s: float, frame_index: int = 0) -> np.ndarray | None:
        """Refresh the map of recently changed pixels; returns it as a 0/255 mask (None at first).

        Texture moves on the object, the background stays put; a pixel stays "moving" for
        ``activity_s`` after its last change, so uniform patches of a turning object do not
        flicker in and out.
        """
        smoothed = cv2.blur(grey, (3, 3))
        references = self._references
        if references:
            # masks of 0 and 255 and OpenCV's own operations throughout: NumPy's boolean
            # assignment into the map took three quarters of this method's time
            changed = self._changed(smoothed, references[-1], frame_index)
            if len(references) > 1:
                # a slow turn (a motor show's turntable at 0.02-0.05 rad/s) changes its pixels too
                # little between frames a few apart: where they show under SLOW_SHARE of the change
                # since activity_s ago, that change counts too (a box at 0.03 rad/s was "no point
                # could be tracked"; at 0.05 it kept 7 tracks, and its 95% interval missed)
                since = self._changed(smoothed, references[0], frame_index)
                share = cv2.countNonZero(changed) / max(1, cv2.countNonZero(since))
                if share < SLOW_SHARE:
                    changed = cv2.bitwise_or(changed, since)
            self._now.fill(time_s)
            cv2.copyTo(self._now, changed, self._last_change)
        references.append((smoothed, time_s, frame_index))
        while len(references) > 2 and time_s - references[1][1] >= self.config.activity_s:
            references.popleft()
        if len(references) == 1:
            return None
        return ((time_s - self._last_change) <= self.config.activity_s).astype(np.uint8) * 255

    def _changed(self, smoothed: np.ndarray, reference: tuple[np.ndarray, float, int], frame_index: int) -> np.ndarray:
        """Where ``smoothed`` differs from an earlier frame by more than ``motion_threshold`` grey
        levels: 255 there, 0 elsewhere."""
        image, _, reference_frame = reference
        if self.camera is not None:  # the reference as the camera stands now: the background still
            image = self.camera.carry(image, reference_frame, frame_index, self.scale)
        # on whole grey levels, "over the threshold" is over its whole part, as OpenCV takes it
        return cv2.threshold(cv2.absdiff(smoothed, image), self.config.motion_threshold, 255, cv2.THRESH_BINARY)[1]

    def _drop_outline(self, moving: np.ndarray) -> None:
        """Drop points whose tracking window reaches into static pixels.

        A window that straddles the outline sees the static background's edge and sticks to it
        while the surface slides past; such a point no longer follows the object.
        """
        if not len(self._points):
            return
        static = (moving == 0).astype(np.uint8)
        integral = cv2.integral(static)
        half_w, half_h = self.config.win_width_px // 2, self.config.win_height_px // 2
        height, width = static.shape
        x = np.clip(np.rint(self._points[:, 0]).astype(int), 0, width - 1)
        y = np.clip(np.rint(self._points[:, 1]).astype(int), 0, height - 1)
        x0, x1 = np.clip(x - half_w, 0, width), np.clip(x + half_w + 1, 0, width)
        y0, y1 = np.clip(y - half_h, 0, height), np.clip(y + half_h + 1, 0, height)
        count = integral[y1, x1] - integral[y0, x1] - integral[y1, x0] + integral[y0, x0]
        area = np.maximum((x1 - x0) * (y1 - y0), 1)
        keep = count / area <= self.config.max_static_fraction
        self._points, self._ids, self._velocity = self._points[keep], self._ids[keep], self._velocity[keep]
        self._anchor, self._anchor_time = self._anchor[keep], self._anchor_time[keep]

    def _near_points(self, box: tuple[int, int, int, int]) -> np.ndarray:
        """255 on the pixels of ``box`` (left, top, width, height) within ``min_distance_px`` of a
        live point (no seeding there), 0 elsewhere: the points' marks dilated by a disk, on the
        box and a disk's reach around it only (the same pixels as on the whole image)."""
        left, top, box_w, box_h = box
        radius = max(1, int(self.config.min_distance_px))
        height, width = self._seed_mask.shape
        x0, y0 = max(0, left - radius), max(0, top - radius)
        x1, y1 = min(width, left + box_w + radius), min(height, top + box_h + radius)
        marks = np.zeros((y1 - y0, x1 - x0), np.uint8)
        if len(self._points):
            x = np.clip(np.rint(self._points[:, 0]).astype(int), 0, width - 1) - x0
            y = np.clip(np.rint(self._points[:, 1]).astype(int), 0, height - 1) - y0
            inside = (x >= 0) & (x < x1 - x0) & (y >= 0) & (y < y1 - y0)
            marks[y[inside], x[inside]] = 255
            disk = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * radius + 1, 2 * radius + 1))
            marks = cv2.dilate(marks, disk)
        return marks[top - y0:top - y0 + box_h, left - x0:left - x0 + box_w]

    def _seed(self, grey: np.ndarray, time_s: float, moving: np.ndarray) -> None:
        wanted = self.config.max_points - len(self._points)
        if wanted < max(1, self.config.max_points // 10):
            return  # a corner search costs the same for 3 points as for 30: wait until it pays
        # Seed only where the whole tracking window is on moving pixels: not on the background,
        # not on the outline.
        shape = (self.config.win_width_px | 1, self.config.win_height_px | 1)
        inner = cv2.erode(moving, cv2.getStructuringElement(cv2.MORPH_RECT, shape))
        mask = cv2.bitwise_and(cv2.bitwise_and(inner, self._seed_mask), self._static_mask)
        box = cv2.boundingRect(mask)
        if box[2] == 0 or box[3] == 0:
            return
        # not near the live points: taken off the box only (a mask of 0 and 255), which it can only shrink
        left, top, box_w, box_h = box
        mask = cv2.subtract(mask[top:top + box_h, left:left + box_w], self._near_points(box))
        # corner detection costs in proportion to the area searched: search the moving box only
        inner_left, inner_top, box_w, box_h = cv2.boundingRect(mask)
        if box_w == 0 or box_h == 0:
            return
        left, top = left + inner_left, top + inner_top
        corners = cv2.goodFeaturesToTrack(
            grey[top:top + box_h, left:left + box_w],
            maxCorners=wanted,
            qualityLevel=self.config.quality_level,
            minDistance=self.config.min_distance_px,
            mask=mask[inner_top:inner_top + box_h, inner_left:inner_left + box_w],
            blockSize=5,
        )
        if corners is None:
            return
        corners = corners.reshape(-1, 2).astype(np.float32) + np.float32([left, top])
        # Kept although a track is whatever point its window starts on: without it (a tenth of
        # the record clip's tracking time) the rendered suite moved by up to 0.5% and a JPEG-
        # compressed clip's interval stopped covering its truth.
        corners = cv2.cornerSubPix(
            grey, corners.reshape(-1, 1, 2), (3, 3), (-1, -1),
            (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 20, 0.03),
        ).reshape(-1, 2)
        new_ids = np.arange(self._next_id, self._next_id + len(corners), dtype=np.int32)
        self._next_id += len(corners)
        usable = self._seeded(grey, corners, new_ids)
        corners, new_ids = corners[usable], new_ids[usable]
        self._points = np.vstack([self._points, corners])
        self._ids = np.concatenate([self._ids, new_ids])
        self._velocity = np.vstack([self._velocity, np.zeros_like(corners)])
        self._anchor = np.vstack([self._anchor, self._held(corners, self._frame_index)])
        self._anchor_time = np.concatenate([self._anchor_time, np.full(len(corners), time_s)])

    def tracks(self) -> pd.DataFrame:
        """All positions: ``frame, time_s, track, x_px, y_px`` in full-resolution pixels.

        Call once, at the end: the store is handed over, not copied."""
        return self._store.frame(self.scale)

    @property
    def kept_one_in(self) -> int:
        """1, or on a long clip the N of "one track in N kept" (see :data:`MAX_STORED_SAMPLES`)."""
        return self._store.keep_every


class KltTracker(CornerTracker):
    """Corners followed by pyramidal Lucas-Kanade, forward and back (see the module's notes)."""

    def __init__(self, frame_size_px: tuple[int, int], config: TrackerConfig) -> None:
        super().__init__(frame_size_px, config)
        # a window taller than wide (5x21: 21 short rows) followed on the transposed images, laid
        # along the rows (21x5: 5 long rows): see TrackerConfig.laid_along_rows
        self._transposed = bool(config.laid_along_rows) and config.win_height_px > config.win_width_px
        window = (config.win_width_px, config.win_height_px)
        self._lk = {"winSize": window[::-1] if self._transposed else window, "maxLevel": config.pyramid_levels}
        self._laid: tuple[np.ndarray, np.ndarray] | None = None  # the last frame as given, and as followed

    def _as_followed(self, grey: np.ndarray) -> np.ndarray:
        """``grey`` as Lucas-Kanade is run on it (transposed, or as it is); the last one is kept,
        so each frame is transposed once, as the target of one step and the source of the next."""
        if not self._transposed:
            return grey
        if self._laid is None or self._laid[0] is not grey:
            self._laid = (grey, cv2.transpose(grey))
        return self._laid[1]

    def _flow(self, source: np.ndarray, target: np.ndarray, points: np.ndarray, guess: np.ndarray,
              levels: int, backward: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Lucas-Kanade from ``source`` to ``target`` (both as :meth:`_as_followed` gives them) for
        ``points`` starting at ``guess`` (n x 2, x and y in the frame as given)."""
        if len(points) == 0:
            return np.empty((0, 2), np.float32), np.empty(0, np.uint8)
        lk = dict(self._lk, maxLevel=levels, criteria=BACKWARD_CRITERIA if backward else FORWARD_CRITERIA)
        if self._transposed:
            points, guess = points[:, ::-1], guess[:, ::-1]
        moved, status, _ = cv2.calcOpticalFlowPyrLK(source, target, np.ascontiguousarray(points).reshape(-1, 1, 2),
                                                    np.ascontiguousarray(guess).reshape(-1, 1, 2),
                                                    flags=cv2.OPTFLOW_USE_INITIAL_FLOW, **lk)
        moved = moved.reshape(-1, 2)
        return (np.ascontiguousarray(moved[:, ::-1]) if self._transposed else moved), status.ravel()

    def _move(self, grey: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        before, after = self._as_followed(self._prev), self._as_followed(grey)
        # Points with a known velocity start from a constant-velocity prediction, close to the
        # answer, so the base level (KNOWN_LEVELS) suffices; new points search the full pyramid.
        # The backward pass starts from the same prediction reversed, independent of the forward
        # answer, so a wrong forward match is not confirmed by starting next to it.
        known = np.any(self._velocity != 0, axis=1)
        if known.all():  # most frames: one pass each way for all points, no regrouping
            points, velocity = self._points, self._velocity
            moved, status = self._flow(before, after, points, points + velocity, KNOWN_LEVELS)
            back, status_back = self._flow(after, before, moved, moved - velocity, KNOWN_LEVELS, backward=True)
        else:
            steps = self._velocity.copy()
            predicted = known.copy()
            if self.config.predict_new:
                new = np.flatnonzero(~known)
                steps[new], predicted[new] = neighbour_steps(self._points[known], self._velocity[known],
                                                             self._points[new])
            moved = np.empty_like(self._points)
            status = np.zeros(len(self._points), np.uint8)
            back = np.empty_like(self._points)
            status_back = np.zeros(len(self._points), np.uint8)
            for group, levels in ((predicted, KNOWN_LEVELS), (~predicted, self.config.pyramid_levels)):
                if not group.any():
                    continue
                points, velocity = self._points[group], steps[group]
                moved[group], status[group] = self._flow(before, after, points, points + velocity, levels)
                back[group], status_back[group] = self._flow(after, before, moved[group],
                                                             moved[group] - velocity, levels, backward=True)
        round_trip_px = np.linalg.norm(back - self._points, axis=1)
        keep = (status == 1) & (status_back == 1) & (round_trip_px < self.config.fb_max_error_px)
        retry = known & ~keep
        lost = retry.sum() / max(known.sum(), 1)
        usual = statistics.median(self._lost) if self._lost else 0.0
        self._lost.append(lost)
        recovering = bool(self._recovered) and statistics.median(self._recovered) >= RECOVERING
        if (self.config.retry_lost and lost >= JOLT_LOST and (lost >= JOLT_TIMES * usual or recovering)
                and KNOWN_LEVELS < self.config.pyramid_levels):
            # a jolt of the camera (held in the hand) takes many points beyond the base level's
            # reach of their predicted step at once: those search the full pyramid once more (a
            # few points lost at the outline of a steady turn, or the many a record's grooves
            # lose every frame, are not worth the search); a hand that trembles jolts every
            # frame, and is known by the searches finding the points again
            points, velocity = self._points[retry], self._velocity[retry]
            levels = self.config.pyramid_levels
            again, status_again = self._flow(before, after, points, points + velocity, levels)
            back_again, status_back_again = self._flow(after, before, again, again - velocity, levels,
                                                       backward=True)
            moved[retry] = again
            keep[retry] = ((status_again == 1) & (status_back_again == 1)
                           & (np.linalg.norm(back_again - points, axis=1) < self.config.fb_max_error_px))
            self._recovered.append(float(keep[retry].mean()))
        return moved, keep


def neighbour_steps(known_px: np.ndarray, steps_px: np.ndarray, new_px: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each new point's step predicted from the known points' steps around it: the value at the
    new point of an affine field of steps fitted to its :data:`NEIGHBOURS` nearest known points
    within :data:`NEIGHBOUR_RADIUS_PX`, and whether that prediction holds (enough neighbours,
    and the field explains their steps within :data:`NEIGHBOUR_RMS_PX` rms). Points without one
    get a zero step. All in tracking pixels; ``known_px`` and ``steps_px`` are n x 2,
    ``new_px`` m x 2."""
    count = len(new_px)
    steps = np.zeros((count, 2), np.float32)
    if count == 0 or len(known_px) < NEIGHBOURS_NEEDED:
        return steps, np.zeros(count, bool)
    nearest = min(NEIGHBOURS, len(known_px))
    known, new = known_px.astype(np.float32), new_px.astype(np.float32)
    # the neighbours chosen in single precision (a tenth of the time of double over all pairs)
    across_x = known[None, :, 0] - new[:, None, 0]  # m x n
    across_y = known[None, :, 1] - new[:, None, 1]
    distance2 = across_x * across_x + across_y * across_y
    index = np.argpartition(distance2, nearest - 1, axis=1)[:, :nearest]  # m x k
    dx = known[index, 0].astype(np.float64) - new[:, None, 0]
    dy = known[index, 1].astype(np.float64) - new[:, None, 1]
    weight = (dx * dx + dy * dy <= NEIGHBOUR_RADIUS_PX**2).astype(np.float64)
    step_x, step_y = steps_px[index, 0].astype(np.float64), steps_px[index, 1].astype(np.float64)
    # The weighted least-squares field s = a + B (x - new point), solved in closed form (a 2 x 2
    # inverse per point, elementwise over all points: a batch of 3 x 3 solves and condition
    # numbers cost four times as much): B from the centred offsets, a = mean step - B mean offset.
    total = weight.sum(axis=1)
    enough = total >= NEIGHBOURS_NEEDED
    total = np.maximum(total, 1.0)
    mean_x, mean_y = (weight * dx).sum(axis=1) / total, (weight * dy).sum(axis=1) / total
    cx, cy = dx - mean_x[:, None], dy - mean_y[:, None]
    wcx, wcy = weight * cx, weight * cy
    sxx, sxy, syy = (wcx * cx).sum(axis=1), (wcx * cy).sum(axis=1), (wcy * cy).sum(axis=1)
    det = sxx * syy - sxy * sxy
    # a neighbourhood on one line leaves the field across it unknown
    enough &= det > 1e-8 * (sxx + syy) ** 2
    det = np.where(enough, det, 1.0)
    fields = []
    for observed in (step_x, step_y):
        tx, ty = (wcx * observed).sum(axis=1), (wcy * observed).sum(axis=1)
        slope_x, slope_y = (syy * tx - sxy * ty) / det, (sxx * ty - sxy * tx) / det
        value = (weight * observed).sum(axis=1) / total - slope_x * mean_x - slope_y * mean_y
        fields.append((value, observed - (value[:, None] + slope_x[:, None] * dx + slope_y[:, None] * dy)))
    (value_x, misfit_x), (value_y, misfit_y) = fields
    rms = np.sqrt((weight * (misfit_x * misfit_x + misfit_y * misfit_y)).sum(axis=1) / total)
    holds = enough & (rms <= NEIGHBOUR_RMS_PX)
    steps[holds, 0], steps[holds, 1] = value_x[holds], value_y[holds]
    return steps, holds


@dataclass(frozen=True)
class TrackingRun:
    """What tracking a stream produced.

    Attributes:
        tracks: ``frame, time_s, track, x_px, y_px`` in full-resolution pixels.
        frames: frames consumed.
        first_time_s, last_time_s: times of the first and last frame (NaN when there were none).
        notes: things the user should know (a chosen point lost, say).
    """

    tracks: pd.DataFrame
    frames: int
    first_time_s: float
    last_time_s: float
    notes: tuple[str, ...] = ()


def track_frames(
    frames: Iterable[Frame],
    frame_size_px: tuple[int, int],
    config: TrackerConfig,
    progress: Callable[[int, float], None] | None = None,
    kind: type[CornerTracker] | None = None,
    camera: CameraPath | None = None,
) -> TrackingRun:
    """Track points through frames whose images are already reduced grey (see :func:`tracking_image`).

    ``progress`` is called after each frame with the frame count so far and the frame's time.
    ``kind`` is the tracker class (default :class:`KltTracker`); ``camera`` the camera's own motion
    where known (:func:`rotrate_cli.tracking.steady.find_shake`): the positions are still as seen.
    """
    tracker = (kind or KltTracker)(frame_size_px, config)
    tracker.camera = camera
    tally = Tally()
    for frame in tally.counted(frames, progress):
        tracker.update(frame.index, frame.time_s, frame.image)
    notes: tuple[str, ...] = ()
    if tracker.kept_one_in > 1:
        notes = (f"a long clip: one track in {tracker.kept_one_in} is kept for the fits, evenly over the clip, "
                 "to bound memory",)
    return TrackingRun(tracker.tracks(), tally.count, tally.first_time_s, tally.last_time_s, notes)


@dataclass
class Tally:
    """The frames a tracker consumed: how many, the first's and the last's times (NaN before any)."""

    count: int = 0
    first_time_s: float = float("nan")
    last_time_s: float = float("nan")

    def counted(self, frames: Iterable[Frame], progress: Callable[[int, float], None] | None = None
                ) -> Iterator[Frame]:
        """``frames``, counted as they pass, with ``progress`` called after each (count, time)."""
        for frame in frames:
            yield frame
            if self.count == 0:
                self.first_time_s = frame.time_s
            self.last_time_s = frame.time_s
            self.count += 1
            if progress is not None:
                progress(self.count, frame.time_s)
