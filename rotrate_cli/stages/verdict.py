"""The judged estimate: the tracks' rate and the clip's repetition weighed into one number, and
how far it can be trusted.

Two measurements can stand behind a result. The tracks' fits (:mod:`rotrate_cli.fitting.estimators`) work on
any length of clip but rest on a model of the projection and on every kept track lying on the
body; on real footage (mirroring paint, grooves that slide under the tracker, people moving
behind) they can be biased while their interval stays narrow. The repetition
(:mod:`rotrate_cli.stages.period`) needs about a turn but no model at all. Where both exist:

- the tracks' rate, when it is informative (its interval within :data:`INFORMATIVE_HALF_WIDTH`),
  says how many repeats make a turn (an object with an m-fold symmetry repeats m times);
- the result is the repetition's, which is the more precise and the less biased;
- where no whole number of repeats fits inside an informative tracks' interval, the two
  disagree: the repetition's rate stands, one repeat a turn, and a note says so; when the
  tracks lie near a whole number of repeats from 2 to :data:`MOST_SYMMETRY` (within
  :data:`NEAR_FACTOR`), the object
  may be symmetric and the result is marked weak.

Where the picture changes almost wholly from one frame to the next (a fast wheel, a fan; or a fine
texture), its repeat is told only up to whole turns between frames
(:attr:`rotrate_cli.stages.period.Period.far_apart`): the tracks count the turns where they gave a rate
(:func:`turns_between`), and unless their interval tells the count, the result is weak.

A picture that comes back only once in the clip may be a view that merely looks alike part of a
turn on (a car's far side half a turn on), not a turn: where it does not come back exactly
(:data:`LOOK_ALIKE_EXCESS`), or the tracks turn well under a turn in that time
(:data:`UNDER_TURN`), and informative tracks do not confirm it, the result is weak. Where the
tracks gave a rate there, either reading may be the truth: the 95% interval spans both (the
repetition's, and the tracks' interval), and the tracks' rate is reported where the return is not
exact or their interval's top lies well under the return's rate (on the EPFL cars' first 50-70
photographs the return read +91% to +101%, the tracks -1% to -53%; car 02's 45th to 94th came back
as exactly as a turn, +99%, its tracks 47% of a turn in that time, -5.6%).

The quality is ``weak`` when the interval is wider than :data:`WEAK_HALF_WIDTH` of the rate,
when fewer than :data:`MIN_TRACKS` tracks stand behind a tracks-only result, or when the
measurements disagree; each reason is given.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace

from rotrate_cli.fitting.outliers import Combined
from rotrate_cli.scene.picture_angle import PictureAngle
from rotrate_cli.scene.turning import PictureTurning
from rotrate_cli.stages.period import SAME_PICTURE, Period

#: An interval wider than this fraction of the rate on either side is weak evidence.
WEAK_HALF_WIDTH = 0.05
#: The tracks' rate tells the number of repeats a turn only when its interval is this narrow (and
#: enough tracks stand behind it): on the record clip with the truth's fixation the tracks said
#: 1.8 rad/s +-20%, which holds half the true rate: a looser rule took two repeats a turn.
INFORMATIVE_HALF_WIDTH = 0.05
#: A tracks-only result needs this many consistent tracks to be called good.
MIN_TRACKS = 5
#: The most repeats a turn a picture is taken to show where nothing tells (a checker of 16
#: columns, a gear's teeth beyond): the interval of an undecided count reaches down to it.
MOST_REPEATS = 16
#: The most repeats a turn that measured rates are matched against (bolts, teeth, spokes).
MOST_TOLD = 64
#: Tracks whose interval is wider than this (half, of their rate) do not tell the repeats: on
#: real footage they slide along grooves and rims and read several times too slow.
TRACKS_TELL = 0.25
#: How far beyond their interval the tracks' rate may lie on real footage (through a lens
#: found, on glossy paint: the EPFL cars' tracks 4-16% off a rate their interval missed).
TRACKS_ALLOWANCE = 0.15
#: Tracks too loose to tell the count still pick which count's rate is shown (the nearest theirs)
#: where their interval spans at most this factor from end to end: the record's sliding tracks,
#: 0.44 rad/s within [0, 0.88] under a 3.55 return, pick none.
TRACKS_HINT = 2.0
#: How far beyond its range of best trial rates the picture's turning may lie.
TURNING_ALLOWANCE = 0.02
#: Repeat counts listed in a warning where they are left open.
LISTED = 6

#: A picture that comes back only once in the clip, with its closest pairs differing by more than
#: this (in typical differences, :attr:`rotrate_cli.stages.period.Period.excess`) beyond what their
#: timing explains, may be a look-alike view rather than a turn. Measured on the EPFL cars: their
#: full turns' single closings differ by 0.00-0.11; the views half a turn to three quarters on
#: that looked alike (clips of 40-80 of their 96-120 photographs) by 0.19-0.38, and read twice
#: the rate, as good, before this rule.
LOOK_ALIKE_EXCESS = 0.15
#: ... and where the tracks turn this many times slower than a turn a period (the top of their
#: interval): the same clips timed by their EXIF clocks match their look-alike views as closely
#: as true turns (0.10), but their tracks turn at a quarter to two fifths of the repetition's rate.
UNDER_TURN = 1.5

#: Halves of the clip whose repeats differ by more than this fraction show a changing rate.
CHANGE_FRACTION = 0.01



@dataclass(frozen=True)
class Repeats:
    """How many times the picture repeats a turn, as the evidence tells it.

    Attributes:
        repeats: the count taken (the smallest left open where undecided).
        decided: True when one count alone fits the evidence.
        candidates: the counts left open (just ``repeats`` where decided).
        told_by: what decided it (``tracks``, ``the picture's turning``, both), or "".
        notes, weak: lines for the report; ``weak`` makes the result weak.
        spanned_by: where the evidence disagrees with every count, the tracks' interval, which
            the reported interval also holds; None otherwise.
        untold: nothing but the return itself was measured (no track's rate, no turning).
        against: the picture's own angle where it was measured, is a firm reading, and its rate
            is no count's of the return (:func:`_angle_apart`); None otherwise.
    """

    repeats: int
    decided: bool
    candidates: tuple[int, ...]
    told_by: str = ""
    notes: tuple[str, ...] = ()
    weak: tuple[str, ...] = ()
    spanned_by: tuple[float, float] | None = field(default=None)
    untold: bool = False
    against: PictureAngle | None = None


def counts_within(period: Period, low_rad_s: float, high_rad_s: float, most: int = MOST_TOLD) -> list[int]:
    """The counts ``k`` of repeats a turn whose rate (a turn every ``k`` periods) lies in
    ``[low_rad_s, high_rad_s]``."""
    return [k for k in range(1, most + 1) if low_rad_s <= period.omega_rad_s(k)[0] <= high_rad_s]


def _by_tracks(period: Period, tracks: Combined | None, tracks_used: int) -> list[int] | None:
    """The one count the tracks tell, or none ([]) where they fit no whole count; None where
    they say nothing (too few, too loose, or several counts fit)."""
    if tracks is None or tracks_used < MIN_TRACKS or not 0 < tracks.omega_rad_s < math.inf:
        return None
    if _half_width(tracks.omega_rad_s, tracks.omega_low_rad_s, tracks.omega_high_rad_s) > TRACKS_TELL:
        return None
    within = counts_within(period, tracks.omega_low_rad_s, tracks.omega_high_rad_s)
    if not within:
        within = counts_within(period, tracks.omega_low_rad_s / (1 + TRACKS_ALLOWANCE),
                               tracks.omega_high_rad_s * (1 + TRACKS_ALLOWANCE))
    # one count decides; several leave the others open too (tracks that slide on a rim read slow
    # and can exclude the true count: the wheel turned a quarter read half its rate, weak, its
    # interval missing it); none is a disagreement
    return within if len(within) <= 1 else None


def _by_turning(period: Period, turning: PictureTurning | None) -> list[int] | None:
    """``[1]`` where the picture's turning tells that the return is a whole turn; None otherwise.
    A test that leaves several counts open rules none out (flat blades fit half their turn
    nearly as well as the whole), and one that prefers a part of a turn is not taken at its word:
    about a misplaced axis a smaller turn fits better (the wheel's picture turned a quarter
    preferred half its turn), so only a whole turn, which that error cannot favour, is told."""
    if turning is None:
        return None
    within = counts_within(period, turning.omega_low_rad_s / (1 + TURNING_ALLOWANCE),
                           turning.omega_high_rad_s * (1 + TURNING_ALLOWANCE))
    return within if within == [1] else None


def _nearest_tracks(period: Period, counts: list[int], tracks: Combined | None, tracks_used: int) -> tuple[int, str]:
    """Of the counts left open, the one whose rate lies nearest the tracks' (as a ratio), and the
    words that say so; the fewest (``counts[0]``) and nothing where no tracks gave a rate, or one
    whose interval (their seen sense's, where the near side's travel told it) is wider than a
    factor of :data:`TRACKS_HINT` from end to end (it holds a count and its double alike). Tracks
    too loose to tell the count are still the only measure of how fast the body turns, where the
    fewest repeats is the fastest reading of all: the first 50 photographs of EPFL car 02 came
    back once, after 52 s (a look-alike view half a turn on), and read 0.121 rad/s for 0.0635,
    weak, while its tracks read 0.0645 within [0.020, 0.145]; nearest them, 0.0605."""
    if tracks is None or tracks_used < MIN_TRACKS or not 0 < tracks.omega_rad_s < math.inf:
        return counts[0], ""
    low, high = (tracks.seen_interval_rad_s if tracks.seen_sense and tracks.seen_interval_rad_s is not None
                 else (tracks.omega_low_rad_s, tracks.omega_high_rad_s))
    if not 0 < low <= high <= TRACKS_HINT * low:
        return counts[0], ""  # tracks that slide on grooves and rims read several times slow, within [0, x]
    nearest = min(counts, key=lambda k: abs(math.log(period.omega_rad_s(k)[0] / tracks.omega_rad_s)))
    if nearest == counts[0]:
        return nearest, ""
    return nearest, (f"; the rate shown is k = {nearest}'s, the nearest to the tracks' ({tracks.omega_rad_s:.4g} "
                     "rad/s), though they are too loose to tell the count")


def _listed(period: Period, counts: list[int] | tuple[int, ...]) -> str:
    shown = ", ".join(f"k = {k}: {period.omega_rad_s(k)[0]:.4g}" for k in counts[:LISTED])
    return shown + (f", ... k = {counts[-1]}: {period.omega_rad_s(counts[-1])[0]:.4g}" if len(counts) > LISTED else "")


#: The picture's own angle tells a count only where its changes line up at least this well through
#: its view (:attr:`rotrate_cli.scene.picture_angle.PictureAngle.score`, the median peak
#: correlation). On bench-symmetry's renders the angles that told the right count lined up at
#: 0.69-0.94 (spokes12-face the lowest); a flat six-spoked wheel face on, its view found tilted 57
#: degrees, at 0.32, read 1.48 times too fast within +-5% and could tell four repeats a turn
#: (+50%, good).
COUNT_SCORE = 0.5


def _count_by_angle(period: Period, angle: PictureAngle | None) -> list[int] | None:
    """The one count the picture's own angle tells (its interval, within
    :data:`TURNING_ALLOWANCE`, holds one count's rate alone); None where it tells none (no
    measurement, changes that line up poorly through its view (:data:`COUNT_SCORE`), several
    counts, or a turn between frames that fits two ways whose other reading fits a count too).

    A symmetric body's first step fits its other shifts alike (a fan of three flat blades turning
    9 degrees between changes fits 129 as well: each shift one blade on): those readings are the
    angle's rate scaled as the step, a blade or two on either way (:func:`_other_steps`). Where the return fits
    none of them, they are ruled out and the angle's own count stands: that fan, its picture back
    every 0.87 s, read 7.20 rad/s for 2.40, weak, every count open, while its angle read 2.3999 and
    its other readings 29 and 34 rad/s, faster than the return's whole turn. Not where the frames
    lie far apart on the turn (:attr:`rotrate_cli.stages.period.Period.far_apart`): there the
    return's counts are a guess too (six blades 25 degrees a frame: the angle read 5 degrees a
    frame, and the return's count that fitted it, -80%)."""
    if angle is None or not angle.score >= COUNT_SCORE:
        return None
    within = counts_within(period, angle.omega_low_rad_s / (1 + TURNING_ALLOWANCE),
                           angle.omega_high_rad_s * (1 + TURNING_ALLOWANCE))
    if len(within) != 1:
        return None
    if angle.alike_deg is not None:
        if period.far_apart:
            return None  # frames far apart on the turn: the return's counts are themselves a guess
        for scale in _other_steps(angle, within[0]):
            low, high = angle.omega_low_rad_s * scale, angle.omega_high_rad_s * scale
            if not math.isfinite(scale) or counts_within(period, low / (1 + TURNING_ALLOWANCE),
                                                         high * (1 + TURNING_ALLOWANCE)):
                return None
    return within


