"""The ``rotrate`` command line: a thin Typer layer over the library.

It parses options into configurations, calls the library, renders the result, and maps the
library's typed errors to one line on stderr and an exit code: 0 a result, 1 no trustworthy
result, 2 bad input or usage, 130 interrupted. ``--debug`` shows tracebacks.
"""

from __future__ import annotations

import math
import os
import re
import sys
import traceback
import warnings
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, TypeVar

import typer
from rich.console import Console

from rotrate_cli.errors import InputError, NoResultError, OutputError, RotrateError, SettingError
from rotrate_cli.output.files import check_output_path, make_folder, output_format, write_text

# Only what --help needs is imported here: typer and rich. The library's stages (OpenCV,
# pandas, SciPy: most of a second) are imported by the commands that run them.
from rotrate_cli.runtime.choices import FORMATS, METHODS, PROJECTIONS, SHAPES

if TYPE_CHECKING:
    import numpy as np

    from rotrate_cli.analysis import Analysis, AnalysisConfig
    from rotrate_cli.batch import Outcome

app = typer.Typer(
    name="rotrate",
    help="Measure how fast a rigid object spins (rad/s) from a video, on a tripod or held by hand.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
T = TypeVar("T")
#: The names --overlay writes a video under (none: .mp4).
OVERLAY_SUFFIXES = ("", ".mp4", ".mov", ".mkv", ".avi")


def _print_version(value: bool) -> None:
    if value:
        from rotrate_cli import __version__

        sys.stdout.write(f"rotrate {__version__}\n")
        raise typer.Exit(0)


@app.callback()
def _options(
    version: Annotated[bool, typer.Option("--version", metavar="", help="Show the version and exit.", is_eager=True,
                                          callback=_print_version)] = False,
) -> None:
    """Measure how fast a rigid object spins (rad/s) from a video, on a tripod or held by hand."""

FormatOption = Annotated[str | None, typer.Option("--format", "-f", metavar="FORMAT",
                                                  help="table, csv (Table I layout) or json; default: from "
                                                       "the --output file's extension (.json, .csv), else table.")]
OutputOption = Annotated[Path | None, typer.Option("--output", "-o", metavar="PATH",
                                                   help="Write the report to this file.")]
ForceOption = Annotated[bool, typer.Option("--force", metavar="", help="Replace an existing --output file.")]
MethodOption = Annotated[str, typer.Option("--method", metavar="fit|paper",
                                           help="fit (ours: sinusoid fit per track) or paper "
                                                            "(the reference paper's backward differences).")]
EveryOption = Annotated[int | None, typer.Option("--every", metavar="N",
                                                 help="Use every N-th frame's positions, as the paper did; "
                                                      "default: 1, and with --method paper the paper's "
                                                      "spacing (about a sixth of a radian).")]
DebugOption = Annotated[bool, typer.Option("--debug", metavar="", help="Show the traceback of an error.")]
QuietOption = Annotated[bool, typer.Option("--quiet", "-q", metavar="", help="No progress bar.")]
SchedulerOption = Annotated[str | None, typer.Option("--scheduler", metavar="ADDRESS",
                                                     help="Run the batch on this Dask cluster "
                                                                         "(tcp://HOST:8786; needs rotrate\\[dask]).")]


#: The flag that sets each setting the library names (`fixation_px`, `every=3`: see rotrate_cli.errors).
FLAGS = {
    "fixation_px": "--fixation", "fps": "--fps", "axis_angle_deg": "--axis-angle", "angle_from": "--angle-from",
    "elevation_deg": "--elevation", "direction": "--direction", "start_s": "--start", "end_s": "--end",
    "every": "--every", "method": "--method", "fov_deg": "--fov", "focal_px": "--focal-px", "find_focal": "--fov",
    "window_s": "--window", "segment": "--segment", "points_px": "--track", "tracker_kind": "--tracker",
    "times_s": "--times", "roi": "--roi", "expected_rad_s": "--expect", "tolerance_pct": "--tolerance",
    "workers": "--jobs", "scheduler": "--scheduler", "force": "--force", "format": "--format", "at_s": "--at",
    "position_column": "--position-column", "duration_s": "--duration", "jpeg_quality": "--jpeg-quality",
    "overlay": "--overlay", "strict": "--strict", "fixation": "--fixation",
}
#: Values a flag spells otherwise than the library (`fixation_px=None` is --fixation auto).
_FLAG_VALUES = {("fixation_px", "None"): "auto", ("find_focal", "False"): "ortho"}
_SETTING = re.compile(r"`([a-z_]+)(?:=([^`]*))?`")
#: Exit codes by error type: 1 no trustworthy result, 2 bad input or an output that cannot be written.
EXIT_CODES: tuple[tuple[type[RotrateError], int], ...] = ((NoResultError, 1), (InputError, 2), (OutputError, 2))


def in_flags(text: str) -> str:
    """A library message as the command line says it: each `setting` (or `setting=value`) named
    by its flag (``--every 3``); backquoted names that are no setting stay as they are."""

    def flag(match: re.Match[str]) -> str:
        name, value = match.group(1), match.group(2)
        if name not in FLAGS:
            return match.group(0)
        if value is None:
            return FLAGS[name]
        return f"{FLAGS[name]} {_FLAG_VALUES.get((name, value), value.strip(chr(39)))}"

    return _SETTING.sub(flag, text)


def said(analysis: Analysis) -> Analysis:
    """The analysis with its warnings in the command line's words (:func:`in_flags`)."""
    return replace(analysis, warnings=tuple(in_flags(w) for w in analysis.warnings))


def said_outcomes(outcomes: list[Outcome]) -> list[Outcome]:
    """A batch's outcomes in the command line's words (:func:`said`)."""
    return [replace(o, analysis=None if o.analysis is None else said(o.analysis), error=in_flags(o.error))
            for o in outcomes]


def exit_code(error: RotrateError) -> int:
    """The exit code of a library error (2 for a type not listed)."""
    return next((code for kind, code in EXIT_CODES if isinstance(error, kind)), 2)


def _fail(message: str, code: int) -> typer.Exit:
    Console(stderr=True, highlight=False, soft_wrap=True).print(f"rotrate: error: {in_flags(message)}", markup=False)
    return typer.Exit(code)


def _run(debug: bool, job: Callable[[], T]) -> T:
    """Run ``job``, turning errors into one line and an exit code."""
    try:
        return job()
    except RotrateError as exc:
        if debug:
            traceback.print_exc()
        raise _fail(str(exc), exit_code(exc)) from None
    except KeyboardInterrupt:
        raise _fail("interrupted", 130) from None
    except BrokenPipeError:
        # the reader of stdout stopped early (| head): nothing to say; keep Python's exit flush quiet
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        raise typer.Exit(0) from None
    except typer.Exit:
        raise
    except Exception as exc:  # noqa: BLE001 - the user gets one line, the developer --debug
        if debug:
            traceback.print_exc()
        raise _fail(f"unexpected {type(exc).__name__}: {exc} (rerun with --debug for details)", 3) from None


def _numbers(text: str, count: int, option: str, example: str) -> list[float]:
    parts = [p.strip() for p in text.split(",")]
    try:
        values = [float(p) for p in parts]
    except ValueError:
        values = []
    if len(values) != count or not all(math.isfinite(v) for v in values):
        raise InputError(f"{option} takes {count} numbers separated by a comma, such as {example}; got {text!r}")
    return values


def _check_format(fmt: str) -> None:
    if fmt not in FORMATS:
        raise InputError(f"--format must be one of {', '.join(FORMATS)}; got {fmt!r}")


def _check_method(method: str) -> None:
    if method not in METHODS:
        raise InputError(f"--method must be one of {', '.join(METHODS)}; got {method!r}")


def _emit(analysis: Analysis, fmt: str, output: Path | None, force: bool) -> None:
    from rotrate_cli.cli.report import render, render_table

    if output is not None:
        write_text(output, render(analysis, fmt), force)
        return
    if fmt == "table":
        render_table(analysis, Console(highlight=False))
    else:
        sys.stdout.write(render(analysis, fmt))
        sys.stdout.flush()


@contextmanager
def _progress_bar(quiet: bool) -> Iterator[tuple[Callable[[int, int | None], None] | None,
                                                 Callable[[str], None] | None]]:
    """The frames' progress callback and the stage callback of :func:`rotrate_cli.analysis.analyze`
    (None, None when quiet or not on a terminal)."""
    console = Console(stderr=True)
    if quiet or not console.is_terminal:
        yield None, None
        return
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        ProgressColumn,
        Task,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )
    from rich.text import Text

    class RateColumn(ProgressColumn):
        """Frames per second so far."""

        def render(self, task: Task) -> Text:
            speed = task.finished_speed or task.speed
            return Text("" if speed is None else f"{speed:.0f} frames/s")

    columns = (TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), RateColumn(),
               TimeElapsedColumn(), TimeRemainingColumn())
    with Progress(*columns, console=console, transient=True) as progress:
        task = progress.add_task("frames", total=None)

        def update(done: int, total: int | None) -> None:
            progress.update(task, completed=done, total=total)

        def stage(text: str) -> None:  # the bar pulses: the fits' length is not known ahead
            progress.update(task, description=text, total=None)

        yield update, stage


