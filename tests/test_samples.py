"""Regression on the bundled sample clips: the user's own CI use of rotrate."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from rotrate_cli import AnalysisConfig, analyze
from rotrate_cli.cli import app
from tests.conftest import SAMPLES, direction_seen_as, truth_of

ORTHOGRAPHIC = sorted(p for p in SAMPLES.glob("*.mp4") if truth_of(p)["scene"]["projection"] == "orthographic"
                      and not truth_of(p)["scene"].get("alpha_rad_s2"))  # constant rates


def test_there_are_orthographic_samples_of_every_shape() -> None:
    assert {truth_of(p)["scene"]["shape"] for p in ORTHOGRAPHIC} == {"box", "cylinder", "sphere"}


@pytest.mark.parametrize("clip", ORTHOGRAPHIC, ids=lambda p: p.stem)
def test_orthographic_sample_within_one_percent(clip: Path) -> None:
    truth = truth_of(clip)
    result = analyze(clip, AnalysisConfig(fixation_px=tuple(truth["fixation_px"])))
    assert result.omega_rad_s == pytest.approx(truth["omega_rad_s"], rel=0.01)
    assert result.omega_low_rad_s <= truth["omega_rad_s"] <= result.omega_high_rad_s
    assert result.direction == direction_seen_as(truth, result.axis_angle_deg)
    assert result.tracks_used >= 50
    assert result.frames == truth["frames"]


def test_cli_json_on_a_sample_has_the_documented_fields() -> None:
    clip = SAMPLES / "box_ortho.mp4"
    fx, fy = truth_of(clip)["fixation_px"]
    result = CliRunner().invoke(app, ["analyze", str(clip), "--fixation", f"{fx},{fy}", "--format", "json"])
    assert result.exit_code == 0, result.output
    report = json.loads(result.stdout)
    for key in ("video", "fps", "frames", "duration_s", "fixation", "omega", "omega_low", "omega_high", "rpm",
                "direction", "tracks_total", "tracks_used", "features"):
        assert key in report
    assert report["fps"] == 30 and report["frames"] == 150
    assert report["duration_s"] == pytest.approx(149 / 30, abs=1e-6)
    assert report["rpm"] == pytest.approx(report["omega"] * 60 / (2 * 3.141592653589793), rel=1e-4)
    feature = report["features"][0]
    assert set(feature) >= {"feature", "omega", "inlier", "reason", "samples"}
    used = [f for f in report["features"] if f["inlier"]]
    assert len(used) == report["tracks_used"]
    assert all(f["reason"] for f in report["features"] if not f["inlier"])


def test_perspective_sample_with_the_pinhole_model() -> None:
    clip = SAMPLES / "box_perspective.mp4"
    truth = truth_of(clip)
    fixation = tuple(truth["fixation_px"])
    plain = analyze(clip, AnalysisConfig(fixation_px=fixation, find_focal=False))  # --fov ortho
    corrected = analyze(clip, AnalysisConfig(fixation_px=fixation, fov_deg=truth["scene"]["fov_deg"]))
    found = analyze(clip, AnalysisConfig(fixation_px=fixation))  # the default: the lens found
    assert abs(plain.omega_rad_s / truth["omega_rad_s"] - 1) > 0.03  # what perspective costs the paper's model
    assert plain.camera_from == "orthographic" and found.camera_from == "found"
    assert found.omega_rad_s == pytest.approx(truth["omega_rad_s"], rel=0.01)
    assert found.omega_low_rad_s <= truth["omega_rad_s"] <= found.omega_high_rad_s
    assert corrected.omega_rad_s == pytest.approx(truth["omega_rad_s"], rel=0.01)
    assert corrected.omega_low_rad_s <= truth["omega_rad_s"] <= corrected.omega_high_rad_s
    assert corrected.direction == truth["direction"]
