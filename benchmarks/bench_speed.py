"""Speed and memory benchmark: ``make bench``.

Renders (once, cached in ``bench_out/``) a 1280x720 clip of a spinning cylinder, 8 s at 30 fps,
one 4x as long (the same turn repeated: the motion is periodic, so it is a real clip) and a
1920x1080 one of 8 s, then measures side by side, alternating, in one run:

* decode-only frames/s (OpenCV decode of every frame to BGR, nothing else) and full ``analyze``
  frames/s on the same clip, and their time ratio (bounds that must not regress, measured on
  2 cores: analyze <= 2.5x decode at 720p, 2.0x at 1080p), on the real record clip in
  ../shared/data/real_videos (H.264, 45,000 short tracks; <= 2.4x), and on the 4x clip, where
  the fits' fixed cost weighs less. Times are taken
  inside each process, after its imports (the stages' own cost), and also for the whole
  process (start-up included, as a shell loop pays it);
* the same on a side view of a textured box, 10 s at 720p through a 40-degree lens, the lens
  sought and the axis found (issue 50's clip: its lens search and fits through the lens, not its
  tracking, take the time; target <= 2.5x);
* start-up: ``rotrate --help``, and from a process's start to the first decoded frame of an
  ``analyze`` (target: <= 0.3 s each), medians; the package's bytecode is compiled first, as an
  installed command has it;
* peak resident memory of ``analyze`` in a fresh process for the clip and the 4x clip
  (target: < 10% growth).
"""

from __future__ import annotations

import argparse
import compileall
import json
import statistics
import subprocess
import sys
import time
from pathlib import Path

import cv2

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from rotrate_cli.runtime.pools import available_cores  # noqa: E402
from rotrate_cli.video.synth import Renderer, SceneConfig  # noqa: E402

OUT = ROOT / "bench_out"
RECORD = ROOT.parent / "shared" / "data" / "real_videos" / "record_oblique_closeup.mp4"
FPS = 30.0
TURN_S = 4.0  # one full turn in 4 s: 120 distinct frames
OMEGA = 2 * 3.141592653589793 / TURN_S


def _clip(path: Path, turns: int, frames: list, size: tuple[int, int]) -> Path:
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), FPS, size)
    for _ in range(turns):
        for frame in frames:
            writer.write(frame)
    writer.release()
    return path


def make_clips() -> dict[str, tuple[Path, tuple[float, float] | None, float]]:
    """The rendered clips: name -> (path, fixation (None: found), true omega)."""
    OUT.mkdir(exist_ok=True)
    clips = {}
    for name, (width, height), turns in (("720p", (1280, 720), 2), ("720p 4x", (1280, 720), 8),
                                        ("1080p", (1920, 1080), 2)):
        scene = SceneConfig(shape="cylinder", omega_rad_s=OMEGA, fps=FPS, duration_s=TURN_S, width_px=width,
                            height_px=height, supersample=1, seed=7)
        renderer = Renderer(scene)
        path = OUT / f"bench_{height}p_{int(turns * TURN_S)}s.mp4"
        if not path.exists():
            _clip(path, turns, list(renderer.frames(range(scene.frame_count))), (width, height))
        clips[name] = (path, renderer.fixation_px, OMEGA)
    # a side view of a textured box through a 40-degree lens, no lens given (--fov auto): about 1700
    # tracks, where the lens search and the fits through it, not the tracking, take the time (issue 50).
    # Encoded as H.264, as a camera or a phone writes it (the clip took 1.3 s to decode; MPEG-4
    # part 2, which OpenCV's own writer makes, decodes twice as fast and is rare in users' footage)
    scene = SceneConfig(shape="box", omega_rad_s=0.5, fps=FPS, duration_s=10.0, width_px=1280, height_px=720,
                        projection="perspective", fov_deg=40.0, supersample=1, seed=11)
    renderer = Renderer(scene)
    path = OUT / "bench_box_side_720p_10s_h264.mp4"
    if not path.exists():
        raw = _clip(OUT / "bench_box_side_720p_10s.mp4", 1, list(renderer.frames(range(scene.frame_count))),
                    (1280, 720))
        _h264(raw, path)
    clips["box side 720p"] = (path, None, 0.5)
    return clips


def _h264(source: Path, path: Path) -> None:
    """``source`` encoded again as H.264 (CRF 18, 4:2:0) by imageio-ffmpeg's FFmpeg."""
    from rotrate_cli.video.pipe import ffmpeg_program

    program = ffmpeg_program()
    if program is None:
        raise SystemExit("the box clip is H.264: FFmpeg is needed (pip install imageio-ffmpeg)")
    subprocess.run([program, "-v", "error", "-y", "-i", str(source), "-c:v", "libx264", "-crf", "18",
                    "-pix_fmt", "yuv420p", str(path)], check=True)