def _other_steps(angle: PictureAngle, repeats: int = 0) -> tuple[float, ...]:
    """The rates the picture's angle would read (as multiples of its own) had its first step been
    another shift a symmetric body fits alike: ``alike_deg``, the one as far the other side of the
    step taken, and, for a body that repeats ``repeats`` times a turn, the step one and two
    repeats either way (``alike_deg`` may lie two repeats off: a five-bladed fan's 20 degrees
    between changes fitted 124 next best, and 52, one blade on, read 2.6 times as fast). Inf
    where the step is none."""
    first, alike = angle.first_step_deg, angle.alike_deg
    if alike is None or first == 0:
        return (math.inf,)  # no other step, or no step to scale
    others = [alike, 2.0 * first - alike]
    if repeats > 0:
        others += [first + j * 360.0 / repeats for j in (-2, -1, 1, 2)]
    return tuple(abs(other / first) for other in others)


def tell_repeats(period: Period, tracks: Combined | None, tracks_used: int,
                 turning: PictureTurning | Callable[[], PictureTurning | None] | None,
                 angle: PictureAngle | Callable[[], PictureAngle | None] | None = None) -> Repeats:
    """How many repeats of the picture make a turn (see :class:`Repeats`): the counts the tracks'
    rate and the picture's own turning each allow (the turning measured only where the tracks
    do not tell one count alone); one count left is decided; none, or several, is weak and
    listed. A return alone never tells: a fan of five blades comes back after a fifth of a turn.
    Where the turning test says nothing, the picture's own angle (``angle``: measured densely, or
    a call that measures it) may tell the count (the wheel shrunk to half its size, whose turning
    test was too broad)."""
    return_s = f"the picture comes back every {period.period_s:.4g} s"
    by_tracks = _by_tracks(period, tracks, tracks_used)
    by_turning = None
    against = None
    if by_tracks is None or len(by_tracks) != 1:
        by_turning = _by_turning(period, turning() if callable(turning) else turning)
        if by_turning is None:  # the picture's angle, measured densely (slower), where the test said nothing
            measured = angle() if callable(angle) else angle
            by_turning = _count_by_angle(period, measured)
            against = _angle_apart(period, measured) if by_turning is None else None
    told = [(name, set(counts)) for name, counts in (("the tracks' rate", by_tracks),
                                                     ("the picture's turning", by_turning)) if counts is not None]
    if not told:
        counts = list(range(1, MOST_REPEATS + 1))
        shown, said = _nearest_tracks(period, counts, tracks, tracks_used)
        return Repeats(shown, False, tuple(counts), weak=(
            f"{return_s}, but nothing tells whether that is a whole turn or a part of one (a body that looks "
            f"alike n times a turn, such as a fan, spokes or a pattern, comes back n times): the rate is "
            f"{_listed(period, counts)} rad/s for k repeats a turn; the 95% interval holds them all{said}",),
            untold=True, against=against)
    common = set.intersection(*(counts for _, counts in told))
    names = " and ".join(name for name, _ in told)
    if len(common) == 1:
        k = common.pop()
        notes = (f"the picture repeats {k} times a turn (a symmetric body); {names} tells which",) if k > 1 else ()
        return Repeats(k, True, (k,), names, notes)
    if common:
        counts = sorted(common)
        shown, said = _nearest_tracks(period, counts, tracks, tracks_used)
        return Repeats(shown, False, tuple(counts), weak=(
            f"{return_s}; {names} leaves open how many times a turn: {_listed(period, counts)} rad/s; the 95% "
            f"interval holds them all{said}",), against=against)
    # the evidence fits no whole number of repeats
    said = "; ".join(f"{name} allows k = {', '.join(map(str, sorted(c)))}" if c else f"{name} fits no whole number"
                     for name, c in told)
    spanned = None
    if tracks is not None and 0 < tracks.omega_rad_s < math.inf:
        spanned = (tracks.omega_low_rad_s, tracks.omega_high_rad_s)
        said = (f"the tracks' rate ({tracks.omega_rad_s:.4g} rad/s) is not a whole number of the picture's repeats "
                f"({period.omega_rad_s()[0]:.4g} rad/s a repeat)" if by_tracks == [] else said)
    counts = list(range(1, MOST_REPEATS + 1))
    return Repeats(1, False, tuple(counts), weak=(
        f"{said}: the measurements disagree; {_listed(period, counts)} rad/s for k repeats a turn, and the 95% "
        "interval holds them and the tracks' rate",), spanned_by=spanned, against=against)


