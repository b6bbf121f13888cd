"""Speed and memory benchmark: ``make bench``.

Renders (once, cached in ``bench_out/``) a 1280x720 clip of a spinning cylinder, 8 s at 30 fps,
and one 4x as long (the same turn repeated: the motion is periodic, so it is a real clip), then
measures side by side, alternating, in one run:

* decode-only frames/s (OpenCV decode of every frame to BGR, nothing else) and full ``analyze``
  frames/s on the same clip, and their time ratio (target: analyze <= 2.5x decode), for the clip
  and (fewer rounds) for the 4x clip, where the fits' fixed cost weighs less; also the
  decode-only rate of the decoder's luma plane, which is what ``analyze`` reads, and the ratio
  against that (the part of the gain that comes from decoding less);
* peak resident memory of ``analyze`` in a fresh process for the clip and the 4x clip
  (target: < 10% growth).
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import time
from pathlib import Path

import cv2

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from rotrate_cli.decode import FrameSource  # noqa: E402
from rotrate_cli.synth import Renderer, SceneConfig  # noqa: E402

OUT = ROOT / "bench_out"
FPS = 30.0
TURN_S = 4.0  # one full turn in 4 s: 120 distinct frames
OMEGA = 2 * 3.141592653589793 / TURN_S


def _clip(name: str, turns: int, renderer: Renderer, frames: list) -> Path:
    path = OUT / name
    if path.exists():
        return path
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), FPS, (1280, 720))
    for _ in range(turns):
        for frame in frames:
            writer.write(frame)
    writer.release()
    return path


def make_clips() -> tuple[Path, Path, dict]:
    OUT.mkdir(exist_ok=True)
    scene = SceneConfig(shape="cylinder", omega_rad_s=OMEGA, fps=FPS, duration_s=TURN_S, width_px=1280,
                        height_px=720, supersample=1, seed=7)
    renderer = Renderer(scene)
    short, long = OUT / "bench_720p_8s.mp4", OUT / "bench_720p_32s.mp4"
    if not (short.exists() and long.exists()):
        frames = [renderer.render(k) for k in range(scene.frame_count)]
        _clip(short.name, 2, renderer, frames)
        _clip(long.name, 8, renderer, frames)
    return short, long, {"fixation": renderer.fixation_px, "omega": OMEGA}


def decode_only(path: Path) -> tuple[int, float]:
    start = time.perf_counter()
    count = sum(1 for _ in FrameSource(path).frames())
    return count, time.perf_counter() - start


CHILD = """
import json, sys, time
from rotrate_cli import AnalysisConfig, analyze
from rotrate_cli.decode import FrameSource
mode, path, fx, fy = sys.argv[1], sys.argv[2], float(sys.argv[3]), float(sys.argv[4])
start = time.perf_counter()
if mode == "decode":
    frames = sum(1 for _ in FrameSource(path).frames()); omega = None
elif mode == "decode-grey":
    frames = sum(1 for _ in FrameSource(path).frames(grey=True)); omega = None
else:
    kind = "csrt" if mode == "analyze-csrt" else "klt"
    result = analyze(path, AnalysisConfig(fixation_px=(fx, fy), tracker_kind=kind))
    frames = result.frames; omega = result.omega_rad_s
elapsed = time.perf_counter() - start
# VmHWM is this process's own peak; ru_maxrss would carry the parent's peak across exec
peak_kib = next(int(line.split()[1]) for line in open("/proc/self/status") if line.startswith("VmHWM"))
print(json.dumps({"frames": frames, "seconds": elapsed, "omega": omega, "peak_mib": peak_kib / 1024}))
"""


def child(mode: str, path: Path, fixation: tuple[float, float]) -> dict:
    completed = subprocess.run([sys.executable, "-c", CHILD, mode, str(path), str(fixation[0]), str(fixation[1])],
                               capture_output=True, text=True, check=True, cwd=ROOT)
    return json.loads(completed.stdout)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=5, help="alternating rounds (medians are reported)")
    args = parser.parse_args()
    short, long, truth = make_clips()
    fixation = truth["fixation"]
    decode_s, grey_s, analyze_s, frames = [], [], [], 0
    results = {}
    for _ in range(args.rounds):  # alternate so that machine noise hits all alike
        d = child("decode", short, fixation)
        g = child("decode-grey", short, fixation)
        a = child("analyze", short, fixation)
        decode_s.append(d["seconds"])
        grey_s.append(g["seconds"])
        analyze_s.append(a["seconds"])
        frames = a["frames"]
        results["omega_short"] = a["omega"]
        results["peak_short_mib"] = a["peak_mib"]
        results["peak_decode_mib"] = d["peak_mib"]
    long_runs, long_decode_s = [], []
    for _ in range(max(1, args.rounds // 2)):
        long_decode_s.append(child("decode", long, fixation)["seconds"])
        long_runs.append(child("analyze", long, fixation))
    decode = statistics.median(decode_s)
    analyze = statistics.median(analyze_s)
    peak_long = statistics.median(r["peak_mib"] for r in long_runs)
    print(f"rotrate benchmark: 1280x720 MPEG-4, 30 fps, cylinder turning at {truth['omega']:.4f} rad/s")
    print(f"  clip: {frames} frames ({frames / FPS:.0f} s); 4x clip: {long_runs[0]['frames']} frames")
    grey = statistics.median(grey_s)
    print(f"  decode only : {frames / decode:8.1f} frames/s  (median of {args.rounds}; BGR, as cv2 gives it)")
    print(f"  decode grey : {frames / grey:8.1f} frames/s  (the decoder's luma, as analyze reads it)")
    print(f"  analyze     : {frames / analyze:8.1f} frames/s  (median of {args.rounds})")
    print(f"  ratio analyze/decode time: {analyze / decode:.2f}x  (target <= 2.5x); "
          f"against grey decoding {analyze / grey:.2f}x")
    csrt_runs = [child("analyze-csrt", short, fixation) for _ in range(max(1, args.rounds // 2))]
    csrt = statistics.median(r["seconds"] for r in csrt_runs)
    csrt_error = 100 * (csrt_runs[0]["omega"] / truth["omega"] - 1)
    print(f"  analyze csrt: {frames / csrt:8.1f} frames/s  (--tracker csrt on the automatic points: "
          f"{csrt / analyze:.1f}x the default's time; omega error {csrt_error:+.3f}%)")
    long_ratio = statistics.median(r["seconds"] for r in long_runs) / statistics.median(long_decode_s)
    print(f"  4x clip     : ratio analyze/decode time {long_ratio:.2f}x  (the fixed costs of the fits spread "
          f"over {long_runs[0]['frames']} frames)")
    growth = 100 * (peak_long / results["peak_short_mib"] - 1)
    print(f"  peak memory : clip {results['peak_short_mib']:.0f} MiB, 4x clip {peak_long:.0f} MiB, "
          f"growth {growth:+.1f}%  (target < 10%); decode-only {results['peak_decode_mib']:.0f} MiB")
    err_short = 100 * (results["omega_short"] / truth["omega"] - 1)
    err_long = 100 * (long_runs[0]["omega"] / truth["omega"] - 1)
    print(f"  omega error : clip {err_short:+.3f}%, 4x clip {err_long:+.3f}%")


if __name__ == "__main__":
    main()
