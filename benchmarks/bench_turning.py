"""Flat rotors rendered under a turn (0.3 of a turn, as issue 49 asks), face on and tilted 45-75
degrees, the axis in the frame and out of it, measured with default settings (``--fixation
auto``): no return of the picture, so the rate is the picture's own turning angle or the tracks'.
Textured discs and fans (:mod:`rotrate_cli.video.rotor`); one marked blade, so that the picture
repeats once a turn.

    python benchmarks/bench_turning.py            # every case (about a minute the first time)
    python benchmarks/bench_turning.py --only tilt

Target: every result within 0.5% of the truth, good, its interval holding the truth. Exits 1
when a good result is more than 0.5% off or its interval misses. Renders are cached in
bench_out/turning.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks.scoring import only_option, rendered_cases  # noqa: E402
from rotrate_cli.video.rotor import RotorScene, rotor_truth, write_rotor_clip  # noqa: E402

OUT = ROOT / "bench_out" / "turning"
#: Within this (a fraction) a result is right.
WITHIN = 0.005
#: The share of a turn each clip shows.
SHARE = 0.3


def _scene(kind: str, omega: float, seed: int, **more: object) -> RotorScene:
    duration = SHARE * 2.0 * math.pi / abs(omega)
    return RotorScene(kind, 1, omega, duration_s=duration, mark=True, texture=1.0,
                      seed=seed, **more)  # type: ignore[arg-type]


@dataclass(frozen=True)
class Case:
    name: str
    rotor: RotorScene


CASES = (
    Case("disc-face", _scene("checker", 1.5, 31)),
    Case("disc-face-fast", _scene("checker", -4.0, 32)),
    Case("fan-face", _scene("fan", 2.0, 33)),
    Case("disc-tilt45", _scene("checker", 1.2, 34, tilt_deg=45.0)),
    Case("disc-tilt60", _scene("checker", -1.8, 35, tilt_deg=60.0)),
    Case("disc-tilt75", _scene("checker", 2.5, 36, tilt_deg=75.0)),
    Case("disc-face-off-frame", _scene("checker", 1.6, 37, centre_px=(560.0, 180.0), radius_px=300.0)),
    Case("disc-tilt60-off-frame", _scene("checker", 2.2, 38, tilt_deg=60.0, centre_px=(240.0, -60.0),
                                         radius_px=320.0)),
)


def main() -> int:
    only = only_option(__doc__ or "", "cases")
    OUT.mkdir(parents=True, exist_ok=True)
    chosen = [(case.name, OUT / f"{case.name}.mp4", lambda path, case=case: write_rotor_clip(case.rotor, path),
               rotor_truth(case.rotor)) for case in CASES if not only or only in case.name]
    return rendered_cases(chosen, WITHIN, 24, f"{WITHIN:.1%}")

if __name__ == "__main__":
    sys.exit(main())