CHILD = """
import json, sys, time
import rotrate_cli.cli
rotrate_cli.cli._one_blas_thread()  # as the command's entry point does first, before NumPy loads
started = time.perf_counter()
mode, path, fx, fy = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4]
if mode == "decode":
    from rotrate_cli.video.decode import FrameSource
else:
    from rotrate_cli.analysis import AnalysisConfig, analyze
    import pandas, scipy.special, scipy.optimize  # loaded on first use in a run: here, so the stages alone are timed
imported = time.perf_counter()
cpu_started = time.process_time()
if mode == "decode":
    frames = sum(1 for _ in FrameSource(path).frames()); omega = None
else:
    fixation = None if fx == "auto" else (float(fx), float(fy))
    result = analyze(path, AnalysisConfig(fixation_px=fixation))
    frames = result.frames; omega = result.omega_rad_s
elapsed = time.perf_counter() - imported
cpu = time.process_time() - cpu_started  # all threads: the decoder's, OpenCV's and the fits'
# VmHWM is this process's own peak; ru_maxrss would carry the parent's peak across exec
peak_kib = next(int(line.split()[1]) for line in open("/proc/self/status") if line.startswith("VmHWM"))
print(json.dumps({"frames": frames, "seconds": elapsed, "cpu_s": cpu, "omega": omega, "peak_mib": peak_kib / 1024}))
"""

FIRST_FRAME = """
import sys
import rotrate_cli.cli  # what the command line loads
rotrate_cli.cli._one_blas_thread()  # what its entry point does first
from rotrate_cli.analysis import analyze  # what analyze loads before it decodes
from rotrate_cli.video.decode import FrameSource
next(FrameSource(sys.argv[1]).frames(grey=True))
"""


def child(mode: str, path: Path, fixation: tuple[float, float] | None) -> dict:
    """One fresh process: its own timing (after imports) and, measured here, the whole process's."""
    point = ("auto", "auto") if fixation is None else (str(fixation[0]), str(fixation[1]))
    started = time.perf_counter()
    completed = subprocess.run([sys.executable, "-c", CHILD, mode, str(path), *point],
                               capture_output=True, text=True, check=True, cwd=ROOT)
    result = json.loads(completed.stdout)
    result["whole_s"] = time.perf_counter() - started
    return result


def whole(command: list[str]) -> float:
    started = time.perf_counter()
    subprocess.run(command, capture_output=True, check=True, cwd=ROOT)
    return time.perf_counter() - started


def compare(path: Path, fixation: tuple[float, float] | None, rounds: int) -> dict:
    """Decode-only and analyze on one clip, alternating; medians."""
    decode, analyze = [], []
    for _ in range(rounds):  # alternate so that machine noise hits both alike
        decode.append(child("decode", path, fixation))
        analyze.append(child("analyze", path, fixation))
    median = statistics.median
    return {
        "frames": analyze[0]["frames"], "omega": analyze[0]["omega"],
        "decode_s": median(d["seconds"] for d in decode), "analyze_s": median(a["seconds"] for a in analyze),
        "analyze_cpu_s": median(a["cpu_s"] for a in analyze),
        "decode_whole_s": median(d["whole_s"] for d in decode),
        "analyze_whole_s": median(a["whole_s"] for a in analyze),
        "peak_mib": median(a["peak_mib"] for a in analyze), "decode_peak_mib": median(d["peak_mib"] for d in decode),
    }


