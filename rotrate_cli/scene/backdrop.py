"""The camera's own turn, as the picture around a turning plane shows it (:func:`backdrop_path`).

Where nothing in the picture stays still and its rim moves (:data:`rotrate_cli.stages.tracks.NO_BACKGROUND_NOTE`),
two cases look alike to the tracks: a body so large that it reaches the picture's rim, before a
still camera, and a camera that turns over a body before a plain backdrop, whose few points the
tracker follows too briefly to tell the camera's motion (:mod:`rotrate_cli.tracking.steady` needs a
dozen long background tracks spread over the picture). Once the tracks have shown one plane turning
(:mod:`rotrate_cli.scene.plane_turn`) and where its picture lies, the rest of the picture tells
them apart: corners found outside the plane on the tracker's first kept image are followed from
image to image and each image's turn, shift and scale fitted to them (RANSAC). A still camera's
backdrop stays put; a turning camera's turns with it, and every point on the plane carries that
turn on top of the body's.

A photograph on a disc turning 1.5 rad/s face on before a plain backdrop (a table, a wall, a
dinosaur behind it), the camera rolling 3 degrees a second: nine short background tracks, no
camera path found, the plane read +3.5% within +-0.1%, good.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from rotrate_cli.runtime.lazy import pandas as pd
from rotrate_cli.scene.disc import PlaneMap
from rotrate_cli.tracking.keyframes import Keyframes

#: The plane's picture, and this share more of its radius, is left out of the backdrop: its tracks
#: reach a little short of its rim (their 98th percentile).
PLANE_MARGIN = 0.25
#: Corners sought on the backdrop (OpenCV's ``goodFeaturesToTrack``): at most, their quality
#: (a share of the strongest) and spacing (tracking pixels).
MOST_CORNERS = 300
CORNER_QUALITY = 0.01
CORNER_SPACING_PX = 8
#: A corner followed from image to image must come back within this (tracking pixels, Lucas-Kanade
#: run backwards), and each image's fit hold at least :data:`MIN_POINTS` of them within
#: :data:`FIT_PX` (RANSAC) ...
ROUND_TRIP_PX = 0.5
MIN_POINTS = 8
FIT_PX = 1.0
#: ... spread across at least this share of the picture's larger side: a small patch turns and
#: shifts alike.
MIN_REACH = 0.25
#: A backdrop that turned less than this over the clip (degrees) is still (as
#: :data:`rotrate_cli.tracking.steady.ROLL_DEG`).
ROLL_DEG = 0.3


@dataclass(frozen=True)
class BackdropPath:
    """The backdrop's motion: for each frame kept, the similarity (2 x 3, full-resolution pixels)
    that takes the first kept frame's picture to it.

    Attributes:
        frames: the frames (indices) it is known at.
        warps: their similarities, ``(len(frames), 2, 3)``.
        turned_deg: the backdrop's turn at each, degrees (anticlockwise as the picture shows it).
        turn_deg_s: its rate of turning, a line over the frames' times, degrees a second.
        points: corners that showed it (in the first image).
    """

    frames: np.ndarray
    warps: np.ndarray
    turned_deg: np.ndarray
    turn_deg_s: float
    points: int

    def steady(self, samples: pd.DataFrame) -> pd.DataFrame:
        """``samples`` (``frame, ..., x_px, y_px``) as a still camera would have seen them (in
        the first kept frame's picture); those at frames where the backdrop's motion is not known
        are left out."""
        index = np.searchsorted(self.frames, samples["frame"].to_numpy())
        known = (index < len(self.frames)) & (self.frames[np.minimum(index, len(self.frames) - 1)]
                                               == samples["frame"].to_numpy())
        samples = samples[known]
        warps = self.warps[index[known]]
        linear, shift = warps[:, :, :2], warps[:, :, 2]
        points = samples[["x_px", "y_px"]].to_numpy(np.float64) - shift
        back = np.linalg.solve(linear, points[:, :, None])[:, :, 0]
        return samples.assign(x_px=back[:, 0], y_px=back[:, 1]).reset_index(drop=True)


def backdrop_path(keyframes: Keyframes, frames: np.ndarray, times_s: np.ndarray,
                  plane_map: PlaneMap) -> BackdropPath | None:
    """The backdrop's motion over ``frames`` (indices with images kept in ``keyframes``, at
    ``times_s``), outside the plane ``plane_map`` (its tracks' picture, full-resolution pixels);
    None where too few corners lie or hold outside it, or it turned less than :data:`ROLL_DEG`
    (see the module's notes)."""
    order = np.argsort(frames)
    frames, times_s = np.asarray(frames)[order], np.asarray(times_s, np.float64)[order]
    if len(frames) < 3:
        return None
    scale = keyframes.scale
    first = keyframes.image(frames[0])
    outside = _outside(plane_map, first.shape, scale)
    corners = cv2.goodFeaturesToTrack(first, MOST_CORNERS, CORNER_QUALITY, CORNER_SPACING_PX,
                                      mask=outside.astype(np.uint8) * 255)
    if corners is None or len(corners) < MIN_POINTS:
        return None
    start = corners.reshape(-1, 2).astype(np.float32)
    alive = np.ones(len(start), bool)
    points, previous = start.copy(), first
    known, warps = [0], [np.hstack([np.eye(2), np.zeros((2, 1))])]
    for k in range(1, len(frames)):
        image = keyframes.image(frames[k])
        ahead, status, _ = cv2.calcOpticalFlowPyrLK(previous, image, points, None)
        back, status_back, _ = cv2.calcOpticalFlowPyrLK(image, previous, ahead, None)
        alive &= (status.ravel() == 1) & (status_back.ravel() == 1)
        alive &= np.hypot(*(back - points).T) <= ROUND_TRIP_PX
        points, previous = ahead, image
        if alive.sum() < MIN_POINTS or _reach(start[alive]) < MIN_REACH * max(first.shape):
            break
        warp, held = cv2.estimateAffinePartial2D(start[alive], points[alive], method=cv2.RANSAC,
                                                 ransacReprojThreshold=FIT_PX)
        if warp is None or int(held.sum()) < MIN_POINTS:
            break
        known.append(k)
        warps.append(warp)
    if len(known) < 3:
        return None
    warps_px = np.array(warps, np.float64)
    warps_px[:, :, 2] /= scale  # the shift in full-resolution pixels
    turned = -np.degrees(np.arctan2(warps_px[:, 1, 0], warps_px[:, 0, 0]))  # y down: anticlockwise as shown
    if float(np.ptp(turned)) < ROLL_DEG:
        return None
    rate = float(np.polyfit(times_s[known], turned, 1)[0])
    return BackdropPath(frames[known], warps_px, turned, rate, int(alive.sum()))


def _outside(plane_map: PlaneMap, shape: tuple[int, ...], scale: float) -> np.ndarray:
    """The tracking image's pixels (``shape``, ``scale`` times full resolution) that lie outside
    the plane's picture, with :data:`PLANE_MARGIN`."""
    height, width = shape[:2]
    yy, xx = np.mgrid[:height, :width].astype(np.float64)
    points = np.stack([xx.ravel(), yy.ravel()], axis=1) / scale
    away = points @ np.array(plane_map.horizon) + 1.0
    ahead = away > 1e-3
    flat = points / np.where(ahead, away, 1.0)[:, None]
    local = np.linalg.solve(np.array(plane_map.metric), (flat - np.array(plane_map.centre)).T)
    radius = np.hypot(local[0], local[1])
    on_plane = ahead & (radius <= (1.0 + PLANE_MARGIN) * plane_map.largest)
    return ~on_plane.reshape(height, width)


def _reach(points: np.ndarray) -> float:
    """The larger side of the points' bounding box."""
    return float(np.max(np.ptp(points, axis=0))) if len(points) > 1 else 0.0
