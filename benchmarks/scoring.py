"""How the benchmarks on rendered clips score a result as a new user would get it (``analyze
--fixation auto``): error, interval, coverage, quality, sense; and their summary line."""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Callable
from pathlib import Path

from rotrate_cli.analysis import AnalysisConfig, analyze
from rotrate_cli.errors import RotrateError

#: Errors above this, as a fraction, must come with ``weak``.
UNMARKED_LIMIT = 0.05


def only_option(description: str, what: str) -> str:
    """A benchmark's ``--only`` filter, from its command line."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--only", default="", help=f"run only the {what} whose name contains this")
    return str(parser.parse_args().only)


def footage_absent(folder: Path) -> bool:
    """True, having said so, where the real footage (the workplace's shared folder) is absent."""
    if folder.exists():
        return False
    print(f"skipped: {folder} is absent (the real footage lives in the workplace's shared folder)")
    return True


def scored(path: Path, truth: dict) -> dict[str, object]:
    """``analyze`` on ``path`` with default settings, scored against ``truth`` (``omega_rad_s``,
    ``direction``); an error the tool gave scores as a miss, with its message."""
    true_omega = float(truth["omega_rad_s"])
    try:
        result = analyze(path, AnalysisConfig(fixation_px=None))
    except RotrateError as error:
        return {"omega": math.nan, "error_pct": math.nan, "low_pct": math.nan, "high_pct": math.nan, "covers": False,
                "quality": "none", "sense": "-", "note": str(error)[:60]}
    return {
        "omega": result.omega_rad_s, "error_pct": 100 * (result.omega_rad_s / true_omega - 1),
        "low_pct": 100 * (result.omega_low_rad_s / true_omega - 1),
        "high_pct": 100 * (result.omega_high_rad_s / true_omega - 1),
        "covers": bool(result.omega_low_rad_s <= true_omega <= result.omega_high_rad_s), "quality": result.quality,
        "sense": "right" if result.direction == truth["direction"] else result.direction,
        "note": result.rate_from + ("; shake found" if result.shake is not None else ""),
    }


#: The scored columns' header, after each benchmark's own leading columns.
SCORE_HEADER = f"{'error':>8} {'95% interval':>18} {'covers':>6} {'quality':>7} {'sense':>7}  from"


def score_columns(row: dict[str, object]) -> str:
    """A scored row's columns under :data:`SCORE_HEADER`."""
    interval = f"[{row['low_pct']:+.2f}, {row['high_pct']:+.2f}]"
    return (f"{row['error_pct']:>+7.2f}% {interval:>18} {'yes' if row['covers'] else 'NO':>6} {row['quality']:>7} "
            f"{row['sense']:>7}  {row['note']}")


def print_scored(lead_header: str, leads: list[str], rows: list[dict[str, object]]) -> bool:
    """Print the table (each row's own leading columns, then the scores) and the summary line;
    True where the benchmark passes (see :func:`summary`)."""
    header = f"{lead_header} {SCORE_HEADER}"
    print(header)
    print("-" * len(header))
    for lead, row in zip(leads, rows, strict=True):
        print(f"{lead} {score_columns(row)}")
    line, passed = summary(rows)
    print(f"\n{line}")
    return passed


def summary(rows: list[dict[str, object]]) -> tuple[str, bool]:
    """The summary line (clips, covering, good, unmarked misses, wrong senses) and whether every
    interval covers, no miss is unmarked and no sense is wrong."""
    covered = sum(bool(row["covers"]) for row in rows)
    unmarked = sum(abs(float(row["error_pct"])) > 100 * UNMARKED_LIMIT and row["quality"] == "good" for row in rows)
    wrong = sum(row["sense"] in ("cw", "ccw") for row in rows)
    good = [row for row in rows if row["quality"] == "good"]
    line = (f"clips {len(rows)}; intervals covering the truth {covered} ({100 * covered / max(len(rows), 1):.0f}%); "
            f"good {len(good)} (covering {sum(bool(r['covers']) for r in good)}); off by more than "
            f"{100 * UNMARKED_LIMIT:.0f}% and not marked weak {unmarked}; sense wrong {wrong}")
    return line, unmarked == 0 and wrong == 0 and covered == len(rows)


def within_case(name: str, path: Path, truth: dict, within: float, width: int = 24) -> tuple[bool, str | None]:
    """Score one rendered case (:func:`scored`) and print its line (the name, the truth, the rate
    and :data:`SCORE_HEADER`'s columns, and the time taken): whether it lies within ``within`` (a
    fraction) of the truth, and a line for :func:`finish` where it is good but off or its interval
    misses."""
    started = time.perf_counter()
    row = scored(path, truth)
    error = abs(float(row["error_pct"])) / 100 if math.isfinite(float(row["error_pct"])) else math.inf
    print(f"{name:<{width}} {float(truth['omega_rad_s']):>8.4f} {float(row['omega']):>8.4f} {score_columns(row)}  "
          f"{time.perf_counter() - started:.1f} s")
    missed = row["quality"] == "good" and (error > within or not row["covers"])
    miss = f"{name}: {float(row['error_pct']):+.2f}%, covers {row['covers']}, good"
    return error <= within, miss if missed else None


#: A rendered case: its name, its clip's path, how to render the clip (to a path given), its truth.
RenderedCase = tuple[str, Path, Callable[[Path], object], dict]


def rendered_cases(cases: list[RenderedCase], within: float, width: int, within_text: str) -> int:
    """Score rendered cases in order (:func:`within_case`), rendering each clip first where it is
    not cached (to a partial file, renamed once whole: an interrupted render is not taken for a
    clip); the header, each line, the summary and the exit code (:func:`finish`)."""
    print(f"{'case':<{width}} {'truth':>8} {'rotrate':>8} {SCORE_HEADER}")
    misses, near_count = [], 0
    for name, path, render, truth in cases:
        if not path.exists():
            partial = path.with_suffix(".partial" + path.suffix)
            partial.unlink(missing_ok=True)
            render(partial)
            partial.replace(path)
        near, miss = within_case(name, path, truth, within, width=width)
        near_count += near
        misses += [miss] if miss else []
    return finish(f"cases {len(cases)}; within {within_text}: {near_count}; good but off or its interval missing: "
                  f"{len(misses)}", misses)


def finish(summary: str, misses: list[str]) -> int:
    """Print a benchmark's summary line and each case that missed its target; the exit code (1
    when any missed)."""
    print(f"\n{summary}")
    for miss in misses:
        print(f"  {miss}")
    return 1 if misses else 0


#: A part's truth from the sticker is read over at least this long about the part, s: its
#: hand-tracked samples (every 5th frame) lie 0.9 degrees rms off a smooth turn, and a line through
#: the few of a 0.8-s part read 1.7% off its neighbours'.
STICKER_SPAN_S = 2.0


def sticker_omega(track_csv: Path, fps: float, start_s: float, end_s: float) -> float:
    """The rate (rad/s) a clip's hand-tracked sticker turns at over ``start_s``-``end_s``: the slope
    of its unwrapped angle (``mp4_frame,x_px,y_px,angle_rad_unwrapped``) over the samples within
    the part, widened about its middle to :data:`STICKER_SPAN_S` (and kept within the samples).
    The wheel slows 2% over its clip, and not quite steadily: its first 2.5 s turn 1.06% faster
    than the clip's mean, which a part's truth must hold. Where the part reaches more than 0.5 s
    past the samples (the wheel's last is frame 335, 3 s before the clip's end), the mean rate of a
    steady slowing fitted to them all (the angle a quadratic of time). NaN with too few samples."""
    import numpy as np
    table = np.loadtxt(track_csv, delimiter=",", skiprows=1, ndmin=2)
    times, angles = table[:, 0] / fps, table[:, 3]
    if len(times) < 4 or not (math.isfinite(end_s) and end_s > start_s):
        return float("nan")
    if start_s < times[0] - 0.5 or end_s > times[-1] + 0.5:
        slowing = np.poly1d(np.polyfit(times, angles, 2))
        return abs(float(slowing(end_s) - slowing(start_s))) / (end_s - start_s)
    half = max(end_s - start_s, STICKER_SPAN_S) / 2
    middle = min(max((start_s + end_s) / 2, times[0] + half), times[-1] - half)
    inside = (times >= middle - half - 1e-9) & (times <= middle + half + 1e-9)
    if inside.sum() < 4:
        return float("nan")
    return abs(float(np.polyfit(times[inside], angles[inside], 1)[0]))


def part_truth(video: Path, omega_rad_s: float, fps: float, start_s: float | None, end_s: float | None) -> float:
    """A part's truth: the rate of the clip's hand-tracked sticker over it where the clip has one
    (``<name>.track.csv``, see :func:`sticker_omega`), else the clip's own."""
    track = video.with_suffix(".track.csv")
    if not track.exists() or (start_s is None and end_s is None):
        return omega_rad_s
    local = sticker_omega(track, fps, start_s or 0.0, end_s if end_s is not None else math.inf)
    return local if math.isfinite(local) else omega_rad_s


def plane_before_lens(size_px: tuple[int, int], focal_widths: float, centre: tuple[float, float], tilt_deg: float,
                      side_px: int) -> tuple:
    """A flat texture ``side_px`` square laid on a plane tilted ``tilt_deg`` about the picture's x
    axis before a pinhole lens (``focal_widths`` picture widths), its middle at ``centre`` (picture
    widths and heights): the homography of the texture's pixels at the plane turned by an angle
    (radians) about its middle, as a function of that angle."""
    import numpy as np

    width, height = size_px
    focal, tilt = focal_widths * width, math.radians(tilt_deg)
    lens = np.array([[focal, 0, centre[0] * width], [0, focal, centre[1] * height], [0, 0, 1.0]])
    plane = lens @ np.array([[1.0, 0, 0], [0, math.cos(tilt), 0], [0, math.sin(tilt), focal]])
    to_centre = np.array([[1.0, 0, -side_px / 2 + 0.5], [0, 1, -side_px / 2 + 0.5], [0, 0, 1]])

    def seen(angle_rad: float):
        turn = np.array([[math.cos(angle_rad), -math.sin(angle_rad), 0], [math.sin(angle_rad), math.cos(angle_rad), 0],
                         [0, 0, 1]])
        return plane @ turn @ to_centre

    return seen


def write_h264_grey(path: Path, pictures, size_px: tuple[int, int], fps: float) -> None:
    """Grey pictures (float, clipped to 0-255) written as H.264 (CRF 23), as a phone writes it,
    through imageio-ffmpeg's FFmpeg."""
    import subprocess

    import imageio_ffmpeg
    import numpy as np

    command = [imageio_ffmpeg.get_ffmpeg_exe(), "-loglevel", "error", "-y", "-f", "rawvideo", "-pix_fmt", "gray",
               "-s", f"{size_px[0]}x{size_px[1]}", "-r", f"{fps:g}", "-i", "-", "-c:v", "libx264", "-crf", "23",
               "-pix_fmt", "yuv420p", "-f", "mp4", str(path)]
    with subprocess.Popen(command, stdin=subprocess.PIPE) as encoder:
        assert encoder.stdin is not None
        for picture in pictures:
            encoder.stdin.write(np.clip(picture, 0, 255).astype(np.uint8).tobytes())
        encoder.stdin.close()
    if encoder.returncode != 0:
        raise SystemExit(f"FFmpeg could not write {path}")


def rendered_main(doc: str, data: Path, out: Path, cases: list, render: Callable, within: float, width: int) -> int:
    """A rendered benchmark's run (:func:`rendered_cases`): ``--only``, skipped without the shared
    photographs, each case (``name``, ``omega_rad_s``: positive clockwise as the picture shows it)
    rendered once into ``out``."""
    only = only_option(doc, "cases")
    if footage_absent(data):
        return 0
    out.mkdir(parents=True, exist_ok=True)
    chosen = [(case.name, out / f"{case.name}.mp4", lambda path, case=case: render(case, path),
               {"omega_rad_s": abs(case.omega_rad_s), "direction": "cw" if case.omega_rad_s > 0 else "ccw"})
              for case in cases if not only or only in case.name]
    return rendered_cases(chosen, within, width, f"{within:.0%}")