@dataclass(frozen=True)
class Verdict:
    """The rate reported, where it comes from, and how far to trust it.

    Attributes:
        omega_rad_s, omega_low_rad_s, omega_high_rad_s: the rate and its 95% interval (rad/s).
        rate_from: ``tracks``, ``repetition`` or ``turning`` (the picture's own turning angle).
        repeats_per_turn: with the repetition, how many repeats make a turn (1 usually).
        quality: ``good`` or ``weak``.
        weak_because: why it is weak (empty when good).
        notes: what the user should know about how the two measurements compared.
        repeats_told_by: with the repetition, what told how many repeats make a turn (``the
            tracks' rate``, ``the picture's turning``); "" where nothing told it.
        thin_part: with the picture's turning, True where it is a thin part's against the clip's
            still picture (a clock's hand: :mod:`rotrate_cli.scene.hand`).
        plane: with the picture's turning, True where it is the tracks' as one plane turning
            (:mod:`rotrate_cli.scene.plane_turn`).
        plane_changes: with ``plane``, True where the rate is the picture's changes unrolled through
            the tracks' plane rather than the tracks' own pairs of frames.
        turns_spanned: with the repetition, how many turns the return found spans, where the
            picture's own angle told more than one (the returns between spoiled); 1 otherwise.
    """

    omega_rad_s: float
    omega_low_rad_s: float
    omega_high_rad_s: float
    rate_from: str
    repeats_per_turn: int
    quality: str
    weak_because: tuple[str, ...]
    notes: tuple[str, ...]
    repeats_told_by: str = ""
    thin_part: bool = False
    plane: bool = False
    plane_changes: bool = False
    turns_spanned: int = 1


