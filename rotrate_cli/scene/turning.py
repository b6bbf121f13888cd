"""The picture's own turning: how fast a body turning in a plane (a record, a wheel, a fan, seen
face on or obliquely) turns its picture about its axis, tested on pairs of consecutive frames.

Each pair's first frame is turned about the axis by a trial angle, both ways, and compared with
the second frame where the picture changes: what turns with the body matches one way only, while
what does not turn (reflections, a still tonearm, concentric grooves that look alike at any angle)
matches both ways alike and cancels in the difference of the two. The trial rates are the ones a
return of the picture allows (a turn every 1, 2, 3 ... returns, and between), so the test says how
many returns make a turn, which the return alone cannot (a fan of five blades comes back after a
fifth of a turn). A body seen from the side does not turn its picture: no trial rate stands out,
and the test says nothing.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass

import cv2
import numpy as np

from rotrate_cli.scene.angle_frames import AngleFrames, reduced_grey
from rotrate_cli.video.frames import Frame

#: Pairs of consecutive frames kept over the clip (evenly spread), and their longer side, pixels.
MOST_PAIRS = 24
PAIR_SIDE_PX = 320
#: Pixels whose grey level changes by more than this between the two frames are the moving area.
MOVING_LEVELS = 6.0
#: A pair is tested only where the moving area is at least this fraction of the picture.
MIN_MOVING = 0.002
#: Trial rates: a turn every ``x`` returns of the picture, for whole and half counts.
TRIALS = tuple(sorted({float(k) for k in range(1, 65)} | {k + 0.5 for k in range(1, 8)} | {0.9}))
#: Pairs tested at most (evenly over those kept).
TESTED_PAIRS = 10
#: The best trial must beat the median trial by this factor to tell anything.
STANDS_OUT = 2.0
#: Trials within this fraction of the best are left open with it.
NEAR_BEST = 0.9


@dataclass(frozen=True)
class PictureTurning:
    """How fast the picture turns, from pairs of nearby frames.

    Attributes:
        omega_rad_s: the trial rate that fits best (a magnitude), rad/s.
        omega_low_rad_s, omega_high_rad_s: the range of trial rates that fit nearly as well.
        sense: +1 anticlockwise, -1 clockwise, as the picture shows it.
        pairs: the pairs kept; ``measured``: the pairs tested.
    """

    omega_rad_s: float
    omega_low_rad_s: float
    omega_high_rad_s: float
    sense: int
    pairs: int
    measured: int


class FramePairs:
    """Keeps pairs of consecutive frames, evenly over the clip, reduced to :data:`PAIR_SIDE_PX`
    (a tap on the frame stream, as :class:`rotrate_cli.stages.period.Thumbnails`)."""

    def __init__(self, most: int = MOST_PAIRS) -> None:
        self._most = most
        #: the frames kept for the picture's turning angle (:mod:`rotrate_cli.scene.picture_angle`),
        #: from the same stream
        self.angle_frames = AngleFrames()
        self._stride = 8
        self._pairs: list[tuple[float, np.ndarray, float, np.ndarray]] = []
        self._held: tuple[int, float, np.ndarray] | None = None
        #: the camera's steady roll (degrees a second, anticlockwise as the picture shows it) from
        #: ``roll_start_s`` on, as :meth:`turned_back` recorded it (the pairs are not turned back)
        self.roll_deg_s = 0.0
        self.roll_start_s = 0.0

    def clear(self) -> None:
        self._pairs.clear()
        self._held = None
        self._stride = 8
        self.angle_frames.clear()

    @property
    def pairs(self) -> list[tuple[float, np.ndarray, float, np.ndarray]]:
        """``(time_s, image, next_time_s, next_image)`` per pair kept."""
        return list(self._pairs)

    @property
    def start_s(self) -> float:
        """The time of the first picture kept (of the pairs, or for the angle): the moment from which
        :meth:`turned_back` turns them back (0 where none is kept)."""
        times = [pair[0] for pair in self._pairs] + [kept[1] for kept in self.angle_frames.frames]
        return min(times) if times else 0.0

    def turned_back(self, roll_deg_s: float) -> FramePairs:
        """A copy for a camera's steady roll (degrees a second, anticlockwise as the picture shows
        it; :mod:`rotrate_cli.stages.roll`) since :attr:`start_s`: the frames for the angle turned
        back about their centres, so that the axis stays where it was; the pairs as they are, with
        the roll recorded (:attr:`roll_deg_s`)."""
        start_s = self.start_s
        copy = FramePairs(self._most)
        copy._stride = self._stride
        # the pairs are kept as the camera saw them, the roll with them: their test turns its axis
        # with the camera (:func:`turning_profile`) rather than the pictures back (each turned
        # back, the record rolled 3 degrees a second told its sense the wrong way in 5 of 10 pairs)
        copy._pairs = list(self._pairs)
        copy.roll_deg_s, copy.roll_start_s = roll_deg_s, start_s
        copy.angle_frames = self.angle_frames.turned_back(roll_deg_s, start_s)
        return copy

    def tap(self, frames: Iterator[Frame]) -> Iterator[Frame]:
        """Yield ``frames`` unchanged, keeping some pairs of consecutive ones (grey or BGR), and
        the frames for the picture's angle."""
        for frame in self.angle_frames.tap(frames):
            index = frame.index
            if self._held is not None and index == self._held[0] + 1:
                second = reduced_grey(frame.image, PAIR_SIDE_PX)
                self._pairs.append((self._held[1], self._held[2], frame.time_s, second))
                self._held = None
                if len(self._pairs) > 2 * self._most:  # a long clip: every second pair kept
                    self._stride *= 2
                    self._pairs = self._pairs[::2]
            if index % self._stride == 0:
                self._held = (index, frame.time_s, reduced_grey(frame.image, PAIR_SIDE_PX))
            yield frame


