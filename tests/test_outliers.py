"""Rejection rules and the combined estimate with its interval."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from rotrate_cli.fitting import estimators
from rotrate_cli.fitting.outliers import RejectionConfig, combine, judge_fits


def _samples(rng: np.random.Generator) -> pd.DataFrame:
    rows = []
    time_s = np.arange(60) / 30.0

    def add(track: int, offset: np.ndarray, times: np.ndarray = time_s) -> None:
        rows.append(pd.DataFrame({"track": track, "frame": np.arange(len(offset)), "time_s": times,
                                  "offset_px": offset}))

    for track in range(10):  # the object: 0.8 rad/s
        add(track, (40 + 8 * track) * np.cos(0.8 * time_s + 0.3 * track) + rng.normal(0, 0.05, 60))
    add(100, np.full(60, 25.0) + rng.normal(0, 0.05, 60))  # background
    add(101, 50 * np.cos(0.8 * time_s[:5]), time_s[:5])  # too short
    add(102, 70 * np.cos(2.0 * time_s) + rng.normal(0, 0.05, 60))  # another body
    add(103, 5 * np.cosh(0.9 * time_s))  # curves away from the axis
    add(104, 60 * np.cos(0.8 * time_s) + rng.normal(0, 3.0, 60))  # a slipping tracker
    return pd.concat(rows, ignore_index=True)


def test_each_rule_rejects_its_case(rng: np.random.Generator) -> None:
    samples = _samples(rng)
    verdict = judge_fits(samples, estimators.fit_tracks(samples), RejectionConfig()).set_index("track")["reason"]
    assert (verdict[list(range(10))] == "").all()
    assert verdict[100] == "static"
    assert verdict[101] == "short"
    assert verdict[102] == "disagrees"
    assert verdict[103] == "no_fit"
    assert verdict[104] == "poor_fit"


def test_combined_interval_covers_and_narrows(rng: np.random.Generator) -> None:
    covered = 0
    for _ in range(200):
        se = rng.uniform(0.01, 0.03, 12)
        omega = 0.5 + rng.normal(0, se)
        result = combine(omega, se)
        covered += result.omega_low_rad_s <= 0.5 <= result.omega_high_rad_s
    assert covered >= 180  # 95% nominal
    narrow = combine(0.5 + rng.normal(0, 0.001, 50), np.full(50, 0.001))
    assert narrow.omega_high_rad_s - narrow.omega_low_rad_s < 0.002


def test_interval_widens_when_tracks_disagree_beyond_their_errors(rng: np.random.Generator) -> None:
    omega = 0.5 + rng.normal(0, 0.02, 20)  # true scatter 0.02, claimed errors 0.001
    result = combine(omega, np.full(20, 0.001))
    assert result.omega_high_rad_s - result.omega_low_rad_s > 2 * 1.96 * 0.02 / np.sqrt(20) * 0.6


def _result_with_sides(left_rate: float, right_rate: float, per_side: int = 6):
    """A rate result whose inlier tracks lie left (offsets < 0) and right of the axis."""
    import pandas as pd

    from rotrate_cli.fitting.outliers import Combined
    from rotrate_cli.stages.fits import RateResult

    rows, offsets = [], []
    for k in range(2 * per_side):
        left = k < per_side
        rows.append({"track": k + 1, "omega_rad_s": (left_rate if left else right_rate) * (1 + 0.002 * (k % 3)),
                     "omega_se_rad_s": 0.001, "inlier": True})
        offsets += [{"track": k + 1, "offset_px": (-50.0 if left else 50.0) + d} for d in (-10.0, 0.0, 10.0)]
    combined = Combined((left_rate + right_rate) / 2, 0.9 * left_rate, 1.1 * right_rate, 2 * per_side)
    return RateResult(pd.DataFrame(offsets), pd.DataFrame(rows), combined, "ccw")


def test_tracks_either_side_of_the_axis_must_agree() -> None:
    from rotrate_cli.stages.checks import sides_disagree

    assert sides_disagree(_result_with_sides(0.50, 0.50)) is None
    doubt = sides_disagree(_result_with_sides(0.46, 0.50))  # 8% apart, each side tight
    assert doubt is not None and "either side of the axis" in doubt
    assert sides_disagree(_result_with_sides(0.46, 0.50, per_side=2)) is None  # too few to tell


def test_sides_that_disagree_widen_the_interval_to_hold_both() -> None:
    """Which side is off is not known: the interval holds both sides' rates (an EPFL car's first
    70 photographs: +5.6% within [+1.9%, +9.3%], the left side 13% lower; now [-22.8%, +9.3%])."""
    from dataclasses import replace

    from rotrate_cli.fitting.outliers import Combined
    from rotrate_cli.stages.checks import with_sides_span

    apart = _result_with_sides(0.46, 0.50)
    narrow = replace(apart, combined=Combined(0.495, 0.49, 0.50, 12))  # the joint fit followed one side
    widened = with_sides_span(narrow).combined
    assert widened.omega_rad_s == 0.495
    assert widened.omega_low_rad_s < 0.461 and widened.omega_high_rad_s >= 0.50
    same = replace(_result_with_sides(0.50, 0.50), combined=Combined(0.5, 0.499, 0.501, 12))
    assert with_sides_span(same).combined == same.combined  # sides that agree change nothing


def _result_with_rates(rate: np.ndarray, se: float = 0.01, reasons: list[str] | None = None):
    """A rate result whose moving tracks have these rates (inliers unless ``reasons`` say
    otherwise), combined as the inliers' random-effects mean."""
    from rotrate_cli.stages.fits import RateResult

    reason = reasons if reasons is not None else [""] * len(rate)
    features = pd.DataFrame({"track": np.arange(1, len(rate) + 1), "omega_rad_s": rate,
                             "omega_se_rad_s": np.full(len(rate), se), "inlier": [r == "" for r in reason],
                             "reason": reason})
    inlier = features["inlier"].to_numpy()
    return RateResult(pd.DataFrame({"track": [], "offset_px": []}), features,
                      combine(rate[inlier], np.full(int(inlier.sum()), se)), "ccw")