def _half_width(omega: float, low: float, high: float) -> float:
    """The interval's larger half as a fraction of the rate (inf when unknown)."""
    if not (math.isfinite(omega) and omega > 0 and math.isfinite(low) and math.isfinite(high)):
        return math.inf
    return max(omega - low, high - omega) / omega


def judge(tracks: Combined | None, period: Period | None, tracks_used: int = 0,
          doubts: tuple[str, ...] = (),
          turning: PictureTurning | Callable[[], PictureTurning | None] | None = None,
          angle: PictureAngle | Callable[[], PictureAngle | None] | None = None) -> Verdict:
    """The reported rate from the tracks' combined rate (None: no track gave one) and the
    clip's repetition (None: none seen); ``tracks_used`` tracks stand behind ``tracks``;
    ``doubts`` about the tracks' rate (a given fixation the tracks disagree with) make a
    tracks-only result weak and are notes beside the repetition's. ``turning``: the picture's
    own turning (:mod:`rotrate_cli.scene.turning`), or a call that measures it, made only where
    the tracks do not tell how many repeats make a turn. ``angle``: the picture's own turning
    angle (:mod:`rotrate_cli.scene.picture_angle`), or a call that measures it, made only where
    the picture does not come back (under a turn): where it gives a rate, that rate is reported
    (:func:`_by_angle`).

    Raises:
        ValueError: neither measurement is given.
    """
    if period is None:
        measured = angle() if callable(angle) else angle
        if measured is not None:
            return _by_angle(measured, tracks, tracks_used, doubts)
        if tracks is None:
            raise ValueError("no measurement to judge")
        return _tracks_only(tracks, tracks_used, doubts)
    notes: list[str] = list(doubts)
    weak: list[str] = []
    told = tell_repeats(period, tracks, tracks_used, turning, angle)
    repeats, confirmed = told.repeats, told.decided
    weak.extend(told.weak)
    if not (confirmed and repeats > 1 and period.excess > SAME_PICTURE):
        notes.extend(told.notes)
    else:
        # a return after part of a turn that is not the same picture again: a look-alike view (a
        # car's other side half a turn on), whose timing is no measure of a symmetric body's turn
        confirmed = False
        weak.append(f"the picture comes back after 1/{repeats} of a turn, but not exactly: it may be a view that looks "
                    "alike rather than a symmetric body; the 95% interval holds the tracks' rate too")
        if tracks is not None and 0 < tracks.omega_rad_s < math.inf:
            told = replace(told, spanned_by=(tracks.omega_low_rad_s, tracks.omega_high_rad_s))
    omega, low, high = period.omega_rad_s(repeats)
    rate_from, spanned, thin_part, plane, plane_changes = "repetition", False, False, False, False
    if not confirmed:  # the interval holds every count of repeats a turn still open: weak for that already
        low = min(low, period.omega_rad_s(max(told.candidates))[1])
        high = max(high, period.omega_rad_s(min(told.candidates))[2])
        spanned = True
        if told.spanned_by is not None:
            low, high = min(low, told.spanned_by[0]), max(high, told.spanned_by[1])
        if told.against is not None:
            # the picture's own angle turns at a rate no count of the return gives: the return may be
            # a light's or the camera's, not the body's (the bicycle wheel under a light swelling 5%
            # once a second came back after 2.99 s, three of the light's swells, and read -7.6%, weak,
            # missing; its angle over 4.9 turns read -0.3% within +-0.2%)
            seen = told.against
            low, high = min(low, seen.omega_low_rad_s), max(high, seen.omega_high_rad_s)
            # reported where it follows a turn, or at least the time the return spans: then it has
            # watched the picture over all the return was timed on (the shared wheel, its picture
            # growing and shrinking 3% with nothing still in it, 0.9 of a turn: the picture came back
            # after 2.40 s as nearly as a look-alike does, +15%; its angle followed 0.9 of a turn at
            # 2.277 rad/s within +-0.5%, 313 degrees in those 2.40 s; the tracks' 0.20 rad/s, -91%,
            # was reported)
            over_return = seen.turned_deg >= min(WHOLE_TURN_DEG, math.degrees(seen.omega_rad_s * period.period_s))
            weak.append(f"the picture's own turning angle reads {seen.omega_rad_s:.4g} rad/s within "
                        f"[{seen.omega_low_rad_s:.4g}, {seen.omega_high_rad_s:.4g}], which no count of the picture's "
                        "returns gives: the return may be a light's or the camera's rather than the body's; the 95% "
                        "interval holds it" + (", and it is the rate reported, as it follows a turn or more"
                                               if seen.turned_deg >= WHOLE_TURN_DEG else
                                               ", and it is the rate reported, as it follows the picture over all "
                                               "the time the return spans" if over_return else ""))
            if over_return:
                omega, rate_from = seen.omega_rad_s, "turning"
                thin_part, plane, plane_changes = seen.thin_part, seen.plane, seen.plane_changes
                # the count whose rate was to be shown is not: its words go (one number, one source)
                shown = _nearest_tracks(period, list(told.candidates), tracks, tracks_used)[1]
                if shown:
                    weak = [why.replace(shown, "") for why in weak]
    sooner = not period.far_apart and math.isfinite(period.sooner_s)
    by_turning_alone = confirmed and told.told_by == "the picture's turning"
    spans = _turns_by_angle(period, repeats, angle) if sooner and by_turning_alone else None
    if spans is not None:
        # the picture came back sooner too, less alike, and its own angle, measured over the clip,
        # tells how many turns the return taken spans (the turning test tries a turn a return at
        # most: it cannot tell several)
        period = period.over(spans * period.turns_between)
        omega, low, high = period.omega_rad_s(repeats)
        notes.append(f"the picture came back sooner too ({period.sooner_s:.4g} s), though less alike, and its own "
                     f"turning angle tells that the return taken spans {spans} turns: a turn every "
                     f"{period.period_s * repeats:.4g} s")
    elif sooner and (told.untold or by_turning_alone):
        # the picture came back sooner too, but less alike: the return taken may span several turns,
        # those between spoiled (the record close-up, its camera wobbling 1.5 degrees at about 1 Hz:
        # its picture came back best after 8.85 s, five turns, less alike after two and three, and
        # read 0.71 rad/s within [0.044, 0.71] for 3.55; the bicycle wheel under a light swelling
        # and fading 8% every 3.3 s: back best after 11.1 s, four turns, once the slow change was
        # taken out, and the turning test, which tries a turn a return at most, told one: -75%,
        # good): the interval holds every count of turns, up to half a repeat a frame, as nothing
        # measured tells it
        high = max(high, period.over(_most_spanned(period)).omega_rad_s(repeats)[2])
        spanned = True
        weak.append(f"the picture came back sooner too ({period.sooner_s:.4g} s), though less alike: the return "
                    f"taken may span several turns (a camera that wobbles, or a light that changes, spoils those "
                    f"between); the 95% interval holds every count of turns up to half a repeat a frame")
    if period.far_apart and not confirmed and not _tracks_count_turns(period, omega, tracks, tracks_used):
        # how many repeats the closest return spans is a guess: the interval holds every count,
        # from one to under half a repeat a frame (rendered boxes at 10 and 25 rad/s, 30 frames/s,
        # no track: the guesses read +100% and +255%)
        weak.append(_far_apart(period))
        low = min(low, period.over(1).omega_rad_s(repeats)[1])
        high = max(high, period.over(_most_spanned(period)).omega_rad_s(repeats)[2])
        spanned = True
    if not confirmed:
        doubt = _look_alike(period, tracks, tracks_used)
        if doubt is not None:
            weak.append(doubt)
            if tracks is not None and tracks_used >= MIN_TRACKS and 0 < tracks.omega_rad_s < math.inf:
                # a turn or a look-alike view: the interval holds both readings, and an inexact
                # return stands for a look-alike (the tracks' rate is reported; not where the
                # picture's own angle, which no count of the return gives, is reported already)
                repeated = period.omega_rad_s(repeats)[0]
                low, high = min(low, tracks.omega_low_rad_s), max(high, tracks.omega_high_rad_s)
                spanned = True
                # the tracks' rate where the return is not exact, or where they rule out a turn in
                # that time: their interval's top well under the return's rate (EPFL car 02's 45th to
                # 94th photographs: its picture back after 50 s as exactly as a turn, +99%; its
                # tracks 47% of a turn in that time, -5.6%, and the look-alike view half a turn on)
                under = _tracks_under(period, tracks, tracks_used)
                if rate_from == "repetition" and (period.excess > LOOK_ALIKE_EXCESS or under):
                    omega, rate_from = tracks.omega_rad_s, "tracks"
                    shown = _nearest_tracks(period, list(told.candidates), tracks, tracks_used)[1]
                    if shown:  # the count's rate is not the one shown: the tracks' is
                        weak = [why.replace(shown, "") for why in weak]
                reported = ("the picture's own turning is reported (above)" if rate_from == "turning"
                            else "the repetition's rate is reported, as the return is exact" if rate_from != "tracks"
                            else "the tracks' rate is reported, as the return is not exact"
                            if period.excess > LOOK_ALIKE_EXCESS
                            else "the tracks' rate is reported, as they turn well under a turn in that time")
                part = "a turn" if repeats == 1 else f"1/{repeats} of a turn"  # (the count shown: the tracks' nearest)
                notes.append(f"the 95% interval spans both readings: the repetition's {repeated:.4g} rad/s if the "
                             f"picture's return is {part}, the tracks' {tracks.omega_rad_s:.4g} rad/s if it is a "
                             f"look-alike view; {reported}")
    if confirmed and not spanned and rate_from == "repetition":
        closer = _closer_by_angle(period, omega, low, high, angle)
        if closer is not None:
            notes.append(f"the picture comes back only once in the clip ({omega:.4g} rad/s within [{low:.4g}, "
                         f"{high:.4g}] for a turn); its own turning, measured more closely over the clip, agrees "
                         "and gives the rate")
            omega, low, high, rate_from = closer.omega_rad_s, closer.omega_low_rad_s, closer.omega_high_rad_s, "turning"
            thin_part, plane, plane_changes = closer.thin_part, closer.plane, closer.plane_changes
        else:
            against = _inexact_against_angle(period, low, high, angle)
            if against is not None:
                weak.append(f"the picture comes back only once in the clip and not exactly ({omega:.4g} rad/s within "
                            f"[{low:.4g}, {high:.4g}] for a turn), and its own turning over the clip reads "
                            f"{against.omega_rad_s:.4g} rad/s within [{against.omega_low_rad_s:.4g}, "
                            f"{against.omega_high_rad_s:.4g}]: they disagree; the 95% interval holds both")
                low, high = min(low, against.omega_low_rad_s), max(high, against.omega_high_rad_s)
                spanned = True
    if period.drift_s > CHANGE_FRACTION * period.period_s:
        notes.append(f"the rate changes over the clip (its halves repeat {period.drift_s / period.period_s:.1%} "
                     "apart); the result is an average: see omega(t) with `window_s`")
    if _half_width(omega, low, high) > WEAK_HALF_WIDTH and not spanned:  # spanned: weak for its doubt already
        weak.append(f"the 95% interval is wider than +-{WEAK_HALF_WIDTH:.0%}")
    return Verdict(omega, low, high, rate_from, repeats, "weak" if weak else "good", tuple(weak), tuple(notes),
                   told.told_by if confirmed else "", thin_part, plane, plane_changes,
                   spans if spans is not None and rate_from == "repetition" else 1)


