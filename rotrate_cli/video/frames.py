"""What every reader of pictures hands on: a source's :class:`VideoInfo` and its :class:`Frame` objects."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np


@dataclass(frozen=True)
class VideoInfo:
    """What is known about a source before decoding it.

    Attributes:
        source: the path or pattern as the user gave it.
        width_px, height_px: frame size in pixels.
        fps: frame rate in frames per second (the container's, or the user's override).
        frame_count: the container's frame count, or the number of images; None when unknown.
        is_image_sequence: True for image patterns and folders.
        fps_overridden: True when the user gave the rate, so times are ``index / fps``.
        clock: where frame times come from: ``container``, ``fps``, ``exif`` or ``times file``
            (see :class:`rotrate_cli.video.clock.Clock`).
        clock_resolution_s: how finely those times are known, seconds.
        focal_px: the lens's focal length in pixels from the photographs' EXIF, or None.
    """

    source: str
    width_px: int
    height_px: int
    fps: float
    frame_count: int | None
    is_image_sequence: bool
    fps_overridden: bool
    clock: str = "container"
    clock_resolution_s: float = 0.0
    focal_px: float | None = None


@dataclass(frozen=True)
class Frame:
    """One decoded frame: its 0-based index in the source, its time in seconds, and its pixels.

    ``image`` is whatever the source's transform returned (BGR uint8 by default).
    """

    index: int
    time_s: float
    image: Any


def mean_rate(times_s: np.ndarray) -> float:
    """Frames per second on average over ``times_s``."""
    return (len(times_s) - 1) / float(times_s[-1] - times_s[0])
