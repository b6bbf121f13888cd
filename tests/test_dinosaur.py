"""Real turntable photographs with published ground truth (Oxford 'dinosaur')."""

from __future__ import annotations

import json

import pytest

from rotrate_cli import AnalysisConfig, analyze
from rotrate_cli.analysis import analyze_tracks
from rotrate_cli.tracks_io import read_tracks
from tests.conftest import DINOSAUR, need


def test_dinosaur_photographs_within_two_percent() -> None:
    need(DINOSAUR / "frames", "the dinosaur photographs")
    truth = json.loads((DINOSAUR / "truth.json").read_text())
    result = analyze(DINOSAUR / "frames", AnalysisConfig(fixation_px=tuple(truth["fixation_px"]), fps=1.0))
    assert result.omega_rad_s == pytest.approx(truth["radians_per_frame"], rel=0.02)
    assert result.omega_low_rad_s <= truth["radians_per_frame"] <= result.omega_high_rad_s
    assert result.direction in (truth["direction"], "unknown")
    assert result.frames == 36


def test_dinosaur_printf_pattern_reads_the_same_frames() -> None:
    need(DINOSAUR / "frames", "the dinosaur photographs")
    pattern = str(DINOSAUR / "frames" / "viff.%03d.png")
    result = analyze(pattern, AnalysisConfig(fixation_px=(353.4, 288.0), fps=2.0, end_s=10.0))
    assert result.frames == 21  # 0 .. 10 s at 2 fps
    assert result.omega_rad_s == pytest.approx(2 * 0.174533, rel=0.05)


def test_dinosaur_published_tracks_within_one_percent() -> None:
    need(DINOSAUR / "tracks.csv", "the dinosaur's published tracks")
    truth = json.loads((DINOSAUR / "truth.json").read_text())
    tracks = read_tracks(DINOSAUR / "tracks.csv", "x")
    result = analyze_tracks(tracks, truth["fixation_px"][0], fps=1.0, source="tracks.csv")
    assert result.omega_rad_s == pytest.approx(truth["radians_per_frame"], rel=0.01)
    assert result.tracks_used > 500
    assert result.direction in (truth["direction"], "unknown")