#: A return seen once whose interval is narrower than this (half, of its rate) is not set against
#: the picture's angle, which takes seconds to measure: the angle read real clips of about a turn
#: to +-0.6-1.3% at best (the wheel, the record), and the EPFL cars' single turns, whose returns
#: hold +-0.6-1%, took 2-4 times as long for it with their results unchanged.
LOOSE_RETURN = 0.02


def _closer_by_angle(period: Period, omega: float, low: float, high: float,
                     angle: PictureAngle | Callable[[], PictureAngle | None] | None) -> PictureAngle | None:
    """The picture's own turning angle where it rates a clip that comes back only once more
    closely than the return does, and agrees with it (their intervals overlap); None otherwise.
    A return seen once is timed by the few pairs of frames a turn apart that the clip holds (the
    record's first turn: one pair, its return -3.1% within [-6.4%, +0.5%]); the angle follows
    the turn in every change of the clip, and matches its end against its start too. The two
    share those end pairs, so the closer one is reported rather than a mean of the two."""
    if period.frames >= 2 * period.lag_frames or angle is None:
        return None  # the clip holds a second return (or could): the return is the closer measure
    if _half_width(omega, low, high) <= LOOSE_RETURN and callable(angle) and period.excess <= LOOK_ALIKE_EXCESS:
        return None  # close enough: the angle (seconds to measure) would seldom be closer
    measured = _firm(angle)
    if measured is None:
        return None  # a loose reading does not stand in for a return
    closer = (_half_width(measured.omega_rad_s, measured.omega_low_rad_s, measured.omega_high_rad_s)
              < _half_width(omega, low, high))
    agrees = measured.omega_low_rad_s <= high and low <= measured.omega_high_rad_s
    return measured if closer and agrees else None


