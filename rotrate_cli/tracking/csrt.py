"""Automatic points followed by OpenCV's CSRT tracker (``--tracker csrt``).

Corners are seeded, and points that stay put or reach the outline are dropped, exactly as for
Lucas-Kanade (:class:`rotrate_cli.tracking.klt.CornerTracker`); what differs is how a point is
followed from frame to frame:

1. **CSRT** (a discriminative correlation filter on a small box around the point) finds it again
   in the new frame, or reports it lost (peak-to-sidelobe ratio below
   :data:`rotrate_cli.tracking.chosen.CSRT_PSR_THRESHOLD`). Its boxes are whole pixels.
2. **Sub-pixel position:** the point's own patch from the frame where it was seeded is matched
   (normalised cross-correlation) within :data:`SEARCH_PX` of CSRT's answer, and the peak is
   placed to a fraction of a pixel by a parabola through its neighbours. The point stops when
   the match is poor (the surface has turned too far from how it was first seen:
   :data:`MIN_CORRELATION`) or lies at the edge of the search (CSRT and the patch disagree).
   Matching against the first patch, not the previous frame's, adds no frame-to-frame drift.

On the bundled clips CSRT's whole-pixel centres alone gave 0.587 (box, truth 0.6), 0.384
(cylinder, 0.4) and 1.003 (sphere, 1.0); with the sub-pixel step 0.601, 0.400 and 0.999.

CSRT is a video tracker: it searches a few box widths around the last position, so stills taken
far apart (the dinosaur's 10 degrees a step) lose every point within a frame or two; use the
default Lucas-Kanade tracker there. It costs about half a millisecond per point and frame
(colour names, HOG and the colour segmentation are off: the frames are grey), in two threads, so
:func:`csrt_settings` follows fewer points than Lucas-Kanade does.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace

import cv2
import numpy as np

from rotrate_cli.tracking.chosen import CSRT_PSR_THRESHOLD
from rotrate_cli.tracking.klt import CornerTracker, TrackerConfig

#: Side of CSRT's box around each point, tracking-image pixels (odd: centred on a pixel).
BOX_PX = 15
#: Side of the patch matched for the sub-pixel position (odd).
TEMPLATE_PX = 11
#: How far (pixels) the patch match may move CSRT's whole-pixel answer.
SEARCH_PX = 2
#: The least normalised cross-correlation of a point's patch with its first appearance.
MIN_CORRELATION = 0.8
#: Points followed at once (Lucas-Kanade follows :attr:`TrackerConfig.max_points`).
MAX_POINTS = 30
#: Spacing of seeded corners, tracking-image pixels: boxes barely overlap.
MIN_DISTANCE_PX = 15.0


def csrt_settings(config: TrackerConfig) -> TrackerConfig:
    """The tracker settings for CSRT: fewer, wider-spaced points, and the outline and seeding
    checks sized to CSRT's box rather than the Lucas-Kanade window."""
    return replace(config, max_points=min(config.max_points, MAX_POINTS), min_distance_px=MIN_DISTANCE_PX,
                   win_width_px=BOX_PX, win_height_px=BOX_PX)


def _create(colour: np.ndarray, x_px: int, y_px: int) -> cv2.Tracker:
    params = cv2.TrackerCSRT.Params()
    params.psr_threshold = CSRT_PSR_THRESHOLD
    params.use_hog = False
    params.use_color_names = False
    params.use_gray = True
    params.use_segmentation = False
    params.template_size = 48
    params.number_of_scales = 3
    tracker = cv2.TrackerCSRT.create(params)
    half = BOX_PX // 2
    tracker.init(colour, (x_px - half, y_px - half, BOX_PX, BOX_PX))
    return tracker


_POOL: ThreadPoolExecutor | None = None


def _pool() -> ThreadPoolExecutor:
    """The threads that update the CSRT trackers (two: the machines this runs on have two cores
    besides the decoder's), made on first use and shared."""
    global _POOL
    if _POOL is None:
        _POOL = ThreadPoolExecutor(max_workers=2, thread_name_prefix="rotrate-csrt")
    return _POOL


