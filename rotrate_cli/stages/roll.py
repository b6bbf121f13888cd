"""The clip's repetition where a camera rolls and nothing still shows it (:func:`rolled_period`).

A camera that rolls about its own axis turns the whole picture about the principal point (taken
at the picture's centre, as the lens's fit takes it). Where a still background shows, its
tracks measure that roll and it is taken out before anything is rated
(:mod:`rotrate_cli.tracking.steady`). A record seen close fills the picture: nothing in it stands
still, and each turn the picture comes back turned by the camera's roll over that turn, so it
does not come back at all (the shared record close-up, rolled 3 degrees a second: its tracks
read -49%, weak, the interval missing).

Turned back by the right roll, frame by frame, the picture comes back again. So where the clip's
plain repetition finds nothing and no still background shows, the thumbnails are turned back
about their centre by a steady roll, tried over :data:`ROLLS_DEG_S` either way, and the
repetition sought in each; the roll whose repetition matches best is refined to a fraction of a
degree a second. It is taken only where it is pinned: the repetitions a couple of degrees a
second either side of it come back clearly less often or match clearly worse, or are not found.
Only the circle inscribed in the thumbnails is compared (:func:`turned_back`). A disc
seen face on about the picture's centre is not pinned (turned back by any roll, it comes back at another rate: its
turn and the camera's are one), and nothing is taken. The rate's interval holds the rates of
the rolls that match nearly as well.

A hand's wobble is not a steady roll: turned back by its mean roll, the picture still sways by a
degree or two, and may line up once by chance; a roll is believed only where the picture then
comes back several times (:data:`MIN_REPEATS`).

So where no still background shows and the plain return is doubtful (none, or fewer than
:data:`MIN_REPEATS`, or a sooner one that matched less well), two pictures are first allowed to
differ by a small turn of the whole picture about its centre (:data:`SWAY_DEG` either way) and
still count as the same (:func:`swayed_period`): a camera that sways in the hand turns the picture
by a degree or two back and forth, and the body's turn does not line up with that. Then the steady
roll is sought, then the roll with the sway allowed, then a zoom of the whole picture about its
centre (:data:`ZOOM_SHARE` either way: a camera coming nearer and going back;
:func:`unsteady_camera_period`). The shared
record, its picture swaying 1.5 and 0.4 degrees at 0.9 and 2.3 Hz with a 4-pixel shake (no still
background): plainly its picture came back only where the sway lined up too, after five turns
(-80%, weak); allowed the sway, after each turn, 13 times, -0.004%. Rolled 3 degrees a second as
well, the steady roll brings it back (+0.09%). A turn of the whole picture about its centre can
stand in for the body's own only where the body turns about the centre seen face on; there the
plain return finds it, and none of this is tried.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace

import cv2
import numpy as np

from rotrate_cli.runtime.lazy import pandas as pd
from rotrate_cli.scene.angle_frames import turned_back as turned_back_picture
from rotrate_cli.stages.period import Differences, Period, changing_pixels, find_period, squared_differences

#: The steady rolls tried first, degrees a second (each either way): a camera on a head turned by
#: hand, or drifting in the hand, rolls a few degrees a second at most.
ROLLS_DEG_S = (1.0, 2.0, 3.0, 4.5, 6.0, 8.0)
#: The best is refined by these steps either side (degrees a second), in turn.
REFINE_STEPS_DEG_S = (0.5, 0.25)
#: Pinned: the repetitions this far either side (degrees a second) come back at most half as
#: often, or match clearly worse (their likeness, a difference, at least LESS_ALIKE above the
#: best's), or are not found. A disc face on about the picture's middle comes back as often and
#: as nearly alike at every roll (5 times, likeness 0.002-0.008); the rolled record came back 14
#: times at 0.14 at 3 degrees a second, twice at 0.34 2 degrees a second either side; a tilted disc rolled 3 degrees a
#: second, 5 times at 0.003, and 3 times at 0.29 at 1.
PINNED_APART_DEG_S = 2.0
LESS_ALIKE = 0.1
#: The rolls whose repetitions match within this factor of the best's likeness are held by the
#: interval.
NEARLY_AS_ALIKE = 1.1
#: A roll is believed only where the picture, turned back by it, comes back at least this many
#: times over the clip: a picture that sways as well (a hand's wobble) can line up once by chance
#: (the rolled and wobbling record came back once, after two turns: -50%; the steadily rolled one
#: six times).
MIN_REPEATS = 3
#: A sway allowed: each picture turned about its centre by up to this many degrees either way, in
#: steps of SWAY_STEP_DEG (a 64-pixel thumbnail's corner moves a third of a pixel in half a step).
#: A hand holding a camera sways it by a degree or two (the record swayed 1.9 at most).
SWAY_DEG = 3.0
SWAY_STEP_DEG = 1.0
#: The sway is sought over the first this many frames only: its differences cost as many matrix
#: products as sway steps (600 frames, 7 steps: about half a second).
SWAY_FRAMES = 600
#: A camera held in the hand also comes nearer and goes back: pictures may be larger or smaller
#: about their centre by up to this share either way, in steps of ZOOM_STEP (a 64-pixel
#: thumbnail's edge moves a sixth of a pixel in half a step), and still count as the same.
ZOOM_SHARE = 0.04
ZOOM_STEP = 0.01


def rolled_period(times_s: np.ndarray, images: np.ndarray, shape: tuple[int, int],
                  clock_resolution_s: float = 0.0, differences: Differences | None = None) -> Period | None:
    """The clip's repetition with a steady camera roll taken out (see the module's notes; its
    ``roll_deg_s``, anticlockwise as the picture shows it); None where no roll gives one, or the
    roll is not pinned. ``images``: one row of thumbnail pixels per frame, ``shape`` their rows
    and columns; ``differences``: how pictures are compared (:func:`rotrate_cli.stages.period.find_period`)."""
    if len(times_s) < 8 or images.size == 0:
        return None
    found: dict[float, Period | None] = {}

    def tried(roll: float) -> Period | None:
        roll = round(roll, 3)
        if roll not in found:
            found[roll] = find_period(times_s, turned_back(times_s, images, shape, roll), clock_resolution_s,
                                      differences)
        return found[roll]

    for size in ROLLS_DEG_S:
        for roll in (size, -size):
            tried(roll)
    best = _best(found)
    if best is None:
        return None
    for step in REFINE_STEPS_DEG_S:
        for roll in (best - step, best + step):
            tried(roll)
        best = _best(found)
        assert best is not None
    period = found[round(best, 3)]
    assert period is not None
    if period.repeats < MIN_REPEATS:
        return None
    # pinned: the rolls a couple of degrees a second either side come back clearly less often
    # or clearly less alike, or not at all (face on about the middle, every roll comes back as
    # often and as nearly alike)
    for side in (-1.0, 1.0):
        other = tried(best + side * PINNED_APART_DEG_S)
        if other is not None and other.repeats > period.repeats / 2 and other.likeness < period.likeness + LESS_ALIKE:
            return None
    # the interval holds the rates of the rolls that match nearly as well, where they come back
    # after as many turns (the rolled and swaying record: a roll near its best came back after two)
    near = [p for roll, p in found.items() if p is not None and abs(roll - best) < PINNED_APART_DEG_S
            and p.likeness <= NEARLY_AS_ALIKE * period.likeness and abs(p.period_s / period.period_s - 1.0) < 0.5]
    low_s = min(p.period_low_s for p in near)
    high_s = max(p.period_high_s for p in near)
    return replace(period, period_low_s=low_s, period_high_s=high_s, roll_deg_s=best)


def unsteady_camera_period(times_s: np.ndarray, images: np.ndarray, shape: tuple[int, int],
                           clock_resolution_s: float, plain: Period | None) -> Period | None:
    """The clip's repetition where no still background shows the camera's motion, given the
    plain one (``plain``, :func:`rotrate_cli.stages.period.find_period`; None where it found none).
    Where the plain one is doubtful (none; back fewer than :data:`MIN_REPEATS` times; or with a
    sooner return that matched less well, :attr:`Period.sooner_s`, so that it may span several
    turns, those between spoiled), it is sought allowing the camera a sway
    (:func:`swayed_period`), with a steady roll taken out (:func:`rolled_period`), then both, and
    then allowing the picture to be larger or smaller (:func:`zoomed_period`), and the first found
    that comes back more often than the plain one, its pictures about as alike (their likeness
    within :data:`LESS_ALIKE`), is taken. The swaying record came back plainly
    only after five turns, where the sway lined up as well (3 times, likeness 0.20), and allowed
    the sway after each turn (13 times, 0.20); a tilted disc filmed rolling and swaying came back
    plainly once, 1.3% early (0.30), and with the roll taken out 6 times (0.02). (The sway is
    sought first: a swaying picture also comes back with a small roll taken out, less closely:
    a tilted disc swaying came back 0.13% late with 0.25 degrees a second taken out, and 0.0003%
    early allowed the sway.)"""
    if plain is not None and plain.repeats >= MIN_REPEATS and not math.isfinite(plain.sooner_s):
        return plain
    searches = (lambda: swayed_period(times_s, images, shape, clock_resolution_s),
                lambda: rolled_period(times_s, images, shape, clock_resolution_s),
                lambda: swayed_period(times_s, images, shape, clock_resolution_s, rolling=True),
                lambda: zoomed_period(times_s, images, shape, clock_resolution_s))
    for search in searches:
        found = search()
        if found is not None and (plain is None or (found.repeats > plain.repeats
                                                    and found.likeness <= plain.likeness + LESS_ALIKE)):
            return found
    return plain


def swayed_period(times_s: np.ndarray, images: np.ndarray, shape: tuple[int, int],
                  clock_resolution_s: float = 0.0, rolling: bool = False) -> Period | None:
    """The clip's repetition where two pictures may differ by a small turn of the whole picture
    (:data:`SWAY_DEG`, a camera swaying in the hand) and still count as the same, over the first
    :data:`SWAY_FRAMES` frames; ``rolling``: with a steady roll taken out as well
    (:func:`rolled_period`). None where it does not come back at least :data:`MIN_REPEATS` times.
    See the module's notes."""
    times_s, images = times_s[:SWAY_FRAMES], images[:SWAY_FRAMES]
    if len(times_s) < 8 or images.size == 0:
        return None
    if rolling:
        found = rolled_period(times_s, images, shape, clock_resolution_s, swaying(shape))
    else:
        found = find_period(times_s, images, clock_resolution_s, swaying(shape))
    if found is None or found.repeats < MIN_REPEATS:
        return None
    return replace(found, sway_deg=SWAY_DEG)