def _turns_by_angle(period: Period, repeats: int,
                    angle: PictureAngle | Callable[[], PictureAngle | None] | None) -> int | None:
    """How many turns the return taken spans (2 or more), where the picture's own angle, a firm
    reading lined up at :data:`COUNT_SCORE` or better, holds that count's rate alone (within
    :data:`TURNING_ALLOWANCE`); None otherwise. Asked only where the picture came back sooner too,
    less alike (measured there alone). The bicycle wheel under a light swelling and fading 8%
    every 3.3 s came back best after 11.1 s; its angle read 2.2666 rad/s within +-0.2% over its
    4.9 turns: four turns, 2.2675."""
    measured = _lined_up(angle)
    if measured is None:
        return None
    low, high = measured.omega_low_rad_s / (1 + TURNING_ALLOWANCE), measured.omega_high_rad_s * (1 + TURNING_ALLOWANCE)
    fits = [turns for turns in range(1, _most_spanned(period) + 1)
            if low <= period.over(turns * period.turns_between).omega_rad_s(repeats)[0] <= high]
    return fits[0] if len(fits) == 1 and fits[0] > 1 else None


#: The picture's angle followed over at least this much (degrees) is reported over a return no
#: count of which gives its rate (:func:`_angle_apart`).
WHOLE_TURN_DEG = 360.0


def _angle_apart(period: Period, angle: PictureAngle | None) -> PictureAngle | None:
    """The picture's own angle where it is a firm reading, lined up at :data:`COUNT_SCORE` or
    better, whose interval (within :data:`TURNING_ALLOWANCE`) holds no count's rate of the
    return at all; None otherwise."""
    measured = _lined_up(angle)
    if measured is None:
        return None
    low, high = measured.omega_low_rad_s / (1 + TURNING_ALLOWANCE), measured.omega_high_rad_s * (1 + TURNING_ALLOWANCE)
    return None if counts_within(period, low, high) else measured


def _lined_up(angle: PictureAngle | Callable[[], PictureAngle | None] | None) -> PictureAngle | None:
    """The picture's own angle where it is a firm reading (:func:`_firm`) whose changes line up
    at :data:`COUNT_SCORE` or better: one that may tell how a return stands to the turn."""
    measured = _firm(angle)
    return measured if measured is not None and measured.score >= COUNT_SCORE else None


def _firm(angle: PictureAngle | Callable[[], PictureAngle | None] | None) -> PictureAngle | None:
    """The picture's own angle (measured now, where ``angle`` is a call) where it is a firm reading:
    not a turn between frames that fits two ways, nor one loosely borne out."""
    measured = angle() if callable(angle) else angle
    return None if measured is None or measured.alike_deg is not None or measured.doubt else measured


def _inexact_against_angle(period: Period, low: float, high: float,
                          angle: PictureAngle | Callable[[], PictureAngle | None] | None) -> PictureAngle | None:
    """The picture's own turning angle where it disagrees (their intervals apart) with a return
    seen once that is not exact (its pairs differ beyond their timing by more than
    :data:`LOOK_ALIKE_EXCESS`); None otherwise. An inexact return is timed where the picture is
    most nearly alike, which what does not come back pulls: two discs side by side turning 1.0 and
    1.6 rad/s, 8 s, came back once after the faster one's turn, its pairs 0.40 apart beyond their
    timing, and read 1.591 within [1.583, 1.599], good, for 1.6; the picture's turning read 1.5999.
    (Measured only there: :func:`_closer_by_angle` asks it first.)"""
    if period.excess <= LOOK_ALIKE_EXCESS or period.frames >= 2 * period.lag_frames:
        return None
    measured = _firm(angle)
    if measured is None:
        return None
    apart = measured.omega_high_rad_s < low or high < measured.omega_low_rad_s
    return measured if apart else None


