"""Random rendered conditions, default settings: ``make bench-random``.

The accuracy suite (``bench_accuracy.py``) measures 17 chosen conditions with the true fixation
given. This draws conditions at random from a seeded generator (shape, rate and sense, frame
rate, length down to 2 s, orthographic or a 35-75 degree lens, axis offset, noise, JPEG, a slight
roll, elevation up to 60 degrees), renders each once (cached in ``bench_out/random/``) and
measures it as a new user would: ``analyze`` with ``--fixation auto`` and nothing else. It
reports what the standards ask of every result: the interval covers the truth, a result off by
more than 5% says it is weak, and the sense is right (or unknown). The first run renders for
about 10 minutes on 2 cores; later runs take about a minute.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import random
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks.scoring import print_scored, scored  # noqa: E402
from rotrate_cli.video.synth import SceneConfig, write_clip  # noqa: E402

OUT = ROOT / "bench_out" / "random"


def condition(index: int, seed: int) -> SceneConfig:
    """The ``index``-th random condition of the generator seeded with ``seed``."""
    draw = random.Random(seed * 100_003 + index)
    perspective = draw.random() < 2 / 3
    return SceneConfig(
        shape=draw.choice(["box", "cylinder", "sphere"]),
        omega_rad_s=draw.choice([-1, 1]) * draw.choice([0.2, 0.4, 0.8, 1.5, 3.0]),
        fps=draw.choice([24.0, 30.0]), duration_s=draw.choice([2.0, 3.0, 4.0, 6.0]),
        projection="perspective" if perspective else "orthographic",
        fov_deg=draw.choice([35.0, 50.0, 65.0, 75.0]) if perspective else 25.0,
        axis_offset_px=draw.choice([0.0, 0.0, 40.0, -80.0]), noise_sigma=draw.choice([0.0, 0.0, 2.0, 5.0]),
        jpeg_quality=draw.choice([None, None, None, 30]), roll_deg=draw.choice([0.0, 0.0, 0.0, 15.0]),
        elevation_deg=draw.choice([0.0, 0.0, 15.0, 30.0, 60.0]), start_angle_rad=draw.uniform(0.0, 2 * math.pi),
        seed=seed * 1000 + index,
    )


def measure(item: tuple[int, SceneConfig]) -> dict[str, object]:
    index, scene = item
    path = OUT / f"random-{scene.seed}.mp4"
    truth = json.loads(path.with_suffix(".json").read_text()) if path.exists() else write_clip(scene, path, force=True)
    row: dict[str, object] = {
        "clip": path.stem, "shape": scene.shape, "omega": scene.omega_rad_s, "s": scene.duration_s,
        "lens": f"{scene.fov_deg:g}" if scene.projection == "perspective" else "ortho",
        "elevation": scene.elevation_deg, "noise": scene.noise_sigma, "jpeg": scene.jpeg_quality or "-",
    }
    row.update({key: value for key, value in scored(path, truth).items() if key != "omega"})
    return row


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=20, help="conditions drawn")
    parser.add_argument("--seed", type=int, default=1, help="the generator's seed (another draws other conditions)")
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1, help="clips measured in parallel")
    args = parser.parse_args()
    OUT.mkdir(parents=True, exist_ok=True)
    items = [(k, condition(k, args.seed)) for k in range(args.count)]
    with ProcessPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        rows = list(pool.map(measure, items))
    leads = [f"{row['clip']:<14} {row['shape']:<8} {row['omega']:>5g} {row['s']:>3g} {row['lens']:>5} "
             f"{row['elevation']:>4g} {row['noise']:>5g} {row['jpeg']!s:>4}" for row in rows]
    header = (f"{'clip':<14} {'shape':<8} {'omega':>5} {'s':>3} {'lens':>5} {'elev':>4} {'noise':>5} "
              f"{'jpeg':>4}")
    return 0 if print_scored(header, leads, rows) else 1

if __name__ == "__main__":
    sys.exit(main())
