"""The rate stage: offsets from the axis -> per-track sinusoid fits -> verdicts -> the combined
rate with its 95% interval (:func:`rates_from_offsets`), and the rates of a clip's two halves (a
rate that changes over the clip)."""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from rotrate_cli.fitting import estimators
from rotrate_cli.fitting.camera import Camera
from rotrate_cli.fitting.joint import joint_fit
from rotrate_cli.fitting.outliers import (
    FEATURE_COLUMNS,
    Combined,
    RejectionConfig,
    combine,
    combine_plain,
    flag_samples,
    judge_fits,
    judge_paper,
)
from rotrate_cli.runtime.lazy import pandas as pd
from rotrate_cli.runtime.memory import release_free_memory
from rotrate_cli.scene import axis as axes

#: Below this many inlier tracks the summary is the random-effects mean of per-track rates
#: rather than the joint fit: the joint fit's gain (no small-track bias) needs many tracks, its
#: jackknife interval needs enough of them to see their spread, and with a handful one track's
#: model error would steer it (the paper's two hand-tracked features: 0.309 joint, 0.334 mean).
JOINT_MIN_TRACKS = 10


#: Halves of a clip whose rates lie outside each other's intervals and this fraction apart show
#: a changing rate.
CHANGE_FRACTION = 0.02


#: Degrees of freedom given to the typical track noise when moderating each track's own.
PRIOR_DOF = 10.0


@dataclass(frozen=True)
class RateResult:
    """What the rate stages produce from a table of offsets."""

    offsets: pd.DataFrame
    features: pd.DataFrame
    combined: Combined
    direction: str


def thin(tracks: pd.DataFrame, every: int) -> pd.DataFrame:
    """Every ``every``-th frame's rows, counted from the first frame (the paper's sampling)."""
    if every == 1 or tracks.empty:
        return tracks
    first = int(tracks["frame"].min())
    return tracks[(tracks["frame"] - first) % every == 0]


#: The paper's method differentiates positions this far apart in angle (its 16 frames at 30 fps
#: of a car turning at 0.327 rad/s): closer, its second differences are noise (+201% at --every 1).
PAPER_SPACING_RAD = 1.0 / 6.0


def sample_spacing(tracks: pd.DataFrame, angle_deg: float, method: str) -> int:
    """``--every`` when not given: 1 for the fit method; for the paper's, the frames that make
    :data:`PAPER_SPACING_RAD` at a first rate from the tracks (the recurrence), at least 1."""
    if method != "paper":
        return 1
    omega = axes.rate_from_recurrence(tracks, axes.offsets_along(tracks, (0.0, 0.0), angle_deg))
    times = tracks.drop_duplicates("frame")["time_s"].to_numpy()
    step_s = float(np.median(np.diff(np.sort(times)))) if len(times) > 1 else math.nan
    if not (math.isfinite(omega) and omega > 0 and math.isfinite(step_s) and step_s > 0):
        return 1
    return max(1, round(PAPER_SPACING_RAD / (omega * step_s)))


def running_measure(method: str, rejection: RejectionConfig,
                    camera: Camera | None = None) -> Callable[[pd.DataFrame], Combined]:
    """The combined rate of a table of offsets by ``method`` (``paper``, else the fit),
    ``rejection`` and ``camera`` (the analysis's pinhole, or None): what
    :func:`rotrate_cli.fitting.series.running_rate` measures with, as the headline was measured (the
    running rate of an EPFL car through its 64-degree lens read 0.052 rad/s orthographically
    beside a headline of 0.046)."""
    method = "paper" if method.startswith("paper") else "fit"
    return lambda part: rates_from_offsets(part, method, rejection, camera).combined


def _direction(offsets: pd.DataFrame, features: pd.DataFrame) -> str:
    """Sense of rotation, given only on a clear majority of the inlier tracks.

    With a pinhole camera each track's fit says which sense explains it (near points move
    faster). Otherwise: the net horizontal travel. An opaque object shows its near side, whose
    points cross in front of the axis: moving right means anticlockwise seen from above.
    Far-side points (a transparent object, a turntable's top seen from above) travel the other
    way, hence the majority rule.
    """
    inliers = features[features["inlier"]]
    used = set(inliers["track"].astype(int))
    if len(used) < 5:
        return "unknown"
    senses = inliers["sense"].dropna().to_numpy()
    if len(senses) >= 5:
        vote = float(senses.mean())
        return "ccw" if vote >= 0.6 else "cw" if vote <= -0.6 else "unknown"
    # offsets are sorted by track then time: a track's first and last rows bound its slice
    tracks = offsets["track"].to_numpy()
    values = offsets["offset_px"].to_numpy()
    starts = np.flatnonzero(np.r_[True, tracks[1:] != tracks[:-1]])
    ends = np.r_[starts[1:], len(tracks)] - 1
    keep = np.isin(tracks[starts], np.fromiter(used, dtype=np.int64, count=len(used)))
    travel = values[ends[keep]] - values[starts[keep]]
    total = float(np.abs(travel).sum())
    if total <= 0:
        return "unknown"
    balance = float(travel.sum()) / total
    if balance >= 0.7:
        return "ccw"
    if balance <= -0.7:
        return "cw"
    return "unknown"