def turns_between(period: Period, tracks: Combined | None, tracks_used: int = 0) -> Period:
    """The repetition with the number of repeats its closest return spans taken, where its frames
    lie far apart on the turn (:attr:`rotrate_cli.stages.period.Period.far_apart`): as the tracks' rate
    says where they gave one (points followed from frame to frame turned by small steps), else
    as the lag profile alone says. A finely textured sphere turning 6 degrees a frame changes as
    wholly from one frame to the next as a box turning 29: the profile took two turns for its
    one (+100%), its tracks one."""
    if not period.far_apart:
        return period
    if tracks is not None and tracks_used >= MIN_TRACKS and 0 < tracks.omega_rad_s < math.inf:
        spans = tracks.omega_rad_s / period.over(1).omega_rad_s()[0]
        return period.over(min(max(1, round(spans)), _most_spanned(period)))
    return period.over(period.turns_guess)


def _most_spanned(period: Period) -> int:
    """The most repeats the closest return first seen can span: under half a repeat a frame
    (more, and the frames could not follow the turn)."""
    return max(1, int(period.lag_frames * period.turns_between / 2))


def _tracks_count_turns(period: Period, omega_rad_s: float, tracks: Combined | None, tracks_used: int) -> bool:
    """True where the tracks' interval, if not narrow enough to confirm the rate (or off it), still
    tells how many repeats a return far apart spans: it lies within half a repeat of the rate (a
    rendered sphere through a 50-degree lens: its tracks' 3.67 rad/s, +22%, tell one turn from two
    of the repetition's 3.00)."""
    if tracks is None or tracks_used < MIN_TRACKS or not 0 < tracks.omega_rad_s < math.inf:
        return False
    turns = period.turns_between
    return omega_rad_s * (turns - 0.5) / turns < tracks.omega_low_rad_s <= tracks.omega_high_rad_s < (
        omega_rad_s * (turns + 0.5) / turns)


def _far_apart(period: Period) -> str:
    """Why a repetition of frames far apart on the turn, unconfirmed by tracks, is weak."""
    spans = (f"; its closest return, after {period.turns_between} repeats, says how far" if period.turns_between > 1
             else "")
    return (f"the picture changes almost wholly from one frame to the next (the repeat turns about "
            f"{period.step_deg:.0f} degrees a frame{spans}): how many repeats its closest return spans is a guess, "
            "and no track tells it; the 95% interval holds every count up to half a repeat a frame, and a turn "
            "faster by whole turns a frame looks the same (a wagon wheel's); a higher frame rate settles it")


def _look_alike(period: Period, tracks: Combined | None, tracks_used: int) -> str | None:
    """Why a repetition seen only once may be a look-alike view rather than a turn: its closest
    pairs differ beyond what their timing explains by more than :data:`LOOK_ALIKE_EXCESS`, or
    the tracks say the clip turned well under a turn in that time (the period is more than
    :data:`UNDER_TURN` times shorter than even the top of their interval makes a turn); None
    where neither holds."""
    if not period.frames < 2 * period.lag_frames:  # the clip holds a second return (or could)
        return None
    said = f"the picture comes back only once in the clip (after {period.period_s:.4g} s)"
    if period.excess > LOOK_ALIKE_EXCESS:
        return (f"{said}, and not exactly: it may be a view that looks alike part of a turn on (a car half a "
                "turn on) rather than a turn; a clip of two turns or more settles it")
    if tracks is not None and _tracks_under(period, tracks, tracks_used):
        turned = tracks.omega_rad_s * period.period_s / (2.0 * math.pi)
        return (f"{said}, but the tracks turn only {turned:.0%} of a turn in that time ({tracks.omega_rad_s:.4g} "
                "rad/s): it may be a view that looks alike part of a turn on (a car half a turn on); a clip of "
                "two turns or more settles it")
    return None


def _tracks_under(period: Period, tracks: Combined | None, tracks_used: int) -> bool:
    """True where informative tracks turn well under a turn in the time the picture takes to come
    back: the top of their interval :data:`UNDER_TURN` times under the return's rate."""
    return (tracks is not None and tracks_used >= MIN_TRACKS and math.isfinite(top := _tracks_top(tracks))
            and 0 < top * UNDER_TURN < period.omega_rad_s()[0])


def _tracks_top(tracks: Combined) -> float:
    """The top of the tracks' interval; where their fits through a lens did not tell the sense
    and the near side's travel did (:attr:`rotrate_cli.fitting.outliers.Combined.seen_sense`), of that
    sense's own interval: the other sense's rate, which the interval also holds, is the
    alternative to the travel's physics, not a measurement of how far the body turned. The
    first 50 photographs of EPFL car 02, clockwise: its tracks 0.053 rad/s within [0.041, 0.143]
    with the anticlockwise 0.092, and its picture back after 52 s (0.121 rad/s, a look-alike
    half a turn on), exactly enough to pass for a turn."""
    if tracks.seen_sense and tracks.seen_interval_rad_s is not None:
        return tracks.seen_interval_rad_s[1]
    return tracks.omega_high_rad_s


def _tracks_only(tracks: Combined, tracks_used: int, doubts: tuple[str, ...]) -> Verdict:
    weak = list(doubts)
    if _half_width(tracks.omega_rad_s, tracks.omega_low_rad_s, tracks.omega_high_rad_s) > WEAK_HALF_WIDTH:
        weak.append(f"the 95% interval is wider than +-{WEAK_HALF_WIDTH:.0%}")
    if tracks_used < MIN_TRACKS:
        weak.append(f"only {tracks_used} track(s) agree")
    return Verdict(tracks.omega_rad_s, tracks.omega_low_rad_s, tracks.omega_high_rad_s, "tracks", 1,
                   "weak" if weak else "good", tuple(weak), ())


