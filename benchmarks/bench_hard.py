"""What cameras and rooms do to a clip, default settings: ``make bench-hard``.

The rendered suites hold a still camera in steady light, filming a turn slow enough to follow.
Real clips are filmed by hand, under lights that flicker with the mains, of wheels and fans
that turn tens of degrees a frame, with motion blur. This renders a few bodies (cached in
``bench_out/hard/``), does those things to their frames, and measures each as a new user would
(``analyze --fixation auto``): the error, the interval, whether it covers the truth, the quality
and the sense. A result off by more than 5% must say it is weak.

- shake: the picture shifted by a hand's smooth random shake (2 or 5 px rms) and turned with it
  (0.2 or 0.5 degrees rms);
- flicker: every frame's brightness times 1 + a sin(2 pi 10 t): 50 Hz lights seen at 30 frames/s;
- fast: turns of 10-25 rad/s at 30 frames/s (19-48 degrees a frame);
- blur: each frame the mean of 8 rendered at 8 times the rate (a shutter open all frame long).

The first run renders for about 3 minutes on 2 cores; later runs take about a minute.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, replace
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks.scoring import print_scored, scored  # noqa: E402
from rotrate_cli.video.synth import Renderer, SceneConfig  # noqa: E402

OUT = ROOT / "bench_out" / "hard"


@dataclass(frozen=True)
class Condition:
    name: str
    scene: SceneConfig
    shake_px: float = 0.0
    flicker: float = 0.0
    blur_frames: int = 1


BOX = SceneConfig(shape="box", omega_rad_s=0.5, fps=30.0, duration_s=6.0, seed=21)
CYLINDER = SceneConfig(shape="cylinder", omega_rad_s=0.8, fps=30.0, duration_s=4.0, projection="perspective",
                       fov_deg=40.0, elevation_deg=20.0, seed=22)
HIGH = SceneConfig(shape="cylinder", omega_rad_s=2.0, fps=30.0, duration_s=8.0, elevation_deg=60.0, seed=23)
FAST = SceneConfig(shape="box", omega_rad_s=15.0, fps=30.0, duration_s=3.0, seed=24)

CONDITIONS = (
    Condition("box-shake-2", BOX, shake_px=2.0),
    Condition("box-shake-5", BOX, shake_px=5.0),
    Condition("cylinder-fov40-shake-2", CYLINDER, shake_px=2.0),
    Condition("cylinder-fov40-shake-5", CYLINDER, shake_px=5.0),
    Condition("box-flicker-5", BOX, flicker=0.05),
    Condition("box-flicker-30", BOX, flicker=0.30),
    Condition("cylinder-above-flicker-15", HIGH, flicker=0.15),
    Condition("box-fast-10", replace(FAST, omega_rad_s=10.0)),
    Condition("box-fast-15", FAST),
    Condition("box-fast-25", replace(FAST, omega_rad_s=25.0)),
    Condition("box-blur-3", replace(FAST, omega_rad_s=3.0), blur_frames=8),
    Condition("box-blur-6", replace(FAST, omega_rad_s=6.0), blur_frames=8),
)


def _shake(frames: int, amplitude_px: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """A hand's smooth random shift (frames x 2, px) and turn (degrees), each of rms size."""
    rng = np.random.default_rng(seed)

    def smooth(scale: float) -> np.ndarray:
        noise = np.convolve(rng.normal(0, 1, frames + 40), np.ones(15) / 15, "same")[20:20 + frames]
        return noise / noise.std() * scale

    return np.stack([smooth(amplitude_px), smooth(amplitude_px)], axis=1), smooth(0.1 * amplitude_px)


def render(condition: Condition, path: Path) -> dict:
    """Write the condition's clip and its truth; the truth."""
    scene = condition.scene
    fast = replace(scene, fps=scene.fps * condition.blur_frames)
    renderer = Renderer(fast)
    size = (scene.width_px, scene.height_px)
    frames = fast.frame_count // condition.blur_frames
    shift, turn = _shake(frames, condition.shake_px, scene.seed)
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), scene.fps, size)
    for k in range(frames):
        image = np.mean([renderer.render(k * condition.blur_frames + j).astype(np.float32)
                         for j in range(condition.blur_frames)], axis=0)
        if condition.shake_px:
            matrix = cv2.getRotationMatrix2D((size[0] / 2, size[1] / 2), float(turn[k]), 1.0)
            matrix[:, 2] += shift[k]
            image = cv2.warpAffine(image, matrix, size, borderMode=cv2.BORDER_REPLICATE)
        if condition.flicker:
            image = image * (1 + condition.flicker * math.sin(2 * math.pi * 10.0 * k / scene.fps))
        writer.write(np.clip(image, 0, 255).astype(np.uint8))
    writer.release()
    truth = {"omega_rad_s": abs(scene.omega_rad_s), "direction": "ccw" if scene.omega_rad_s > 0 else "cw"}
    path.with_suffix(".json").write_text(json.dumps(truth))
    return truth


def measure(condition: Condition) -> dict[str, object]:
    path = OUT / f"{condition.name}.mp4"
    truth = json.loads(path.with_suffix(".json").read_text()) if path.exists() else render(condition, path)
    return {"clip": condition.name, "truth": float(truth["omega_rad_s"]), **scored(path, truth)}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1, help="clips measured in parallel")
    args = parser.parse_args()
    OUT.mkdir(parents=True, exist_ok=True)
    with ProcessPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        rows = list(pool.map(measure, CONDITIONS))
    leads = [f"{row['clip']:<26} {row['truth']:>6g} {row['omega']:>8.4f}" for row in rows]
    return 0 if print_scored(f"{'clip':<26} {'truth':>6} {'omega':>8}", leads, rows) else 1

if __name__ == "__main__":
    sys.exit(main())