def sample_rates(
    offsets: pd.DataFrame, features: pd.DataFrame, method: str, rejection: RejectionConfig
) -> pd.DataFrame:
    """Per-sample derivatives, rates and verdicts for offsets already judged per track."""
    if method == "paper":
        return judge_paper(estimators.paper_samples(offsets))[0]
    rate = dict(zip(features["track"].astype(int), features["omega_rad_s"], strict=True))
    return flag_samples(estimators.fit_samples(offsets, rate), features, rejection)


#: The sense of rotation of a reported direction: +1 anticlockwise, -1 clockwise.
SENSES = {"ccw": 1, "cw": -1}


def _sorted_by_track_and_time(offsets: pd.DataFrame) -> bool:
    track_step = np.diff(offsets["track"].to_numpy())
    time_step = np.diff(offsets["time_s"].to_numpy())
    return bool(((track_step > 0) | ((track_step == 0) & (time_step > 0))).all())


def rates_from_offsets(
    offsets: pd.DataFrame, method: str, rejection: RejectionConfig, camera: Camera | None = None
) -> RateResult:
    """Per-track rates and verdicts, and the combined rate.

    ``offsets`` has columns ``track, frame, time_s, offset_px``, one row per sample; ``camera``
    (fit method only) switches from orthographic to pinhole projection.
    """
    if not _sorted_by_track_and_time(offsets):
        offsets = offsets.sort_values(["track", "time_s"], kind="stable").reset_index(drop=True)
    if method == "paper":
        _, features = judge_paper(estimators.paper_samples(offsets))
        combined = combine_plain(features.loc[features["inlier"], "omega_rad_s"].to_numpy())
        direction = _direction(offsets, features)
    else:
        long_enough, short = _split_short(offsets, max(rejection.min_samples, 4))
        features = judge_fits(long_enough, estimators.fit_tracks(long_enough, rejection.min_samples, camera), rejection)
        if short is not None:
            features = pd.concat([features, short], ignore_index=True).sort_values("track", kind="stable")
            features = features.reset_index(drop=True)
        release_free_memory()  # the per-track fits' padded batches are gone
        used = features[features["inlier"]]
        combined = combine(used["omega_rad_s"].to_numpy(), used["omega_se_rad_s"].to_numpy())
        direction = _direction(offsets, features)
        combined = _joint(offsets, used, combined, rejection, camera, SENSES.get(direction, 0))
    return RateResult(offsets, features, combined, direction)


#: Tracks too short to fit are set apart before the fits only where they are at least this share
#: of all tracks (real footage with fast, short-lived tracks), not at the cost of copying the rest.
SPLIT_SHARE = 0.5


def _split_short(offsets: pd.DataFrame, min_samples: int) -> tuple[pd.DataFrame, pd.DataFrame | None]:
    """The offsets of the tracks long enough to fit, and the feature rows of the others (reason
    ``short``), made at once: on the record clip 43,000 of 45,000 tracks are a few frames long,
    and fitting and judging them one by one took a fifth of its fits' time. None when there are
    none."""
    track = offsets["track"].to_numpy()
    if len(track) == 0:
        return offsets, None
    starts = np.flatnonzero(np.r_[True, track[1:] != track[:-1]])
    counts = np.diff(np.r_[starts, len(track)])
    short = counts < min_samples
    if short.sum() < SPLIT_SHARE * len(counts):
        return offsets, None  # the fits pass over a few themselves; a copy of the rest would cost memory
    offset = offsets["offset_px"].to_numpy(dtype=np.float64)
    spread = np.maximum.reduceat(offset, starts) - np.minimum.reduceat(offset, starts)
    nan = np.full(int(short.sum()), math.nan)
    rows = pd.DataFrame({
        "track": track[starts[short]].astype(int), "samples": counts[short].astype(int),
        "omega_rad_s": nan, "omega_se_rad_s": nan, "rms_residual": nan, "amplitude": nan, "arc_rad": nan,
        "sense": nan, "range": spread[short], "inlier": False, "reason": "short",
    })[list(FEATURE_COLUMNS)]
    keep = np.repeat(~short, counts)
    return offsets[keep].reset_index(drop=True), rows


