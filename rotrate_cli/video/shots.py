"""The clip's shots: where it cuts from one picture to another (:func:`longest_shot`).

Real clips are edited: a still calibration frame before the turning starts, a title card, a cut
to another camera. A track cannot cross a cut, and the clip's repetition is blurred by frames
that belong to another scene, so a run measures one shot: the longest.

A cut shows in the frames' thumbnails (:class:`rotrate_cli.stages.period.Thumbnails`, the light's
flicker already taken out) as a change from one frame to the next far larger than the clip's
usual one. Motion alone does not do that: a fast turn, a shaken camera or motion blur change
every frame alike. A single odd frame (a flash, a glitch) differs from both its neighbours
while they match each other, so a cut must also part the frames on either side of it:
every pair of frames up to two apart across it must differ that much.

A damaged spot in a file (bytes lost mid-file) is no cut either. The decoder skips the frames it
cannot read, and those after them up to the next key frame decode garbled, drawn against a
picture that is gone; at that key frame the picture jumps back to the true one, which looks like
a cut. A cut that comes within :data:`RECOVERY_S` after a damaged spot is the decoder's recovery:
the garbled frames between are left out (:attr:`Shot.skipped_s`) and both sides are measured (a
box clip with 100 KB overwritten mid-file: 84 of 126 frames measured, weak, +1.5%, before).

A fade (in from black at the start, out to it at the end, or a camera's exposure settling as it
starts) changes the light of every frame a little, which no cut shows and the light's steadying
(:mod:`rotrate_cli.video.light`) only follows a few frames behind: Lucas-Kanade, which takes a point's
brightness to stay as it was, then misreads the motion (a rendered box fading in over 20 frames
read -39%). A shot therefore begins where its picture's mean brightness stops rising from under
:data:`FADE_SHARE` of the shot's usual brightness, and ends where it starts falling below it.
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

#: A cut this soon after a damaged spot (seconds from its first decoded frame) is the decoder's
#: recovery at the next key frame (encoders place one every 1-10 s; 2 s at 30 frames/s is 60).
RECOVERY_S = 10.0


#: A fade is a run of at least this many frames whose mean brightness rises (at a shot's start)
#: or falls (at its end) from frame to frame, while under this share of the shot's median
#: brightness. A mains flicker (10 Hz at 30 frames/s) rises for 2 frames at most; a fade of
#: two thirds of a second, for 20.
FADE_FRAMES = 5
FADE_SHARE = 0.9
#: ... and over the run, at least this share of the picture's pixels must brighten (or darken)
#: with it: a fade or an exposure changes the whole picture, while a body turning its brighter
#: side into view changes its own pixels only (a car's photographs brightened their mean for 5
#: frames on end from under 90% of the median, through a quarter of the pixels).
FADE_PIXELS = 0.75


@dataclass(frozen=True)
class Shot:
    """The part of a clip between two cuts.

    Attributes:
        first, last: the shot's first and last frame, counted from the first frame analysed.
        start_s, end_s: their times, seconds.
        frames: frames analysed in the whole clip.
        cuts: how many cuts the clip has.
        faded: frames left out of the shot where it fades in or out.
        skipped_s: stretches (first and last time, seconds) of garbled frames left out inside
            the shot: those after a damaged spot up to the decoder's recovery.
        skipped: frames left out so.
    """

    first: int
    last: int
    start_s: float
    end_s: float
    frames: int
    cuts: int
    faded: int = 0
    skipped_s: tuple[tuple[float, float], ...] = ()
    skipped: int = 0

    @property
    def note(self) -> str:
        """What the user should know: the run measured this shot alone."""
        span = f"{self.start_s:.2f}-{self.end_s:.2f} s ({self.last - self.first + 1} of {self.frames} frames)"
        fades = f"{self.faded} frames of fading light left out" if self.faded else ""
        garbled = "; ".join(f"{first:.2f}-{last:.2f} s" for first, last in self.skipped_s)
        skipped = (f"the {self.skipped} frame(s) after the damaged spot up to the decoder's next key frame "
                   f"({garbled}) decode garbled and are left out; the frames either side are measured"
                   if self.skipped else "")
        if not self.cuts and not self.faded:
            return skipped
        if not self.cuts:
            return (f"the clip fades in or out: {span} is measured, {fades}; give `start_s` and `end_s` to measure "
                    "another" + (f"; {skipped}" if skipped else ""))
        cut = "cuts once" if self.cuts == 1 else f"cuts {self.cuts} times"
        return (f"the clip {cut} from one picture to another: the longest shot, {span}, is measured"
                f"{', ' + fades if fades else ''}; give `start_s` and `end_s` to measure another"
                + (f"; {skipped}" if skipped else ""))


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


def fades(levels: np.ndarray, images: np.ndarray) -> tuple[int, int]:
    """How many frames a shot fades in over at its start, and out over at its end (see the
    module's notes), from its frames' mean brightness ``levels`` and thumbnails ``images`` (one
    row of pixels per frame); (0, 0) where it does not."""
    levels = np.asarray(levels, dtype=np.float64)
    if len(levels) < 2 * FADE_FRAMES:
        return 0, 0
    dim = FADE_SHARE * float(np.median(levels))

    def ramp(values: np.ndarray, pictures: np.ndarray) -> int:  # frames from the first that rise while dim
        run = 0
        while run + 1 < len(values) and values[run] < dim and values[run + 1] >= values[run]:
            run += 1
        whole = np.count_nonzero(pictures[run] > pictures[0]) >= FADE_PIXELS * pictures.shape[1]
        return run if run >= FADE_FRAMES and whole else 0

    fade_in, fade_out = ramp(levels, images), ramp(levels[::-1], images[::-1])
    if len(levels) - fade_in - fade_out < 2 * FADE_FRAMES:
        return 0, 0  # all fading: nothing steadier to keep
    return fade_in, fade_out


def longest_shot(times_s: np.ndarray, images: np.ndarray, levels: np.ndarray | None = None,
                 damaged_s: tuple[tuple[float, float], ...] = ()) -> Shot | None:
    """The clip's longest shot, past its fades where the frames' mean brightness ``levels`` are
    given; None where the clip neither cuts nor fades nor holds garbled frames (or is too short to
    tell). ``damaged_s``: the decoder's damaged spots (the times of the frames either side of
    each), after which a cut is its recovery (see the module's notes)."""
    starts, garbled = [], []
    for start in cuts(images):
        after = [after_s for _, after_s in damaged_s
                 if after_s - 1e-9 <= times_s[start] <= after_s + RECOVERY_S and times_s[start - 1] >= after_s - 1e-9]
        if after:
            garbled.append((int(np.searchsorted(times_s, max(after) - 1e-9)), start - 1))
        else:
            starts.append(start)
    bounds = [0, *starts, len(images)]
    first, end = max(zip(bounds, bounds[1:], strict=False), key=lambda pair: pair[1] - pair[0])
    fade_in, fade_out = (0, 0) if levels is None else fades(np.asarray(levels)[first:end], images[first:end])
    first, last = first + fade_in, end - 1 - fade_out
    inside = [(a, b) for a, b in garbled if first <= a and b <= last]
    if not starts and not fade_in and not fade_out and not inside:
        return None
    return Shot(first, last, float(times_s[first]), float(times_s[last]), len(images), len(starts),
                fade_in + fade_out, tuple((float(times_s[a]), float(times_s[b])) for a, b in inside),
                sum(b - a + 1 for a, b in inside))
