"""Rejection rules and the combined estimate with its interval."""

from __future__ import annotations

import numpy as np
import pandas as pd

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