@app.command("analyze")
def analyze_command(
    videos: Annotated[list[str], typer.Argument(help="Video file(s), image folder, printf pattern like "
                                                      "frames/img.%03d.png, folders of videos, or globs.")],
    fixation: Annotated[str | None, typer.Option("--fixation", metavar="X,Y|auto",
                                                 help="X,Y pixel of a point on the rotation axis, or "
                                                                    "'auto' to find the axis from the motion "
                                                                    "(required, except with --segment).")] = None,
    fps: Annotated[
        float | None, typer.Option("--fps", metavar="FPS",
                                   help="Frame rate; overrides the file's, required for images.")
    ] = None,
    start: Annotated[float, typer.Option("--start", metavar="SECONDS", help="Start time, s.")] = 0.0,
    end: Annotated[float | None, typer.Option("--end", metavar="SECONDS", help="End time, s.")] = None,
    roi: Annotated[str | None, typer.Option("--roi", metavar="X,Y,W,H",
                                            help="X,Y,W,H: seed points only in this box.")] = None,
    every: EveryOption = None,
    method: MethodOption = "fit",
    fov: Annotated[str | None, typer.Option("--fov", metavar="DEG|auto|ortho",
                                            help="Horizontal field of view, degrees: corrects "
                                                          "for perspective (pinhole camera); auto: found "
                                                          "from the tracks (with the camera's elevation).")
                   ] = None,
    focal_px: Annotated[float | None, typer.Option("--focal-px", metavar="PX",
                                                   help="Focal length in pixels, instead of "
                                                                      "--fov.")] = None,
    axis_angle: Annotated[float | None, typer.Option("--axis-angle", metavar="DEG",
                                                     help="Axis angle in the image, degrees (0 "
                                                                        "vertical, + top end right); default: "
                                                                        "from the motion.")] = None,
    angle_from: Annotated[str, typer.Option("--angle-from", metavar="auto|motion|paths",
                                            help="How to find the axis angle: motion (the steps' "
                                                                 "main direction), paths (each track's "
                                                                 "elliptical path; right when the camera "
                                                                 "looks down on the object; slower), or auto "
                                                                 "(default: paths where the steps show the "
                                                                 "camera looking down by 15 degrees or "
                                                                 "more).")] = "auto",
    elevation: Annotated[float | None, typer.Option("--elevation", metavar="DEG",
                                                    help="How far the camera looks down on the "
                                                                       "object, degrees, for the pinhole model "
                                                                       "(--fov); found where the angle comes from the "
                                                                       "paths.")
                         ] = None,
    direction: Annotated[str | None, typer.Option("--direction", metavar="ccw|cw",
                                                  help="Which way the object turns, seen from the top "
                                                       "end of its axis, if you know it: through a lens "
                                                       "the two ways fit different rates, and a short, "
                                                       "level view cannot always tell them apart.")
                         ] = None,
    window: Annotated[float | None, typer.Option("--window", metavar="SECONDS",
                                                 help="Also measure omega(t) over a sliding "
                                                                  "window of this many seconds.")] = None,
    series_csv_path: Annotated[Path | None, typer.Option("--series-csv", metavar="PATH",
                                                         help="Write omega(t) (needs --window) "
                                                                               "to this CSV file.")] = None,
    track: Annotated[list[str] | None, typer.Option("--track", metavar="X,Y",
                                                    help="X,Y of a point to follow (repeat for "
                                                                     "more): features 1..n, as the paper's "
                                                                     "hand-tracked ones.")] = None,
    tracker_kind: Annotated[str | None, typer.Option("--tracker", metavar="klt|csrt",
                                                     help="klt or csrt (default: klt; csrt with "
                                                                       "--track). Automatic csrt follows 30 "
                                                                       "corners, about 5x slower; videos only, "
                                                                       "not stills far apart.")] = None,
    scale: Annotated[float | None, typer.Option("--scale", metavar="UNITS_PER_PX",
                                                help="Physical units per pixel: positions and "
                                                                "derivatives in the reports in those units "
                                                                "(omega is unchanged).")] = None,
    unit: Annotated[str | None, typer.Option("--unit", metavar="NAME",
                                             help="The name of --scale's unit (e.g. in, mm).")] = None,
    plot: Annotated[Path | None, typer.Option("--plot", metavar="PATH",
                                              help="Also write a picture: tracks against the fit, "
                                                              "each feature's rate, omega over time (.png; "
                                                              "needs rotrate\\[plot]).")] = None,
    overlay: Annotated[Path | None, typer.Option("--overlay", metavar="PATH",
                                                 help="Also write a video with the axis, the "
                                                                    "tracks and the running omega drawn on it "
                                                                    "(.mp4).")] = None,
    segment: Annotated[bool, typer.Option("--segment", metavar="", help="Several objects: group the points into rigid "
                                                            "bodies by rate and axis and report each.")] = False,
    blur: Annotated[float | None, typer.Option("--blur", metavar="SIGMA_PX",
                                               help="Blur (sigma, px) before tracking; default 1 "
                                                              "for videos, 0 for image sequences.")] = None,
    expect: Annotated[float | None, typer.Option("--expect", metavar="RAD_S",
                                                 help="Expected omega, rad/s: exit 1 when the "
                                                                  "result is outside --tolerance of it.")] = None,
    tolerance: Annotated[float | None, typer.Option("--tolerance", metavar="PCT",
                                                    help="Tolerance of --expect, percent.")] = None,
    strict: Annotated[bool, typer.Option("--strict", metavar="",
                                         help="Exit 1 when the evidence is weak (quality: weak).")
                      ] = False,
    times: Annotated[Path | None, typer.Option("--times", metavar="PATH",
                                               help="A file of frame times, seconds, one per line (one per frame), "
                                                    "instead of --fps or the photographs' EXIF times.")] = None,
    jobs: Annotated[int, typer.Option("--jobs", "-j", metavar="N", help="Inputs analysed at once (processes).")] = 1,
    scheduler: SchedulerOption = None,
    output_dir: Annotated[Path | None, typer.Option("--output-dir", metavar="PATH",
                                                    help="With several inputs: write each "
                                                                         "one's report here as STEM.json "
                                                                         "(STEM.csv with --format csv).")] = None,
    fmt: FormatOption = None,
    output: OutputOption = None,
    force: ForceOption = False,
    quiet: QuietOption = False,
    debug: DebugOption = False,
) -> None:
    """Track points on the spinning object(s) and report the rotation rate.

    With several inputs (files, folders of videos, globs) each gets one summary row and a bad
    input does not stop the others; the exit code is the worst input's.
    """

    def job() -> int:
        import numpy as np

        from rotrate_cli.analysis import AnalysisConfig, analyze
        from rotrate_cli.batch import check_expectation, check_expected, expand_inputs, weak_message
        from rotrate_cli.cli.report import series_csv, with_units
        from rotrate_cli.scene.focal import parse_fov
        from rotrate_cli.tracking.klt import Roi, TrackerConfig
        from rotrate_cli.video.clock import read_times

        form = output_format(output, fmt)
        _check_format(form)
        _check_method(method)
        if fixation is None and not segment:
            raise InputError("give --fixation X,Y (a pixel on the rotation axis) or --fixation auto")
        auto = fixation is None or fixation.strip().lower() == "auto"
        point = None if auto else _numbers(fixation or "", 2, "--fixation", "640,360 (or auto)")
        if blur is not None and not (math.isfinite(blur) and 0 <= blur <= 20):
            raise InputError("--blur takes a sigma in pixels between 0 and 20")
        tracker = TrackerConfig(blur_sigma_px=blur)
        if roi is not None:
            x, y, w, h = _numbers(roi, 4, "--roi", "100,50,400,300")
            tracker = replace(tracker, roi=Roi(int(x), int(y), int(w), int(h)))
        if output is not None:
            check_output_path(output, force)  # fail before a long run, not after
        if series_csv_path is not None:
            if window is None:
                raise InputError("--series-csv needs --window SECONDS")
            check_output_path(series_csv_path, force)
        fov_deg, find_focal = parse_fov(fov)
        if fov is not None and fov.strip().lower() == "auto" and (focal_px is not None or method == "paper"):
            raise InputError("--fov auto finds the lens from the tracks: drop --focal-px (a given lens) or use "
                             "--method fit (the paper's method is orthographic)")
        frame_times = None if times is None else tuple(float(t) for t in read_times(times))
        config = AnalysisConfig(fixation_px=None if point is None else (point[0], point[1]), fps=fps,
                                times_s=frame_times,
                                axis_angle_deg=axis_angle, angle_from=angle_from, elevation_deg=elevation,
                                direction=None if direction is None else direction.strip().lower(),
                                window_s=window, start_s=start,
                                end_s=end, every=every,
                                method=method, fov_deg=fov_deg, focal_px=focal_px, find_focal=find_focal,
                                tracker=tracker, segment=segment,
                                keep_tracks=overlay is not None,
                                points_px=tuple((x, y) for x, y in (_numbers(t, 2, "--track", "320,180")
                                                                    for t in track or [])),
                                tracker_kind=tracker_kind or ("csrt" if track else "klt"))
        for picture in (overlay, plot):
            if picture is not None:
                check_output_path(picture, force)
        if overlay is not None and overlay.suffix.lower() not in OVERLAY_SUFFIXES:
            # OpenCV wrote a stream of JPEG frames under an image's name (out.png): a broken picture
            raise InputError(f"--overlay writes a video: give it a name ending in {', '.join(OVERLAY_SUFFIXES[1:])}"
                             f" (got {overlay.name}; --plot draws a picture)")
        check_expectation(expect, tolerance)
        units = _units(scale, unit)
        sources = expand_inputs(videos)
        if len(videos) > 1 or sources != videos:
            if series_csv_path is not None or overlay is not None or plot is not None:
                raise InputError("--series-csv, --overlay and --plot take one input; with several, use --output-dir")
            return _batch(sources, config, expect, tolerance, jobs, scheduler, output_dir, form, output, force,
                          strict)
        if scheduler is not None:
            raise InputError("--scheduler is for several inputs (a batch); with one, drop it")
        if output_dir is not None:
            raise InputError("--output-dir is for several inputs; with one, use --output")
        with _progress_bar(quiet) as (progress, stage):
            analysis = said(analyze(sources[0], config, progress, stage))
        # the files first, the report on stdout last: a reader that stops early (| head) costs no file
        if series_csv_path is not None:
            write_text(series_csv_path, series_csv(analysis), force)
        if overlay is not None:
            _write_overlay(sources[0], fps, start, end, analysis, overlay, force,
                           None if frame_times is None else np.asarray(frame_times))
        if plot is not None:
            from rotrate_cli.cli.plots import write_plot

            write_plot(analysis if units is None else with_units(analysis, *units), plot, force)
        _emit(analysis if units is None else with_units(analysis, *units), form, output, force)
        for warning in analysis.warnings:
            Console(stderr=True, soft_wrap=True).print(f"rotrate: warning: {in_flags(warning)}", markup=False,
                                                       highlight=False)
        if expect is not None and tolerance is not None:
            miss = check_expected(analysis.omega_rad_s, expect, tolerance)
            if miss:
                raise _fail(miss, 1)
        if strict and analysis.quality == "weak":
            raise _fail(weak_message(analysis), 1)
        return 0

    code = _run(debug, job)
    if code:
        raise typer.Exit(code)


