"""Clocks rendered under a turn: a second hand sweeping or stepping once a second over a third of a
turn (20 s), its minute hand creeping, the face seen face on or tilted, filmed by a camera that
stands still, or rolls and wobbles, or is held in the hand (it also leans, comes nearer and goes
back, and its exposure follows the light); measured with default settings (``--fixation
auto``). The hand is two pixels wide: its tracks slide along it, and a hand that steps changes no
pixel between most frames, so the rate is the picture's turning (:mod:`rotrate_cli.scene.hand`).

    python benchmarks/bench_clock.py            # every case (about a minute and a half the first time)
    python benchmarks/bench_clock.py --only roll

The wall behind is a frame of the shared bicycle-wheel clip where ../shared is there, else a
rendered texture. Target: nothing off by more than 1% and good, no good interval missing the truth.
Exits 1 otherwise. Renders are cached in bench_out/clock.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks.scoring import only_option, rendered_cases  # noqa: E402

OUT = ROOT / "bench_out" / "clock"
WALL = ROOT.parent / "shared" / "data" / "real_videos" / "bicycle_wheel_frontal.mp4"
#: Within this (a fraction) a good result is right.
WITHIN = 0.01
FPS = 30
SIZE = (640, 480)


@dataclass(frozen=True)
class Clock:
    """A clock clip: the second hand's rate (degrees a second, clockwise), whether it steps each
    second, the face's tilt (degrees, about a line 30 degrees from x), the camera's roll (degrees a
    second) and a hand's wobble (1.5 degrees and 12 px), the face's radius, the clip's length; and
    a camera held in the hand: how far it leans to and fro (degrees, about both axes, its focal
    length 700 px), how much nearer it comes and goes back (a fraction), how far its exposure
    follows the light (a fraction), and its tremor (px rms a frame, and a seventh as many degrees
    of roll)."""

    hand_deg_s: float = 6.0
    ticking: bool = False
    tilt_deg: float = 0.0
    roll_deg_s: float = 0.0
    wobble: bool = False
    radius_px: int = 150
    seconds: float = 20.0
    lean_deg: float = 0.0
    zoom: float = 0.0
    exposure: float = 0.0
    tremor_px: float = 0.0


CASES = {
    "sweep": Clock(),
    "tick": Clock(ticking=True),
    "tilt30": Clock(tilt_deg=30.0),
    "tilt55-tick": Clock(tilt_deg=55.0, ticking=True),
    "short-8s": Clock(seconds=8.0),
    "roll3": Clock(roll_deg_s=3.0),
    "roll3-wobble-tick": Clock(roll_deg_s=3.0, wobble=True, ticking=True),
    "roll-2-small-tick": Clock(roll_deg_s=-2.0, ticking=True, radius_px=70),
    "roll3-wobble-tilt35": Clock(roll_deg_s=3.0, wobble=True, tilt_deg=35.0),
    "wobble-tilt35": Clock(wobble=True, tilt_deg=35.0),
    "in-hand-tick": Clock(roll_deg_s=2.0, wobble=True, ticking=True, lean_deg=2.0, zoom=0.04, exposure=0.08),
    "in-hand-tilt40": Clock(roll_deg_s=-2.0, wobble=True, tilt_deg=40.0, lean_deg=1.5, zoom=0.03, exposure=0.05),
    "in-hand-tremor-10s": Clock(roll_deg_s=-4.0, wobble=True, seconds=10.0, lean_deg=2.0, zoom=0.04,
                                exposure=0.08, tremor_px=2.0),
}


def _wall() -> np.ndarray:
    reader = cv2.VideoCapture(str(WALL))
    reader.set(cv2.CAP_PROP_POS_FRAMES, 100)
    ok, frame = reader.read()
    reader.release()
    if ok:
        return frame
    rng = np.random.default_rng(4)
    texture = cv2.resize(rng.random((48, 64)).astype(np.float32), SIZE, interpolation=cv2.INTER_CUBIC)
    return cv2.cvtColor((texture * 160 + 50).astype(np.uint8), cv2.COLOR_GRAY2BGR)


def _hand(image: np.ndarray, centre: tuple[int, int], clock_deg: float, length: float, width: int,
          colour: tuple[int, int, int]) -> None:
    a, s = math.radians(clock_deg), 16  # sub-pixel ends (4 fractional bits)
    cx, cy = centre
    tail = (int(s * (cx - 0.15 * length * math.sin(a))), int(s * (cy + 0.15 * length * math.cos(a))))
    tip = (int(s * (cx + length * math.sin(a))), int(s * (cy - length * math.cos(a))))
    cv2.line(image, tail, tip, colour, width, cv2.LINE_AA, shift=4)


def _in_hand(clock: Clock, time_s: float) -> np.ndarray:
    """The view (3x3, on the picture) of a camera that leans to and fro about its centre and comes
    nearer and goes back (:attr:`Clock.lean_deg`, :attr:`Clock.zoom`); none where it does neither."""
    width, height = SIZE
    lean = np.radians([clock.lean_deg * math.sin(2 * math.pi * 0.45 * time_s + 2.0),
                       clock.lean_deg * math.sin(2 * math.pi * 0.3 * time_s + 0.7), 0.0])
    turn, _ = cv2.Rodrigues(lean)
    focal = 700.0 * (1.0 + clock.zoom * math.sin(2 * math.pi * 0.1 * time_s + 1.3))
    inner = np.array([[700.0, 0.0, width / 2], [0.0, 700.0, height / 2], [0.0, 0.0, 1.0]])
    outer = np.array([[focal, 0.0, width / 2], [0.0, focal, height / 2], [0.0, 0.0, 1.0]])
    return outer @ turn @ np.linalg.inv(inner)


def write_clock(clock: Clock, path: Path) -> None:
    width, height = SIZE
    wall = cv2.resize(_wall(), (2 * width, 2 * height))
    cx, cy, radius = width, height, clock.radius_px
    face = wall.copy()
    cv2.circle(face, (cx, cy), radius + 8, (40, 40, 40), -1)
    cv2.circle(face, (cx, cy), radius, (235, 235, 230), -1)
    for k in range(60):
        a = math.radians(6 * k)
        inner = radius - (18 if k % 5 == 0 else 8)
        cv2.line(face, (int(cx + inner * math.sin(a)), int(cy - inner * math.cos(a))),
                 (int(cx + (radius - 3) * math.sin(a)), int(cy - (radius - 3) * math.cos(a))), (20, 20, 20),
                 3 if k % 5 == 0 else 1, cv2.LINE_AA)
    b = math.radians(30.0)
    turn = np.array([[math.cos(b), -math.sin(b)], [math.sin(b), math.cos(b)]])
    squash = turn @ np.diag([1.0, math.cos(math.radians(clock.tilt_deg))]) @ turn.T
    tilt = np.hstack([squash, (np.array([cx, cy]) - squash @ np.array([cx, cy]))[:, None]])
    rng = np.random.default_rng(2)
    tremor = np.random.default_rng(9)
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), FPS, SIZE)
    for index in range(int(clock.seconds * FPS)):
        time_s = index / FPS
        image = face.copy()
        _hand(image, (cx, cy), 300.0 + 0.1 * time_s, radius * 0.55, 7, (10, 10, 10))  # the minute hand
        second = 40.0 + clock.hand_deg_s * (math.floor(time_s) if clock.ticking else time_s)
        _hand(image, (cx, cy), second, radius * 0.92, 2, (30, 30, 200))
        cv2.circle(image, (cx, cy), 6, (30, 30, 200), -1)
        if clock.tilt_deg:
            image = cv2.warpAffine(image, tilt, (2 * width, 2 * height), flags=cv2.INTER_LINEAR)
        roll, dx, dy = clock.roll_deg_s * time_s, 0.0, 0.0
        if clock.tremor_px:
            jolt = tremor.normal(0.0, clock.tremor_px, 3)
            roll, dx, dy = roll + jolt[0] / 7.0, jolt[1], jolt[2]
        if clock.wobble:
            roll += 1.5 * math.sin(2 * math.pi * 0.7 * time_s)
            dx += 12 * math.sin(2 * math.pi * 0.4 * time_s + 1)
            dy += 9 * math.sin(2 * math.pi * 0.55 * time_s)
        camera = cv2.getRotationMatrix2D((cx + 40, cy - 30), roll, 1.0)
        camera[0, 2] += dx - width / 2 - 20
        camera[1, 2] += dy - height / 2 + 10
        if clock.lean_deg or clock.zoom:
            view = _in_hand(clock, time_s) @ np.vstack([camera, [0.0, 0.0, 1.0]])
            frame = cv2.warpPerspective(image, view, SIZE, flags=cv2.INTER_LINEAR)
        else:
            frame = cv2.warpAffine(image, camera, SIZE, flags=cv2.INTER_LINEAR)
        light = 1.0 + clock.exposure * math.sin(2 * math.pi * 0.2 * time_s + 0.5)
        writer.write(np.clip(light * frame + rng.normal(0.0, 2.0, frame.shape), 0, 255).astype(np.uint8))
    writer.release()


def main() -> int:
    only = only_option(__doc__ or "", "cases")
    OUT.mkdir(parents=True, exist_ok=True)
    chosen = [(name, OUT / f"{name}.mp4", lambda path, clock=clock: write_clock(clock, path),
               {"omega_rad_s": math.radians(clock.hand_deg_s), "direction": "n/a"})
              for name, clock in CASES.items() if not only or only in name]
    return rendered_cases(chosen, WITHIN, 22, f"{WITHIN:.0%}")

if __name__ == "__main__":
    sys.exit(main())
