"""The frames the picture's turning angle is measured on (:mod:`rotrate_cli.scene.picture_angle`):
kept from the decoded stream in runs of two consecutive ones, evenly over the clip, reduced and
grey; and turned back by a camera's roll (:mod:`rotrate_cli.stages.roll`), consecutive ones together.
"""

from __future__ import annotations

from collections.abc import Iterator

import cv2
import numpy as np

from rotrate_cli.video.frames import Frame

#: Frames kept (in runs of two consecutive ones, evenly over the clip), and their longer side, px.
MOST_KEPT = 128
SIDE_PX = 320


class AngleFrames:
    """Keeps frames for the picture's angle: in runs of two consecutive ones, at most
    :data:`MOST_KEPT` (every other run let go, and the spacing doubled, when more come), reduced to
    :data:`SIDE_PX` (a tap on the frame stream, as :class:`rotrate_cli.scene.turning.FramePairs`)."""

    def __init__(self, most: int = MOST_KEPT) -> None:
        self._most = most
        self._stride = 1
        self._kept: list[tuple[int, float, np.ndarray]] = []
        self.width_px = 0

    def clear(self) -> None:
        self._kept.clear()
        self._stride = 1

    @property
    def frames(self) -> list[tuple[int, float, np.ndarray]]:
        """``(index, time_s, grey image)`` per frame kept, in order."""
        return list(self._kept)

    def tap(self, frames: Iterator[Frame]) -> Iterator[Frame]:
        """Yield ``frames`` unchanged, keeping some (see the class)."""
        for frame in frames:
            if frame.index % self._stride < 2:
                self.width_px = frame.image.shape[1]
                self._kept.append((frame.index, frame.time_s, reduced_grey(frame.image)))
                while len(self._kept) > self._most:  # (a spacing of 2 keeps every frame: 1, 4, 8 ...)
                    self._stride = max(4, self._stride * 2)
                    self._kept = [kept for kept in self._kept if kept[0] % self._stride < 2]
            yield frame


    def turned_back(self, roll_deg_s: float, start_s: float) -> AngleFrames:
        """A copy whose frames are turned back about their centres by a camera's steady roll
        (degrees a second, anticlockwise as the picture shows it) since ``start_s``."""
        copy = AngleFrames(self._most)
        copy._stride, copy.width_px = self._stride, self.width_px
        # consecutive frames (whose change is measured) turned back together: see turned_back_together
        runs: list[list[tuple[int, float, np.ndarray]]] = []
        for kept in self._kept:
            if runs and kept[0] == runs[-1][-1][0] + 1:
                runs[-1].append(kept)
            else:
                runs.append([kept])
        for run in runs:
            images = turned_back_together([image for _, _, image in run],
                                          [roll_deg_s * (time_s - start_s) for _, time_s, _ in run])
            copy._kept += [(index, time_s, image) for (index, time_s, _), image in zip(run, images, strict=True)]
        return copy


def turned_back(image: np.ndarray, roll_deg: float, border: int = cv2.BORDER_CONSTANT) -> np.ndarray:
    """``image`` turned back about its centre by a camera's roll of ``roll_deg`` (anticlockwise as
    shown). The corners turned in are black by default (alike in consecutive frames: no change
    there); ``border``: OpenCV's rule for them otherwise."""
    rows, columns = image.shape[:2]
    matrix = cv2.getRotationMatrix2D(((columns - 1) / 2.0, (rows - 1) / 2.0), -roll_deg, 1.0)
    return cv2.warpAffine(image, matrix, (columns, rows), flags=cv2.INTER_LINEAR, borderMode=border)


#: The pictures turned back together are kept this far (pixels) inside what every one of them shows.
SHOWN_MARGIN_PX = 2


def turned_back_together(images: list[np.ndarray], rolls_deg: list[float]) -> list[np.ndarray]:
    """Each of ``images`` (pictures a moment apart) turned back by its camera's roll (as
    :func:`turned_back`), and all of them black outside what every one of them shows: turned by
    different rolls, their edges of the frame lie apart, and would change the picture where nothing
    turned (a still scene's two frames a moment apart, turned back alone, differ along the frame's
    edges by the whole grey level there; together, nowhere)."""
    turned = [turned_back(image, roll) for image, roll in zip(images, rolls_deg, strict=True)]
    if not any(rolls_deg):
        return turned
    shown = np.full(images[0].shape[:2], 255, np.uint8)
    for roll in rolls_deg:
        shown = np.minimum(shown, turned_back(np.full(images[0].shape[:2], 255, np.uint8), roll))
    shown = cv2.erode(shown, np.ones((2 * SHOWN_MARGIN_PX + 1,) * 2, np.uint8)) == 255
    for image in turned:
        image[~shown] = 0
    return turned


def reduced_grey(image: np.ndarray, side_px: int = SIDE_PX) -> np.ndarray:
    """``image`` (grey or BGR) in grey, its longer side at most ``side_px``."""
    if image.ndim == 3:
        image = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
    scale = side_px / max(image.shape[:2])
    if scale < 1:
        image = cv2.resize(image, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)
    return np.asarray(image, dtype=np.uint8)