def _units(scale: float | None, unit: str | None) -> tuple[float, str] | None:
    """``(units per pixel, unit name)`` from --scale/--unit, or None."""
    if scale is None:
        if unit is not None:
            raise InputError("--unit names the unit of --scale; give --scale UNITS_PER_PX too")
        return None
    if not (math.isfinite(scale) and scale > 0):
        raise InputError("--scale takes the physical size of one pixel, a positive number (e.g. 0.02)")
    name = (unit or "units").strip()
    if not name or not all(c.isalnum() or c in "_-" for c in name):
        raise InputError("--unit takes a short name of letters and digits, such as in or mm")
    return scale, name


def _write_overlay(source: str, fps: float | None, start: float, end: float | None, analysis: Analysis,
                   path: Path, force: bool, times_s: np.ndarray | None = None) -> None:
    """The overlay video of a finished analysis (see :func:`rotrate_cli.output.overlay.write_overlay`):
    the running rate of the tracks, or, where the rate is the clip's repetition (a whole-clip
    measurement), the reported rate throughout."""
    import numpy as np

    from rotrate_cli.fitting.series import running_rate
    from rotrate_cli.output.overlay import write_overlay
    from rotrate_cli.stages.fits import running_measure
    from rotrate_cli.video.decode import FrameSource

    running = running_rate(analysis.offsets, running_measure(analysis.method, analysis.rejection, analysis.camera))
    times = running["time_s"].to_numpy()

    def at(time_s: float) -> tuple[float, float, float]:
        if analysis.rate_from == "repetition":
            return analysis.omega_rad_s, analysis.omega_low_rad_s, analysis.omega_high_rad_s
        index = int(np.searchsorted(times, time_s + 1e-9, side="right")) - 1
        if index < 0:
            return math.nan, math.nan, math.nan
        row = running.iloc[index]
        return float(row.omega_rad_s), float(row.omega_low_rad_s), float(row.omega_high_rad_s)

    features = analysis.features
    inliers = set(features.loc[features["inlier"], "track"].astype(int))
    assert analysis.tracks is not None  # noqa: S101 - asked for with keep_tracks
    named = {int(track): str(reason) for track, reason in zip(features["track"], features["reason"], strict=True)
             if reason in ("reflection", "slides", "other_motion")}
    write_overlay(FrameSource(source, fps=fps, times_s=times_s), path, analysis.tracks, inliers, analysis.fixation_px,
                  analysis.axis_angle_deg, at, start, end, force, named)