def _by_angle(angle: PictureAngle, tracks: Combined | None, tracks_used: int, doubts: tuple[str, ...]) -> Verdict:
    """The rate of the picture's own turning angle, where the picture does not come back. The
    tracks confirm it or not: informative tracks (enough of them, within :data:`TRACKS_TELL`)
    that miss it by more than :data:`TRACKS_ALLOWANCE` beyond their interval make it weak, their
    rate is reported, and the interval spans both; loose tracks (sliding along grooves and rims) are only noted. A first
    step that another shift fits as well (a symmetric body turning fast) leaves the turn open:
    weak, with the other reading."""
    omega, low, high = angle.omega_rad_s, angle.omega_low_rad_s, angle.omega_high_rad_s
    weak: list[str] = []
    notes = [f"the rate is the picture's own turning: {angle.turned_deg:.0f} degrees seen turned, measured through "
             f"the plane's view{' its circles tell' if angle.view_from_circles else ''} (tilted "
             f"{angle.view.tilt_deg:.0f} degrees)" if not (angle.thin_part or angle.plane) else
             f"the rate is the picture's own turning: a thin part (a hand, a needle) against the clip's still picture, "
             f"{angle.turned_deg:.0f} degrees seen turned (its plane tilted {angle.view.tilt_deg:.0f} degrees, as its "
             "length shows)" if angle.thin_part else
             f"the rate is the picture's own turning: {angle.turned_deg:.0f} degrees seen turned, its changes unrolled "
             "through the plane the tracks turn as one about its axis (through any view)" if angle.plane_changes else
             f"the rate is the picture's own turning: {angle.turned_deg:.0f} degrees seen turned, the tracks "
             f"{'(each matched again against its first patch) ' if angle.plane_placed else ''}fitted as one plane "
             "turning about its axis (through any view)"]
    if angle.camera_turn_deg_s:
        way = "anticlockwise" if angle.camera_turn_deg_s > 0 else "clockwise"
        notes.append(f"the camera turned {abs(angle.camera_turn_deg_s):.2g} degrees a second ({way} as the picture "
                     "shows it), as the picture around the plane shows it: taken out of the plane's tracks")
    # the ``doubts`` are of the tracks' rate: told only where it is the one reported
    if angle.alike_deg is not None and angle.first_step_deg != 0:
        other = omega * _other_steps(angle)[0]
        weak.append(f"the picture's turning between frames fits {abs(angle.first_step_deg):.1f} and "
                    f"{abs(angle.alike_deg):.1f} degrees alike (a body that looks alike several times a turn, "
                    f"turning fast): {omega:.4g} or {other:.4g} rad/s; the 95% interval holds both")
        low, high = min(low, other), max(high, other)
    if tracks is not None and 0 < tracks.omega_rad_s < math.inf:
        told = tracks_used >= MIN_TRACKS and _half_width(
            tracks.omega_rad_s, tracks.omega_low_rad_s, tracks.omega_high_rad_s) <= TRACKS_TELL
        agrees = (tracks.omega_low_rad_s / (1 + TRACKS_ALLOWANCE) <= omega
                  <= tracks.omega_high_rad_s * (1 + TRACKS_ALLOWANCE))
        closer = (tracks_used >= MIN_TRACKS and not weak
                  and _half_width(tracks.omega_rad_s, tracks.omega_low_rad_s, tracks.omega_high_rad_s)
                  < min(_half_width(omega, low, high), WEAK_HALF_WIDTH))
        if closer:
            # the tracks measure it more closely than the picture's turning, itself loose: theirs is
            # reported, and where the turning's interval does not hold it, the interval holds both
            # (a disc tilted 60 degrees, its axis above the frame: its tracks -0.05% within +-2.3%,
            # its turning through a view that lined its changes up poorly +19.5% +-20%; face on,
            # its axis beside the frame, -0.3% +-2.4% and +15% within [+8%, +22%])
            verdict = _tracks_only(tracks, tracks_used, doubts)
            if low <= tracks.omega_rad_s <= high:
                note = (f"the picture's own turning reads {omega:.4g} rad/s within [{low:.4g}, {high:.4g}], "
                        "which holds the tracks' rate")
                return replace(verdict, notes=(*verdict.notes, note))
            if angle.doubt:
                # a loose reading (a plane the picture bears out only loosely) does not overrule
                # closer tracks (a sphere seen from 60 degrees above: its tracks -0.8% within
                # +-2%; a plane fitted to its cap's points -20%, not borne out)
                note = (f"the picture's own turning reads {omega:.4g} rad/s within [{low:.4g}, {high:.4g}], "
                        f"loosely: {angle.doubt}; the tracks' closer rate is reported")
                return replace(verdict, notes=(*verdict.notes, note))
            weak.append(f"the picture's turning ({omega:.4g} rad/s) disagrees with the tracks' rate "
                        f"({tracks.omega_rad_s:.4g} rad/s), which is reported; the 95% interval holds both")
            return Verdict(tracks.omega_rad_s, min(low, tracks.omega_low_rad_s), max(high, tracks.omega_high_rad_s),
                           "tracks", 1, "weak", (*verdict.weak_because, *weak), (*verdict.notes, *notes[1:]))
        if told and not agrees and angle.plane:
            # the same tracks, fitted as one plane turning through any view: their one-point fits
            # (the paper's model: a fixation on the axis, a view from nearly the side) are the
            # looser model of them (a printed disc tilted 45 degrees, its axis below the frame:
            # +39% against +0.3%)
            notes.append(f"the tracks' one-point fits read {tracks.omega_rad_s:.4g} rad/s; fitted as one plane "
                         "turning, they read the rate reported")
        elif told and not agrees:
            # the tracks' rate is reported (their model is the paper's, and they agree among
            # themselves); the interval holds both
            weak.append(f"the picture's turning ({omega:.4g} rad/s) disagrees with the tracks' rate "
                        f"({tracks.omega_rad_s:.4g} rad/s), which is reported; the 95% interval holds both")
            low, high = min(low, tracks.omega_low_rad_s), max(high, tracks.omega_high_rad_s)
            return Verdict(tracks.omega_rad_s, low, high, "tracks", 1, "weak", tuple(weak), (*doubts, *notes[1:]))
        elif not agrees:
            notes.append(f"the tracks read {tracks.omega_rad_s:.4g} rad/s, loosely (points that slide along "
                         "grooves or rims, or stay on reflections): they do not stand behind the rate")
    if angle.doubt:
        weak.append(f"{angle.doubt}; the 95% interval holds both")
    if _half_width(omega, low, high) > WEAK_HALF_WIDTH and not weak:
        weak.append(f"the 95% interval is wider than +-{WEAK_HALF_WIDTH:.0%}")
    return Verdict(omega, low, high, "turning", 1, "weak" if weak else "good", tuple(weak), tuple(notes),
                   thin_part=angle.thin_part, plane=angle.plane, plane_changes=angle.plane_changes)