def test_tracks_that_fall_into_two_groups_of_rates_are_told_and_the_interval_holds_both(
        rng: np.random.Generator) -> None:
    """The real record's first 1.5 s: 19 tracks on the grooves' highlights near 0.6 rad/s, 6 on
    the label near 4 (rejected as disagreeing), nothing between; the result 0.60 within [0, 1.39],
    its truth 3.55."""
    from dataclasses import replace

    from rotrate_cli.stages.checks import rates_split, split_doubt

    slow = 0.6 + 0.15 * rng.standard_normal(19)
    fast = 4.3 + 0.4 * rng.standard_normal(6)
    result = _result_with_rates(np.r_[slow, fast], reasons=[""] * 19 + ["slides"] * 6)
    assert result.combined.omega_high_rad_s < 3.5
    split = rates_split(result)
    assert split is not None
    slower, faster = split
    assert (slower.tracks_used, faster.tracks_used) == (19, 6)
    assert faster.omega_low_rad_s < 4.3 < faster.omega_high_rad_s
    assert "19 read" in split_doubt(slower, faster) and "6 read" in split_doubt(slower, faster)
    # both groups within the inliers (the truth's fixation): the mean falls between, and again
    assert rates_split(_result_with_rates(np.r_[slow, fast])) is not None
    # a clockwise result's groups are signed as its rate
    mixed = _result_with_rates(np.r_[slow, fast])
    slower, faster = rates_split(replace(mixed, combined=combine(-slow, np.full(19, 0.01))))
    assert faster.omega_rad_s < slower.omega_rad_s < 0
    assert faster.omega_low_rad_s < -4.3 < faster.omega_high_rad_s