def long_clips() -> int:
    """Peak memory and time of ``analyze --fixation auto`` on 640x480 clips of 1, 10 and 30 minutes
    (a rendered 4-s turn of a box, looped by stream copy: a real clip of that length). Target: the
    30-minute clip under 500 MB, and growth under 5 MB a minute."""
    from rotrate_cli.video.pipe import ffmpeg_program

    program = ffmpeg_program()
    if program is None:
        print("skipped: no FFmpeg program to loop the clip (pip install imageio-ffmpeg)")
        return 0
    OUT.mkdir(exist_ok=True)
    turn = OUT / "mem_480p_4s.mp4"
    if not turn.exists():
        subprocess.run([str(Path(sys.executable).parent / "rotrate"), "synth", str(turn), "--shape", "box",
                        "--omega", str(OMEGA), "--duration", "4", "--size", "640x480"], check=True,
                       capture_output=True)
    peaks = {}
    for minutes in (1, 10, 30):
        clip = OUT / f"mem_480p_{minutes}min.mp4"
        if not clip.exists():
            subprocess.run([program, "-v", "error", "-y", "-stream_loop", str(minutes * 15 - 1), "-i", str(turn),
                            "-c", "copy", str(clip)], check=True)
        result = child("analyze", clip, None)
        peaks[minutes] = result["peak_mib"]
        error = 100 * (result["omega"] / OMEGA - 1)
        print(f"{minutes:>3} min: peak {result['peak_mib']:6.0f} MiB, {result['whole_s']:6.1f} s, "
              f"omega error {error:+.3f}%")
    growth = (peaks[30] - peaks[1]) / 29
    print(f"growth {growth:+.1f} MiB a minute from 1 to 30 minutes (target < 5); 30 minutes {peaks[30]:.0f} MiB "
          "(target < 500)")
    return 0 if growth < 5 and peaks[30] < 500 else 1


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=5, help="alternating rounds (medians are reported)")
    parser.add_argument("--long", action="store_true",
                        help="instead: peak memory of --fixation auto on 640x480 clips of 1, 10 and 30 minutes")
    args = parser.parse_args()
    if args.long:
        return long_clips()
    clips = make_clips()
    # the package's bytecode compiled, as an installed command has it (pip compiles it on install;
    # an editable install writes it at the first import, except where PYTHONDONTWRITEBYTECODE is set,
    # as on these machines, where every process compiled the package's 50 modules again: 0.06 s of
    # the start-up to the first frame, measured)
    compileall.compile_dir(str(ROOT / "rotrate_cli"), quiet=1)
    cores = available_cores()
    print("rotrate benchmark: side by side in one run, medians; ratio = analyze time / decode-only time")
    print(f"CPU floor = analyze's processor time (all its threads) shared over this machine's {cores} cores, "
          "over the decode-only time: the ratio no scheduling of the same work could beat")
    print(f"{'clip':<34} {'frames':>6} {'decode f/s':>10} {'analyze f/s':>11} {'ratio':>6} {'target':>6} "
          f"{'CPU floor':>9} {'whole-process ratio':>19} {'omega error':>11}")
    missed = 0
    bounds = {"720p": 2.5, "1080p": 2.0, "box side 720p": 2.5}
    rows = [(name, path, fixation, omega, bounds.get(name)) for name, (path, fixation, omega) in clips.items()]
    if RECORD.exists():
        truth = json.loads(RECORD.with_suffix(".truth.json").read_text())
        rows.append(("record clip (real, H.264, auto)", RECORD, None, truth["omega"], 2.4))
    measured = {}
    for name, path, fixation, omega, target in rows:
        rounds = args.rounds if name != "720p 4x" else max(1, args.rounds // 2)
        m = compare(path, fixation, rounds)
        measured[name] = m
        ratio = m["analyze_s"] / m["decode_s"]
        missed += target is not None and ratio > target
        error = 100 * (m["omega"] / omega - 1)
        print(f"{name + ' (' + path.name + ')':<34} {m['frames']:>6} {m['frames'] / m['decode_s']:>10.0f} "
              f"{m['frames'] / m['analyze_s']:>11.0f} {ratio:>6.2f} {'<= ' + str(target) if target else '':>6} "
              f"{m['analyze_cpu_s'] / cores / m['decode_s']:>9.2f} "
              f"{m['analyze_whole_s'] / m['decode_whole_s']:>19.2f} {error:>+10.3f}%")
    help_s = statistics.median(whole([str(Path(sys.executable).parent / "rotrate"), "--help"])
                               for _ in range(args.rounds))
    first_s = statistics.median(whole([sys.executable, "-c", FIRST_FRAME, str(clips["720p"][0])])
                                for _ in range(args.rounds))
    missed += help_s > 0.3 or first_s > 0.3
    print(f"start-up: rotrate --help {help_s:.2f} s; to the first 720p frame of an analyze {first_s:.2f} s "
          "(target <= 0.3 s each; whole processes, the package's bytecode compiled)")
    short, long = measured["720p"]["peak_mib"], measured["720p 4x"]["peak_mib"]
    growth = 100 * (long / short - 1)
    missed += growth >= 10
    print(f"peak memory: clip {short:.0f} MiB, 4x clip {long:.0f} MiB, growth {growth:+.1f}% (target < 10%); "
          f"decode-only {measured['720p']['decode_peak_mib']:.0f} MiB")
    return 1 if missed else 0


if __name__ == "__main__":
    sys.exit(main())
