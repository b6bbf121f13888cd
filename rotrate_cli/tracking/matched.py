"""Tracks for photographs taken far apart on the turn: features matched from one photograph to the
next (:func:`match_frames`).

Lucas-Kanade follows a point by the small step it takes between frames. Photographs of a
turntable lie 5-10 degrees apart (the shared dinosaur's 10, the EPFL cars' 5): a point's picture
changes with the view, and Lucas-Kanade keeps few points for more than a photograph or two (the
dinosaur's first 9 photographs: 104 tracks, 77 of one photograph, none from the first four). SIFT
features (scale- and turn-invariant descriptors, in OpenCV's main module since 4.4) are matched
instead: each to its nearest in the next photograph where that is clearly nearer than the second
nearest (Lowe's ratio), and the matches kept are those one rigid motion explains (a fundamental
matrix fitted by RANSAC: a body turning before a still camera is one rigid motion). Points that
do not move (the still background) are let go first, as the tracker lets go of still points.
A track is a feature followed by its matches from photograph to photograph.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable

import cv2
import numpy as np

from rotrate_cli.runtime.lazy import pandas as pd
from rotrate_cli.tracking.klt import Tally, TrackingRun
from rotrate_cli.video.frames import Frame

#: Features sought per photograph, at most.
MOST_FEATURES = 3000
#: A match is kept where its descriptor is nearer than this share of the second nearest's.
RATIO = 0.75
#: Matches that moved less than this (tracking pixels) are the still background's.
STILL_PX = 0.5
#: Matches within this many tracking pixels of their epipolar lines are the rigid motion's.
EPIPOLAR_PX = 1.0
#: Fewer matches than this between two photographs tell no rigid motion: none are kept.
MIN_MATCHES = 8


def match_frames(frames: Iterable[Frame], scale: float,
                 progress: Callable[[int, float], None] | None = None) -> TrackingRun:
    """Tracks (``frame, time_s, track, x_px, y_px``, full-resolution pixels) of SIFT features
    matched from each frame to the next (see the module's notes); ``frames``' images are grey
    tracking images, ``scale`` times the full resolution."""
    sift = cv2.SIFT_create(nfeatures=MOST_FEATURES)
    matcher = cv2.BFMatcher(cv2.NORM_L2)
    rows: list[tuple[int, float, int, float, float]] = []
    previous: tuple[Frame, np.ndarray, np.ndarray | None] | None = None
    track_of: dict[int, int] = {}
    next_track = 0
    tally = Tally()
    for frame in tally.counted(frames, progress):
        points, descriptors = _features(sift, frame.image, scale)
        current_track: dict[int, int] = {}
        if previous is not None and previous[2] is not None and descriptors is not None:
            before, before_points, before_descriptors = previous
            for i, j in _rigid_matches(matcher, before_points, before_descriptors, points, descriptors):
                track = track_of.get(i)
                if track is None:
                    track = next_track
                    next_track += 1
                    x, y = before_points[i] / scale
                    rows.append((before.index, before.time_s, track, float(x), float(y)))
                current_track[j] = track
                x, y = points[j] / scale
                rows.append((frame.index, frame.time_s, track, float(x), float(y)))
        track_of = current_track
        previous = (frame, points, descriptors)
    tracks = pd.DataFrame(rows, columns=["frame", "time_s", "track", "x_px", "y_px"])
    tracks = tracks.astype({"frame": np.int64, "time_s": np.float64, "track": np.int64,
                            "x_px": np.float32, "y_px": np.float32})
    tracks = tracks.sort_values(["track", "frame"], kind="stable").reset_index(drop=True)
    return TrackingRun(tracks, tally.count, tally.first_time_s, tally.last_time_s)


def _features(sift: cv2.SIFT, image: np.ndarray, scale: float) -> tuple[np.ndarray, np.ndarray | None]:
    """SIFT features of a tracking image (``scale`` times the full resolution): sought in the
    picture at its own size where the tracker enlarged it (SIFT doubles its picture itself;
    the EPFL cars' 376-px photographs enlarged twice took four times as long), placed in the
    tracking image's pixels."""
    grey = image if image.dtype == np.uint8 else np.clip(image, 0, 255).astype(np.uint8)
    if scale > 1.0:
        grey = cv2.resize(grey, None, fx=1.0 / scale, fy=1.0 / scale, interpolation=cv2.INTER_AREA)
    keypoints, descriptors = sift.detectAndCompute(grey, None)
    points = np.array([point.pt for point in keypoints], np.float32).reshape(-1, 2)
    if scale > 1.0:
        points = (points + 0.5) * scale - 0.5
    return points, descriptors


def _rigid_matches(matcher: cv2.DescriptorMatcher, points_a: np.ndarray, descriptors_a: np.ndarray,
                   points_b: np.ndarray, descriptors_b: np.ndarray) -> list[tuple[int, int]]:
    """Index pairs of features of two photographs that match clearly, move, and agree with one
    rigid motion (see the module's notes)."""
    if len(points_a) < 2 or len(points_b) < 2:
        return []
    pairs = [(best.queryIdx, best.trainIdx) for best, second in
             (m for m in matcher.knnMatch(descriptors_a, descriptors_b, k=2) if len(m) == 2)
             if best.distance < RATIO * second.distance]
    if not pairs:
        return []
    index = np.array(pairs)
    a, b = points_a[index[:, 0]], points_b[index[:, 1]]
    moving = np.hypot(*(b - a).T) >= STILL_PX
    index, a, b = index[moving], a[moving], b[moving]
    if len(index) < MIN_MATCHES:
        return []
    _, inliers = cv2.findFundamentalMat(a, b, cv2.FM_RANSAC, EPIPOLAR_PX, 0.999)
    if inliers is None:
        return []
    return [(int(i), int(j)) for (i, j), kept in zip(index, inliers.ravel().astype(bool), strict=True) if kept]
