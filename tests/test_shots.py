"""Cuts in a clip (:mod:`rotrate_cli.shots`): found between two scenes, not in fast motion, a
shaken camera or a single flash; and a clip that opens on a still, other picture is measured on
its longest shot."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from rotrate_cli.shots import cuts, longest_shot


def _texture(seed: int, size: int = 64) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return cv2.GaussianBlur(rng.uniform(0, 255, (3 * size, 10 * size)).astype(np.float32), (0, 0), 2.0)


def _moving(texture: np.ndarray, count: int, step_px: float, size: int = 64, start: int = 0) -> list[np.ndarray]:
    """``count`` thumbnails of ``texture`` seen through a window that slides ``step_px`` a frame."""
    frames = []
    for index in range(start, start + count):
        shift = index * step_px
        matrix = np.float32([[1, 0, -shift], [0, 1, -size]])
        frames.append(cv2.warpAffine(texture, matrix, (size, size)).clip(0, 255).astype(np.uint8).ravel())
    return frames


def test_a_still_other_picture_before_the_turning_is_a_cut() -> None:
    images = np.stack(_moving(_texture(1), 1, 0.0) + _moving(_texture(2), 60, 0.5))
    assert cuts(images) == [1]
    shot = longest_shot(np.arange(61) / 30.0, images)
    assert shot is not None
    assert (shot.first, shot.last, shot.cuts) == (1, 60, 1)
    assert shot.start_s == pytest.approx(1 / 30.0)
    assert "cuts once" in shot.note


def test_of_three_shots_the_longest_is_measured() -> None:
    images = np.stack(_moving(_texture(1), 20, 0.5) + _moving(_texture(2), 50, 0.5) + _moving(_texture(3), 30, 0.5))
    assert cuts(images) == [20, 70]
    shot = longest_shot(np.arange(100) / 25.0, images)
    assert shot is not None and (shot.first, shot.last, shot.cuts) == (20, 69, 2)


@pytest.mark.parametrize("step_px", [0.3, 2.0, 6.0])
def test_motion_alone_is_no_cut(step_px: float) -> None:
    """The whole picture moving, slowly or by several pixels a frame (a 64-px thumbnail of a fast
    turn), changes every frame alike."""
    assert cuts(np.stack(_moving(_texture(4), 80, step_px))) == []


def test_a_camera_jolt_is_no_cut(rng: np.random.Generator) -> None:
    """A hand-held camera: the picture jumps a few pixels at random, most frames a little."""
    texture = _texture(5)
    frames = []
    for index in range(90):
        jolt = rng.normal(0.0, 1.0, 2) * (4.0 if index % 17 == 0 else 0.7)
        matrix = np.float32([[1, 0, -0.5 * index + jolt[0]], [0, 1, jolt[1] - 64]])
        frames.append(cv2.warpAffine(texture, matrix, (64, 64)).clip(0, 255).astype(np.uint8).ravel())
    assert cuts(np.stack(frames)) == []


def test_a_single_flash_is_no_cut() -> None:
    """A flash (or a glitched frame) differs from both its neighbours, which match each other."""
    frames = _moving(_texture(6), 60, 0.5)
    frames[30] = np.clip(frames[30].astype(np.int32) + 120, 0, 255).astype(np.uint8)
    assert cuts(np.stack(frames)) == []


def test_a_still_clip_is_no_cut() -> None:
    """Nothing moves: the change is the noise alone; a small change of light is no cut."""
    base = _moving(_texture(7), 1, 0.0)[0].astype(np.int32)
    noise = np.random.default_rng(8).normal(0, 0.3, (50, base.size))
    frames = np.clip(base + noise + np.where(np.arange(50) >= 25, 3.0, 0.0)[:, None], 0, 255).astype(np.uint8)
    assert cuts(frames) == []


@pytest.mark.parametrize("opening", ["still", "black"])
def test_a_clip_that_opens_on_another_picture_is_measured_on_its_turning(tmp_path, opening: str) -> None:
    """A calibration still before the turning starts (the real bicycle wheel's first frame), or
    half a second of black: the tracks seeded on it and the repetition read across it spoilt the
    measurement. After black, the light's steadying held the picture black for 5 more frames
    (brought to the recent frames' median brightness), and the cut was found 5 frames late."""
    from rotrate_cli.analysis import AnalysisConfig, analyze
    from rotrate_cli.synth import Renderer, SceneConfig

    scene = SceneConfig(shape="box", omega_rad_s=0.8, fps=30.0, duration_s=3.0, supersample=1, seed=11)
    still = Renderer(SceneConfig(shape="cylinder", omega_rad_s=0.8, seed=12, supersample=1)).render(0)
    renderer = Renderer(scene)
    clip = tmp_path / "calibrated.mp4"
    writer = cv2.VideoWriter(str(clip), cv2.VideoWriter_fourcc(*"mp4v"), scene.fps, (scene.width_px, scene.height_px))
    for _ in range(1 if opening == "still" else 15):
        writer.write(still if opening == "still" else np.zeros_like(still))
    for index in range(scene.frame_count):
        writer.write(renderer.render(index))
    writer.release()
    result = analyze(clip, AnalysisConfig(fixation_px=None))
    assert result.omega_rad_s == pytest.approx(0.8, rel=0.01)
    assert result.omega_low_rad_s <= 0.8 <= result.omega_high_rad_s
    assert any("cuts once" in warning for warning in result.warnings)
    assert result.frames == scene.frame_count