def zoomed_period(times_s: np.ndarray, images: np.ndarray, shape: tuple[int, int],
                  clock_resolution_s: float = 0.0) -> Period | None:
    """The clip's repetition where two pictures may differ by a small enlargement of the whole
    picture about its centre (:data:`ZOOM_SHARE` either way: a camera coming nearer and going back
    in the hand) and still count as the same, over the first :data:`SWAY_FRAMES` frames; None where
    it does not come back at least :data:`MIN_REPEATS` times. The shared record, its picture 3%
    larger and smaller once in five seconds: plainly back best after three turns, and sooner less
    alike (-66.6%, weak); allowed the zoom, after each turn, 16 times, +0.01%."""
    times_s, images = times_s[:SWAY_FRAMES], images[:SWAY_FRAMES]
    if len(times_s) < 8 or images.size == 0:
        return None
    found = find_period(times_s, images, clock_resolution_s, zooming(shape))
    if found is None or found.repeats < MIN_REPEATS:
        return None
    return replace(found, zoom_share=ZOOM_SHARE)


def zooming(shape: tuple[int, int], share: float = ZOOM_SHARE) -> Differences:
    """Pictures' differences allowing a zoom: for each pair of frames, the least squared difference
    over the first made larger or smaller about its centre by up to ``share`` either way
    (:data:`ZOOM_STEP` steps), over the pixels that change most (as the plain differences are)."""
    steps = np.arange(-share, share + 1e-9, ZOOM_STEP)
    rows, columns = shape
    centre = ((columns - 1) / 2.0, (rows - 1) / 2.0)

    def scaled(step: float) -> Callable[[np.ndarray], np.ndarray]:
        matrix = cv2.getRotationMatrix2D(centre, 0.0, 1.0 + step)
        return lambda image: cv2.warpAffine(image, matrix, (columns, rows), flags=cv2.INTER_LINEAR,
                                            borderMode=cv2.BORDER_REPLICATE)

    return _allowing(shape, [scaled(float(step)) for step in steps[np.abs(steps) > 1e-9]])


