"""The decoder's own luma plane, used as the grey image where it checks out against OpenCV's
colour conversion (skipping the conversion to BGR and back), and OpenCV's log kept quiet while
it is read."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

import cv2
import numpy as np

#: Codecs whose luma plane OpenCV hands over faster than its BGR conversion (FOURCC, upper case).
#: For others it is slower, though it skips the conversion: 720p, 240 frames, luma against BGR
#: and grey conversion, seconds: MPEG-4 part 2 (FMP4) 0.15 / 0.26, MJPEG 0.54 / 0.57; H.264
#: 0.68 / 0.37, HEVC 0.73 / 0.61, VP9 0.70 / 0.64, and on the real record clip (H.264, 722
#: frames) 2.30 / 1.76. Their grey is converted from BGR.
LUMA_CODECS = frozenset({"FMP4", "MP4V", "XVID", "DIVX", "DX50", "MJPG"})
#: Checks of the decoder's own luma against its colour conversion (see :meth:`FrameSource.frames`):
#: the gain must be near that of studio-range luma (255/219), and the fit within this many levels.
_LUMA_GAIN_RANGE = (0.9, 1.3)
_LUMA_MAX_RMS = 2.0


@contextmanager
def quiet_opencv() -> Iterator[None]:
    """Silence OpenCV's log for a while: the FFmpeg backend warns on stderr every time it is
    asked for undecoded (luma) frames, which we check ourselves."""
    logging = getattr(getattr(cv2, "utils", None), "logging", None)  # not in every OpenCV build (4.9-4.12)
    if logging is None:
        yield
        return
    level = logging.getLogLevel()
    logging.setLogLevel(min(level, logging.LOG_LEVEL_ERROR))
    try:
        yield
    finally:
        logging.setLogLevel(level)


def luma_table(luma: np.ndarray | None, first_grey: np.ndarray | None, size: tuple[int, int]) -> np.ndarray | None:
    """A 256-entry table taking the decoder's luma of the first frame (``size`` = rows, columns)
    to ``COLOR_BGR2GRAY`` grey (``first_grey``, that frame's grey at every 4th pixel), or None
    where the luma is missing, too flat to check, or does not fit a straight line closely: the
    grey of BGR is, up to rounding, a straight-line function of studio-range luma."""
    if luma is None or first_grey is None or luma.dtype != np.uint8 or luma.shape != size:
        return None
    x = luma[::4, ::4].astype(float).ravel()
    y = first_grey.astype(float).ravel()
    if x.std() <= 4.0:
        return None
    gain, bias = np.polyfit(x, y, 1)
    rms = float(np.sqrt(np.mean((gain * x + bias - y) ** 2)))
    if not (_LUMA_GAIN_RANGE[0] <= gain <= _LUMA_GAIN_RANGE[1] and rms <= _LUMA_MAX_RMS):
        return None
    return np.clip(np.rint(gain * np.arange(256) + bias), 0, 255).astype(np.uint8)
