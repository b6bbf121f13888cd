"""Rejection rules and the combined estimate with its interval."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from rotrate_cli import rates
from rotrate_cli.outliers import RejectionConfig, combine, judge_fits


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
    verdict = judge_fits(samples, rates.fit_tracks(samples), RejectionConfig()).set_index("track")["reason"]
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

    from rotrate_cli.fits import RateResult
    from rotrate_cli.outliers import Combined

    rows, offsets = [], []
    for k in range(2 * per_side):
        left = k < per_side
        rows.append({"track": k + 1, "omega_rad_s": (left_rate if left else right_rate) * (1 + 0.002 * (k % 3)),
                     "omega_se_rad_s": 0.001, "inlier": True})
        offsets += [{"track": k + 1, "offset_px": (-50.0 if left else 50.0) + d} for d in (-10.0, 0.0, 10.0)]
    combined = Combined((left_rate + right_rate) / 2, 0.9 * left_rate, 1.1 * right_rate, 2 * per_side)
    return RateResult(pd.DataFrame(offsets), pd.DataFrame(rows), combined, "ccw")


def test_tracks_either_side_of_the_axis_must_agree() -> None:
    from rotrate_cli.doubts import sides_disagree

    assert sides_disagree(_result_with_sides(0.50, 0.50)) is None
    doubt = sides_disagree(_result_with_sides(0.46, 0.50))  # 8% apart, each side tight
    assert doubt is not None and "either side of the axis" in doubt
    assert sides_disagree(_result_with_sides(0.46, 0.50, per_side=2)) is None  # too few to tell


def test_sides_that_disagree_widen_the_interval_to_hold_both() -> None:
    """Which side is off is not known: the interval holds both sides' rates (an EPFL car's first
    70 photographs: +5.6% within [+1.9%, +9.3%], the left side 13% lower; now [-22.8%, +9.3%])."""
    from dataclasses import replace

    from rotrate_cli.doubts import with_sides_span
    from rotrate_cli.outliers import Combined

    apart = _result_with_sides(0.46, 0.50)
    narrow = replace(apart, combined=Combined(0.495, 0.49, 0.50, 12))  # the joint fit followed one side
    widened = with_sides_span(narrow).combined
    assert widened.omega_rad_s == 0.495
    assert widened.omega_low_rad_s < 0.461 and widened.omega_high_rad_s >= 0.50
    same = replace(_result_with_sides(0.50, 0.50), combined=Combined(0.5, 0.499, 0.501, 12))
    assert with_sides_span(same).combined == same.combined  # sides that agree change nothing


def test_a_coarse_clock_widens_the_tracks_interval() -> None:
    from dataclasses import replace

    import pandas as pd

    from rotrate_cli.doubts import with_clock_doubt
    from rotrate_cli.fits import RateResult
    from rotrate_cli.outliers import Combined

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