def _parabola_peak(left: float, centre: float, right: float) -> float:
    """Offset (-0.5..0.5) of the top of the parabola through three equally spaced values."""
    curvature = left - 2.0 * centre + right
    return 0.0 if curvature >= 0 else float(np.clip(0.5 * (left - right) / curvature, -0.5, 0.5))


class CsrtTracker(CornerTracker):
    """Corners followed by CSRT, placed to sub-pixel by matching their first patch."""

    def __init__(self, frame_size_px: tuple[int, int], config: TrackerConfig) -> None:
        super().__init__(frame_size_px, config)
        # per point id: its CSRT tracker, its first patch, and the seed's fraction of a pixel
        self._trackers: dict[int, cv2.Tracker] = {}
        self._patches: dict[int, np.ndarray] = {}
        self._fractions: dict[int, tuple[float, float]] = {}

    def _seeded(self, grey: np.ndarray, corners: np.ndarray, ids: np.ndarray) -> np.ndarray:
        colour = cv2.cvtColor(grey, cv2.COLOR_GRAY2BGR)
        height, width = grey.shape
        half = max(BOX_PX, TEMPLATE_PX) // 2 + SEARCH_PX
        usable = np.zeros(len(corners), bool)
        for k, ((x, y), point_id) in enumerate(zip(corners, ids, strict=True)):
            ix, iy = int(round(float(x))), int(round(float(y)))
            if not (half <= ix < width - half and half <= iy < height - half):
                continue
            t = TEMPLATE_PX // 2
            self._trackers[int(point_id)] = _create(colour, ix, iy)
            self._patches[int(point_id)] = grey[iy - t:iy + t + 1, ix - t:ix + t + 1].copy()
            self._fractions[int(point_id)] = (float(x) - ix, float(y) - iy)
            usable[k] = True
        return usable

    def _move(self, grey: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        self._forget_dropped()
        colour = cv2.cvtColor(grey, cv2.COLOR_GRAY2BGR)
        moved = self._points.copy()
        keep = np.zeros(len(self._ids), bool)
        ids = self._ids.tolist()
        # OpenCV lets go of the interpreter inside each update: two at once use both cores (1.45x)
        answers = _pool().map(lambda point_id: self._trackers[point_id].update(colour), ids)
        for k, (point_id, (found, box)) in enumerate(zip(ids, answers, strict=True)):
            if not found:
                continue
            x_box, y_box, w_box, h_box = box
            where = self._refine(grey, point_id, x_box + w_box / 2.0 - 0.5, y_box + h_box / 2.0 - 0.5)
            if where is not None:
                moved[k] = where
                keep[k] = True
        return moved, keep

    def _refine(self, grey: np.ndarray, point_id: int, x_px: float, y_px: float) -> tuple[float, float] | None:
        """The point's sub-pixel position near CSRT's centre (x_px, y_px), or None when its first
        patch matches poorly there or only at the edge of the search."""
        patch = self._patches[point_id]
        t = TEMPLATE_PX // 2
        ix, iy = int(round(x_px)), int(round(y_px))
        x0, y0 = ix - t - SEARCH_PX, iy - t - SEARCH_PX
        size = TEMPLATE_PX + 2 * SEARCH_PX
        height, width = grey.shape
        if x0 < 0 or y0 < 0 or x0 + size > width or y0 + size > height:
            return None
        scores = cv2.matchTemplate(grey[y0:y0 + size, x0:x0 + size], patch, cv2.TM_CCOEFF_NORMED)
        _, best, _, (px, py) = cv2.minMaxLoc(scores)
        edge = 2 * SEARCH_PX
        if best < MIN_CORRELATION or px in (0, edge) or py in (0, edge):
            return None
        dx = _parabola_peak(scores[py, px - 1], scores[py, px], scores[py, px + 1])
        dy = _parabola_peak(scores[py - 1, px], scores[py, px], scores[py + 1, px])
        fx, fy = self._fractions[point_id]
        return x0 + px + t + dx + fx, y0 + py + t + dy + fy

    def _forget_dropped(self) -> None:
        """Free the trackers of points dropped since the last frame (static, outline, lost)."""
        if len(self._trackers) == len(self._ids):
            return
        live = set(self._ids.tolist())
        for point_id in [i for i in self._trackers if i not in live]:
            del self._trackers[point_id], self._patches[point_id], self._fractions[point_id]
