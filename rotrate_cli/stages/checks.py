"""The checks stage, all in one place: the tracks' rate checked before it is judged
(:func:`check_rate`): by the found lens's
uncertainty, the clock's resolution, a given fixation the tracks disagree with, a rate that
changes over the clip or differs either side of the axis, and, seen obliquely or face on, the
rate of the tracks' paths in both image coordinates. Each either widens the interval or names a
doubt that makes a tracks-only result weak."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from rotrate_cli.config import AnalysisConfig
from rotrate_cli.fitting import estimators
from rotrate_cli.fitting.camera import Camera, focal_px_from_fov
from rotrate_cli.fitting.outliers import Combined, RejectionConfig, combine
from rotrate_cli.runtime.lazy import pandas as pd
from rotrate_cli.scene import axis as axes
from rotrate_cli.scene.focal import ORTHOGRAPHIC_WIDTHS
from rotrate_cli.scene.view import rate_from_paths, view_from_paths
from rotrate_cli.stages.camera import WIDEST_FOV_DEG, Lens, camera_at
from rotrate_cli.stages.fits import (
    JOINT_MIN_TRACKS,
    RateResult,
    changes,
    followed_up,
    half_rates,
    rates_from_offsets,
    rejoined,
)
from rotrate_cli.stages.geometry import AxisSpread, Geometry, inliers_and_rate
from rotrate_cli.stages.verdict import MIN_TRACKS, WEAK_HALF_WIDTH


@dataclass(frozen=True)
class Checked:
    """The tracks' result after the checks.

    Attributes:
        result: the result, its interval widened where a check asked.
        doubts: doubts about the tracks' rate (they make a tracks-only result weak).
        notes: what the user should know (an interval widened).
    """

    result: RateResult
    doubts: tuple[str, ...] = ()
    notes: tuple[str, ...] = ()


def check_rate(result: RateResult, geometry: Geometry, config: AnalysisConfig, size_px: tuple[int, int],
               view_tracks: pd.DataFrame, repeating: bool, clock_resolution_s: float = 0.0,
               fps: float = math.nan) -> Checked:
    """The checks of the module's notes. ``repeating``: the clip's repetition gives the rate,
    which needs no axis and no lens and is its own check of a steady rate: only the lens's
    uncertainty is then carried (it shows in the tracks' own interval). ``clock_resolution_s``:
    how finely the frames' times are known (whole seconds in photographs' EXIF); ``fps``: the
    frame rate (a lone track's interval reaches half a turn a frame)."""
    sense_note = undecided_sense(result.combined)
    # first the found axis, whose coupling with the rate multiplies the tracks' own uncertainty
    # (not the lens's range, the far ends of a generous interval, nor the clock's, which scales
    # the rate and leaves the paths, and so the axis, as they are); None where the rate repeats
    result, axis_note = with_axis_doubt(result, geometry.axis_spread)
    result = with_lens_doubt(result, geometry.lens, geometry.fixation_px, geometry.axis_angle_deg, config.method,
                             config.rejection, size_px)
    result = with_clock_doubt(result, clock_resolution_s)
    if repeating or result.combined.tracks_used == 0:
        return Checked(result)
    result = with_height_doubt(result, geometry.lens, geometry.fixation_px, geometry.axis_angle_deg, config.method,
                               config.rejection, size_px)
    lens_notes: tuple[str, ...] = (sense_note,) if sense_note else ()
    if geometry.lens.unsettled and geometry.lens.focal_px is None:
        lens_notes += (f"the tracks could not tell the camera's lens (too few turned far enough, or the rate changes): "
                      f"the paper's orthographic model is used, and the 95% interval holds the rates through any "
                      f"lens up to {WIDEST_FOV_DEG:g} degrees across; give `fov_deg` if you know it",)
    doubts: tuple[str, ...] = ()
    if not config.points_px:
        result, lone = with_lone_track(result, fps)
        doubts += (lone,) if lone else ()
        result = with_few_tracks(result)
    result, unplaced = with_unplaced_axis(result, geometry.fixation_found, fps)
    doubts += (unplaced,) if unplaced else ()
    lens_notes += (axis_note,) if axis_note else ()
    camera = geometry.camera(size_px)
    doubt = fixation_doubt(result, geometry, config.method, config.rejection, bool(config.points_px), size_px)
    if doubt is not None:
        # which is off, the given point or the tracks' axis, is not known: the interval holds both
        # rates (a sample box given a point 1,680 px to the side: 0.134 within [0.088, 0.179],
        # its truth 0.6; about the axis found 7 px off its own, 0.58, and now [0.088, 0.587])
        message, about_found = doubt
        doubts += (message,)
        result = _spanning(result, about_found)
    told = told_sense_doubt(result, camera, geometry.lens.told_sense)
    if told is not None:
        doubts += (told,)
    change = rate_change(result, config.method, config.rejection, camera, geometry.halves)
    if change is not None:
        doubts += (change,)
    sides = sides_disagree(result)
    if sides is not None:
        doubts += (sides,)
        result = with_sides_span(result)
    split = rates_split(result)
    if split is not None:
        doubts += (split_doubt(*split),)
        result = _spanning(result, *split)
    result, note = with_paths_rate(result, view_tracks) if camera is None else (result, None)
    return Checked(result, doubts, lens_notes + ((note,) if note else ()))


#: The two senses' rates must differ by more than this fraction of the rate for the user to be
#: told that the tracks could not choose between them.
SENSES_APART_FRACTION = 0.02


def undecided_sense(combined: Combined) -> str | None:
    """A line saying that the tracks did not tell the sense of rotation and that, through the
    lens, the two senses fit rates more than :data:`SENSES_APART_FRACTION` apart; None otherwise."""
    if combined.senses_rad_s is None:
        return None
    anticlockwise, clockwise = combined.senses_rad_s
    if abs(anticlockwise - clockwise) <= SENSES_APART_FRACTION * abs(combined.omega_rad_s):
        return None
    if combined.seen_sense:
        seen, rate = ("ccw", anticlockwise) if combined.seen_sense > 0 else ("cw", clockwise)
        unseen, other = ("cw", clockwise) if combined.seen_sense > 0 else ("ccw", anticlockwise)
        return (f"the tracks' fits do not tell which way the body turns, and through this lens the two ways fit "
                f"different rates: the rate is the {seen} one ({rate:.4g} rad/s), the way the near side travels "
                f"in the picture (its points cross in front of the axis), and the 95% interval also holds the "
                f"{unseen} one ({other:.4g} rad/s); give `direction` (ccw or cw) (seen from the axis's top end) if you "
                "know which way it turns")
    return (f"the tracks do not tell which way the body turns, and through this lens the two ways fit different "
            f"rates ({min(anticlockwise, clockwise):.4g} and {max(anticlockwise, clockwise):.4g} rad/s): the rate "
            "is midway and the 95% interval holds both; give `direction` (ccw or cw) (seen from the axis's top end) if "
            "you know which way it turns")


def told_sense_doubt(result: RateResult, camera: Camera | None, told_sense: int) -> str | None:
    """A line saying that the inlier tracks, fitted in both senses, clearly tell the sense
    opposite to the one the user gave (``--direction``), whose rate is then wrong; None
    otherwise (no lens, no sense given, or the tracks do not tell)."""
    if camera is None or not told_sense:
        return None
    inliers = result.features.loc[result.features["inlier"], "track"]
    samples = result.offsets[result.offsets["track"].isin(inliers)]
    if samples.empty:
        return None
    fits = estimators.fit_tracks(samples, camera=replace(camera, sense=0))
    senses = {fit.sense for fit in fits.values() if math.isfinite(fit.sense)}
    if senses != {float(-told_sense)}:
        return None
    given, found = ("ccw", "cw") if told_sense > 0 else ("cw", "ccw")
    return (f"the tracks say the object turns {found}, not {given} as `direction` says, and through a lens "
            "the two ways fit different rates: check `direction`")


#: Each side of the axis needs this many inlier tracks for the sides to be compared.
SIDE_MIN_TRACKS = 3


def sides_disagree(result: RateResult) -> str | None:
    """A line saying the inlier tracks on either side of the axis turn at different rates (each
    side's random-effects mean outside the other's interval, and more than
    :data:`rotrate_cli.stages.fits.CHANGE_FRACTION` apart); None otherwise. A rigid body's points turn
    at one rate on both sides; a misplaced axis, a wrong lens or elevation, or a part that is
    not the body (a turntable's floor seen from above, a reflection) shows as a difference. On
    an EPFL car timed by its EXIF clock (seq10, its first 70 photographs) the right side's
    tracks read +5.6% within +-0.3%, the left side's 10-40% lower: the joint fit followed the
    right side's many long tracks, +5.6% [+1.9%, +9.3%], and called it good."""
    sides = _sides_apart(result)
    if sides is None:
        return None
    left, right = sides
    return (f"the tracks either side of the axis disagree ({left.omega_rad_s:.4g} and {right.omega_rad_s:.4g} "
            "rad/s): a misplaced axis, a wrong lens, or tracks off the body; check `fixation_px`, `fov_deg`")


def with_sides_span(result: RateResult) -> RateResult:
    """The result with its interval widened to hold both sides' intervals where the sides
    disagree (:func:`sides_disagree`): which side is off is not known, nor whether the truth
    lies between them. The EPFL car of that line (seq10, its first 70 photographs, truth +0%):
    +5.6% within [+1.9%, +9.3%] before; both sides' rates bracket the truth."""
    sides = _sides_apart(result)
    return result if sides is None else _spanning(result, *sides)


def _spanning(result: RateResult, *others: Combined) -> RateResult:
    """The result with its interval widened to hold ``others``' intervals too (bounds that are
    NaN, of a rate that could not be measured, are passed over); its rate as it was."""
    combined = result.combined
    low = float(np.nanmin([combined.omega_low_rad_s, *(other.omega_low_rad_s for other in others)]))
    high = float(np.nanmax([combined.omega_high_rad_s, *(other.omega_high_rad_s for other in others)]))
    return replace(result, combined=replace(combined, omega_low_rad_s=low, omega_high_rad_s=high))


def _sides_apart(result: RateResult) -> tuple[Combined, Combined] | None:
    """The inlier tracks' rates left and right of the axis (random-effects means) where they
    differ beyond each other's intervals (see :func:`sides_disagree`); None otherwise."""
    features = result.features
    inlier = features["inlier"].to_numpy(dtype=bool)
    if inlier.sum() < 2 * SIDE_MIN_TRACKS:
        return None
    mean_offset = result.offsets.groupby("track")["offset_px"].mean()
    chosen = features[inlier]
    side = np.sign(mean_offset.reindex(chosen["track"]).to_numpy())
    parts = []
    for sign in (-1.0, 1.0):
        part = chosen[side == sign]
        if len(part) < SIDE_MIN_TRACKS:
            return None
        parts.append(combine(part["omega_rad_s"].to_numpy(dtype=float), part["omega_se_rad_s"].to_numpy(dtype=float)))
    left, right = parts
    return (left, right) if changes(result.combined, left, right) else None


def with_lone_track(result: RateResult, fps: float) -> tuple[RateResult, str | None]:
    """Where one automatic track alone gave the rate, the result with its interval running from 0
    to half a turn a frame (the fastest turn frames at ``fps`` show), and the doubt saying why:
    its own standard error says how well it follows its path, not whether that path is the
    body's. The bicycle wheel's first 2.5 s kept one track of 24, on the hands that hold the
    axle: -78%, within an interval of +-4% of its own."""
    combined = result.combined
    if combined.tracks_used != 1 or not math.isfinite(combined.omega_rad_s):
        return result, None
    top = math.pi * fps if math.isfinite(fps) and fps > 0 else math.inf
    high = max(top, combined.omega_high_rad_s)
    widened = replace(result, combined=Combined(combined.omega_rad_s, 0.0, high, 1))
    return widened, (f"one track alone gave the rate, and nothing says it lies on the turning body: the 95% interval "
                     f"runs from 0 to {'half a turn a frame' if math.isfinite(high) else 'any rate'}")


#: A found axis's placement is measured from this many inlier tracks or more (its jackknife over
#: tracks: :func:`rotrate_cli.scene.axis.axis_offset_se`).
AXIS_PLACING_TRACKS = 3


def with_unplaced_axis(result: RateResult, fixation_found: bool, fps: float) -> tuple[RateResult, str | None]:
    """Where the axis was found from the tracks and fewer than :data:`AXIS_PLACING_TRACKS` of
    them gave the rate (two: one alone is :func:`with_lone_track`'s), the result with its interval
    running from 0 to half a turn a frame, and the doubt saying why: nothing measures how well
    those tracks placed the axis, and about a misplaced axis a body's own tracks read any rate.
    An EPFL car's 48th to 75th photographs kept two tracks on its front wheel, and about the axis
    they placed on its rear wheel they read 0.014 rad/s within [0, 0.030], the truth 0.063."""
    combined = result.combined
    if not (fixation_found and 1 < combined.tracks_used < AXIS_PLACING_TRACKS
            and math.isfinite(combined.omega_rad_s)):
        return result, None
    top = math.pi * fps if math.isfinite(fps) and fps > 0 else math.inf
    if combined.omega_rad_s < 0:
        low, high = min(-top, combined.omega_low_rad_s), 0.0
    else:
        low, high = 0.0, max(top, combined.omega_high_rad_s)
    widened = replace(result, combined=replace(combined, omega_low_rad_s=low, omega_high_rad_s=high))
    return widened, (f"the axis was found from {combined.tracks_used} tracks, too few to say how well they place it, "
                     "and about a misplaced axis a body's tracks read any rate: the 95% interval runs from 0 to "
                     f"{'half a turn a frame' if math.isfinite(top) else 'any rate'}; give `fixation_px` (X,Y)")


def with_few_tracks(result: RateResult) -> RateResult:
    """Where fewer automatic tracks than :data:`rotrate_cli.stages.verdict.MIN_TRACKS` (but more than
    one) gave the rate, the result with its interval widened to hold each of those tracks' own
    95% interval. So few say nothing of which of them lie on the turning body, nor does their
    scatter give an interval (the verdict calls such a result weak): any one may be the body's.
    The bicycle wheel's 3-7 s about the truth's fixation kept three tracks, at 0.76, 1.08 and 2.80
    rad/s (the wheel's tyre and rim carry almost no texture the tracker holds): 0.94 within
    [0, 2.00], its truth 2.27 outside; now [0, 5.26]."""
    combined = result.combined
    if not (1 < combined.tracks_used < MIN_TRACKS and math.isfinite(combined.omega_rad_s)):
        return result
    chosen = result.features[result.features["inlier"].to_numpy(dtype=bool)]
    sign = -1.0 if combined.omega_rad_s < 0 else 1.0
    each = [Combined(sign * abs(rate), sign * abs(rate) - Z95 * se, sign * abs(rate) + Z95 * se, 1)
            for rate, se in zip(chosen["omega_rad_s"], chosen["omega_se_rad_s"], strict=True)]
    widened = _spanning(result, *each).combined
    low = max(widened.omega_low_rad_s, 0.0) if combined.omega_low_rad_s >= 0 else widened.omega_low_rad_s
    return replace(result, combined=replace(widened, omega_low_rad_s=low))


#: The moving tracks split in two where each group holds at least this share of them (and
#: :data:`SIDE_MIN_TRACKS`)...
SPLIT_MIN_SHARE = 0.15
#: ...and no track's rate lies between the groups over this many times the wider group's spread
#: (its median absolute deviation, as a standard deviation).
SPLIT_GAP = 3.0
#: The widest gaps between neighbouring rates tried as the split.
_SPLIT_TRIES = 20
#: The reasons of the tracks that moved and gave a rate: the inliers and those rejected only for
#: disagreeing with them (on the body, ``slides``; off it, ``other_motion``, is left out).
_MOVING = ("", "disagrees", "slides")


def rates_split(result: RateResult) -> tuple[Combined, Combined] | None:
    """The slower and the faster group's rates (random-effects means, signed as the result's)
    where the moving tracks' rates fall into two groups with none between them (see
    :data:`SPLIT_MIN_SHARE`, :data:`SPLIT_GAP`); None otherwise.

    One rigid body's points share one rate, scattered about it by the tracker; two groups apart
    say some points are not on it, or not held on it. Where a surface looks the same after a turn
    (a record's grooves, spokes, a rim), the tracker's window slips along it and reads slow, and
    a reflection keeps its own pace, while the outlier rejection keeps whichever group is the
    larger, or, where they are near in size, both, and the random-effects mean falls between
    them. The real record's first 1.5 s (less than a turn, so its repetition cannot give the
    rate): 19 tracks on the grooves' highlights read 0.60 rad/s, 6 on the label read 3.7-5.0
    with nothing between, and the result was 0.60 within [0, 1.39] against a truth of 3.55;
    about the truth's own fixation both groups were kept, 0.66 within [0, 1.89]. Over the
    benchmarks' results (renders, the real clips, their variants and parts, the EPFL cars' parts
    of a turn) the widest gap between two such groups in a result called good was 2.4 spreads,
    the whole record's (its rate its repetition's, where this is not asked: :func:`check_rate`),
    and 1.6 from the tracks alone (an EPFL car's part); on renders 0.22. It split five results,
    each tracks-only and weak already: that part of the record and four EPFL parts. At a tenth's
    share it would also have split two good EPFL parts, right to 1%, for 3 tracks of 22 and 25."""
    features = result.features
    moving = features[features["reason"].isin(_MOVING).to_numpy()]
    n = len(moving)
    least = max(SIDE_MIN_TRACKS, math.ceil(SPLIT_MIN_SHARE * n))
    if n < 2 * least or not math.isfinite(result.combined.omega_rad_s):
        return None
    order = np.argsort(moving["omega_rad_s"].to_numpy(dtype=float), kind="stable")
    rate = moving["omega_rad_s"].to_numpy(dtype=float)[order]
    se = moving["omega_se_rad_s"].to_numpy(dtype=float)[order]
    if not np.isfinite(rate).all():
        return None
    gaps = np.diff(rate)[least - 1:n - least]  # gaps[j]: between rate[least - 1 + j] and the next
    best, split_at = SPLIT_GAP, None
    for j in np.argsort(gaps)[::-1][:_SPLIT_TRIES]:
        k = int(j) + least  # the slower group's size
        spread = max(_robust_sd(rate[:k]), _robust_sd(rate[k:]))
        if spread > 0 and gaps[j] / spread >= best:
            best, split_at = gaps[j] / spread, k
    if split_at is None:
        return None
    sign = -1.0 if result.combined.omega_rad_s < 0 else 1.0
    groups = []
    for part in (slice(0, split_at), slice(split_at, n)):
        group = combine(rate[part], se[part])
        low, high = sorted((sign * group.omega_low_rad_s, sign * group.omega_high_rad_s))
        groups.append(Combined(sign * group.omega_rad_s, low, high, group.tracks_used))
    return groups[0], groups[1]


def _robust_sd(values: np.ndarray) -> float:
    """The median absolute deviation of ``values``, scaled to a normal standard deviation."""
    return 1.4826 * float(np.median(np.abs(values - np.median(values))))


def split_doubt(slower: Combined, faster: Combined) -> str:
    """The line for :func:`rates_split`'s two groups."""
    return (f"the moving tracks fall into two groups with no rate between them: {slower.tracks_used} read "
            f"{abs(slower.omega_rad_s):.4g} rad/s and {faster.tracks_used} read {abs(faster.omega_rad_s):.4g}: "
            "points slip along a surface that looks the same after a turn (grooves, spokes, a rim) and read slow, "
            "and reflections keep their own pace; the 95% interval holds both groups: look at the tracks with "
            "`overlay`, and keep the points on the body's own texture with `roi` (X,Y,W,H)")


#: The normal distribution's two-sided 95% point.
Z95 = 1.96
#: A found axis's placement that widens the interval's half-width more than this many times is told.
AXIS_WIDENS = 1.5


def with_axis_doubt(result: RateResult, spread: AxisSpread | None) -> tuple[RateResult, str | None]:
    """The result with its interval widened by the found axis's placement: in quadrature, its
    standard error across the axis times the rate's change per pixel across it, at 95%; and the
    whole, times the gain of the axis's and the rate's coupling (:class:`rotrate_cli.geometry.
    AxisSpread`); with a note where that widened it much.

    The tracks' own interval holds the axis where it was put, while the same tracks place it only
    so well: on arcs shorter than a turn, a pixel across moves the rate by about a percent (a
    rendered cylinder seen from 30 degrees above, its axis found 0.7 px across from the truth's:
    +0.73% within [+0.07%, +4.54%], missing; an EPFL car's first 30 photographs, placed to +-13
    px: +53% within [+30%, +77%]). And the axis is placed at the rate measured about it: on a
    short arc a rate a little high puts the axis a little aside, about which the rate reads high
    again, so that tracks agreeing closely can agree on an axis and a rate both off, even with
    the axis settled where the two agree (:func:`rotrate_cli.stages.geometry._refine_fixation`). The
    EPFL cars' parts of a turn, timed by their EXIF clocks (five cars, 30, 50 and 70 photographs
    from every 15th), settled: without the gain 7 of the 21 results called good missed the truth
    (one car's 60th to 89th photographs -3.6% within [-4.4%, -2.8%], at a coupling of 0.84); with
    it, 1 of 15, a rate from the clip's repetition, which needs no axis."""
    combined = result.combined
    if spread is None or combined.tracks_used == 0 or not math.isfinite(combined.omega_rad_s):
        return result, None
    reach = Z95 * spread.rate_se_rad_s
    if not math.isfinite(reach):
        return result, None
    gain = spread.gain
    omega = combined.omega_rad_s
    below = math.hypot(omega - combined.omega_low_rad_s, reach)  # the placement alone, in quadrature
    above = math.hypot(combined.omega_high_rad_s - omega, reach)
    low, high = omega - gain * below, omega + gain * above
    if omega > 0 and combined.omega_low_rad_s >= 0:
        low = max(low, 0.0)  # as the lens's (camera.with_lens_doubt): a rate's size is not negative
    widened = replace(result, combined=replace(combined, omega_low_rad_s=low, omega_high_rad_s=high))
    before = combined.omega_high_rad_s - combined.omega_low_rad_s
    placing_widens = below + above > AXIS_WIDENS * before
    # the coupling's gain is told where the interval it widens is wide: a narrow one needs no telling
    coupling_widens = gain > AXIS_WIDENS and (high - low) / 2 > WEAK_HALF_WIDTH * abs(omega)
    if not (placing_widens or coupling_widens):
        return widened, None
    placed = (f"the axis found from the tracks is placed to +-{spread.se_px:.1f} px across itself, which moves "
              f"the rate by +-{abs(100 * spread.rate_se_rad_s / omega):.1f}%")
    if coupling_widens:
        placed += (f", and it is placed at the rate measured about it: on this arc the two trade off (a rate a "
                   f"little off and an axis a little aside fit the tracks alike), which multiplies the rate's "
                   f"uncertainty by {gain:.1f}")
    return widened, f"{placed}: the 95% interval holds that; give `fixation_px` (X,Y) if you know a point on the axis"


def with_clock_doubt(result: RateResult, clock_resolution_s: float) -> RateResult:
    """The result with its interval widened (in quadrature) by what a clock good to
    ``clock_resolution_s`` leaves unknown of a rate measured over the tracks' time span: the
    span's ends are each known to half the resolution. Photographs' EXIF times are whole
    seconds: over the 30 s of 30 photographs of a turntable, +-3%, where the fits' own interval
    said +-1% to +-3% (EPFL cars, tracks-only results: 2 of 4 intervals missed the truth)."""
    combined = result.combined
    times = result.offsets["time_s"].to_numpy()
    if not (clock_resolution_s > 0 and combined.tracks_used > 0 and len(times) > 1):
        return result
    span_s = float(times.max() - times.min())
    omega = combined.omega_rad_s
    if not (span_s > 0 and math.isfinite(omega)):
        return result
    clock = abs(omega) * clock_resolution_s / span_s
    low = omega - math.hypot(omega - combined.omega_low_rad_s, clock)
    if omega > 0 and combined.omega_low_rad_s >= 0:
        low = max(low, 0.0)  # a rate's size is not negative (nor does the next widening make it so)
    high = omega + math.hypot(combined.omega_high_rad_s - omega, clock)
    return replace(result, combined=replace(combined, omega_low_rad_s=low, omega_high_rad_s=high))


def with_paths_rate(result: RateResult, view_tracks: pd.DataFrame) -> tuple[RateResult, str | None]:
    """Seen obliquely or face on, the result with its interval widened to hold the rate of the
    tracks' paths in both image coordinates (:func:`rotrate_cli.scene.view.rate_from_paths`), and a
    note saying so; as it was in a side view, or where the two agree. The offsets across one
    image direction assume the paths' centres line up across it, which an axis leaning towards
    the camera breaks (rendered box from 60 degrees above: -2.5%, interval [-4.7%, -0.3%]; its
    paths: +0.6%).

    Orthographic fits only (:func:`check_rate` does not ask with a pinhole camera): the paths
    are fitted as circles seen from far away, which a near camera does not see. Through 25-40
    degree lenses from 30-45 degrees above, the paths read +6.6% to +15% on renders whose
    pinhole fits were within 1.5% (a sphere's, -2.1% and -2.8%) with their intervals covering,
    and widening to them called those results weak; seen orthographically the paths were within 0.6% on boxes and
    cylinders from 45 and 70 degrees above (one cylinder from 30: +4.7%)."""
    combined = result.combined
    view = view_from_paths(view_tracks, combined.omega_rad_s)
    if view is None or view.name == "side":
        return result, None
    paths = rate_from_paths(view_tracks, combined.omega_rad_s) * (1.0 if combined.omega_rad_s >= 0 else -1.0)
    if not math.isfinite(paths) or combined.omega_low_rad_s <= paths <= combined.omega_high_rad_s:
        return result, None
    widened = Combined(combined.omega_rad_s, min(combined.omega_low_rad_s, paths),
                       max(combined.omega_high_rad_s, paths), combined.tracks_used)
    note = (f"seen {view.name} ({view.elevation_deg:.0f} deg), the tracks' paths fitted in both image coordinates "
            f"give {paths:.4g} rad/s, outside the offsets' interval: the interval is widened to hold it")
    return replace(result, combined=widened), note


#: A found axis about which the tracks' interval is this many times narrower than about a given
#: fixation shows the given one to be off by more than the measurement resolves.
SHARPER = 1.5


#: A given fixation is checked against the shared axis found, and the rate measured about it, in
#: turn, this many times at most (until the axis moves by under 2 px).
FOLLOW_STEPS = 12


def _within_reach(point_px: tuple[float, float], given_px: tuple[float, float], size_px: tuple[int, int]) -> bool:
    """Whether ``point_px`` lies no further from the frame's centre than the given fixation does,
    plus the frame's diagonal (an axis outside the picture can still be told: a record player's
    spindle beside it)."""
    width, height = size_px
    centre = (width / 2.0, height / 2.0)
    reach = math.hypot(width, height) + math.hypot(given_px[0] - centre[0], given_px[1] - centre[1])
    return math.hypot(point_px[0] - centre[0], point_px[1] - centre[1]) <= reach


def fixation_doubt(result: RateResult, geometry: Geometry, method: str, rejection: RejectionConfig,
                   chosen_points: bool, size_px: tuple[int, int]) -> tuple[str, Combined] | None:
    """A given fixation checked against the axis the inlier tracks turn about (the shared-axis
    least squares at the measured rate, :func:`rotrate_cli.scene.axis.refine_axis_offset`): a line
    naming the found axis point when measuring about it moves the rate outside the interval
    measured about the given one, or narrows the interval :data:`SHARPER` times (what the
    measurement can resolve), with the rate measured about the found point; None otherwise."""
    features = result.features
    inlier = features["inlier"].to_numpy(dtype=bool)
    if geometry.fixation_found or method != "fit" or chosen_points or inlier.sum() < JOINT_MIN_TRACKS:
        return None
    offsets, omega, placing = inliers_and_rate(result, geometry.camera(size_px))
    ux, uy = axes.unit_offset(geometry.axis_angle_deg)
    fixation = geometry.fixation_px
    sense = math.copysign(1.0, omega)
    shift, again, camera = 0.0, None, geometry.camera(size_px)
    # the shared axis at the rate measured about it, in turn: the rate measured about a point far
    # off the axis is far off too, and the axis found at it lies only part of the way (a sample box
    # given a fixation 1,680 px to the side: 600 px towards its axis, and no warning; now 7 px
    # from it. Choosing the inliers anew about each point went less far: 98 px)
    for _ in range(FOLLOW_STEPS):
        step = axes.refine_axis_offset(offsets.assign(offset_px=offsets["offset_px"].to_numpy() - shift), omega,
                                       camera if placing is not None else None)
        if not math.isfinite(step) or (again is not None and abs(step) < 2.0):
            break
        shift += step
        found = (fixation[0] + shift * ux, fixation[1] + shift * uy)
        if not _within_reach(found, fixation, size_px):
            # the tracks show no axis near the picture (a record's first 1.5 s, its tracks on the
            # still reflections: the walk named a point 544,179 px away)
            return None
        camera = camera_at(geometry.lens, size_px, found, geometry.axis_angle_deg)
        moved = offsets.assign(offset_px=offsets["offset_px"].to_numpy() - shift)  # the inliers: memory
        again = rates_from_offsets(moved, method, rejection, camera)
        omega = sense * again.combined.omega_rad_s
        if abs(step) < 2.0 or not math.isfinite(omega):
            break
    if again is None or abs(shift) < 2.0:
        return None
    found = (fixation[0] + shift * ux, fixation[1] + shift * uy)
    rate, combined = again.combined.omega_rad_s, result.combined
    width = combined.omega_high_rad_s - combined.omega_low_rad_s
    width_found = again.combined.omega_high_rad_s - again.combined.omega_low_rad_s
    # resolved: about the found axis the rate moves outside the given one's interval, or the
    # tracks agree markedly better (a 10 px error on the sample box: interval 0.098 -> 0.006)
    if not math.isfinite(rate) or (combined.omega_low_rad_s <= rate <= combined.omega_high_rad_s
                                   and not width > SHARPER * width_found):
        return None
    return (f"the tracks turn about an axis through ({found[0]:.1f}, {found[1]:.1f}), {abs(shift):.0f} px from the "
            f"given fixation; measured about it the rate is {rate:.4g} rad/s, which the 95% interval holds: check "
            "`fixation_px`, or use `fixation_px=None`", again.combined)


def with_lens_doubt(result: RateResult, lens: Lens, fixation_px: tuple[float, float], angle_deg: float,
                    method: str, rejection: RejectionConfig, size_px: tuple[int, int]) -> RateResult:
    """The result with its interval widened to hold the rates measured through the lenses at the
    ends of a found lens's 95% interval (its inverse focal length +- the widest of
    :data:`LENS_SE_WIDTHS` standard errors, :data:`LENS_FLOOR` of it and :data:`LENS_FLOOR_TAN` in
    tan(fov/2); 0 is orthographic), or where the lens was sought and could
    not be told, through the orthographic camera and a :data:`WIDEST_FOV_DEG` lens. As it is for
    any other lens."""
    focal = lens.estimate
    if result.combined.tracks_used == 0:
        return result
    if lens.unsettled and lens.focal_px is None:
        # the tracks could not tell the lens: any from the paper's orthographic camera to a wide one
        ends: tuple[float, ...] = (0.0, 1.0 / focal_px_from_fov(WIDEST_FOV_DEG, size_px[0]))
    elif lens.source != "found" or focal is None or lens.focal_px is None:
        return result
    else:
        half = max(LENS_SE_WIDTHS * focal.inverse_focal_se, LENS_FLOOR * focal.inverse_focal,
                   LENS_FLOOR_TAN * 2.0 / size_px[0])
        lower = focal.inverse_focal - half
        if lower < 1.0 / (ORTHOGRAPHIC_WIDTHS * size_px[0]):
            lower = 0.0  # within its uncertainty of a lens called orthographic: the paper's model is as likely
        ends = (lower, focal.inverse_focal + half)
    rates_at_ends = []
    for inverse in ends:
        end = replace(lens, focal_px=1.0 / inverse if inverse > 0 else None)
        camera = camera_at(end, size_px, fixation_px, angle_deg)
        if method == "fit":  # the same tracks, the same weights, through the other lens
            rates_at_ends.append(rejoined(result, result.offsets, rejection, camera))
        else:
            rates_at_ends.append(rates_from_offsets(result.offsets, method, rejection, camera).combined.omega_rad_s)
    combined = result.combined
    # where the paper's orthographic camera is one end, it is as likely as the lens found, and its
    # rate carries the tracks' own scatter too (an orthographic noisy sphere, 0.38 of a turn: a
    # lens found at 8.9 degrees read -3.5%, the paper's model -0.7% within +-0.9%; the interval
    # held the latter's rate only, and missed the truth by 0.7%); so do both ends of an unknown
    # lens's range (the box of WIDEST_FOV_DEG: orthographic +13.2% within [+2.1%, +24.2%], its
    # true 60-degree lens given -0.25%; now within [-8.5%, +24.2%]). The ends of a found lens's
    # range are the far edges of a generous interval (:data:`LENS_FLOOR`): their rates alone.
    below = combined.omega_rad_s - combined.omega_low_rad_s
    above = combined.omega_high_rad_s - combined.omega_rad_s
    spread = [(below, above) if inverse == 0.0 or lens.unsettled else (0.0, 0.0) for inverse in ends]
    low = float(np.nanmin([combined.omega_low_rad_s,
                           *(rate - down for rate, (down, _) in zip(rates_at_ends, spread, strict=True))]))
    if combined.omega_rad_s > 0 and combined.omega_low_rad_s >= 0:
        low = max(low, 0.0)  # a scatter carried to an end does not make the rate negative
    high = float(np.nanmax([combined.omega_high_rad_s,
                            *(rate + up for rate, (_, up) in zip(rates_at_ends, spread, strict=True))]))
    return replace(result, combined=replace(combined, omega_low_rad_s=low, omega_high_rad_s=high))


#: Where the photographs' own lens (EXIF) is known but not the camera's height over the turning
#: plane, the interval holds the rate through a camera this many degrees above it too
#: (turntables are photographed from about level to 30 degrees above: the dinosaur's 27-30).
#: An EPFL car's photographs 15-44 through their EXIF lens, the camera taken as level: -4.03%
#: within [-6.76%, -0.53%], good, missing the truth; seen from 20 degrees above, -2.32%.
HEIGHT_DOUBT_DEG = 20.0


def with_height_doubt(result: RateResult, lens: Lens, fixation_px: tuple[float, float], angle_deg: float,
                      method: str, rejection: RejectionConfig, size_px: tuple[int, int]) -> RateResult:
    """The result with its interval widened to hold the rate through the same lens from
    :data:`HEIGHT_DOUBT_DEG` above the plane, with the tracks' own scatter about it, where the lens
    is the photographs' own and the camera's height is not known (the fits take it as level; a
    lens the user gives comes with the user's view)."""
    if (result.combined.tracks_used == 0 or lens.focal_px is None or lens.source != "exif"
            or math.isfinite(lens.elevation_deg)):
        return result
    offsets, camera = followed_up(result, camera_at(replace(lens, elevation_deg=HEIGHT_DOUBT_DEG), size_px,
                                                    fixation_px, angle_deg))
    rate = rates_from_offsets(offsets, method, rejection, camera).combined.omega_rad_s
    if not math.isfinite(rate):
        return result
    # as likely as the level camera's, its rate carries the tracks' own scatter too
    combined = result.combined
    below = combined.omega_rad_s - combined.omega_low_rad_s
    above = combined.omega_high_rad_s - combined.omega_rad_s
    low = min(combined.omega_low_rad_s, max(rate - below, 0.0))
    return replace(result, combined=replace(combined, omega_low_rad_s=low,
                                            omega_high_rad_s=max(combined.omega_high_rad_s, rate + above)))


def rate_change(result: RateResult, method: str, rejection: RejectionConfig, camera: Camera | None,
                halves: tuple[Combined, Combined, float, float] | None = None) -> str | None:
    """A line saying the rate changes over the clip (see :func:`changes`); None otherwise.
    ``halves``: the halves' rates where they were measured already (:attr:`Geometry.halves`)."""
    if halves is None:
        halves = half_rates(result, method, rejection, camera)
    if halves is None or not changes(result.combined, *halves):
        return None
    early, late = halves[0], halves[1]
    return (f"the rate changes over the clip: {early.omega_rad_s:.4g} rad/s in its first half, {late.omega_rad_s:.4g} "
            "in its second; the result is an average: see omega(t) with `window_s`")


#: A found lens's 95% interval, in its inverse focal length, is the widest of three: this many of
#: its standard errors, :data:`LENS_FLOOR` of itself, and :data:`LENS_FLOOR_TAN` in tan(fov/2).
#: The standard error understates the error: on 111 lenses found in bench-random renders (35-75
#: degrees, 0-80 degrees of elevation) the error was a median 1.9 and a 95th percentile 6.9 of
#: it; the worst, 0.18 in tan(fov/2) (a box from 60 degrees above, bench-random 7002, found at
#: 79 degrees for 65), held only by this. Near a curved outline the tracker pulls points towards
#: the object's middle height, which reads as a shorter lens.
LENS_SE_WIDTHS = 7.0


#: ... at least this fraction of the inverse focal length either side. It was 0.5, set on 13
#: renders through 15-35 degree lenses before the tracker matched each point against its first
#: patch (then off by a median of 12%, the worst 56%). Chosen on the survey of 200 bench-random
#: renders (seeds 1-6 to choose, 7-11 to check): the intervals cover the truth as often as with
#: 0.5 (181 of 183 with a lens, the same two misses), and 47 rather than 103 are wider than
#: +-5%, 38 of those within 2%.
LENS_FLOOR = 0.2


#: ... and at least this much in tan(fov/2) either side: a narrow lens's error is a larger part
#: of it (a sphere through a 20-degree lens found at 26.6 degrees, 0.06; before the patch
#: matching, at 30.7 degrees, 0.1).
LENS_FLOOR_TAN = 0.1
