"""Lights that flicker with the mains taken out of a stream of frames: a frame whose mean
brightness differs from the recent frames' is brought to it (videos; stills exposed one by one
differ for their own reasons)."""

from __future__ import annotations

import statistics
from collections import deque

import cv2
import numpy as np

#: A frame whose mean brightness differs by more than this fraction from the median of the last
#: :data:`LIGHT_FRAMES` frames' is brought to it: lights that flicker with the mains (50 Hz seen at
#: 30 frames/s as 10 Hz). A 5% flicker marked the whole still background as moving, its points
#: stuck at the outline, and a rendered box read 0.065 rad/s for 0.5; at 30% Lucas-Kanade lost
#: every point within a few frames (12,700 tracks). A turning body changes the mean slowly, which
#: the median follows (against the first frame's, the accuracy suite's clips drift past 1%).
FLICKER_GAIN = 0.01
LIGHT_FRAMES = 9
#: ... and by at most this fraction: a larger change is a cut, a fade or a light switched, not a
#: flicker. Brought to the recent frames' median, a cut from black to the picture left it black
#: for 5 frames (the median was black until most of the last 9 were not).
FLICKER_MOST = 0.5


def steady_light(levels: deque[float], level: float) -> float:
    """The factor that brings a frame of mean brightness ``level`` to the median of the recent
    ``levels`` where it differs by more than :data:`FLICKER_GAIN` and at most :data:`FLICKER_MOST`
    (else 1); ``level`` joins them."""
    usual = statistics.median(levels) if levels else level  # a few values: faster than numpy's
    levels.append(level)
    if level > 0 and FLICKER_GAIN < abs(usual / level - 1.0) <= FLICKER_MOST:
        return usual / level
    return 1.0


class SteadyLight:
    """Brings each grey image passed to :meth:`steadied`, in order, to the brightness usual in the
    last :data:`LIGHT_FRAMES` (see :func:`steady_light`)."""

    def __init__(self) -> None:
        self._levels: deque[float] = deque(maxlen=LIGHT_FRAMES)

    def steadied(self, image: np.ndarray) -> np.ndarray:
        scale = steady_light(self._levels, float(cv2.mean(image)[0]))
        return image if scale == 1.0 else cv2.convertScaleAbs(image, alpha=scale)

    def clear(self) -> None:
        self._levels.clear()
