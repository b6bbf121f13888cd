"""Bodies whose picture repeats n times a turn (fans, spokes, checkered discs and drums), measured
with default settings (``--fixation auto``): the picture's return comes after 1/n of a turn, and a
rule that takes it for a turn reads n times too fast. Face on and tilted (rotor renders,
:mod:`rotrate_cli.video.rotor`), from the side (:mod:`rotrate_cli.video.synth` with a symmetric
texture), slow and at 20-40 degrees a frame; flat paint (little for the tracks to follow) and
rich texture; a marked blade (the picture repeats once a turn).

    python benchmarks/bench_symmetry.py            # every case (about 2 minutes the first time)
    python benchmarks/bench_symmetry.py --only fan

Target: every result within 0.5% of the truth or weak, and none a multiple of the rate (2x or
more off) called good. Exits 1 when a case misses it. Renders are cached in bench_out/symmetry.
"""

from __future__ import annotations

import math
import sys
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks.scoring import SCORE_HEADER, finish, only_option, score_columns, scored  # noqa: E402
from rotrate_cli.video.rotor import RotorScene, rotor_truth, write_rotor_clip  # noqa: E402
from rotrate_cli.video.synth import SceneConfig, truth, write_clip  # noqa: E402

OUT = ROOT / "bench_out" / "symmetry"
#: Within this (a fraction) a good result is right.
GOOD_WITHIN = 0.005


def _deg_a_frame(degrees: float, fps: float = 30.0) -> float:
    return math.radians(degrees) * fps


@dataclass(frozen=True)
class Case:
    name: str
    rotor: RotorScene | None = None
    drum: SceneConfig | None = None


CASES = (
    Case("fan2-face", RotorScene("fan", 2, 1.7, texture=0.6, seed=1)),
    Case("fan3-face-flat", RotorScene("fan", 3, 2.4, texture=0.0, seed=2)),
    Case("fan4-tilt60", RotorScene("fan", 4, 1.9, tilt_deg=60, texture=0.5, seed=3)),
    Case("fan5-face-flat", RotorScene("fan", 5, 2.0, texture=0.0, seed=4)),
    Case("fan5-face-textured", RotorScene("fan", 5, 2.0, seed=5)),
    Case("fan5-marked", RotorScene("fan", 5, 2.0, mark=True, duration_s=6.0, seed=6)),
    Case("fan6-tilt45-off-frame", RotorScene("fan", 6, 1.3, tilt_deg=45, centre_px=(470.0, 200.0), texture=0.4,
                                               duration_s=5.0, seed=7)),
    Case("spokes6-face-flat", RotorScene("spokes", 6, 1.5, texture=0.0, duration_s=5.0, seed=8)),
    Case("spokes8-tilt55", RotorScene("spokes", 8, 1.2, texture=0.1, tilt_deg=55, duration_s=5.0, seed=9)),
    Case("spokes12-face", RotorScene("spokes", 12, 0.9, texture=0.3, duration_s=6.0, seed=10)),
    Case("checker8-face", RotorScene("checker", 8, 1.2, texture=0.2, duration_s=6.0, seed=11)),
    Case("checker16-tilt40", RotorScene("checker", 16, 0.8, texture=0.2, tilt_deg=40, duration_s=6.0, seed=12)),
    Case("fan4-fast-35deg", RotorScene("fan", 4, _deg_a_frame(35), texture=0.3, duration_s=3.0, seed=13)),
    Case("fan6-fast-25deg", RotorScene("fan", 6, _deg_a_frame(25), texture=0.3, duration_s=3.0, seed=14)),
    Case("spokes3-fast-40deg", RotorScene("spokes", 3, _deg_a_frame(40), texture=0.5, duration_s=3.0, seed=15)),
    Case("fan2-fast-20deg", RotorScene("fan", 2, _deg_a_frame(20), texture=0.8, duration_s=3.0, seed=16)),
    # flat blades whose count the picture's own angle tells (their first step fits a blade on as
    # well: readings a count of the return must rule out), tilted, clockwise, with the axis out of
    # the frame, and at 10 degrees a frame, where the angle's first step fits two ways
    Case("fan3-flat-tilt40", RotorScene("fan", 3, 2.0, texture=0.0, tilt_deg=40, duration_s=3.0, seed=21)),
    Case("fan4-flat-cw", RotorScene("fan", 4, -1.6, texture=0.0, duration_s=3.0, seed=22)),
    Case("fan3-flat-off-frame", RotorScene("fan", 3, 1.5, texture=0.0, centre_px=(520.0, 180.0), radius_px=220,
                                           duration_s=4.0, seed=25)),
    Case("fan5-flat-10deg", RotorScene("fan", 5, _deg_a_frame(10), texture=0.0, duration_s=2.5, seed=23)),
    Case("drum16-checker-side", drum=SceneConfig("cylinder", 1.3, duration_s=6.0, symmetry=16, checker=True, seed=17)),
    Case("drum6-side", drum=SceneConfig("cylinder", 0.8, duration_s=5.0, symmetry=6, seed=18)),
    Case("drum4-checker-side-fast", drum=SceneConfig("cylinder", _deg_a_frame(25), duration_s=3.0, symmetry=4,
                                                    checker=True, seed=19)),
)


def _clip(case: Case) -> tuple[Path, dict]:
    """The case's clip (rendered once) and its truth."""
    path = OUT / f"{case.name}.mp4"
    if case.rotor is not None:
        record = rotor_truth(case.rotor)
        if not path.exists():
            write_rotor_clip(case.rotor, path)
        return path, record
    assert case.drum is not None  # noqa: S101 - a case is one or the other
    if not path.exists():
        return path, write_clip(case.drum, path)
    from rotrate_cli.video.synth import Renderer

    return path, truth(case.drum, Renderer(case.drum))


def main() -> int:
    only = only_option(__doc__ or "", "cases")
    OUT.mkdir(parents=True, exist_ok=True)
    print(f"{'case':<26} {'repeats':>7} {'truth':>8} {'rotrate':>8} {SCORE_HEADER}")
    misses, rows = [], 0
    for case in CASES:
        if only and only not in case.name:
            continue
        path, record = _clip(case)
        started = time.perf_counter()
        row = scored(path, record)
        rows += 1
        error = abs(float(row["error_pct"])) / 100 if math.isfinite(float(row["error_pct"])) else math.inf
        repeats = int(record["repeats_per_turn"]) if case.rotor is not None else case.drum.symmetry
        print(f"{case.name:<26} {repeats:>7} {float(record['omega_rad_s']):>8.4f} {float(row['omega']):>8.4f} "
              f"{score_columns(row)}  {time.perf_counter() - started:.1f} s")
        if row["quality"] == "good" and error > GOOD_WITHIN:
            misses.append(f"{case.name}: {float(row['error_pct']):+.2f}% and good")
    return finish(f"cases {rows}; good and more than {GOOD_WITHIN:.1%} off: {len(misses)}", misses)


if __name__ == "__main__":
    sys.exit(main())