def swaying(shape: tuple[int, int], sway_deg: float = SWAY_DEG) -> Differences:
    """Pictures' differences allowing a sway: for each pair of frames, the least squared
    difference over the first turned about its centre by up to ``sway_deg`` either way
    (:data:`SWAY_STEP_DEG` steps), over the pixels that change most (as the plain differences are)."""
    steps = np.arange(-sway_deg, sway_deg + 1e-9, SWAY_STEP_DEG)

    def turned(step: float) -> Callable[[np.ndarray], np.ndarray]:
        return lambda image: turned_back_picture(image, step, cv2.BORDER_REPLICATE)

    return _allowing(shape, [turned(float(step)) for step in steps[steps != 0.0]])


def _allowing(shape: tuple[int, int], moves: list[Callable[[np.ndarray], np.ndarray]]) -> Differences:
    """Pictures' differences where the first of each pair may be moved by any of ``moves`` (each
    a picture of ``shape`` to one), the least squared difference taken; over the pixels that change
    most (as the plain differences are)."""
    def differences(images: np.ndarray) -> np.ndarray:
        pixels, mean = changing_pixels(images)
        chosen = slice(None) if pixels is None else pixels
        mean = mean[chosen].astype(np.float32)
        values = images[:, chosen].astype(np.float32) - mean
        least = squared_differences(values, values)  # not moved
        for move in moves:
            moved = np.stack([move(image.reshape(shape)).ravel() for image in images])
            moved = moved[:, chosen].astype(np.float32) - mean
            np.minimum(least, squared_differences(moved, values), out=least)
        return np.minimum(least, least.T)  # (i moved to j and j moved back to i: about the same move)

    return differences


