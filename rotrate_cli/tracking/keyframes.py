"""Some of the tracker's own images, kept evenly over the clip: for the lens's fit and the plane's
turning, which place their samples again on them (:mod:`rotrate_cli.scene.patches`).

A tap on the stream of reduced grey frames (as :class:`rotrate_cli.stages.period.Thumbnails` is): every
``step``-th frame is kept, and when the kept images pass :data:`MAX_BYTES` the step doubles and
every other one goes. So whatever the clip's length, at most that much memory is held, and the
kept frames stay evenly spread over the whole clip. A clip long enough to thin them far apart
(thousands of frames) usually repeats itself, and then no lens is sought.
"""

from __future__ import annotations

from collections.abc import Iterator

import cv2
import numpy as np

from rotrate_cli.tracking.steady import CameraPath
from rotrate_cli.video.frames import Frame

#: At most this many bytes of images are kept: 109 frames of 640x360, 81 of 640x480.
MAX_BYTES = 24 << 20


class Keyframes:
    """Reduced grey frames (the tracker's, ``scale`` times the full resolution) kept by index.

    ``camera``: a shaken camera's motion (:mod:`rotrate_cli.tracking.steady`), where the tracks were
    steadied: their positions are carried back to where the camera saw them before being matched
    on these images.
    """

    def __init__(self, scale: float, max_bytes: int = MAX_BYTES) -> None:
        self.scale = scale
        self.step = 1
        self.camera: CameraPath | None = None
        self._max = max_bytes
        self._images: dict[int, np.ndarray] = {}

    def tap(self, frames: Iterator[Frame]) -> Iterator[Frame]:
        """Yield ``frames`` unchanged, keeping every ``step``-th one's image."""
        for frame in frames:
            if frame.index % self.step == 0:
                self._add(frame.index, frame.image)
            yield frame

    def _add(self, index: int, image: np.ndarray) -> None:
        grey = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY) if image.ndim == 3 else np.array(image, dtype=np.uint8)
        self._images[index] = grey
        while len(self._images) > 2 and len(self._images) * grey.nbytes > self._max:
            self.step *= 2
            self._images = {kept: picture for kept, picture in self._images.items() if kept % self.step == 0}

    def has(self, frames: np.ndarray) -> np.ndarray:
        """Which of ``frames`` (indices) have an image kept."""
        return np.isin(frames, np.fromiter(self._images, dtype=np.int64, count=len(self._images)))

    def indices(self) -> np.ndarray:
        """The frames (indices) whose images are kept, in order."""
        return np.array(sorted(self._images), dtype=np.int64)

    def keep_only(self, frames: np.ndarray) -> None:
        """Let go of every image but those of ``frames`` (indices)."""
        wanted = {int(frame) for frame in frames}
        self._images = {kept: picture for kept, picture in self._images.items() if kept in wanted}

    def image(self, frame: int) -> np.ndarray:
        return self._images[int(frame)]

    def __len__(self) -> int:
        return len(self._images)

    def clear(self) -> None:
        """Let the images go (the clip is tracked again, or the lens is found)."""
        self._images = {}
        self.step = 1