def _moving(first: np.ndarray, second: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    a = cv2.GaussianBlur(first.astype(np.float32), (0, 0), 1.0)
    b = cv2.GaussianBlur(second.astype(np.float32), (0, 0), 1.0)
    mask = np.abs(a - b) > MOVING_LEVELS
    return (a, b, mask) if mask.mean() >= MIN_MOVING else None


def _turn_matrix(centre: tuple[float, float], angle_deg: float, ellipse: tuple[float, float] | None) -> np.ndarray:
    """The 2x3 map of a turn by ``angle_deg`` (anticlockwise as the picture shows it) about
    ``centre`` of a plane whose circles appear as ellipses with their long axes along
    ``ellipse[0]`` degrees (from the image x axis, y down) and ``ellipse[1]`` as wide as long."""
    a = math.radians(angle_deg)
    turn = np.array([[math.cos(a), math.sin(a)], [-math.sin(a), math.cos(a)]])
    if ellipse is not None:
        phi = math.radians(ellipse[0])
        along = np.array([[math.cos(phi), -math.sin(phi)], [math.sin(phi), math.cos(phi)]])
        width = min(max(ellipse[1], 0.05), 1.0)
        squash = along @ np.diag([1.0, width]) @ along.T
        turn = squash @ turn @ np.linalg.inv(squash)
    c = np.asarray(centre)
    return np.hstack([turn, (c - turn @ c)[:, None]])


def _misfit(first: np.ndarray, second: np.ndarray, mask: np.ndarray, matrix: np.ndarray) -> float:
    """The mean grey difference, where the picture changes, of ``second`` and ``first`` mapped by
    ``matrix``."""
    turned = cv2.warpAffine(first, matrix, (first.shape[1], first.shape[0]), flags=cv2.INTER_LINEAR,
                            borderMode=cv2.BORDER_REPLICATE)
    return float(np.mean(np.abs(turned[mask] - second[mask])))


def turning_profile(pairs: list[tuple[float, np.ndarray, float, np.ndarray]], centre_px: tuple[float, float],
                    width_px: int, return_rad_s: float, ellipse: tuple[float, float] | None = None,
                    roll: tuple[float, float] = (0.0, 0.0)) -> np.ndarray | None:
    """For each tested pair (rows) and each of :data:`TRIALS` ``x`` (columns), how much better the
    pair's first frame turned by ``return_rad_s / x`` times their time apart matches its second
    frame one way than the other (anticlockwise minus clockwise); None where no pair shows motion.
    ``centre_px``: where the axis meets the picture, in the frame's own pixels (``width_px`` wide);
    ``ellipse``: the direction (degrees) and width (to its length) of the circles' pictures, for
    an oblique view (None: face on). ``roll``: a camera's steady roll (degrees a second,
    anticlockwise as shown) and the moment since which it turned the picture about its centre,
    where ``centre_px`` and ``ellipse`` are as at that moment: each pair's axis and ellipse are
    turned with the camera, and its turn between the two frames added to the body's."""
    chosen = pairs[:: max(1, len(pairs) // TESTED_PAIRS)][:TESTED_PAIRS]
    roll_deg_s, roll_start_s = roll
    rows = []
    for time_s, first, next_s, second in chosen:
        step_s = next_s - time_s
        moving = _moving(first, second) if step_s > 0 and first.shape == second.shape else None
        if moving is None:
            continue
        a, b, mask = moving
        scale = a.shape[1] / width_px
        centre, along = (centre_px[0] * scale, centre_px[1] * scale), ellipse
        camera = None
        if roll_deg_s:
            middle = ((a.shape[1] - 1) / 2.0, (a.shape[0] - 1) / 2.0)
            rolled = roll_deg_s * (time_s - roll_start_s)
            centre = tuple(cv2.getRotationMatrix2D(middle, rolled, 1.0) @ np.array([*centre, 1.0]))
            along = None if ellipse is None else (ellipse[0] - rolled, ellipse[1])
            camera = cv2.getRotationMatrix2D(middle, roll_deg_s * step_s, 1.0)
        row = np.zeros(len(TRIALS))
        for index, x in enumerate(TRIALS):
            angle = math.degrees(return_rad_s / x * step_s)
            # positive: the turn anticlockwise as the picture shows it fits better
            row[index] = (_misfit(a, b, mask, _then(_turn_matrix(centre, -angle, along), camera))
                          - _misfit(a, b, mask, _then(_turn_matrix(centre, angle, along), camera)))
        rows.append(row)
    return np.array(rows) if rows else None


def _then(matrix: np.ndarray, after: np.ndarray | None) -> np.ndarray:
    """The 2x3 map ``matrix`` followed by the 2x3 map ``after`` (None: by nothing)."""
    if after is None:
        return matrix
    return np.hstack([after[:, :2] @ matrix[:, :2], (after[:, :2] @ matrix[:, 2] + after[:, 2])[:, None]])


def picture_turning(pairs: list[tuple[float, np.ndarray, float, np.ndarray]], centre_px: tuple[float, float],
                    width_px: int, return_rad_s: float, ellipse: tuple[float, float] | None = None,
                    roll: tuple[float, float] = (0.0, 0.0)) -> PictureTurning | None:
    """The picture's rate of turning among those a return of ``return_rad_s`` allows (see the
    module's notes), with the range of trial rates that fit nearly as well as the best; None
    where no trial stands out (a picture that does not turn, or too little that turns).
    ``roll``: as :func:`turning_profile`'s."""
    if not (math.isfinite(centre_px[0]) and math.isfinite(centre_px[1]) and return_rad_s > 0):
        return None  # no axis to turn about (none given, none found)
    rows = turning_profile(pairs, centre_px, width_px, return_rad_s, ellipse, roll)
    if rows is None or len(rows) < 2:
        return None
    profile = rows.sum(axis=0)
    strength = np.abs(profile)
    best = int(np.argmax(strength))
    typical = float(np.median(strength))
    if not strength[best] > STANDS_OUT * max(typical, 1e-9):
        return None
    sense = 1 if profile[best] > 0 else -1
    near = [x for x, value in zip(TRIALS, profile, strict=True) if sense * value >= NEAR_BEST * strength[best]]
    # the pairs' two halves must each find their best within that range: a test that a few pairs
    # sway (thin spokes, a picture turned a quarter) is no evidence
    # (the earlier and the later pairs: every other pair, evenly spaced, can see the body at one
    # side only where it turns about one and a half turns between pairs: the record rolled 3
    # degrees a second, its pairs 2.67 s apart, saw its blank side of the label in every other)
    middle = len(rows) // 2
    for half in (rows[:middle].sum(axis=0), rows[middle:].sum(axis=0)):
        if not min(near) <= TRIALS[int(np.argmax(sense * half))] <= max(near):
            return None
    rates = [return_rad_s / x for x in near]
    return PictureTurning(return_rad_s / TRIALS[best], min(rates), max(rates), sense, len(pairs), len(rows))