def _joint(
    offsets: pd.DataFrame, used: pd.DataFrame, pooled: Combined, rejection: RejectionConfig,
    camera: Camera | None, seen_sense: int = 0,
) -> Combined:
    """The joint fit of the inlier tracks (see :mod:`rotrate_cli.fitting.joint`), started from the
    pooled per-track rates; the pooled result stands where the joint fit finds no minimum, and
    for fewer than :data:`JOINT_MIN_TRACKS` tracks. ``seen_sense``: the sense the tracks'
    travel shows (:func:`_direction`; 0 where it shows none), used where their fits through the
    ``camera`` do not tell it."""
    if len(used) < JOINT_MIN_TRACKS or not math.isfinite(pooled.omega_rad_s):
        return pooled
    # Each track's noise from its own residuals, moderated towards the tracks' typical noise
    # (a few degrees of freedom say little on their own; the tracker is the same for all).
    samples = used["samples"].to_numpy(dtype=float)
    dof = np.maximum(samples - 3, 1)
    variance = used["rms_residual"].to_numpy() ** 2 * samples / dof
    typical = float(np.median(variance))
    noise_px = np.maximum(np.sqrt((dof * variance + PRIOR_DOF * typical) / (dof + PRIOR_DOF)),
                          max(rejection.residual_floor, 1e-9))
    told = told_sense(used["sense"].to_numpy(dtype=float))
    decided = told is not None
    sense = float(told if told is not None else seen_sense) or 1.0
    spread = (pooled.omega_high_rad_s - pooled.omega_low_rad_s) / pooled.omega_rad_s
    noise = dict(zip(used["track"], noise_px, strict=True))
    span = float(np.clip(2 * spread, 0.02, 0.5)) if math.isfinite(spread) else 0.2
    joint = joint_fit(offsets, noise, pooled.omega_rad_s, span=span, camera=camera, sense=sense)
    if not math.isfinite(joint.omega_rad_s):
        return pooled
    # Through a pinhole the two senses of rotation fit different rates (a cylinder through a
    # 50-degree lens: 0.27 against 0.21 rad/s). Where the tracks do not tell the sense (see
    # estimators.fit_tracks), the interval holds the other sense's rate and interval too: a half of a
    # clip measured in the wrong sense read as a spin-up, and moving the axis for it put renders
    # 6-21% off. The point is then midway between the two senses' rates, so that a clip and its
    # mirror image read alike: the anticlockwise default's rate put bench-random 3001 (turning
    # clockwise) at +35%, midway +7%. Where the tracks' net travel shows the sense (an opaque body
    # seen from the side shows its near side, whose travel tells the sense: the paper's rule) the
    # point is that sense's rate, and the interval still holds both. On the four of 200
    # bench-random renders whose fits could not tell the sense the travel told it rightly, and
    # their rates went from +7% to +20% midway to -0.3% to +1.7%; the real EPFL car 10's first 30
    # photographs from +70% to -2.3%.
    other = Combined(math.nan, math.nan, math.nan, 0)
    if camera is not None and not decided:
        other = joint_fit(offsets, noise, pooled.omega_rad_s, span=span, camera=camera, sense=-sense)
    # The jackknife sees scatter between tracks but not a bias they share (tracking drift,
    # projection error); where the two weightings disagree, that disagreement is such a bias,
    # so the interval spans both estimators' intervals.
    low = np.nanmin([joint.omega_low_rad_s, pooled.omega_low_rad_s, pooled.omega_rad_s,
                     other.omega_low_rad_s, other.omega_rad_s])
    high = np.nanmax([joint.omega_high_rad_s, pooled.omega_high_rad_s, pooled.omega_rad_s,
                      other.omega_high_rad_s, other.omega_rad_s])
    if not math.isfinite(other.omega_rad_s):
        return Combined(joint.omega_rad_s, float(low), float(high), joint.tracks_used)
    both = (joint.omega_rad_s, other.omega_rad_s) if sense > 0 else (other.omega_rad_s, joint.omega_rad_s)
    if not seen_sense:
        point = 0.5 * (joint.omega_rad_s + other.omega_rad_s)
        return Combined(point, float(low), float(high), joint.tracks_used, both)
    own = (float(np.nanmin([joint.omega_low_rad_s, pooled.omega_low_rad_s, pooled.omega_rad_s])),
           float(np.nanmax([joint.omega_high_rad_s, pooled.omega_high_rad_s, pooled.omega_rad_s])))
    return Combined(joint.omega_rad_s, float(low), float(high), joint.tracks_used, both, int(sense), own)


def no_result_message(features: pd.DataFrame) -> str:
    if features.empty:
        return "no point could be tracked; check that the object moves and has texture, or pass `roi`"
    counts = Counter(features["reason"])
    detail = ", ".join(f"{n} {why}" for why, n in counts.most_common())
    return (f"no track gave a trustworthy rate ({detail}); "
            "try a longer clip, `roi` around the object, or check `fixation_px`")