def _wide_console() -> Console:
    """stdout, at least 140 columns wide when it is not a terminal (file names stay whole in logs)."""
    console = Console(highlight=False)
    return console if console.is_terminal else Console(highlight=False, width=max(console.width, 140))


def _detail_paths(sources: list[str], folder: Path, suffix: str) -> list[Path]:
    """``folder/STEM.suffix`` per source, numbered where two sources share a stem."""
    paths, seen = [], {}
    for source in sources:
        stem = Path(source.rstrip("/")).stem.replace("%", "") or "input"
        seen[stem] = seen.get(stem, 0) + 1
        paths.append(folder / (f"{stem}{suffix}" if seen[stem] == 1 else f"{stem}-{seen[stem]}{suffix}"))
    return paths


def _batch(sources: list[str], config: AnalysisConfig, expect: float | None, tolerance: float | None, jobs: int,
           scheduler: str | None, output_dir: Path | None, fmt: str, output: Path | None, force: bool,
           strict: bool = False) -> int:
    """Analyse several inputs; one summary row each; the worst input's exit code."""
    from rotrate_cli.batch import Job, batch_exit_code, run_batch
    from rotrate_cli.cli.report import render, render_summary, summary_text

    details: list[Path] = []
    if output_dir is not None:
        make_folder(output_dir)
        details = _detail_paths(sources, output_dir, ".csv" if fmt == "csv" else ".json")
        for path in details:
            check_output_path(path, force)  # before a long run, not after
    outcomes = said_outcomes(run_batch([Job(source, config, expect, tolerance, strict) for source in sources], jobs,
                                       scheduler=scheduler))
    for outcome, path in zip(outcomes, details, strict=False):
        if outcome.analysis is not None:
            write_text(path, render(outcome.analysis, "csv" if fmt == "csv" else "json"), force)
    if output is not None:
        write_text(output, summary_text(outcomes, fmt), force)
    elif fmt == "table":
        render_summary(outcomes, _wide_console())
    else:
        sys.stdout.write(summary_text(outcomes, fmt))
        sys.stdout.flush()
    return batch_exit_code(outcomes)


