"""The picture's own turning angle, frame by frame: the rate of a body turning in a plane (a record,
a wheel, a fan, a clock, a turntable seen from above) from part of a turn, without tracks.

The picture is unrolled about the axis through the plane's view (:mod:`rotrate_cli.scene.disc`);
there the body's turn is a shift along the angle. What is compared is the picture's change from
one frame to the next, not the picture: what stays still (a background, a hub, a reflection, a
tonearm) does not change and drops out, and each ring's mean is taken out (grooves and plain rims,
alike at every angle, carry no angle). The changes of two moments line up when shifted by the
angle turned between them; the shift is found by correlation along the angle, to a fraction of a
sample.

The angles are chained from nearby changes (which tell the turn's sense and unwrap it), and the
rate is fitted to the shifts between changes far apart (up to :data:`FARTHEST_DEG`), with an
offset: the shift between nearby changes is pulled a little towards none by what changes without
turning (the shared record read 1.7% slow from steps of 8 degrees, 0.0% over 170), and an offset
common to every pair does not bias the slope. The interval holds the fit's scatter and how far the
rate moves when the view's lens and tilt are varied within what the picture allows (a view found
from part of a turn is uncertain, and turns the picture unevenly where wrong). Where that leaves
the interval wide, the view the picture's circles tell is read too (:mod:`rotrate_cli.scene.circles`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import cv2
import numpy as np

from rotrate_cli.scene.circles import Start, circle_view, ellipse_starts
from rotrate_cli.scene.disc import (
    LAG_SHARES,
    Candidate,
    DiscView,
    PlaneMap,
    RingCorrelations,
    fitted_views,
    moving_weight,
    second_peak,
    shift_deg,
    unrolled,
)

#: A reading whose interval is wider than this fraction of its rate either way is read again
#: through the view the picture's circles tell (:func:`_through_circles`).
CIRCLES_WANTED = 0.02
#: Changes measured at most (evenly over those kept), angles a turn and rings of the measurement.
MOST_CHANGES = 64
ANGLES = 720
RINGS = 128
#: A change is compared with a new one once the picture has turned this far from it.
KEY_DEG = 60.0
#: ... unless the key lies this many times that far back (the changes since it were left out).
STALE_KEY = 1.5
#: Nearby shifts are sought within this (plus a share of the shift) of the one the rate so far
#: predicts (from the median slope of the :data:`RECENT` latest angles).
PREDICTED_WITHIN_DEG = 4.0
PREDICTED_SHARE = 0.15
RECENT = 8
#: A change whose peak is lower than this fraction of the typical one is left out.
WEAK_PEAK = 0.5
#: Changes larger than this many times the median (energy) are left out; the chain starts from
#: the median rate of this many pairs of nearby changes.
OUTSIZE = 6.0
FIRST_PAIRS = 9
#: Changes this far apart (at most) time the rate.
FARTHEST_DEG = 150.0
#: Their shift is sought within this of the chained angles (degrees); one found within this of the
#: search's edge is no peak, but the slope of one outside it, and the pair is left out. What stays
#: still where the body turns behind it (a tonearm over a record, the picture's edge across a
#: disc whose axis lies outside it) changes the picture at no shift; far apart, where the body's
#: own changes overlap little, that peak's slope reached into the search: a record rendered with
#: its axis below the frame, 0.6 of a turn, read its changes 146 degrees apart at 131 (the search's
#: edge) and its rate -14% (its chained angles 0.5% from the truth).
FAR_WITHIN_DEG = 15.0
FAR_EDGE_DEG = 1.0
#: Changes whose chained angles lie within this of a whole turn apart show nearly the same view of
#: the body, so their shift (less the whole turn) is small and read nearly free of the view's
#: errors: where at least :data:`MIN_CLOSINGS` such pairs are seen (a clip of about a turn), they
#: time the rate, the end matched against the start. The record's 0.95 turn, its view found
#: 60 px off the spindle: +7.2% from the shifts within 150 degrees, -0.3% from these.
CLOSING_DEG = 60.0
MIN_CLOSINGS = 3
#: ... and whose shift has no rival within its search that peaks this fraction as high.
RIVAL_PEAK = 0.9
#: The shifts are read to about this much (degrees: a tenth of the unrolled picture's step).
READ_TO_DEG = 0.1 * 360.0 / ANGLES
#: Fewer changes than this, or a turn smaller than this, tell no rate.
MIN_CHANGES = 6
MIN_TURNED_DEG = 15.0
#: The changes must line up at least this well (median peak correlation) to tell a rate.
MIN_SCORE = 0.3
#: A step of the view's variations for the interval: its lens (a factor), its tilt (degrees), its
#: axis's point (:data:`CENTRE_VARIED`, of the width); varied up to this many steps.
VIEW_STEPS = {"focal": 2.0, "tilt": 2.0}
CENTRE_VARIED = 0.004
FARTHEST_STEPS = 4.0
#: ... and up to this many where the changes line up clearly better there than through the view
#: found (the view is then no best one, and the picture does not hold the rate near it). A flat
#: three-bladed fan face on, its axis 40 px right of the frame, 0.3 of a turn: its view found 9 px
#: off the axis (in a 320-px picture) and tilted 18 degrees lined its changes up worse, by 5
#: standard errors, than one moved 4 steps towards the axis; stopped there, it read +6.3% within
#: +-4.6%, good, missing; followed on, within +-9.4%, weak, covering. (Every way followed to 16
#: steps, views that lined up no better, only not clearly worse, made 7 of the real wheel's
#: copies' parts weak that were within 0.7%.)
FARTHEST_BETTER_STEPS = 16.0
#: Views more tilted than this (degrees), or through a lens shorter than this (focal length, of
#: the picture's width), are no plane's a camera sees turning: a side view's cylinder fitted 85
#: degrees through a 5-pixel lens and read 0.25 rad/s for 0.7 before this rule.
MOST_TILT_DEG = 80.0
SHORTEST_FOCAL = 0.3
#: A rate whose interval's half is wider than this fraction of it is no measurement.
LOOSEST = 0.5
#: Clips that turn this far (degrees, at least and at most) have their view sought again through
#: changes nearer together (:data:`rotrate_cli.scene.disc.LAG_SHARES`): under half a turn, half the
#: clip apart is near enough; over one and a half, the return gives the rate.
NEARER_LAGS_DEG = (180.0, 540.0)
#: Views that line the picture up this nearly as well as the best (their scores' ratio) are as
#: likely: the interval holds their readings.
NEARLY_AS_WELL = 0.8
#: ... unless, change by change, their peaks fall short of the best's by more than this many
#: standard errors (of the mean shortfall, counting half the changes as free: nearby ones share a
#: key): the record's 0.9 turn from 5 s, a view 28 px off its spindle scored 0.76 against 0.87 but
#: fell short in 32 of 36 changes (-0.11 +- 0.03) and read +6.3% against +1.4%.
CLEARLY_SHORT = 3.0
FREE_SHARE = 0.5
#: A view sought away from the tracks' axis is taken when it scores this many times the best about it.
CLEARLY_BETTER = 1.25
#: Another shift that fits nearly as well (this fraction of the best) leaves the turn open.
ALIKE_PEAK = 0.9
#: ... and where most pairs of changes fit two so, each is read as the one this much smaller.
CLEARLY_SMALLER = 0.75


@dataclass(frozen=True)
class PictureAngle:
    """The picture's turning angle over the clip and the rate it gives.

    Attributes:
        omega_rad_s: the rate (a magnitude), rad/s; ``omega_low_rad_s``, ``omega_high_rad_s``: its
            95% interval.
        sense: +1 anticlockwise, -1 clockwise, as the picture shows it.
        times_s, angles_deg: the angle turned (signed, from the first change) at each change measured.
        turned_deg: the angle turned over the changes measured (a magnitude).
        score: how well the changes line up (median peak correlation, 1 at best).
        view: the plane's view the angle was measured through (the picture's own pixels).
        alike_deg: the first step's other shift that fits nearly as well (a symmetric body turning
            fast), or None.
        first_step_deg: the first step measured, against which ``alike_deg`` is an alternative.
        heights: each change's peak (after the first, at ``times_s[1:]``), or None.
        thin_part: measured from a thin part against the clip's still picture (a clock's hand:
            :mod:`rotrate_cli.scene.hand`), not from the picture's changes.
        plane: measured from the tracks as one plane turning (:mod:`rotrate_cli.scene.plane_turn`),
            through no view: ``view`` holds only the axis's point, and ``plane_map`` the plane's
            picture as the tracks tell it.
        doubt: why the reading is loose (empty where it is not): a plane that the picture's own
            changes bear out only loosely (:mod:`rotrate_cli.stages.angle`); its interval then holds
            both readings, and a result from it is weak.
        plane_tracks: with ``plane``, the tracks (their numbers in the tracks table) that lay on
            the plane in the pairs of frames it was read from: those that stand behind the rate.
        plane_changes: with ``plane``, True where the rate and angles are the picture's changes
            unrolled through the tracks' plane (:func:`rate_through_map`), not the tracks' own.
        plane_placed: with ``plane``, True where its tracks were placed again on the tracker's
            images (:func:`rotrate_cli.scene.plane_turn.plane_angle`): they do not slide.
        camera_turn_deg_s: the camera's own turn (degrees a second, anticlockwise as the picture
            shows it) taken out of the reading, as the picture around the plane showed it
            (:mod:`rotrate_cli.scene.backdrop`); 0 where none was.
        view_from_circles: read through the view the picture's circles tell
            (:mod:`rotrate_cli.scene.circles`), not the one its changes do.
    """

    omega_rad_s: float
    omega_low_rad_s: float
    omega_high_rad_s: float
    sense: int
    times_s: np.ndarray
    angles_deg: np.ndarray
    turned_deg: float
    score: float
    view: DiscView
    alike_deg: float | None = None
    first_step_deg: float = 0.0
    heights: np.ndarray | None = None
    thin_part: bool = False
    plane: bool = False
    plane_map: PlaneMap | None = None
    doubt: str = ""
    plane_tracks: tuple[int, ...] = ()
    plane_changes: bool = False
    plane_placed: bool = False
    camera_turn_deg_s: float = 0.0
    view_from_circles: bool = False


@dataclass(frozen=True)
class _Change:
    """A change of the picture: between frames ``index`` and ``index + 1``, at their mid-time."""

    index: int
    time_s: float
    first: np.ndarray
    second: np.ndarray
    #: ``second`` less ``first``, kept: it is unrolled through every view tried (the unrolling is
    #: linear, so the change unrolled is the difference of the frames unrolled)
    difference: np.ndarray


def _changes(kept: list[tuple[int, float, np.ndarray]]) -> list[_Change]:
    found = []
    for (index, time_s, image), (next_index, next_s, next_image) in zip(kept, kept[1:], strict=False):
        if next_index == index + 1 and next_s > time_s:
            first, second = _smoothed(image), _smoothed(next_image)
            found.append(_Change(index, 0.5 * (time_s + next_s), first, second, second - first))
    if len(found) > MOST_CHANGES:
        chosen = np.unique(np.linspace(0, len(found) - 1, MOST_CHANGES).round().astype(int))
        found = [found[i] for i in chosen]
    return found


def _smoothed(image: np.ndarray) -> np.ndarray:
    return cv2.GaussianBlur(image.astype(np.float32), (0, 0), 1.0)


def _apart(a: _Change, b: _Change) -> bool:
    """True when the two changes share no frame (a shared frame correlates them at no shift)."""
    return abs(a.index - b.index) >= 2


def measure_angle(kept: list[tuple[int, float, np.ndarray]], start: DiscView, width_px: int,
                  search_tilt: bool, search_centre: bool = False, circles: bool = True) -> PictureAngle | None:
    """The picture's turning angle and rate (see the module's notes) from the frames ``kept``
    (:class:`rotrate_cli.scene.angle_frames.AngleFrames`), through the view found from ``start``
    (the picture's own pixels, ``width_px`` wide; ``search_tilt``: where nothing tells the plane's
    tilt; ``search_centre``: where the axis's point is a guess; ``circles``: where a loose reading
    may be read again through the view the picture's circles tell, :func:`_through_circles`); None
    where too little of the picture turns, or its changes do not line up."""
    changes = _changes(kept)
    if len(changes) < MIN_CHANGES or not all(math.isfinite(v) for v in start.centre_px):
        return None
    scale = changes[0].first.shape[1] / width_px
    pairs = [(change.first, change.second) for change in changes]
    step_px = 0.04 * pairs[0][0].shape[1]

    readings = _readings(changes, fitted_views(pairs, start.scaled(scale), step_px=step_px, search_tilt=search_tilt,
                                               search_centre=search_centre, lag_shares=LAG_SHARES[0]))
    if not readings:
        alone = _circles_alone(changes, kept) if circles else None
        return None if alone is None else replace(alone, view=alone.view.scaled(1.0 / scale))
    best = max(readings, key=lambda angle: angle.score)
    if NEARER_LAGS_DEG[0] <= best.turned_deg <= NEARER_LAGS_DEG[1]:
        # about a turn: half the clip apart, the changes compare opposite sides of the body; the
        # view is refined again from the best through nearer ones (only where it can matter)
        again = fitted_views(pairs, best.view, step_px=step_px, search_tilt=False, search_centre=False,
                             lag_shares=LAG_SHARES[1])
        readings += [angle for angle in (_through(changes, again[0].view),) if angle is not None]
    # of views that line the picture up nearly alike, the one through which its changes line up
    # best over the whole clip (the wheel tilted 38 degrees scored 0.48 against 0.47 face on, but
    # its changes lined up at 0.38 against 0.65, and it read -16% against +0.6%)
    taken = max(readings, key=lambda angle: angle.score)
    # the interval holds the readings of the views through which the changes also line up nearly
    # as well: a view that lines the picture up alike but its changes clearly worse is a wrong one
    # (the record's 0.6 turn: a view tilted 63 degrees through a 280-px lens scored 0.50 against
    # 0.63, its changes 0.55 against 0.87, and read +27% against +0.7%)
    readings = [angle for angle in readings
                if angle.score >= NEARLY_AS_WELL * taken.score and not _clearly_short(angle, taken)]
    low = min(angle.omega_low_rad_s for angle in readings)
    high = max(angle.omega_high_rad_s for angle in readings)
    taken = replace(taken, omega_low_rad_s=low, omega_high_rad_s=high)
    if circles and high - low > 2.0 * CIRCLES_WANTED * taken.omega_rad_s:
        taken = _through_circles(changes, kept, taken) or taken
    return replace(taken, view=taken.view.scaled(1.0 / scale))


def _through_circles(changes: list[_Change], kept: list[tuple[int, float, np.ndarray]],
                     taken: PictureAngle) -> PictureAngle | None:
    """The reading through the view the picture's circles tell (:func:`_circles_reading`, searched
    from ``taken``'s view too), where it is closer than ``taken`` (read through the view the changes
    tell, the reduced frames' pixels) and the changes line up through it no worse; None where the
    circles tell no view, or one no closer than ``taken``'s. (Not sought where nothing still shows
    the camera: :func:`measure_angle`'s ``circles``.)"""
    reading = _circles_reading(changes, kept, taken.view)
    if (reading is None or _clearly_short(reading, taken)
            or reading.omega_high_rad_s - reading.omega_low_rad_s >= taken.omega_high_rad_s - taken.omega_low_rad_s):
        return None
    return reading


def _circles_alone(changes: list[_Change], kept: list[tuple[int, float, np.ndarray]]) -> PictureAngle | None:
    """The reading through the view the picture's circles tell (:func:`_circles_reading`) where no
    view the changes tell gives one: a record tilted 65 degrees turning 9 degrees a frame, 0.3 of a
    turn, whose changes' views (searched from face on) lay tilted 53-69 degrees about other
    directions, and told no rate."""
    return _circles_reading(changes, kept, None)


def _circles_reading(changes: list[_Change], kept: list[tuple[int, float, np.ndarray]],
                     start: DiscView | None) -> PictureAngle | None:
    """The reading through the view the picture's circles tell (:mod:`rotrate_cli.scene.circles`),
    the most coherent found from ``start`` (where given) and from the ellipses the picture's edges
    draw (:func:`rotrate_cli.scene.circles.ellipse_starts`: the search is local, and from a view
    the changes told tilted 35 degrees the wheel turned a quarter found no circle, where it faces
    the camera within 10); None where none is found. From the ellipses only views whose axis lies
    in the picture: there its circles are seen all round it (a disc tilted 60 degrees, its axis
    60 px above the frame, showed arcs that lined up through a view 17 px and 3 degrees off: +21%
    within [+16%, +26%], missing, where its tracks read -0.05%). The interval holds the rates
    through the views the circles do not tell from the one read: along its valleys, other starts'
    views nearly as coherent (the wheel's 1.2-2.03 s: tilted 6.5 to 11 degrees through lenses of
    130 to 3,500 px), the other ellipses' among them (:data:`rotrate_cli.scene.circles.RIVALS`);
    the reduced frames' pixels."""
    mean = np.mean([image for _, _, image in kept], axis=0, dtype=np.float32)
    starts = [] if start is None else [Start(start)]
    found = circle_view(mean, starts + [Start(first, in_picture=True) for first in ellipse_starts(mean)])
    if found is None:
        return None
    reading = _through(changes, found.view, found.held + found.rivals)
    return None if reading is None else replace(reading, view_from_circles=True)


def _readings(changes: list[_Change], views: list[Candidate]) -> list[PictureAngle]:
    """The readings through the views found (best first) that :func:`measure_angle` weighs."""
    # the view about the axis the tracks tell (given, or found from them: evidence the picture's
    # changes do not have), unless another lines the picture up clearly better (the record's
    # found axis lay 600 px from its spindle); views that line it up nearly as well as the one
    # taken are measured too, and the interval holds their readings (the record's first 0.3 turn:
    # the best view read -8.5%, the next +0.1%); the others are not measured (a second or more each)
    about = [candidate for candidate in views if candidate.about_given]
    elsewhere = [candidate for candidate in views if not candidate.about_given]
    first = about[0] if about else elsewhere[0]
    if elsewhere and elsewhere[0].score >= CLEARLY_BETTER * first.score:
        first = elsewhere[0]
    pool = [first] + [candidate for candidate in views
                      if candidate is not first and candidate.score >= NEARLY_AS_WELL * first.score]
    readings = [angle for candidate in pool if (angle := _through(changes, candidate.view)) is not None]
    if not readings:  # the views taken tell no rate: the next best that does
        rest = (_through(changes, candidate.view) for candidate in views if candidate not in pool)
        readings = [angle for angle in (next((angle for angle in rest if angle is not None), None),) if angle]
    return readings


@dataclass(frozen=True)
class MapReading:
    """The picture's changes unrolled through the tracks' plane (:func:`rate_through_map`).

    Attributes:
        omega_rad_s: the rate (a magnitude), rad/s; ``half_rad_s``: its 95% interval's half.
        times_s, angles_deg: the angle turned (signed, from the first change) at each change chained.
        turned_deg: the angle turned over the changes chained (a magnitude).
    """

    omega_rad_s: float
    half_rad_s: float
    times_s: np.ndarray
    angles_deg: np.ndarray
    turned_deg: float


def rate_through_map(kept: list[tuple[int, float, np.ndarray]], plane_map: PlaneMap,
                     width_px: int) -> MapReading | None:
    """The rate of the picture's changes (from the frames ``kept``,
    :class:`rotrate_cli.scene.angle_frames.AngleFrames`) unrolled through ``plane_map`` (the
    tracks' picture, ``width_px`` wide) rather than a view found from the picture, with its chained
    angles; None where they tell none: the picture's own check of the tracks' plane, and its turn
    measured without the tracks' sliding."""
    changes = _changes(kept)
    if len(changes) < MIN_CHANGES:
        return None
    maps = plane_map.unrolled(changes[0].first.shape, changes[0].first.shape[1] / width_px, ANGLES, RINGS)
    unrolled_changes = [maps.of(change.difference) for change in changes]
    weight = moving_weight(unrolled_changes, maps.inside)
    correlate = RingCorrelations(unrolled_changes, weight)
    chain = _chain(changes, unrolled_changes, weight, correlate)
    if chain is None:
        return None
    times, angles = chain[0], chain[1]
    turned = float(abs(angles[-1] - angles[0]))
    if turned < MIN_TURNED_DEG:
        return None
    rate, scatter = _rate_of(changes, correlate, times, angles)
    if not math.isfinite(rate):
        return None
    return MapReading(math.radians(abs(rate)), math.radians(1.96 * scatter), times, angles, turned)


def _clearly_short(angle: PictureAngle, best: PictureAngle) -> bool:
    """True where ``angle``'s changes line up worse than ``best``'s change by change, beyond chance
    (:data:`CLEARLY_SHORT`): the same changes compared through two views."""
    if angle is best or angle.heights is None or best.heights is None:
        return False
    return _clearly_short_of(angle.times_s, angle.heights, best.times_s, best.heights)


def _clearly_short_of(times_s: np.ndarray, heights: np.ndarray, best_times_s: np.ndarray,
                      best_heights: np.ndarray) -> bool:
    """:func:`_clearly_short` of two chains' changes (their times, and peaks after the first)."""
    theirs = dict(zip(times_s[1:].tolist(), heights.tolist(), strict=True))
    ours = dict(zip(best_times_s[1:].tolist(), best_heights.tolist(), strict=True))
    shortfall = np.array([theirs[time] - ours[time] for time in theirs if time in ours])
    if len(shortfall) < MIN_CHANGES:
        return False
    error = float(np.std(shortfall, ddof=1)) / math.sqrt(FREE_SHARE * len(shortfall))
    return float(np.mean(shortfall)) < -CLEARLY_SHORT * max(error, 1e-9)


def _through(changes: list[_Change], view: DiscView, held: tuple[DiscView, ...] | None = None) -> PictureAngle | None:
    """The angle and rate through ``view`` (the reduced frames' pixels); None where it tells none.
    ``held``: the view moved as far as other evidence holds it each way (its circles:
    :mod:`rotrate_cli.scene.circles`), over which the rate's spread is taken instead of over what
    the changes hold (:func:`_view_spread`)."""
    if view.tilt_deg > MOST_TILT_DEG or view.focal_px < SHORTEST_FOCAL * changes[0].first.shape[1]:
        return None  # a plane edge on (a side view: its picture does not turn), or no lens a camera has
    unrolled_changes = _unrolled_changes(changes, view, ANGLES, RINGS)
    chain = _chain(changes, *unrolled_changes)
    if chain is None:
        return None
    times, angles, scores, alike, first_step = chain
    turned = float(abs(angles[-1] - angles[0]))
    score = float(np.median(scores))
    if turned < MIN_TURNED_DEG or score < MIN_SCORE:
        return None
    rate, scatter = _rate_of(changes, unrolled_changes[2], times, angles)
    del unrolled_changes
    if not math.isfinite(rate):
        return None
    spread = _view_spread(changes, view, times, angles) if held is None else _held_spread(changes, view, times,
                                                                                            angles, held)
    # at least what reading the shifts to a tenth of the unrolled picture's step allows over the
    # turn seen (a rendered fan's 1.9 turns: -0.0018% within +-0.0017%, missing by a hair)
    half = max(1.96 * scatter + spread, READ_TO_DEG * abs(rate) / turned)
    if not half < LOOSEST * abs(rate):
        return None  # a rate the picture does not hold to within half itself tells nothing
    omega = math.radians(abs(rate))
    return PictureAngle(omega, max(0.0, omega - math.radians(half)), omega + math.radians(half), 1 if rate > 0 else -1,
                        times, angles, turned, score, view, alike, first_step, scores)


#: Changes unrolled through a view, the weight of their moving rings, and their correlations.
_Unrolled = tuple[list[np.ndarray], np.ndarray, RingCorrelations]


def _unrolled_changes(changes: list[_Change], view: DiscView, angles: int, rings: int) -> _Unrolled:
    """The changes unrolled through ``view``, the weight of their moving rings, and their
    correlations (one for the chain and the rate alike: each change's spectra computed once)."""
    maps = unrolled(changes[0].first.shape, view, angles, rings)
    unrolled_changes = [maps.of(change.difference) for change in changes]
    weight = moving_weight(unrolled_changes, maps.inside)
    return unrolled_changes, weight, RingCorrelations(unrolled_changes, weight)


def _chain(changes: list[_Change], unrolled_changes: list[np.ndarray], weight: np.ndarray,
           correlate: RingCorrelations) -> tuple[
        np.ndarray, np.ndarray, np.ndarray, float | None, float] | None:
    """The angle at each change (unrolled through a view), chained from nearby ones (the latest
    key change sharing no frame); the peaks' heights; the first step's alternative shift (see
    :class:`PictureAngle`)."""
    if weight.sum() < 50:
        return None
    # a change far larger than the typical one is no turn's (a still first frame, a flash, a
    # damaged stretch): left out
    energy = np.array([float(np.sum((change * weight) ** 2)) for change in unrolled_changes])
    ordinary = np.flatnonzero(energy <= OUTSIZE * max(float(np.median(energy)), 1e-9))
    if len(ordinary) < MIN_CHANGES:
        return None
    start = int(ordinary[0])
    rate, first_step, alike = _first_rate(changes, correlate, ordinary)
    measured: dict[int, float] = {start: 0.0}
    heights: dict[int, float] = {start: 1.0}
    keys = [start]
    for k in ordinary[1:]:
        usable = [key for key in keys if _apart(changes[key], changes[k])]
        if not usable:
            continue
        key = usable[-1]
        if abs(rate * (changes[k].time_s - changes[key].time_s)) > STALE_KEY * KEY_DEG:
            # changes since the key were left out: the latest one measured leads on, rather than
            # a key ever farther back (the record's 0.95 turn stopped at 0.74 of it, its peaks
            # falling from 0.6 to 0.15 as the shift from the key grew to 137 degrees)
            key = max(i for i in measured if _apart(changes[i], changes[k]))
            keys.append(key)
        correlation = correlate(key, int(k))
        predicted = rate * (changes[k].time_s - changes[key].time_s)
        shift, height = shift_deg(correlation, predicted, PREDICTED_WITHIN_DEG + PREDICTED_SHARE * abs(predicted))
        if len(heights) > 3 and height < WEAK_PEAK * float(np.median(list(heights.values())[1:])):
            continue  # a change that does not line up (a hand across the picture): left out
        measured[int(k)] = measured[key] + shift
        heights[int(k)] = height
        rate = _recent_rate([(changes[i].time_s, measured[i]) for i in sorted(measured)[-RECENT:]]) or rate
        if abs(measured[int(k)] - measured[key]) > KEY_DEG:
            keys.append(int(k))
    order = sorted(measured)
    if len(order) < MIN_CHANGES:
        return None
    return (np.array([changes[i].time_s for i in order]), np.array([measured[i] for i in order]),
            np.array([heights[i] for i in order[1:]]), alike, first_step)


def _first_rate(changes: list[_Change], correlate: RingCorrelations,
                ordinary: np.ndarray) -> tuple[float, float, float | None]:
    """The rate to start the chain with (degrees a second): the median of the rates of up to
    :data:`FIRST_PAIRS` pairs of nearby changes over the clip, each its best shift anywhere
    (one pair's could be a still frame's or a hand's); the step of the pair nearest that median,
    and its other shift that fits nearly as well (see :class:`PictureAngle`), or None."""
    found = []
    for i in ordinary[:: max(1, len(ordinary) // FIRST_PAIRS)]:
        later = [k for k in ordinary if k > i and _apart(changes[int(i)], changes[int(k)])]
        if not later:
            continue
        k = int(later[0])
        correlation = correlate(int(i), k)
        shift, height = shift_deg(correlation)
        apart = max(5.0, 0.5 * abs(shift))
        other_shift, other_height = second_peak(correlation, shift, apart)
        other = other_shift if other_height >= ALIKE_PEAK * height else None
        found.append((shift / (changes[k].time_s - changes[int(i)].time_s), shift, other))
    if not found:
        return 0.0, 0.0, None
    alike = sum(item[2] is not None for item in found) > len(found) / 2
    if alike:
        # most pairs fit two shifts alike (a symmetric body): each is read as the smaller, the
        # turn a frame that does not outrun its picture's repeat (a flat five-bladed fan turning 10
        # degrees a frame: 20 between changes fitted -52 as well, and read 2.6 times too fast)
        # (clearly smaller: at half a repeat a frame the two are alike in size too, and the better
        # fit stands; six blades at 15 degrees a frame, 30 between changes, fitted -30 as well)
        found = [(rate * other / shift, other, shift) if other is not None and abs(other) < CLEARLY_SMALLER * abs(shift)
                 else (rate, shift, other) for rate, shift, other in found]
    middle = float(np.median([rate for rate, _, _ in found]))
    rate, step, other = min(found, key=lambda item: abs(item[0] - middle))
    return middle, step, other if alike else None


def _recent_rate(points: list[tuple[float, float]]) -> float | None:
    """The median of the slopes between the recent angles (degrees a second): one that went astray
    does not lead the next astray."""
    slopes = [(b - a) / (tb - ta) for i, (ta, a) in enumerate(points) for tb, b in points[i + 1:] if tb > ta]
    return float(np.median(slopes)) if slopes else None


def _rate_of(changes: list[_Change], correlate: RingCorrelations, times: np.ndarray,
             angles_deg: np.ndarray, edges_out: bool = True) -> tuple[float, float]:
    """The rate (degrees a second, signed) of changes unrolled, fitted with an offset to the shifts
    between changes far apart (the farthest within :data:`FARTHEST_DEG`, and one half way), sought
    near the chained angles; and its standard error, widened for changes used in several pairs.
    From the pairs about a whole turn apart where there are enough (:data:`CLOSING_DEG`)."""
    index_of = {changes[i].time_s: i for i in range(len(changes))}
    chained = [(index_of[t], float(a)) for t, a in zip(times, angles_deg, strict=True)]
    rows: list[tuple[float, float]] = []
    closings = []
    for position, (i, angle_i) in enumerate(chained):
        later = [(k, angle_k) for k, angle_k in chained[position + 1:] if _apart(changes[i], changes[k])]
        far = [(k, angle_k) for k, angle_k in later if abs(angle_k - angle_i) <= FARTHEST_DEG]
        for k, angle_k in {far[-1], far[len(far) // 2]} if far else ():
            correlation = correlate(i, k)
            shift, _ = shift_deg(correlation, angle_k - angle_i, FAR_WITHIN_DEG)
            if edges_out and abs((shift - (angle_k - angle_i) + 180.0) % 360.0 - 180.0) > FAR_WITHIN_DEG - FAR_EDGE_DEG:
                continue  # no peak inside the search, only its edge: see FAR_WITHIN_DEG
            rows.append((changes[k].time_s - changes[i].time_s, shift))
        turns = [(k, angle_k) for k, angle_k in later if abs(abs(angle_k - angle_i) - 360.0) <= CLOSING_DEG]
        if turns:
            k, angle_k = min(turns, key=lambda item: abs(abs(item[1] - angle_i) - 360.0))
            predicted = angle_k - angle_i
            correlation = correlate(i, k)
            within = 15.0 + 0.1 * abs(predicted)
            shift, height = shift_deg(correlation, predicted, within)
            if _rival_within(correlation, shift, height, predicted, within):
                continue  # a symmetric body: another of its repeats fits as well within the search
            closings.append((changes[k].time_s - changes[i].time_s, shift + 360.0 * round((predicted - shift) / 360.0)))
    far = _with_offset(rows, len(chained))
    if len(closings) < MIN_CLOSINGS:
        return far
    closing = _through_origin(np.array(closings), len(chained))
    if not math.isfinite(far[0]):
        return closing
    # the closings found one repeat of a symmetric body off (an 8-spoked wheel tilted 55 degrees,
    # its spokes 45 degrees apart peaking at 0.43 and 0.33, read 8/7 of its rate from them and
    # its own rate from the far shifts), or the far shifts read through a view a little off (the
    # record's 0.95 turn, +7.2%, its closings -2.1%): where they disagree, the interval holds both
    apart = abs(closing[0] - far[0])
    if apart <= 1.96 * math.hypot(closing[1], far[1]):
        return closing
    return closing[0], apart / 1.96 + max(closing[1], far[1])


#: A far shift whose residual from the line through the others exceeds this many robust standard
#: deviations (and :data:`READ_TO_DEG` several times) is a wrong peak, and is left out: a record
#: rendered with its axis below the frame and a still tonearm, 0.6 of a turn, read two pairs 113 and
#: 107 degrees apart at 101 and 102 (the peak of what stays still reaching in), and its rate -3.5%
#: with them, -0.2% without.
FAR_OUTLIER = 5.0


def _with_offset(rows: list[tuple[float, float]], chained: int) -> tuple[float, float]:
    """The rate (degrees a second) of shifts over spans fitted with an offset, the shifts far off
    the line through the others left out (:data:`FAR_OUTLIER`), and its standard error from every
    shift about that line, widened for changes used in several pairs."""
    every = np.array(rows, dtype=float).reshape(-1, 2)
    table = every
    for fitted in range(2):  # fitted, then again without the shifts far off it
        if len(table) < 3:
            return math.nan, math.nan
        design = np.vstack([table[:, 0], np.ones(len(table))]).T
        coefficients = np.linalg.lstsq(design, table[:, 1], rcond=None)[0]
        residuals = table[:, 1] - design @ coefficients
        scale = 1.4826 * float(np.median(np.abs(residuals - np.median(residuals))))
        kept = np.abs(residuals) <= max(FAR_OUTLIER * scale, 5.0 * READ_TO_DEG)
        if fitted or kept.all():
            break
        table = table[kept]
    slope = float(coefficients[0])
    # the error from every shift about that line, the wrong peaks too: they also tell how loosely
    # the picture holds its turn
    spans = every[:, 0]
    residuals = every[:, 1] - (slope * spans + float(coefficients[1]))
    spread = float(np.sum((spans - spans.mean()) ** 2))
    if spread <= 0:
        return math.nan, math.nan
    error = math.sqrt(float(np.sum(residuals ** 2)) / max(1, len(every) - 2) / spread)
    return slope, error * math.sqrt(len(every) / chained)


def _rival_within(correlation: np.ndarray, shift_deg_: float, height: float, near_deg: float,
                  within_deg: float) -> bool:
    """True where another shift within ``within_deg`` of ``near_deg``, more than 5 degrees from the
    best (``shift_deg_``, ``height``), fits at least :data:`RIVAL_PEAK` as well: a symmetric body,
    whose whole turn's closing may be found one repeat off."""
    count = len(correlation)
    shifts = (np.arange(count) * (360.0 / count) + 180.0) % 360.0 - 180.0
    inside = np.abs((shifts - near_deg + 180.0) % 360.0 - 180.0) <= within_deg
    apart = np.abs((shifts - shift_deg_ + 180.0) % 360.0 - 180.0) > 5.0
    others = correlation[inside & apart]
    return bool(len(others)) and float(others.max()) >= RIVAL_PEAK * height


def _through_origin(table: np.ndarray, chained: int) -> tuple[float, float]:
    """The rate (degrees a second) of shifts over spans (rows of ``table``) as one line through
    the origin, and its standard error, widened for changes used in several pairs."""
    spans, shifts = table[:, 0], table[:, 1]
    total = float(np.sum(spans ** 2))
    slope = float(np.sum(spans * shifts)) / total
    residuals = shifts - slope * spans
    error = math.sqrt(float(np.sum(residuals ** 2)) / max(1, len(table) - 1) / total)
    return slope, error * math.sqrt(max(1.0, len(table) / max(chained, 1)))


def _view_spread(changes: list[_Change], view: DiscView, times: np.ndarray, angles_deg: np.ndarray) -> float:
    """How far the rate moves (degrees a second) when the view is varied within what the picture
    tells of it (measured coarsely, against the same measure through the view found). Each way the
    view may be off (the lens longer or shorter, the axis's point across or down either way, the
    tilt more or less, or about two directions where the plane faces the camera) is varied by a
    step (:data:`VIEW_STEPS`); where its changes line up clearly worse (:func:`_clearly_short`),
    the picture holds the view within that step and the half of it is taken; where they do not,
    the step is doubled while they still do not, up to :data:`FARTHEST_STEPS`, or
    :data:`FARTHEST_BETTER_STEPS` while they line up clearly better (the wheel's part from
    1.2 s: its view 2.5 px left of the hub, whose changes lined up no worse 1.3 px right, read
    +5.9% within +-2.3%; the record's first 0.3 turn: its tilt 2 degrees more or less fell short by
    4 standard errors either way, and moved the rate +4.7% and -3.6%)."""
    coarse = (256, 64)
    step_px = CENTRE_VARIED * changes[0].first.shape[1]
    memo: dict[tuple[int, float], _Unrolled] = {}

    def unrolled_at(way: int, steps: float) -> _Unrolled:  # way -1: the view found
        if (way, steps) not in memo:
            memo[(way, steps)] = _unrolled_changes(changes, view if way < 0 else _varied(view, way, steps, step_px),
                                                   *coarse)
        return memo[(way, steps)]

    # through views varied, far changes that show no peak inside their search are kept: a view
    # varied off the one found lines the far changes up less, and how far its rate moves with them
    # is how loosely the picture holds the view (a wheel played backwards at half size, 0.3 of a
    # turn through a view tilted 37 degrees, face on: -10.8%; its views varied without those
    # changes moved its rate 3%, and it was good, missing; with them 4.5%, weak)
    base, _ = _rate_of(changes, unrolled_at(-1, 0.0)[2], times, angles_deg, edges_out=False)
    found = _chain(changes, *unrolled_at(-1, 0.0))
    if not math.isfinite(base) or found is None:
        return 0.0

    def short(way: int, steps: float) -> bool:
        chain = _chain(changes, *unrolled_at(way, steps))
        return chain is None or _clearly_short_of(chain[0], chain[2], found[0], found[2])

    fine: list[tuple[np.ndarray, np.ndarray, np.ndarray, float | None, float] | None] = []

    def better(way: int, steps: float) -> bool:
        # the view found clearly short of this one, at the full resolution (asked only at the
        # search's end: coarsely the fan's changes lined up better by 1 standard error, fully by 5)
        if not fine:
            fine.append(_chain(changes, *_unrolled_changes(changes, view, ANGLES, RINGS)))
        chain = _chain(changes, *_unrolled_changes(changes, _varied(view, way, steps, step_px), ANGLES, RINGS))
        return (chain is not None and fine[0] is not None
                and _clearly_short_of(fine[0][0], fine[0][2], chain[0], chain[2]))

    moved = []
    for way in range(len(_WAYS)):
        steps = 1.0
        if short(way, steps):
            steps = 0.5
        else:
            while ((steps < FARTHEST_STEPS or (steps < FARTHEST_BETTER_STEPS and better(way, steps)))
                   and not short(way, 2.0 * steps)):
                steps *= 2.0
        rate = _rate_of(changes, unrolled_at(way, steps)[2], times, angles_deg, edges_out=False)[0]
        if math.isfinite(rate):
            moved.append(abs(rate - base))
        for key in [key for key in memo if key[0] == way]:
            del memo[key]  # (a few MB each)
    return max(moved) if moved else 0.0


def _held_spread(changes: list[_Change], view: DiscView, times: np.ndarray, angles_deg: np.ndarray,
                 held: tuple[DiscView, ...]) -> float:
    """How far the rate moves (degrees a second) through the views ``held`` (``view`` moved as far
    as other evidence holds it each way), measured coarsely as :func:`_view_spread` does; infinite
    where one of them tells no rate."""
    coarse = (256, 64)
    base, _ = _rate_of(changes, _unrolled_changes(changes, view, *coarse)[2], times, angles_deg, edges_out=False)
    moved = [0.0]
    for other in held:
        rate = _rate_of(changes, _unrolled_changes(changes, other, *coarse)[2], times, angles_deg, edges_out=False)[0]
        moved.append(abs(rate - base) if math.isfinite(rate) and math.isfinite(base) else math.inf)
    return max(moved)


#: The ways :func:`_varied` moves a view: the lens (a factor), the axis's point across and down
#: (px), the tilt (degrees; about the long axis, or the other, where the plane faces the camera).
_WAYS = (("focal", 1), ("focal", -1), ("x", 1), ("x", -1), ("y", 1), ("y", -1), ("tilt", 1), ("tilt", -1))


def _varied(view: DiscView, way: int, steps: float, step_px: float) -> DiscView:
    """``view`` moved ``steps`` of :data:`VIEW_STEPS` the ``way``-th of :data:`_WAYS`."""
    what, sign = _WAYS[way]
    if what == "focal":
        return replace(view, focal_px=view.focal_px * VIEW_STEPS["focal"] ** (sign * steps))
    x, y = view.centre_px
    if what == "x":
        return replace(view, centre_px=(x + sign * steps * step_px, y))
    if what == "y":
        return replace(view, centre_px=(x, y + sign * steps * step_px))
    tilt = steps * VIEW_STEPS["tilt"]
    if view.tilt_deg <= VIEW_STEPS["tilt"]:  # facing the camera: more tilt, about two directions
        return replace(view, tilt_deg=view.tilt_deg + tilt,
                       long_axis_deg=view.long_axis_deg + (0.0 if sign > 0 else 90.0))
    return replace(view, tilt_deg=min(85.0, max(0.0, view.tilt_deg + sign * tilt)))


def window_rates(kept: list[tuple[int, float, np.ndarray]], angle: PictureAngle, width_px: int,
                 centres_s: np.ndarray, window_s: float) -> list[tuple[float, float, float] | None]:
    """omega(t) from the picture's angle: per window (``centres_s``, ``window_s`` long) the rate
    and 95% interval (rad/s, magnitudes) fitted as the whole clip's is (:func:`_rate_of`) to the
    changes inside it, through the clip's view; the interval also holds the clip's own view
    uncertainty, in proportion. None for a window with too few changes or too small a turn."""
    changes = _changes(kept)
    if len(changes) < MIN_CHANGES:
        return [None] * len(centres_s)
    scale = changes[0].first.shape[1] / width_px
    view = angle.view.scaled(scale)
    share = max(angle.omega_rad_s - angle.omega_low_rad_s,
                angle.omega_high_rad_s - angle.omega_rad_s) / angle.omega_rad_s
    times = np.array([change.time_s for change in changes])
    chained = np.interp(times, angle.times_s, angle.angles_deg)
    unrolled_changes, weight, _ = _unrolled_changes(changes, view, ANGLES, RINGS)
    rates: list[tuple[float, float, float] | None] = []
    for centre in centres_s:
        inside = np.flatnonzero(np.abs(times - centre) <= window_s / 2 + 1e-9)
        if len(inside) < MIN_CHANGES or abs(chained[inside[-1]] - chained[inside[0]]) < MIN_TURNED_DEG:
            rates.append(None)
            continue
        part = [changes[i] for i in inside]
        correlate = RingCorrelations([unrolled_changes[i] for i in inside], weight)
        rate, scatter = _rate_of(part, correlate, times[inside], chained[inside])
        if not math.isfinite(rate):
            rates.append(None)
            continue
        omega = math.radians(abs(rate))
        half = math.radians(1.96 * scatter) + share * omega
        rates.append((omega, max(0.0, omega - half), omega + half))
    return rates
