"""The clip's shots: where it cuts from one picture to another (:func:`longest_shot`).

Real clips are edited: a still calibration frame before the turning starts, a title card, a cut
to another camera. A track cannot cross a cut, and the clip's repetition is blurred by frames
that belong to another scene, so a run measures one shot: the longest.

A cut shows in the frames' thumbnails (:class:`rotrate_cli.period.Thumbnails`, the light's
flicker already taken out) as a change from one frame to the next far larger than the clip's
usual one. Motion alone does not do that: a fast turn, a shaken camera or motion blur change
every frame alike. A single odd frame (a flash, a glitch) differs from both its neighbours
while they match each other, so a cut must also part the frames on either side of it:
every pair of frames up to two apart across it must differ that much.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

#: A change across a cut is at least this many times the clip's median change from one frame to
#: the next. Measured on 64-px thumbnails: the rendered and real clips of the benchmarks (fast
#: turns, shaken cameras, blur, flicker, turntable photographs 10 degrees apart) stay under 2.5;
#: the still calibration frame before a bicycle wheel turns, 14.5.
CUT_RATIO = 6.0

#: ... and at least this mean difference in grey levels (0-255): a still clip's change is its
#: noise alone, and a small change in the light is not a cut.
CUT_MIN_GREY = 4.0


@dataclass(frozen=True)
class Shot:
    """The part of a clip between two cuts.

    Attributes:
        first, last: the shot's first and last frame, counted from the first frame analysed.
        start_s, end_s: their times, seconds.
        frames: frames analysed in the whole clip.
        cuts: how many cuts the clip has.
    """

    first: int
    last: int
    start_s: float
    end_s: float
    frames: int
    cuts: int

    @property
    def note(self) -> str:
        """What the user should know: the run measured this shot alone."""
        cut = "cuts once" if self.cuts == 1 else f"cuts {self.cuts} times"
        return (f"the clip {cut} from one picture to another: the longest shot, {self.start_s:.2f}-{self.end_s:.2f} s "
                f"({self.last - self.first + 1} of {self.frames} frames), is measured; give --start and --end to "
                "measure another")


def cuts(images: np.ndarray) -> list[int]:
    """The frames that begin a new shot: the index of the first frame after each cut.

    ``images``: one row of thumbnail pixels per frame.
    """
    count = len(images)
    if count < 3:
        return []

    def change(before: int, after: int) -> float:  # mean absolute difference, without a float copy
        return cv2.norm(images[before], images[after], cv2.NORM_L1) / images.shape[1]

    steps = np.array([change(index - 1, index) for index in range(1, count)])
    floor = max(CUT_RATIO * float(np.median(steps)), CUT_MIN_GREY)
    found = []
    for index in np.flatnonzero(steps > floor) + 1:
        pairs = [(before, after) for before in (index - 1, index - 2) for after in (index, index + 1)
                 if before >= 0 and after < count]
        if all(change(before, after) > floor for before, after in pairs):
            found.append(int(index))
    return found


def longest_shot(times_s: np.ndarray, images: np.ndarray) -> Shot | None:
    """The clip's longest shot, or None where the clip does not cut (or is too short to tell)."""
    starts = cuts(images)
    if not starts:
        return None
    bounds = [0, *starts, len(images)]
    first, end = max(zip(bounds, bounds[1:], strict=False), key=lambda pair: pair[1] - pair[0])
    return Shot(first, end - 1, float(times_s[first]), float(times_s[end - 1]), len(images), len(starts))