@app.command("check")
def check_command(
    manifest: Annotated[Path, typer.Argument(help="CSV: file, expected_omega, tolerance_pct, and optional "
                                                  "per-row fixation, fov, focal_px, fps, axis_angle, every, "
                                                  "method, start, end.")],
    junit: Annotated[Path | None, typer.Option("--junit", metavar="PATH",
                                               help="Also write JUnit XML here, for CI.")] = None,
    jobs: Annotated[int, typer.Option("--jobs", "-j", metavar="N", help="Rows analysed at once (processes).")] = 1,
    scheduler: SchedulerOption = None,
    fmt: Annotated[str | None, typer.Option("--format", "-f", metavar="FORMAT",
                                            help="table (pass/fail), csv or json (one row per file).")] = None,
    force: Annotated[bool, typer.Option("--force", metavar="", help="Replace an existing --junit file.")] = False,
    debug: DebugOption = False,
) -> None:
    """Run a regression manifest: pass when every file's omega is within its tolerance."""

    def job() -> int:
        from rotrate_cli.analysis import AnalysisConfig
        from rotrate_cli.batch import read_manifest, run_batch
        from rotrate_cli.cli.report import junit_xml, render_check, summary_text

        form = fmt or "table"
        _check_format(form)
        if junit is not None:
            check_output_path(junit, force)
        jobs_list = read_manifest(manifest, AnalysisConfig(fixation_px=None))
        outcomes = said_outcomes(run_batch(jobs_list, jobs, scheduler=scheduler))
        expected = [(j.expected_rad_s or math.nan, j.tolerance_pct or 0.0) for j in jobs_list]
        if junit is not None:
            write_text(junit, junit_xml(outcomes, expected, manifest.stem), force)
        if form == "table":
            render_check(outcomes, expected, _wide_console())
        else:
            sys.stdout.write(summary_text(outcomes, form))
        failed = sum(o.status != "ok" for o in outcomes)
        if failed:
            raise _fail(f"{failed} of {len(outcomes)} manifest rows failed", 1)
        return 0

    _run(debug, job)


