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
second either side of it come back clearly less often and match worse, or are not found. A disc
seen face on about the picture's centre is not pinned (turned back by any roll, it comes back at another rate: its
turn and the camera's are one), and nothing is taken. The rate's interval holds the rates of
the rolls that match nearly as well.

A hand's wobble is not a steady roll: turned back by its mean roll, the picture still sways by a
degree or two, and may line up once by chance; a roll is believed only where the picture then
comes back several times (:data:`MIN_REPEATS`). The shared record rolled and wobbling reads no
roll.
"""

from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np

from rotrate_cli.scene.picture_angle import turned_back as turned_back_picture
from rotrate_cli.stages.period import Period, find_period

#: The steady rolls tried first, degrees a second (each either way): a camera on a head turned by
#: hand, or drifting in the hand, rolls a few degrees a second at most.
ROLLS_DEG_S = (1.0, 2.0, 3.0, 4.5, 6.0, 8.0)
#: The best is refined by these steps either side (degrees a second), in turn.
REFINE_STEPS_DEG_S = (0.5, 0.25)
#: Pinned: the repetitions this far either side (degrees a second) come back at most half as
#: often and match at best this share as well (their likeness, a difference, at least 1 / PINNED
#: of the best's), or are not found. The rolled record: 6 times at 0.29 at 3 degrees a second,
#: once at 0.41 at 1 and 5; a disc face on about the picture's middle, 5 times at every roll.
PINNED_APART_DEG_S = 2.0
PINNED = 0.85
#: The rolls whose repetitions match within this factor of the best's likeness are held by the
#: interval.
NEARLY_AS_ALIKE = 1.1
#: A roll is believed only where the picture, turned back by it, comes back at least this many
#: times over the clip: a picture that sways as well (a hand's wobble) can line up once by chance
#: (the rolled and wobbling record came back once, after two turns: -50%; the steadily rolled one
#: six times).
MIN_REPEATS = 3


def rolled_period(times_s: np.ndarray, images: np.ndarray, shape: tuple[int, int],
                  clock_resolution_s: float = 0.0) -> Period | None:
    """The clip's repetition with a steady camera roll taken out (see the module's notes; its
    ``roll_deg_s``, anticlockwise as the picture shows it); None where no roll gives one, or the
    roll is not pinned. ``images``: one row of thumbnail pixels per frame, ``shape`` their rows
    and columns."""
    if len(times_s) < 8 or images.size == 0:
        return None
    found: dict[float, Period | None] = {}

    def tried(roll: float) -> Period | None:
        roll = round(roll, 3)
        if roll not in found:
            found[roll] = find_period(times_s, turned_back(times_s, images, shape, roll), clock_resolution_s)
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
    # and less alike, or not at all (face on about the middle, every roll comes back as often)
    for side in (-1.0, 1.0):
        other = tried(best + side * PINNED_APART_DEG_S)
        if other is not None and (other.repeats > period.repeats / 2 or period.likeness > PINNED * other.likeness):
            return None
    # the interval holds the rates of the rolls that match nearly as well
    near = [p for roll, p in found.items() if p is not None and abs(roll - best) < PINNED_APART_DEG_S
            and p.likeness <= NEARLY_AS_ALIKE * period.likeness]
    low_s = min(p.period_low_s for p in near)
    high_s = max(p.period_high_s for p in near)
    return replace(period, period_low_s=low_s, period_high_s=high_s, roll_deg_s=best)


def _best(found: dict[float, Period | None]) -> float | None:
    """The roll whose repetition matches best (least likeness); None where none was found."""
    rolls = [roll for roll, period in found.items() if period is not None]
    if not rolls:
        return None
    return min(rolls, key=lambda roll: found[roll].likeness)  # type: ignore[union-attr]


def turned_back(times_s: np.ndarray, images: np.ndarray, shape: tuple[int, int], roll_deg_s: float) -> np.ndarray:
    """Each thumbnail (one row of pixels, ``shape`` its rows and columns) turned back about its
    centre by ``roll_deg_s`` times its time since the first (the corners turned in repeat the
    picture's edge: black corners read as a change where the period compares whole pictures)."""
    turned = np.empty_like(images)
    for k, time_s in enumerate(times_s):
        turned[k] = turned_back_picture(images[k].reshape(shape), roll_deg_s * (time_s - times_s[0]),
                                        cv2.BORDER_REPLICATE).ravel()
    return turned


def roll_note(roll_deg_s: float) -> str:
    """What the user is told where the repetition was found with the camera's roll taken out."""
    way = "anticlockwise" if roll_deg_s > 0 else "clockwise"
    return (f"no still background is seen, but the picture comes back after each turn turned as by a camera "
            f"rolling {abs(roll_deg_s):.2f} degrees a second ({way} as the picture shows it): the rate is the "
            f"clip's repetition with that roll taken out (a turn of the whole scene would look the same)")

