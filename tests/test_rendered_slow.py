"""Fresh renders beyond the bundled samples: other seeds, rates, frame rates and sizes.

Slow (rendering takes minutes): ``make test-slow``.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from rotrate_cli import AnalysisConfig, analyze
from rotrate_cli.synth import SceneConfig, write_clip

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