@app.command("frame")
def frame_command(
    video: Annotated[str, typer.Argument(help="Video file, image folder, or printf pattern.")],
    output: Annotated[Path, typer.Option("--output", "-o", metavar="PATH", help="The still to write (.png).")],
    at: Annotated[float, typer.Option("--at", metavar="SECONDS", help="Time of the frame, s.")] = 0.0,
    fps: Annotated[float | None, typer.Option("--fps", metavar="FPS",
                                              help="Frame rate; required for image sequences.")] = None,
    grid: Annotated[int, typer.Option("--grid", help="Grid spacing, px.")] = 50,
    angle_from: Annotated[str, typer.Option("--angle-from", metavar="auto|motion|paths",
                                            help="How to find the axis angle: auto (default), "
                                                                 "motion or paths (as for analyze).")] = "auto",
    force: ForceOption = False,
    debug: DebugOption = False,
) -> None:
    """Write one frame with a pixel grid and the rotation axis where it is found: read --fixation off it."""

    def job() -> int:
        from rotrate_cli.analysis import AnalysisConfig, analyze
        from rotrate_cli.output.overlay import draw_axis, draw_grid, frame_at, write_image
        from rotrate_cli.video.decode import FrameSource

        if not 5 <= grid <= 10_000:
            raise InputError("--grid takes a spacing in pixels, 5 or more")
        source = FrameSource(video, fps=fps)
        frame = frame_at(source, at)
        image = draw_grid(frame.image, grid)
        try:  # the axis from the motion around that time
            analysis = analyze(video, AnalysisConfig(fixation_px=None, fps=fps, start_s=max(0.0, at - 3.0),
                                                     end_s=at + 3.0, angle_from=angle_from))
        except SettingError as exc:
            if exc.setting == "angle_from":
                raise
            message = f"no axis found ({in_flags(str(exc))}); read --fixation X,Y off the grid"
        except RotrateError as exc:
            message = f"no axis found ({in_flags(str(exc))}); read --fixation X,Y off the grid"
        else:
            x, y = analysis.fixation_px
            draw_axis(image, (x, y), analysis.axis_angle_deg, f"{x:.1f},{y:.1f}")
            hint = "" if angle_from == "auto" else f" --angle-from {angle_from}"
            message = (f"axis found through {x:.1f},{y:.1f} ({analysis.axis_angle_deg:+.1f} deg from vertical; "
                       f"omega {analysis.omega_rad_s:.4f} rad/s): try --fixation {x:.1f},{y:.1f}{hint}")
        write_image(output, image, force)
        Console(highlight=False, soft_wrap=True).print(f"wrote {output} (frame {frame.index}, {frame.time_s:.3f} s); "
                                                       f"{message}", markup=False)
        return 0

    _run(debug, job)