def test_one_body_s_scattered_rates_do_not_split(rng: np.random.Generator) -> None:
    """A heavy-tailed scatter of one rate (Student's t, 3 degrees of freedom: tracker slips) does
    not split however many tracks; nor do two groups far apart where the smaller is under the
    share (3 of 25), nor those with tracks between them."""
    from rotrate_cli.stages.checks import SPLIT_MIN_SHARE, rates_split

    for count in (8, 25, 300, 3000):
        assert rates_split(_result_with_rates(0.5 + 0.01 * rng.standard_t(3, count))) is None
    few = np.r_[0.6 + 0.1 * rng.standard_normal(22), 4.0 + 0.1 * rng.standard_normal(3)]
    assert 3 / 25 < SPLIT_MIN_SHARE and rates_split(_result_with_rates(few)) is None
    bridged = np.r_[0.6 + 0.1 * rng.standard_normal(19), np.linspace(0.9, 3.8, 12), 4.0 + 0.1 * rng.standard_normal(6)]
    assert rates_split(_result_with_rates(bridged)) is None
    # off the body's rejected tracks (other motion) are not the body's second group
    apart = np.r_[0.6 + 0.1 * rng.standard_normal(19), 4.0 + 0.1 * rng.standard_normal(6)]
    assert rates_split(_result_with_rates(apart, reasons=[""] * 19 + ["other_motion"] * 6)) is None


def test_an_axis_found_from_two_tracks_leaves_the_rate_open() -> None:
    """Two tracks cannot say how well they place an axis found from them: the interval runs from
    0 to half a turn a frame, either way of turning; with the axis given, or three tracks, the
    interval stays as it was."""
    from dataclasses import replace

    from rotrate_cli.fitting.outliers import Combined
    from rotrate_cli.stages.checks import with_unplaced_axis

    two = _result_with_rates(np.array([0.0148, 0.0129]), se=0.002)
    widened, doubt = with_unplaced_axis(two, fixation_found=True, fps=1.0)
    assert (widened.combined.omega_low_rad_s, widened.combined.omega_high_rad_s) == (0.0, math.pi)
    assert widened.combined.omega_rad_s == two.combined.omega_rad_s and "from 2 tracks" in doubt
    assert with_unplaced_axis(two, fixation_found=False, fps=1.0) == (two, None)
    three = _result_with_rates(np.array([0.0148, 0.0129, 0.0140]), se=0.002)
    assert with_unplaced_axis(three, fixation_found=True, fps=1.0) == (three, None)
    clockwise = replace(two, combined=Combined(-0.014, -0.03, -0.001, 2))
    turned = with_unplaced_axis(clockwise, fixation_found=True, fps=1.0)[0].combined
    assert (turned.omega_low_rad_s, turned.omega_high_rad_s) == (-math.pi, 0.0)


def test_a_coarse_clock_widens_the_tracks_interval() -> None:
    from dataclasses import replace

    import pandas as pd

    from rotrate_cli.fitting.outliers import Combined
    from rotrate_cli.stages.checks import with_clock_doubt
    from rotrate_cli.stages.fits import RateResult

    offsets = pd.DataFrame({"track": [1] * 31, "time_s": np.arange(31.0), "offset_px": np.zeros(31)})
    result = RateResult(offsets, pd.DataFrame(), Combined(0.1, 0.099, 0.101, 20), "ccw")
    widened = with_clock_doubt(result, 1.0).combined  # whole seconds over 30 s: +-3.3%
    assert widened.omega_low_rad_s == pytest.approx(0.1 - math.hypot(0.001, 0.1 / 30), rel=1e-9)
    assert widened.omega_high_rad_s == pytest.approx(0.1 + math.hypot(0.001, 0.1 / 30), rel=1e-9)
    assert with_clock_doubt(result, 0.0).combined == result.combined  # a video's clock
    # an interval that reaches 0 stays there: 1e-17 below it, the next widening took it to -0.30
    # rad/s (EPFL car 02's first 30 photographs, three tracks)
    touching = replace(result, combined=Combined(0.07, 0.0, 0.27, 3, (0.09, 0.07), -1, (0.05, 0.09)))
    widened = with_clock_doubt(touching, 1.0).combined
    assert widened.omega_low_rad_s == 0.0
    assert (widened.senses_rad_s, widened.seen_sense) == ((0.09, 0.07), -1)  # carried through
