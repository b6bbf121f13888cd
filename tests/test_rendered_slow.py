"""Fresh renders beyond the bundled samples: other seeds, rates, frame rates and sizes.

Slow (rendering takes minutes): ``make test-slow``.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from rotrate_cli import AnalysisConfig, analyze
from rotrate_cli.video.synth import SceneConfig, write_clip

CASES = {
    "slow-spin-cylinder": SceneConfig(shape="cylinder", omega_rad_s=0.1, duration_s=10, fps=15, seed=11),
    "fast-spin-box-60fps": SceneConfig(shape="box", omega_rad_s=-3.14, duration_s=2, fps=60, seed=12),
    "sphere-noisy-10fps": SceneConfig(shape="sphere", omega_rad_s=0.7, duration_s=6, fps=10, noise_sigma=4, seed=13),
    "box-off-centre-axis": SceneConfig(shape="box", omega_rad_s=0.45, duration_s=5, axis_offset_px=-80, seed=14),
}


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(CASES))
def test_rendered_orthographic_clip_within_one_percent(name: str, tmp_path: Path) -> None:
    scene = CASES[name]
    truth = write_clip(scene, tmp_path / f"{name}.mp4")
    result = analyze(tmp_path / f"{name}.mp4", AnalysisConfig(fixation_px=tuple(truth["fixation_px"])))
    assert result.omega_rad_s == pytest.approx(truth["omega_rad_s"], rel=0.01)
    assert result.direction in (truth["direction"], "unknown")


#: Spheres through a 35-degree lens turning 0.6-0.8 rad (bench-random 4009 and 5015).
UNDECIDED_SENSE = {
    4009: SceneConfig(shape="sphere", omega_rad_s=-0.2, fps=30.0, duration_s=4.0, projection="perspective",
                      fov_deg=35.0, axis_offset_px=-80.0, jpeg_quality=30, start_angle_rad=3.706792403697556,
                      seed=4009),
    5015: SceneConfig(shape="sphere", omega_rad_s=0.2, fps=30.0, duration_s=3.0, projection="perspective",
                      fov_deg=35.0, start_angle_rad=1.3433300801933392, seed=5015),
}


@pytest.mark.slow
@pytest.mark.parametrize("seed", sorted(UNDECIDED_SENSE))
def test_an_undecided_sense_does_not_read_as_a_spin_up(seed: int, tmp_path: Path) -> None:
    """The tracks of these spheres do not tell the sense, and a half of the clip fitted in the
    wrong one read as a spin-up; moving the axis for it gave -5.6% and -20.8% (weak). The
    halves' intervals now hold both senses' rates (fits._joint)."""
    write_clip(UNDECIDED_SENSE[seed], tmp_path / "sphere.mp4")
    result = analyze(tmp_path / "sphere.mp4", AnalysisConfig(fixation_px=None))
    assert result.omega_rad_s == pytest.approx(0.2, rel=0.03)
    assert result.omega_low_rad_s <= 0.2 <= result.omega_high_rad_s
    assert not any("rate changes" in line for line in result.warnings)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["out-06", "small-label-03"])
def test_a_record_under_a_turn_with_a_still_tonearm_is_right_or_honestly_weak(name: str, tmp_path: Path) -> None:
    """`make bench-records`' cases that failed: its axis below the frame, 0.6 of a turn, read -14%
    (weak, missing) from far shifts found at their search's edge (the tonearm's peak reaching in);
    a small label's dust tracks saw 20 degrees of the turn, and their plane read +0.77% within
    +-0.5%, good, missing. Needs the shared photographs (the labels)."""
    from benchmarks.bench_records import CASES as RECORDS
    from benchmarks.bench_records import DATA, render
    from tests.conftest import need

    need(DATA / "epfl_cars", "the shared EPFL photographs")
    case = next(case for case in RECORDS if case.name == name)
    clip = tmp_path / f"{name}.mp4"
    render(case, clip)
    result = analyze(clip, AnalysisConfig(fixation_px=None))
    truth = abs(case.omega_rad_s)
    assert result.omega_low_rad_s <= truth <= result.omega_high_rad_s
    if result.quality == "good":
        assert result.omega_rad_s == pytest.approx(truth, rel=0.01)
    if name == "out-06":
        assert result.quality == "good"