@app.command("omega")
def omega_command(
    tracks: Annotated[Path, typer.Argument(help="Tracks CSV: track (or feature), frame, optional time_s, position.")],
    fixation: Annotated[float, typer.Option("--fixation", metavar="X,Y|auto",
                                            help="Axis position, in the position column's units.")],
    position_column: Annotated[str, typer.Option("--position-column", metavar="NAME",
                                                 help="The horizontal position column.")] = "x",
    fps: Annotated[float | None, typer.Option("--fps", metavar="FPS",
                                              help="Frame rate: times are frame / fps (else time_s).")] = None,
    every: EveryOption = None,
    method: MethodOption = "fit",
    fmt: FormatOption = None,
    output: OutputOption = None,
    force: ForceOption = False,
    debug: DebugOption = False,
) -> None:
    """Rotation rate from tracked positions in a file (for example the paper's Table I)."""

    def job() -> int:
        from rotrate_cli.analysis import analyze_tracks
        from rotrate_cli.tracking.tracks_io import read_tracks

        form = output_format(output, fmt)
        _check_format(form)
        _check_method(method)
        table = read_tracks(tracks, position_column)
        unit = position_column.rsplit("_", 1)[1] if "_" in position_column else "units"
        analysis = analyze_tracks(table, fixation, source=str(tracks), fps=fps, every=every, method=method,
                                  position_unit=unit)
        _emit(analysis, form, output, force)
        return 0

    _run(debug, job)


