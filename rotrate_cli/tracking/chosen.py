"""Following points the user chose (``--track X,Y``), as the paper followed its two features by
hand.

Two trackers: OpenCV's CSRT (a discriminative correlation filter on a box around each point,
robust to appearance change, whole-pixel positions) and pyramidal Lucas-Kanade with a
forward-backward check (sub-pixel). A point whose tracker loses it (CSRT reports failure, the
box leaves the frame, or the Lucas-Kanade round trip misses) stops there, and the run says so,
rather than drifting on.

Output: the same tidy table as :mod:`rotrate_cli.tracking.klt` (``frame, time_s, track, x_px,
y_px``, full-resolution pixels), with the points numbered 0..n-1 in the order given.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable

import cv2
import numpy as np

from rotrate_cli.errors import InputError
from rotrate_cli.runtime.lazy import pandas as pd
from rotrate_cli.tracking.klt import TrackerConfig, TrackingRun, tracking_scale
from rotrate_cli.video.frames import Frame

TRACKERS = ("klt", "csrt")
#: Side of the box CSRT follows around a point, in tracking-image pixels.
CSRT_BOX_PX = 31
#: CSRT's peak-to-sidelobe threshold below which it reports the target lost. OpenCV's default
#: (0.035) lets the box slide over a turning surface while still reporting success: on the box
#: clip a chosen corner drifted 30 px from where Lucas-Kanade followed it; at 0.1 it stops
#: (saying so) before it is 7 px off.
CSRT_PSR_THRESHOLD = 0.1


def follow_points(
    frames: Iterable[Frame],
    frame_size_px: tuple[int, int],
    points_px: list[tuple[float, float]],
    kind: str,
    config: TrackerConfig,
    progress: Callable[[int, float], None] | None = None,
) -> TrackingRun:
    """Follow ``points_px`` (full-resolution x, y) through reduced grey ``frames`` with ``kind``
    (``csrt`` or ``klt``). ``notes`` of the run say which points were lost where."""
    if not points_px:
        raise InputError("no point to follow: give `points_px` (X,Y)")
    if kind not in TRACKERS:
        raise InputError(f"`tracker_kind` must be one of {', '.join(TRACKERS)}; got {kind!r}")
    width_px, height_px = frame_size_px
    for x, y in points_px:
        if not (0 <= x <= width_px - 1 and 0 <= y <= height_px - 1):
            raise InputError(f"`points_px` ({x:g},{y:g}) lies outside the {width_px}x{height_px} frame")
    scale = tracking_scale(frame_size_px, config)
    rows: list[tuple[int, float, int, float, float]] = []
    notes: list[str] = []
    state: _Csrt | _Klt | None = None
    count = 0
    first_time_s = last_time_s = float("nan")
    for frame in frames:
        if state is None:
            start = np.array(points_px, np.float32).reshape(-1, 2) * scale
            state = _Csrt(frame.image, start) if kind == "csrt" else _Klt(frame.image, start, config)
            positions, alive = start, np.ones(len(start), bool)
            first_time_s = frame.time_s
        else:
            positions, alive, lost = state.update(frame.image)
            notes.extend(f"feature {k + 1} lost at frame {frame.index} ({frame.time_s:.2f} s): {why}"
                         for k, why in lost)
        for k in np.flatnonzero(alive):
            rows.append((frame.index, frame.time_s, int(k), float(positions[k, 0]) / scale,
                         float(positions[k, 1]) / scale))
        last_time_s = frame.time_s
        count += 1
        if progress is not None:
            progress(count, frame.time_s)
    tracks = pd.DataFrame(rows, columns=["frame", "time_s", "track", "x_px", "y_px"])
    tracks = tracks.astype({"frame": np.int32, "track": np.int32, "x_px": np.float32, "y_px": np.float32})
    return TrackingRun(tracks.sort_values(["track", "frame"], kind="stable").reset_index(drop=True), count,
                       first_time_s, last_time_s, tuple(notes))


class _Csrt:
    """One CSRT tracker per point, on a box centred on it."""

    def __init__(self, image: np.ndarray, points: np.ndarray) -> None:
        colour = cv2.cvtColor(image, cv2.COLOR_GRAY2BGR) if image.ndim == 2 else image
        self._size = image.shape[1], image.shape[0]
        self._trackers = []
        half = CSRT_BOX_PX // 2
        for x, y in points:
            params = cv2.TrackerCSRT.Params()
            params.psr_threshold = CSRT_PSR_THRESHOLD
            tracker = cv2.TrackerCSRT.create(params)
            tracker.init(colour, (int(round(x)) - half, int(round(y)) - half, CSRT_BOX_PX, CSRT_BOX_PX))
            self._trackers.append(tracker)
        self._positions = points.astype(np.float64).copy()
        self._alive = np.ones(len(points), bool)

    def update(self, image: np.ndarray) -> tuple[np.ndarray, np.ndarray, list[tuple[int, str]]]:
        colour = cv2.cvtColor(image, cv2.COLOR_GRAY2BGR) if image.ndim == 2 else image
        lost = []
        width, height = self._size
        for k in np.flatnonzero(self._alive):
            ok, (x, y, w, h) = self._trackers[k].update(colour)
            inside = ok and x >= 0 and y >= 0 and x + w <= width and y + h <= height
            if not inside:
                self._alive[k] = False
                lost.append((int(k), "CSRT lost it" if not ok else "it left the frame"))
                continue
            self._positions[k] = (x + w / 2.0 - 0.5, y + h / 2.0 - 0.5)
        return self._positions, self._alive.copy(), lost


class _Klt:
    """Pyramidal Lucas-Kanade on the chosen points, with the forward-backward check."""

    def __init__(self, image: np.ndarray, points: np.ndarray, config: TrackerConfig) -> None:
        self._prev = image
        self._positions = points.astype(np.float32).copy()
        self._velocity = np.zeros_like(self._positions)  # the last step, to predict the next
        self._alive = np.ones(len(points), bool)
        self._config = config
        self._lk = {"winSize": (config.win_width_px, config.win_height_px), "maxLevel": config.pyramid_levels,
                    "criteria": (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 30, 0.01)}

    def update(self, image: np.ndarray) -> tuple[np.ndarray, np.ndarray, list[tuple[int, str]]]:
        lost: list[tuple[int, str]] = []
        live = np.flatnonzero(self._alive)
        if len(live):
            start = self._positions[live].reshape(-1, 1, 2)
            velocity = self._velocity[live].reshape(-1, 1, 2)
            flags = cv2.OPTFLOW_USE_INITIAL_FLOW
            moved, status, _ = cv2.calcOpticalFlowPyrLK(self._prev, image, start, start + velocity, flags=flags,
                                                        **self._lk)
            back, status_back, _ = cv2.calcOpticalFlowPyrLK(image, self._prev, moved, moved - velocity, flags=flags,
                                                            **self._lk)
            error = np.linalg.norm((back - start).reshape(-1, 2), axis=1)
            height, width = image.shape[:2]
            moved = moved.reshape(-1, 2)
            for i, k in enumerate(live):
                x, y = moved[i]
                if status[i, 0] != 1 or status_back[i, 0] != 1 or error[i] >= self._config.fb_max_error_px:
                    self._alive[k] = False
                    lost.append((int(k), "the forward-backward check failed"))
                elif not (0 <= x <= width - 1 and 0 <= y <= height - 1):
                    self._alive[k] = False
                    lost.append((int(k), "it left the frame"))
                else:
                    self._velocity[k] = moved[i] - self._positions[k]
                    self._positions[k] = moved[i]
        self._prev = image
        return self._positions, self._alive.copy(), lost