def told_sense(senses: np.ndarray) -> int | None:
    """The sense of rotation that tracks' fits through a lens told (their ``sense`` column, +1
    anticlockwise, -1 clockwise, NaN where a track's did not; see
    :func:`rotrate_cli.fitting.estimators.fit_tracks`): the sign of their sum, 0 where they are
    evenly split; None where none told one. The one reading of it: the joint fit, the axis's
    placing and the second looks (:func:`decided_sense`) all take it from here."""
    told = senses[np.isfinite(senses)]
    return int(np.sign(told.sum())) if len(told) else None


def decided_sense(result: RateResult) -> int:
    """The sense of rotation the inlier tracks' fits through a lens decided (:func:`told_sense`),
    0 where they did not or are evenly split."""
    return told_sense(result.features.loc[result.features["inlier"], "sense"].to_numpy(dtype=float)) or 0


def with_sense(camera: Camera | None, sense: int) -> Camera | None:
    """``camera`` told the body's sense of rotation, so that fits through it try that sense only
    (half the work); as it is where it is orthographic, already told, or ``sense`` is 0."""
    if camera is None or camera.sense or not sense:
        return camera
    return replace(camera, sense=sense)


def followed_up(result: RateResult, camera: Camera | None) -> tuple[pd.DataFrame, Camera | None]:
    """The offsets and camera that a second look at a measured ``result`` fits (its halves, the
    ends of the lens's range, another height): its inlier tracks only, in the sense their fits
    decided. A track the first fit rejected (a slide, a reflection, the background) is not one the
    second look should weigh, and fitting 1,700 tracks in both senses again, several times, took
    most of a textured box's analysis (issue 50)."""
    inliers = result.features.loc[result.features["inlier"], "track"]
    offsets = result.offsets
    if len(inliers) < len(result.features):
        offsets = offsets[offsets["track"].isin(inliers)].reset_index(drop=True)
    return offsets, with_sense(camera, decided_sense(result))


def rejoined(result: RateResult, offsets: pd.DataFrame, rejection: RejectionConfig, camera: Camera | None) -> float:
    """The rate of ``result``'s inlier tracks measured again from ``offsets`` (the same samples
    about an axis point moved a little, or seen through another lens) by their joint fit alone:
    each track keeps the noise and the sense its own fit found, and none is judged again. A
    derivative (the rate per pixel of the axis's place) or an end of a range (the lens's) wants
    the same tracks, and fitting and judging 1,700 tracks again for each took a second of a
    textured box's analysis (issue 50). Where the tracks are too few for a joint fit they are
    all fitted again; NaN where no rate is found."""
    used = result.features[result.features["inlier"]]
    if len(used) < JOINT_MIN_TRACKS or not math.isfinite(result.combined.omega_rad_s):
        return rates_from_offsets(offsets, "fit", rejection, camera).combined.omega_rad_s
    if not _sorted_by_track_and_time(offsets):
        offsets = offsets.sort_values(["track", "time_s"], kind="stable").reset_index(drop=True)
    combined = _joint(offsets, used, result.combined, rejection, camera, SENSES.get(result.direction, 0))
    return math.nan if combined is result.combined else combined.omega_rad_s


def half_rates(result: RateResult, method: str, rejection: RejectionConfig,
               camera: Camera | None) -> tuple[Combined, Combined, float, float] | None:
    """The rates of the clip's first and second halves (the whole's inlier tracks, in its sense,
    same rules) and the middle time of each; None where a half gives no rate."""
    if method != "fit" or result.combined.tracks_used < JOINT_MIN_TRACKS:
        return None
    offsets, camera = followed_up(result, camera)
    times = offsets["time_s"].to_numpy()
    first, last = float(times.min()), float(times.max())
    middle = 0.5 * (first + last)
    halves = []
    for part in (times <= middle, times > middle):
        try:
            halves.append(rates_from_offsets(offsets[part], method, rejection, camera).combined)
        except (ValueError, IndexError):
            return None
    if not all(h.tracks_used > 0 and math.isfinite(h.omega_rad_s) for h in halves):
        return None
    return halves[0], halves[1], 0.5 * (first + middle), 0.5 * (middle + last)


def changes(whole: Combined, early: Combined, late: Combined, *_: float) -> bool:
    """True when the halves' rates lie outside each other's intervals and more than
    :data:`CHANGE_FRACTION` of the whole's rate apart."""
    separate = late.omega_low_rad_s > early.omega_high_rad_s or early.omega_low_rad_s > late.omega_high_rad_s
    return separate and abs(late.omega_rad_s - early.omega_rad_s) > CHANGE_FRACTION * whole.omega_rad_s


