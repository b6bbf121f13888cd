"""Several bodies: tracks grouped by rate and axis (analytic tracks and a rendered clip)."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from rotrate_cli import AnalysisConfig, analyze
from rotrate_cli.cli import app
from rotrate_cli.fitting.segment import segment_tracks
from tests.conftest import SAMPLES, truth_of

TWO = SAMPLES / "two_bodies.mp4"


def _bodies(rng: np.random.Generator, specs: list[tuple[float, float]], per_body: int = 40) -> pd.DataFrame:
    """Tracks of bodies ``(omega, axis_px)``: each 30-90 frames at 30 fps, radius 20-120 px,
    0.2 px noise; track ids run on across bodies (body b owns ``b * per_body ...``)."""
    rows = []
    for body, (omega, axis_px) in enumerate(specs):
        for k in range(per_body):
            length = int(rng.integers(30, 90))
            frame = int(rng.integers(0, 100)) + np.arange(length)
            time_s = frame / 30.0
            radius = rng.uniform(20, 120)
            position = axis_px + radius * np.sin(omega * time_s + rng.uniform(0, 2 * np.pi))
            rows.append(pd.DataFrame({"track": body * per_body + k, "frame": frame, "time_s": time_s,
                                      "position": position + rng.normal(0, 0.2, length)}))
    return pd.concat(rows, ignore_index=True)


@pytest.mark.parametrize("specs", [
    [(0.5, 160.0), (1.2, 480.0)],  # side by side
    [(0.5, 320.0), (0.8, 320.0)],  # one axis, two rates (a turntable and a part on it)
    [(0.9, 150.0), (0.9, 450.0), (0.4, 300.0)],  # same rate, different axes; and a third
])
def test_tracks_are_grouped_by_rate_and_axis(rng: np.random.Generator, specs: list[tuple[float, float]]) -> None:
    tracks = _bodies(rng, specs)
    groups = segment_tracks(tracks, tracks["position"].to_numpy(), extent_px=640)
    assert len(groups) == len(specs)
    owners = sorted(sorted({int(t) // 40 for t in group}) for group in groups)
    assert owners == [[b] for b in range(len(specs))]  # no group mixes bodies
    assert sum(len(g) for g in groups) >= 0.9 * len(specs) * 40


def test_one_body_stays_one(rng: np.random.Generator) -> None:
    tracks = _bodies(rng, [(0.7, 300.0)], per_body=120)
    assert len(segment_tracks(tracks, tracks["position"].to_numpy(), extent_px=640)) == 1


def test_two_rendered_bodies_are_measured_each_within_two_percent() -> None:
    truth = truth_of(TWO)["bodies"]
    analysis = analyze(TWO, AnalysisConfig(fixation_px=None, segment=True))
    assert analysis.bodies is not None and len(analysis.bodies) == 2
    for expected in truth:
        body = min(analysis.bodies, key=lambda b: abs(b.axis_px[0] - expected["axis_px"][0]))
        assert body.omega_rad_s == pytest.approx(expected["omega_rad_s"], rel=0.02)
        assert body.omega_low_rad_s <= expected["omega_rad_s"] <= body.omega_high_rad_s
        assert body.axis_px[0] == pytest.approx(expected["axis_px"][0], abs=3.0)
        assert body.direction == expected["direction"]
        assert body.tracks_used >= 50
    assert analysis.omega_rad_s == analysis.bodies[0].omega_rad_s  # the headline is the largest body


@pytest.mark.parametrize(("clip", "options"), [
    # both in make test-slow (7 s and more): a body split in two stays tested by the two bodies' clip
    pytest.param("box_ortho", {}, marks=pytest.mark.slow),
    pytest.param("box_perspective", {"fov_deg": 25.0}, marks=pytest.mark.slow),
])
def test_a_single_body_clip_segments_into_one_body(clip: str, options: dict) -> None:
    path = SAMPLES / f"{clip}.mp4"
    analysis = analyze(path, AnalysisConfig(fixation_px=None, segment=True, **options))
    assert analysis.bodies is not None and len(analysis.bodies) == 1
    assert analysis.omega_rad_s == pytest.approx(truth_of(path)["omega_rad_s"], rel=0.01)


@pytest.mark.slow  # over 10 s: `make test-slow`
def test_segment_on_the_command_line() -> None:
    runner = CliRunner()
    result = runner.invoke(app, ["analyze", str(TWO), "--segment", "--format", "json", "--quiet"])
    assert result.exit_code == 0, result.output
    report = json.loads(result.stdout)
    assert [sorted(body) for body in report["bodies"]] == [
        ["axis_px", "direction", "omega", "omega_high", "omega_low", "rpm", "tracks", "tracks_total"]] * 2
    assert sorted(round(b["omega"], 1) for b in report["bodies"]) == [0.5, 1.2]
    table = runner.invoke(app, ["analyze", str(TWO), "--segment", "--quiet"])
    assert table.exit_code == 0 and "bodies" in table.stdout


@pytest.mark.parametrize(("options", "word"), [
    (["--segment", "--fixation", "320,180"], "--segment"),
    (["--segment", "--fixation", "auto", "--window", "2"], "--window"),
    ([], "--fixation"),
])
def test_segment_usage_errors(options: list[str], word: str) -> None:
    result = CliRunner().invoke(app, ["analyze", str(TWO), *options])
    assert result.exit_code == 2
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("rotrate: error: ") and word in lines[0]


def test_a_group_that_measures_like_a_larger_body_is_not_a_body_of_its_own() -> None:
    # seen on a 32 s 720p cylinder: 57 rim tracks measured 1.27 rad/s about an axis 8 px from the
    # body's (1.57 rad/s); within the resolution, so not reported as a second body
    from types import SimpleNamespace

    from rotrate_cli.stages.bodies import distinct_bodies

    def entry(omega: float, x_px: float) -> tuple:
        geometry = SimpleNamespace(fixation_px=(x_px, 360.0))
        return (geometry, SimpleNamespace(combined=SimpleNamespace(omega_rad_s=omega)), 100)

    measured = [entry(1.57, 638.0), entry(1.27, 630.0), entry(0.5, 640.0), entry(1.57, 1000.0)]
    kept, folded = distinct_bodies(measured, 1.0, 0.0, 1280.0)
    assert folded == 1
    assert [(e[1].combined.omega_rad_s, e[0].fixation_px[0]) for e in kept] == [(1.57, 638.0), (0.5, 640.0),
                                                                                 (1.57, 1000.0)]