@app.command("synth")
def synth_command(
    output: Annotated[Path, typer.Argument(help="Video to write (.mp4); the truth goes beside it as .json.")],
    shape: Annotated[str, typer.Option("--shape", metavar="NAME", help=f"One of {', '.join(SHAPES)}.")] = "box",
    omega: Annotated[
        float, typer.Option("--omega", metavar="RAD_S", help="Rate in rad/s; negative turns clockwise seen from above.")
    ] = 0.5,
    fps: Annotated[float, typer.Option("--fps", metavar="FPS", help="Frames per second.")] = 30.0,
    duration: Annotated[float, typer.Option("--duration", metavar="SECONDS", help="Length, s.")] = 5.0,
    size: Annotated[str, typer.Option("--size", metavar="WxH", help="WIDTHxHEIGHT in pixels.")] = "640x360",
    projection: Annotated[str, typer.Option("--projection", metavar="NAME",
                                            help=f"One of {', '.join(PROJECTIONS)}.")] = "orthographic",
    fov: Annotated[float, typer.Option("--fov", metavar="DEG|auto|ortho",
                                       help="Horizontal field of view, degrees (perspective).")] = 25.0,
    axis_offset: Annotated[float, typer.Option("--axis-offset", metavar="PX",
                                               help="Axis offset from the centre, px.")] = 0.0,
    noise: Annotated[float, typer.Option("--noise", metavar="LEVELS", help="Sensor noise, grey levels.")] = 0.0,
    jpeg_quality: Annotated[
        int | None, typer.Option("--jpeg-quality", metavar="1-100",
                                 help="Pass each frame through JPEG at this quality (1-100).")
    ] = None,
    roll: Annotated[float, typer.Option("--roll", metavar="DEG", help="Camera roll, degrees (the axis's top end leans "
                                                       "right; 90: a horizontal axis).")] = 0.0,
    elevation: Annotated[float, typer.Option("--elevation", metavar="DEG", help="Camera elevation, degrees above the "
                                                                 "object's mid-height (the top shows).")] = 0.0,
    seed: Annotated[int, typer.Option("--seed", metavar="N", help="Seed of textures and noise.")] = 0,
    force: ForceOption = False,
    debug: DebugOption = False,
) -> None:
    """Render a synthetic clip of a spinning solid with a known rate, and its truth JSON."""

    def job() -> int:
        from rotrate_cli.video.synth import SceneConfig, write_clip

        try:
            width, height = (int(v) for v in size.lower().split("x"))
        except ValueError:
            raise InputError(f"--size takes WIDTHxHEIGHT such as 640x360; got {size!r}") from None
        scene = SceneConfig(shape=shape, omega_rad_s=omega, fps=fps, duration_s=duration, width_px=width,
                            height_px=height, projection=projection, fov_deg=fov, axis_offset_px=axis_offset,
                            noise_sigma=noise, jpeg_quality=jpeg_quality, roll_deg=roll, elevation_deg=elevation,
                            seed=seed)
        truth = write_clip(scene, output, force=force)
        fx, fy = truth["fixation_px"]  # type: ignore[misc]
        Console(highlight=False).print(
            f"wrote {output} ({scene.frame_count} frames); truth: omega {abs(omega):g} rad/s, "
            f"fixation {fx:g},{fy:g}", markup=False)
        return 0

    _run(debug, job)


def _quiet_native_logs() -> None:
    """Keep OpenCV's and FFmpeg's own log lines (e.g. "moov atom not found") off the terminal:
    the user gets our one-line message instead. ``--debug`` keeps them."""
    os.environ.setdefault("OPENCV_FFMPEG_LOGLEVEL", "-8")  # AV_LOG_QUIET; read when FFmpeg is first used
    os.environ.setdefault("OPENCV_LOG_LEVEL", "SILENT")  # read when OpenCV is imported, by the command that runs
    if "cv2" in sys.modules:  # imported already (an embedding program): tell it directly, where it can be told
        logging = getattr(getattr(sys.modules["cv2"], "utils", None), "logging", None)
        if logging is not None:
            logging.setLogLevel(logging.LOG_LEVEL_SILENT)
    # numpy's floating-point warnings on degenerate tracks are handled (NaN, rejected) by the library
    warnings.simplefilter("ignore", RuntimeWarning)


def _one_blas_thread() -> None:
    """OpenBLAS (NumPy's, and SciPy's own copy) at one thread for this process and the batch's
    workers, set before either is loaded (they read it once, at load). An analysis runs BLAS at
    one thread anyway (:mod:`rotrate_cli.runtime.pools`), but each copy starts a thread per core when it
    loads, and those spin while the imports go on: measured on a 2-core machine, whole processes
    of ``rotrate analyze`` took 0.82 times the processor time on the 720p bench clip (0.27 s less)
    and 0.97 times on the record clip, wall time the same, and ``rotrate synth`` half. A user's
    own setting is kept."""
    if "numpy" not in sys.modules:
        os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")


def main() -> None:
    """Console-script entry point."""
    _one_blas_thread()
    if "--debug" not in sys.argv:
        _quiet_native_logs()
    app()