def _best(found: dict[float, Period | None]) -> float | None:
    """The roll whose repetition matches best (least likeness); None where none was found."""
    rolls = [roll for roll, period in found.items() if period is not None]
    if not rolls:
        return None
    return min(rolls, key=lambda roll: found[roll].likeness)  # type: ignore[union-attr]


def turned_back(times_s: np.ndarray, images: np.ndarray, shape: tuple[int, int], roll_deg_s: float) -> np.ndarray:
    """Each thumbnail (one row of pixels, ``shape`` its rows and columns) turned back about its
    centre by ``roll_deg_s`` times its time since the first, and only the circle inscribed in it
    kept (the rest 0, alike in every frame: no change there). Turned by the roll, a picture's
    corners come from outside the frame, and a little more of them every moment: pictures turns
    apart differ there by the roll alone. (The record rolled 3 degrees a second came back 6 times
    in 30 s over the whole thumbnails, 14 times over the circle; rolled and swaying, not at all,
    and 13 times.)"""
    rows, columns = shape
    y, x = np.mgrid[:rows, :columns]
    outside = ((y - (rows - 1) / 2.0) ** 2 + (x - (columns - 1) / 2.0) ** 2 > (min(rows, columns) / 2.0) ** 2).ravel()
    turned = np.empty_like(images)
    for k, time_s in enumerate(times_s):
        turned[k] = turned_back_picture(images[k].reshape(shape), roll_deg_s * (time_s - times_s[0]),
                                        cv2.BORDER_REPLICATE).ravel()
    turned[:, outside] = 0
    return turned


def turned_back_positions(tracks: pd.DataFrame, roll_deg_s: float, start_s: float,
                          size_px: tuple[int, int]) -> pd.DataFrame:
    """A copy of a tracks table (``time_s, x_px, y_px``) whose positions are turned back about the
    picture's centre (``size_px`` its width and height) by ``roll_deg_s`` times their time since
    ``start_s``, as :func:`rotrate_cli.scene.angle_frames.turned_back` turns a picture: the paths
    the body drew in a picture that did not roll (the rolled record's tracks, their ellipses turned
    by the roll, were read as a side view's, and neither the picture's turning nor its angle was
    sought)."""
    centre_x, centre_y = (size_px[0] - 1) / 2.0, (size_px[1] - 1) / 2.0
    # OpenCV's rotation by -roll (anticlockwise as shown, positive): the picture's own turn undone
    angle = np.radians(-roll_deg_s * (tracks["time_s"].to_numpy(dtype=float) - start_s))
    cosine, sine = np.cos(angle), np.sin(angle)
    x = tracks["x_px"].to_numpy(dtype=float) - centre_x
    y = tracks["y_px"].to_numpy(dtype=float) - centre_y
    return tracks.assign(x_px=centre_x + cosine * x + sine * y, y_px=centre_y - sine * x + cosine * y)


def sway_note(period: Period) -> str:
    """What the user is told where the repetition was found allowing the camera's sway."""
    rolling = f", {_rolling(period.roll_deg_s)}" if period.roll_deg_s else ""
    return (f"no still background is seen, and the picture comes back after each turn only turned by a degree or so "
            f"as by a camera that sways in the hand{rolling}: the rate is the clip's repetition allowing the whole "
            f"picture a turn of up to {period.sway_deg:g} degrees either way (a turn of the whole scene would look "
            f"the same; sought over the clip's first {SWAY_FRAMES} frames at most)")


def zoom_note(period: Period) -> str:
    """What the user is told where the repetition was found allowing the camera to come nearer."""
    return (f"no still background is seen, and the picture comes back after each turn only larger or smaller by a "
            f"few percent, as by a camera coming nearer and going back in the hand: the rate is the clip's "
            f"repetition allowing the whole picture to be up to {100 * period.zoom_share:g}% larger or smaller "
            f"(sought over the clip's first {SWAY_FRAMES} frames at most)")


def roll_note(roll_deg_s: float) -> str:
    """What the user is told where the repetition was found with the camera's roll taken out."""
    return (f"no still background is seen, but the picture comes back after each turn turned as by a camera "
            f"{_rolling(roll_deg_s)}: the rate is the clip's repetition with that roll taken out (a turn of the "
            "whole scene would look the same)")


def _rolling(roll_deg_s: float) -> str:
    """A camera's steady roll in words, its sense as the picture shows it."""
    way = "anticlockwise" if roll_deg_s > 0 else "clockwise"
    return f"rolling {abs(roll_deg_s):.2f} degrees a second ({way} as the picture shows it)"
