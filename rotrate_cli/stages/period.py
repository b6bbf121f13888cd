"""The rotation period from the clip's own repetition: how long until the picture comes back.

A rigid body turning at a steady rate looks the same again after each full turn, whatever the
camera, the lens, the view or where the axis lies, and whatever its surfaces do: mirrors,
grooves and glints repeat with the turn too. So when a clip spans about a turn or more, the
time after which each frame is seen again measures the rate with no model of the projection
at all. This is how the record clip's own truth was measured (frame t matches frame t + L at
L = k x 42.427 frames for k = 1..16).

Every frame is reduced to a small grey thumbnail (:class:`Thumbnails`, a tap on the frame
stream); the pixels' mean over the clip is removed, so the static background drops out, and the
squared difference of every pair of frames comes from one matrix product. Near a pair of frames
whose times differ by ``k`` periods (or a bit more or less), their difference grows with the
mismatch as a frame's difference from its own neighbours grows with the time between them. So
for a period ``P`` each such pair predicts its difference from its two frames' own neighbours
(a local, measured shape: views differ in how much they change per degree), and ``P`` is the
one that predicts best. A single closing of the turn is enough: a sequence of photographs of one
full turn, whose last frame is a step before its first (the dinosaur's 36 frames, the EPFL cars),
gives the period from the few pairs across the wrap, to a fraction of a frame.

Times are the frames' own (:attr:`rotrate_cli.video.decode.Frame.time_s`): photographs taken at
irregular moments of a steadily turning table are placed by their capture times.

A return buried in slow change (light through a window swinging across the picture, rain on the
glass, a camera drifting a few pixels) is no return by the frames' plain differences: the pairs
a turn apart differ by everything that changed slowly between them. Any filter applied alike at
every moment keeps a picture that repeats repeating, so where nothing is found the search is made
again on the frames less their running mean over :data:`DETREND_FRAMES` (:func:`_detrended`),
which keeps the turn's quick change and leaves out the slow one.

An object with an m-fold symmetry (a fan's blades, spokes) repeats m times a turn; the period
found is then a fraction of the turn, which the return alone cannot tell: the tracks' rate or the
picture's own turning tell which (:func:`rotrate_cli.stages.verdict.tell_repeats`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass, replace

import cv2
import numpy as np

from rotrate_cli.video.frames import Frame
from rotrate_cli.video.light import SteadyLight

#: The thumbnails' longer side, pixels: the whole picture's repetition needs little detail, and
#: the pairwise differences cost the square of the frame count times this squared.
THUMB_SIDE_PX = 64
#: The differences are taken over at most this many pixels, those that change most over the clip.
MOST_PIXELS = 1024
#: At most this many frames (the first ones analysed) are kept: 2000 thumbnails are 8 MB and
#: their differences 16 MB; a period is measured within them.
MAX_FRAMES = 2000
#: Pairs of frames whose difference is under this fraction of the typical one look alike.
ALIKE = 0.5
#: A frame's neighbours describe how fast its picture changes, up to this many each side.
MAX_NEIGHBOURS = 8
#: The best-matching pairs must differ by at most this fraction of what their frames differ
#: from their farthest neighbours, and the fit must prefer the period by this much (1 - the
#: cost there over the worst cost a few frames off).
CONTRAST = 0.6
MIN_FIT = 0.3
#: A repeat whose closest pairs differ by no more than this beyond their timing shows the same
#: picture again (a merely similar view, a car half a turn on, differs by more).
SAME_PICTURE = 0.02
#: Frames a step apart that differ by at least this fraction of the typical difference show a
#: turn too fast for the frame rate to follow (a wheel or fan turning tens of degrees a frame):
#: the first closest return may span several turns (:func:`_turns_between`). Measured: a rendered
#: box 6-19 degrees a frame, 0.44-0.91; the real clips and photographs (5-10 degrees a step),
#: 0.09-0.32.
FAR_APART = 1.0 - 0.8 * ALIKE
#: Harmonics of the turn that describe how a frame's difference from another grows with the angle
#: between them (a box seen from the side looks alike every quarter turn: its fourth). Measured on
#: renders 19-170 degrees a frame (28 clips: boxes, and a finely textured disk whose views differ
#: only near a return): 4 harmonics found the turns of 23 and all the boxes; 2, 3, 6 and 8 found
#: 6-18; taking each closest return for one turn, 5.
PROFILE_HARMONICS = 4
#: Residuals of the differences (in typical differences) are capped here in the fit.
CAP = 0.3
#: Points of the tabulated neighbour shape; period candidates scanned coarsely, then finely.
SHAPE_POINTS = 32
COARSE_POINTS = 81
FINE_POINTS = 21
#: The fit uses at most this many pairs of frames (evenly spread over the lags).
MAX_PAIRS = 30_000
#: Even with a perfect fit, where a repetition falls between two frames is known only to a
#: fraction of a frame's step (photographs' steps are irregular): the interval's floor, in steps.
#: Measured on the six real turns of photographs (five EPFL cars, whose shutter was pressed by
#: hand, and the dinosaur) timed by frame index: their single closings sit 0.00-0.56 steps from
#: the truth (seq18: 0.56, whose interval at a floor of 0.4 missed it by 0.04%).
RESOLUTION_STEPS = 0.6
#: A picture that moves in steps (a clock's second hand): consecutive frames that differ by more
#: than this many times the 30th percentile of their differences (the still ones' noise) hold a
#: step, and where at most :data:`STEPPED_SHARE` of them do, the motion is stepped. Its repeat can
#: be placed only to within the time a step is held: one turn of a hand stepping 3 degrees every
#: half second, at 25 frames/s, read +0.32% within +-0.05% (the truth outside) and in the held-out
#: clip one step early, +0.82% within +-0.07%.
STEP_CONTRAST = 4.0
STEPPED_SHARE = 0.5

#: Where the plain search finds no return, each pixel's running mean over this many frames is
#: taken out and the search made again: longer than the picture's own change from frame to frame
#: (the neighbours the fit reads, up to :data:`MAX_NEIGHBOURS` each side), shorter than a light or
#: a drift that changes over seconds. A record seen nearly edge on (80 degrees), the light swinging
#: across the picture, drops running down the glass, a 4-pixel drift: no return plainly; over 15
#: frames, -0.04% (5 frames kept too little of the turn, 25 too much of the weather).
DETREND_FRAMES = 2 * MAX_NEIGHBOURS - 1


@dataclass(frozen=True)
class Period:
    """The clip's repetition (see the module's notes).

    Attributes:
        period_s: time between repetitions, seconds.
        period_low_s, period_high_s: its 95% interval.
        repeats: how many repetitions the clip spans (1: the turn closes once).
        frames: thumbnails compared.
        likeness: the difference of the best-matching pairs over the typical difference
            (0: identical pictures); under :data:`ALIKE` to count.
        fit: how sharply the period is preferred: 1 - its cost over the worst cost of the
            periods a few frames off (0..1).
        drift_s: how far apart the periods measured on the clip's first and second halves lie
            (a changing rate), seconds.
        excess: what the best-matching pairs differ by beyond what their timing explains (0:
            the same picture again; more: a merely similar view, as a car half a turn on).
        lag_frames: the repeat in frames (the whole number first seen, over ``turns_between``).
        far_apart: the picture changes almost wholly from one frame to the next
            (:data:`FAR_APART`): a turn too fast for the frame rate to follow (faster turns that
            land on the same views, a wagon wheel's, cannot be told apart), or a fine texture
            that changes wholly with a small turn. The closest return may then span several
            repeats (:meth:`over`).
        turns_guess: where ``far_apart``, how many repeats the closest return spans as the lag
            profile alone says (:func:`_turns_between`): a box 29 degrees a frame looks most
            alike after 88 frames, 7 turns.
        turns_between: how many repeats the closest return first seen spans, as taken
            (:meth:`over`; 1 until then).
        detrended: found only once the slow change was taken out (:data:`DETREND_FRAMES`).
        sooner_s: the shortest return fitted that matched clearly less well than the one taken
            (NaN where none): the return taken may then span several repeats, those between
            spoiled (:func:`rotrate_cli.stages.verdict.judge`).
        roll_deg_s: the camera's steady roll taken out of the pictures before the repetition was
            found, degrees a second, anticlockwise as the picture shows it (0: none;
            :mod:`rotrate_cli.stages.roll`).
        sway_deg: the turn of the whole picture, degrees either way, that two pictures were
            allowed to differ by and still count as the same (0: none): a camera that sways in the
            hand, with no still background to measure it by (:mod:`rotrate_cli.stages.roll`).
        zoom_share: likewise, how much larger or smaller (a share, either way) the whole picture
            was allowed to be: a camera coming nearer and going back (0: none).
    """

    period_s: float
    period_low_s: float
    period_high_s: float
    repeats: int
    frames: int
    likeness: float
    fit: float
    drift_s: float = 0.0
    excess: float = 0.0
    lag_frames: float = math.nan
    far_apart: bool = False
    turns_guess: int = 1
    turns_between: int = 1
    detrended: bool = False
    sooner_s: float = math.nan
    roll_deg_s: float = 0.0
    sway_deg: float = 0.0
    zoom_share: float = 0.0

    def over(self, turns: int) -> Period:
        """The repetition where the closest return spans ``turns`` repeats."""
        if turns == self.turns_between:
            return self
        ratio = self.turns_between / turns
        return replace(self, period_s=self.period_s * ratio, period_low_s=self.period_low_s * ratio,
                       period_high_s=self.period_high_s * ratio, drift_s=self.drift_s * ratio,
                       lag_frames=self.lag_frames * ratio, repeats=max(1, round(self.repeats / ratio)),
                       turns_between=turns)

    @property
    def step_deg(self) -> float:
        """How far the picture's repeat turns between frames, degrees (NaN when unknown)."""
        return 360.0 / self.lag_frames if self.lag_frames > 0 else math.nan

    def omega_rad_s(self, multiple: int = 1) -> tuple[float, float, float]:
        """The rate, and its 95% interval, if a turn takes ``multiple`` periods (rad/s)."""
        turn = 2.0 * math.pi / multiple
        return turn / self.period_s, turn / self.period_high_s, turn / self.period_low_s


class Thumbnails:
    """Collects a small grey thumbnail of each frame that passes through :meth:`tap`."""

    def __init__(self, max_frames: int = MAX_FRAMES, steady_light: bool = False) -> None:
        self._max = max_frames
        self.steady_light = steady_light  # flickering light taken out (videos; see rotrate_cli.video.light)
        self._images: list[np.ndarray] = []
        self._times: list[float] = []
        self._levels: list[float] = []  # each thumbnail's mean brightness, before the light's steadying
        self._light = SteadyLight()
        #: the thumbnails' rows and columns (None before the first)
        self.shape: tuple[int, int] | None = None

    def tap(self, frames: Iterator[Frame]) -> Iterator[Frame]:
        """Yield ``frames`` unchanged, keeping a thumbnail of each (grey or BGR images)."""
        for frame in frames:
            if len(self._images) < self._max:
                self._add(frame.time_s, frame.image)
            yield frame

    def _add(self, time_s: float, image: np.ndarray) -> None:
        if image.ndim == 3:
            image = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
        # a pixel in a few first where the picture is large: an area average over a 10x reduction
        # costs 0.35 ms a frame at 640 px, a fraction of that over twice the thumbnail's size
        step = max(1, int(max(image.shape[:2]) / THUMB_SIDE_PX / 2))
        image = image[::step, ::step]
        scale = THUMB_SIDE_PX / max(image.shape[:2])
        small = cv2.resize(image, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA) if scale < 1 else image
        small = np.asarray(small, dtype=np.uint8)
        self._levels.append(float(cv2.mean(small)[0]))
        if self.steady_light:
            small = self._light.steadied(small)
        self.shape = (int(small.shape[0]), int(small.shape[1]))
        self._images.append(small.ravel())
        self._times.append(float(time_s))

    def black_fraction(self) -> float:
        """The fraction of the frames seen whose thumbnail is all black (0 when none were seen)."""
        return sum(not image.any() for image in self._images) / len(self._images) if self._images else 0.0

    def lifeless_fraction(self) -> float:
        """The fraction of the frames seen whose thumbnail is all black or the same, pixel for
        pixel, as the frame before (0 when none were seen): what a decoder gives that hands back
        nothing (a camera's picture always changes a little, if only by its noise)."""
        images = self._images
        if not images:
            return 0.0
        dead = sum(not image.any() for image in images[:1])
        dead += sum(not image.any() or np.array_equal(image, before)
                    for before, image in zip(images, images[1:], strict=False))
        return dead / len(images)

    def clear(self) -> None:
        self._images.clear()
        self._times.clear()
        self._levels.clear()
        self._light.clear()

    @property
    def times_s(self) -> np.ndarray:
        return np.asarray(self._times, dtype=np.float64)

    @property
    def levels(self) -> np.ndarray:
        """Each frame's mean brightness (0-255), as it came: before the light's steadying."""
        return np.asarray(self._levels, dtype=np.float64)

    @property
    def images(self) -> np.ndarray:
        """One row of pixels per frame."""
        return np.stack(self._images) if self._images else np.zeros((0, 0), np.uint8)


def changing_pixels(images: np.ndarray) -> tuple[np.ndarray | None, np.ndarray]:
    """The :data:`MOST_PIXELS` pixels (columns of ``images``) that change most over the clip
    (None: all of them, where there are no more), and every pixel's mean."""
    count = len(images)
    total = np.zeros(images.shape[1], np.float64)
    squares = np.zeros(images.shape[1], np.float64)
    for start in range(0, count, 256):  # in blocks: no full-size float copy for the selection
        block = images[start:start + 256].astype(np.float32)
        total += block.sum(axis=0)
        squares += (block * block).sum(axis=0)
    variance = squares / count - (total / count) ** 2
    if images.shape[1] <= MOST_PIXELS:
        return None, total / count
    return np.sort(np.argpartition(variance, -MOST_PIXELS)[-MOST_PIXELS:]), total / count


def pixel_differences(images: np.ndarray) -> np.ndarray:
    """Squared differences of every pair of frames, after the pixels' mean is removed, over the
    :data:`MOST_PIXELS` pixels that change most (still background adds only noise)."""
    pixels, mean = changing_pixels(images)
    if pixels is not None:
        images, mean = images[:, pixels], mean[pixels]
    values = images.astype(np.float32)
    values -= mean.astype(np.float32)
    return squared_differences(values, values)


def squared_differences(first: np.ndarray, second: np.ndarray) -> np.ndarray:
    """``|first[i] - second[j]|^2`` for every pair of rows, from one matrix product (float32)."""
    gram = first @ second.T
    gram *= -2.0
    gram += np.einsum("ij,ij->i", first, first)[:, None]
    gram += np.einsum("ij,ij->i", second, second)[None, :]
    return np.maximum(gram, 0.0, out=gram)


def _lag_profile(diff: np.ndarray) -> np.ndarray:
    """The mean difference of frames ``L`` apart, for every lag ``L`` (0 first)."""
    return np.array([diff.diagonal(lag).mean() for lag in range(len(diff))])


def _neighbour_shapes(diff: np.ndarray, times_s: np.ndarray, reach: int, grid_s: np.ndarray) -> np.ndarray:
    """Each frame's difference from its neighbours against the time between them, tabulated on
    ``grid_s`` (piecewise linear through the measured points and 0 at 0, made non-decreasing,
    flat beyond the last): one row per frame."""
    count = len(times_s)
    shapes = np.empty((count, len(grid_s)), dtype=np.float32)  # one row per pair later: kept small
    for i in range(count):
        near = [j for j in range(i - reach, i + reach + 1) if 0 <= j < count and j != i]
        gaps = np.abs(times_s[near] - times_s[i])
        values = diff[i, near]
        order = np.argsort(gaps, kind="stable")
        gaps = np.r_[0.0, gaps[order]]
        values = np.maximum.accumulate(np.r_[0.0, values[order]])
        shapes[i] = np.interp(grid_s, gaps, values)
    return shapes


def _robust_cost(residuals: np.ndarray) -> float:
    """Mean squared residual, each capped at :data:`CAP`: pairs that differ for reasons of
    their own (a person walking through one of the two frames) weigh no more than a miss."""
    return float(np.mean(np.minimum(residuals ** 2, CAP ** 2)))


def _candidates(profile: np.ndarray, reach: int, most: int = 6) -> list[float]:
    """First periods in frames: the lags past the neighbours whose frames look alike and that
    are local minima (valleys inside the clip), and the turn closing at the clip's end (its last
    lags falling towards alike)."""
    count = len(profile)
    found: list[float] = []
    for lag in range(reach + 1, count - 1):
        lo, hi = max(reach + 1, lag - max(reach, 1)), min(count, lag + max(reach, 1) + 1)
        if profile[lag] <= ALIKE and profile[lag] == profile[lo:hi].min():
            found.append(float(lag))
            if len(found) == most:
                return found
    tail = profile[max(reach + 1, count - 1 - reach):]
    if len(tail) >= 1 and tail[-1] <= ALIKE and (len(tail) < 2 or tail[-1] < tail[0]):
        found.append(float(count - 1))
    return found


def _repeats(profile: np.ndarray, lag0: float, reach: int) -> int:
    """How many whole multiples of ``lag0`` (from the first on) still look alike in the lag
    profile: a scene that drifts (a person moving behind) stops matching after a while."""
    count, k = len(profile), 1
    while True:
        lag = (k + 1) * lag0
        lo, hi = int(math.floor(lag - reach)), int(math.ceil(lag + reach)) + 1
        if lo >= count or profile[max(lo, 0):min(hi, count)].min() > ALIKE:
            return k
        k += 1


#: The squared differences of every pair of frames, given their thumbnails (one row each).
Differences = Callable[[np.ndarray], np.ndarray]


def find_period(times_s: np.ndarray, images: np.ndarray, clock_resolution_s: float = 0.0,
                differences: Differences | None = None) -> Period | None:
    """The time after which the clip's pictures repeat (see the module's notes); None when the
    clip does not come back to a picture it has shown (under about a turn, or nothing turns).

    ``times_s``: each frame's time; ``images``: one row of thumbnail pixels per frame;
    ``clock_resolution_s``: how finely the times are known (widens the interval);
    ``differences``: how two frames' pictures differ (by default their squared difference over the
    pixels that change most, :func:`pixel_differences`).

    Searched on the frames as they are, then, where that finds nothing, on the frames less their
    slow change (:func:`_detrended`).
    """
    differences = differences or pixel_differences
    found = _search(times_s, images, clock_resolution_s, differences)
    if found is not None or len(times_s) < 4 * DETREND_FRAMES:
        return found
    times_s, images = _detrended(times_s, images)
    found = _search(times_s, images, clock_resolution_s, differences)
    return None if found is None else replace(found, detrended=True)


def _detrended(times_s: np.ndarray, images: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each pixel less its running mean over :data:`DETREND_FRAMES` frames centred on it (float32;
    the frames at the ends, without a whole window, left out), with the kept frames' times."""
    width = DETREND_FRAMES
    total = np.zeros((len(images) + 1, images.shape[1]), np.float32)
    np.cumsum(images, axis=0, dtype=np.float32, out=total[1:])
    means = (total[width:] - total[:-width]) / width
    half = width // 2
    return times_s[half:half + len(means)], images[half:half + len(means)].astype(np.float32) - means


def _search(times_s: np.ndarray, images: np.ndarray, clock_resolution_s: float,
            differences: Differences = pixel_differences) -> Period | None:
    """The repetition in one set of thumbnails (see :func:`find_period`).

    Every valley of the lag profile (and the closing of a single turn) is fitted; the period is
    the shortest of those whose pictures match nearly as well as the best match: a turned car
    half a turn on looks somewhat like itself, a record's label after 42 frames exactly so.
    """
    count = len(times_s)
    if count < 8 or images.size == 0:
        return None
    steps = np.diff(times_s)
    if not (steps > 0).all():
        return None
    diff = differences(images)
    rows = diff[::max(1, count // 400)]  # a few hundred frames' differences tell the typical one
    typical = float(np.median(rows[rows > 0])) if (rows > 0).any() else 0.0
    if not typical > 0:
        return None
    diff /= typical
    hold_s = _hold_s(diff.diagonal(1), times_s)
    profile = _lag_profile(diff)
    reach = 1
    while reach < MAX_NEIGHBOURS and reach + 1 < count and profile[reach] < 1.0 - ALIKE * 0.8:
        reach += 1
    shapes_cache: dict[int, np.ndarray] = {}
    fits: list[Period] = []
    for lag0 in _candidates(profile, reach):
        # a multiple of a true repeat already measured is that repeat again: not fitted twice
        if any(fit.excess <= SAME_PICTURE and abs(lag0 - round(lag0 / fit.lag_frames) * fit.lag_frames) <= reach + 1
               for fit in fits):
            continue
        fit = _fit_period(diff, times_s, lag0, _repeats(profile, lag0, reach), reach, clock_resolution_s,
                          shapes_cache, hold_s)
        if fit is not None:
            fits.append(fit)
    if not fits:
        return None
    best = min(fit.excess for fit in fits)
    chosen = min((fit for fit in fits if fit.excess <= 2.0 * best + SAME_PICTURE), key=lambda fit: fit.period_s)
    sooner = [fit.period_s for fit in fits if fit.period_s < chosen.period_s]
    if sooner:
        chosen = replace(chosen, sooner_s=min(sooner))
    if profile[1] < FAR_APART:
        return chosen
    return replace(chosen, far_apart=True, turns_guess=_turns_between(profile, times_s, chosen.period_s))


def _hold_s(consecutive: np.ndarray, times_s: np.ndarray) -> float:
    """How long a stepped picture holds each step (the median time between the frames where it
    moves, :data:`STEP_CONTRAST`), seconds; 0 for a picture that moves smoothly."""
    if len(consecutive) < 8:
        return 0.0
    moves = consecutive > STEP_CONTRAST * float(np.percentile(consecutive, 30))
    if moves.mean() > STEPPED_SHARE or moves.sum() < 3:
        return 0.0
    return float(np.median(np.diff(times_s[1:][moves])))


def _turns_between(profile: np.ndarray, times_s: np.ndarray, period_s: float) -> int:
    """How many repeats a return after ``period_s`` spans, where frames lie far apart on the turn:
    the whole number ``n`` (under half a repeat a frame) for which the lag profile (the mean
    difference of frames a lag apart) is best described as a smooth function of the angle turned
    in a lag, ``2 pi n lag_time / period_s``: a constant and :data:`PROFILE_HARMONICS` cosines of
    it, by weighted least squares (lags with more pairs weigh more).

    The box turning 29 degrees a frame looks most alike after 88 frames (7 turns, 1 degree
    off); 25 frames (2 turns, 4 degrees off) is also a valley. Taking 88 frames for one turn
    read the rate 7 times too slow; a turn of 12.6 frames describes every valley at once. A
    guess all the same: frames that show only a few distinct views are described as well at
    other rates (see :data:`PROFILE_HARMONICS`)."""
    count = len(profile)
    lags = np.arange(1, max(2, count - 4))
    gaps_s = np.array([float(np.mean(times_s[lag:] - times_s[:-lag])) for lag in lags])
    weights = np.sqrt(count - lags)
    values = profile[lags] * weights
    step_s = float(np.mean(np.diff(times_s)))
    most = max(1, int(period_s / (2.0 * step_s)))
    misfit = np.full(most + 1, np.inf)
    for turns in range(1, most + 1):
        angle = 2.0 * math.pi * turns * gaps_s / period_s
        design = np.column_stack([np.ones_like(angle)] + [np.cos(k * angle) for k in range(1, PROFILE_HARMONICS + 1)])
        design *= weights[:, None]
        residual = values - design @ np.linalg.lstsq(design, values, rcond=None)[0]
        misfit[turns] = float(residual @ residual)
    return int(np.argmin(misfit))


def _pairs_near(count: int, lag0: float, repeats: int, reach: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The frame pairs ``(i, j)`` whose lag lies within ``reach + 1`` frames of a whole multiple
    (up to ``repeats``) of ``lag0`` and beyond the neighbours, with that multiple; built lag by
    lag (the pairs of every lag would be millions for a long clip). At most
    :data:`MAX_PAIRS`, evenly spread."""
    lags: dict[int, int] = {}
    for k in range(1, repeats + 1):
        for lag in range(int(math.ceil(k * lag0 - reach - 1)), int(math.floor(k * lag0 + reach + 1)) + 1):
            if reach < lag < count:
                lags.setdefault(lag, k)
    total = sum(count - lag for lag in lags)
    stride = max(1, int(math.ceil(total / MAX_PAIRS)))
    starts = [np.arange(0, count - lag, stride) for lag in lags]
    i = np.concatenate(starts) if starts else np.zeros(0, int)
    j = i + np.concatenate([np.full(len(part), lag) for part, lag in zip(starts, lags, strict=True)]) if starts else i
    multiple = (np.concatenate([np.full(len(part), k, np.float64) for part, k in zip(starts, lags.values(),
                                                                                     strict=True)])
                if starts else np.zeros(0))
    return i, j, multiple


def _fit_period(diff: np.ndarray, times_s: np.ndarray, lag0: float, repeats: int, reach: int,
                clock_resolution_s: float, shapes_cache: dict[int, np.ndarray] | None = None,
                hold_s: float = 0.0) -> Period | None:
    """The period near ``lag0`` frames that best predicts the differences of the pairs near its
    first ``repeats`` multiples from their frames' neighbours (see the module's notes); ``hold_s``:
    how long a stepped picture holds each step (:func:`_hold_s`), which the interval holds."""
    count = len(times_s)
    step_s = float(np.mean(np.diff(times_s)))
    i, j, multiple = _pairs_near(count, lag0, repeats, reach)
    if len(i) < 1:
        return None
    values = diff[i, j]
    gap_s = times_s[j] - times_s[i]
    reach_s = (reach + 1.5) * step_s
    grid_s = np.linspace(0.0, reach_s, SHAPE_POINTS)
    cache = shapes_cache if shapes_cache is not None else {}
    if reach not in cache:
        cache[reach] = _neighbour_shapes(diff, times_s, reach + 1, grid_s)
    shapes = cache[reach]
    table = shapes[i]  # float32, a fresh copy: the pairs' mean neighbour shape, in place
    table += shapes[j]
    table *= 0.5
    flat = table.ravel()
    row_starts = np.arange(len(i)) * SHAPE_POINTS  # each pair's row in ``flat``

    def predicted_at(period: float, part: np.ndarray | slice = slice(None)) -> np.ndarray:
        miss = np.abs(gap_s[part] - multiple[part] * period) / reach_s * (SHAPE_POINTS - 1)
        low = np.minimum(miss.astype(np.intp), SHAPE_POINTS - 2)
        frac = np.minimum(miss - low, 1.0)
        # the table read flat (``take``): half the time of indexing its rows and columns
        at = row_starts[part] + low
        return flat.take(at) * (1 - frac) + flat.take(at + 1) * frac

    def costs(periods_s: np.ndarray, part: np.ndarray | slice = slice(None)) -> np.ndarray:
        out = np.empty(len(periods_s))
        for k, period in enumerate(periods_s):
            out[k] = _robust_cost(values[part] - predicted_at(period, part))
        return out

    # photographs taken at irregular moments: the time a lag spans is its own mean, not lag x step
    whole = int(round(lag0))
    centre_s = float(np.mean(times_s[whole:] - times_s[:count - whole])) + (lag0 - whole) * step_s
    span_s = (reach + 1.0) * step_s
    coarse = np.linspace(centre_s - span_s, centre_s + span_s, COARSE_POINTS)
    coarse = coarse[coarse > reach * step_s]
    if len(coarse) < 3:
        return None
    coarse_cost = costs(coarse)
    best = int(np.argmin(coarse_cost))
    if best in (0, len(coarse) - 1):
        return None  # no minimum inside the search: the clip does not say where the repeat lies
    step = coarse[1] - coarse[0]
    scan = np.linspace(coarse[best] - step, coarse[best] + step, FINE_POINTS)
    cost = costs(scan)
    best = int(np.argmin(cost))
    best = min(max(best, 1), len(scan) - 2)
    # parabola through the best scan point and its neighbours
    c0, c1, c2 = cost[best - 1:best + 2]
    h = scan[1] - scan[0]
    curvature = (c0 - 2 * c1 + c2) / h ** 2
    shift = float(np.clip(0.5 * h * (c0 - c2) / (c0 - 2 * c1 + c2), -h, h)) if curvature > 0 else 0.0
    period_s = float(scan[best] + shift)
    minimum = float(costs(np.array([period_s]))[0])
    # how well the pictures match at the period: the closest pairs' difference, and the fit
    miss_s = np.abs(gap_s - multiple * period_s)
    nearest = miss_s <= max(0.5 * step_s, miss_s.min() + 1e-12)
    closest = values[nearest]
    likeness = float(np.mean(closest)) if len(closest) else math.inf
    # what the closest pairs differ by beyond what their frames' timing explains: 0 for a true
    # repeat whether it falls on a frame or between two, more for a merely similar view
    excess = float(np.mean(np.maximum(closest - predicted_at(period_s)[nearest], 0.0))) if len(closest) else math.inf
    # the closest pairs against their frames' farthest neighbours, and how sharply the fit
    # prefers this period over those a few frames off
    apart = table[miss_s <= max(0.5 * step_s, miss_s.min() + 1e-12), -1]
    contrast = float(np.mean(closest) / np.mean(apart)) if len(apart) and np.mean(apart) > 0 else math.inf
    fit = 1.0 - minimum / float(coarse_cost.max()) if coarse_cost.max() > 0 else 0.0
    if likeness > ALIKE or contrast > CONTRAST or fit < MIN_FIT:
        return None
    # interval: the cost's curvature with one independent residual per frame involved, and a
    # floor for where between two frames a repeat can be placed (per repeat spanned)
    frames_involved = len(np.union1d(i, j))
    se_s = math.sqrt(2.0 * minimum / max(frames_involved, 1) / curvature) if curvature > 0 else math.inf
    floor_s = max(RESOLUTION_STEPS * step_s, hold_s) / repeats
    clock_s = clock_resolution_s / repeats
    # a rate that changes over the clip: the pairs of its first and second halves disagree, and
    # the mean rate is known no better than half their difference
    middle_s = 0.5 * (times_s[i] + times_s[j])
    early = middle_s <= float(np.median(middle_s))
    window = np.linspace(period_s - 3 * step, period_s + 3 * step, FINE_POINTS * 2 + 1)
    halves = [float(window[int(np.argmin(costs(window, part)))]) for part in (early, ~early) if part.sum() >= 3]
    drift_s = abs(halves[0] - halves[1]) if len(halves) == 2 else 0.0
    half_s = math.sqrt((1.96 * se_s) ** 2 + floor_s ** 2 + clock_s ** 2 + (0.5 * drift_s) ** 2)
    return Period(period_s, period_s - half_s, period_s + half_s, repeats, count, likeness, fit, drift_s, excess,
                  lag0)
