"""The ``analyze`` command: flags -> settings, the outputs checked before any frame is read, then
one input measured (its files, then its report) or a batch of them."""

from __future__ import annotations

import math
import sys
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from rotrate_cli.cli import (
    OVERLAY_SUFFIXES,
    DebugOption,
    EveryOption,
    ForceOption,
    FormatOption,
    MethodOption,
    OutputOption,
    QuietOption,
    SchedulerOption,
    app,
    batch_line,
    check_format,
    check_method,
    console,
    emit,
    fail,
    numbers,
    progress_bar,
    run,
    said,
    said_outcomes,
    standard_output,
    wide_console,
)
from rotrate_cli.errors import InputError
from rotrate_cli.output.files import check_output_path, make_folder, output_format, write_text

if TYPE_CHECKING:
    import numpy as np

    from rotrate_cli.analysis import Analysis, AnalysisConfig


@app.command("analyze")
def analyze_command(
    videos: Annotated[list[str], typer.Argument(metavar="VIDEO",
                                                help="Video file(s), image folder, printf pattern like "
                                                      "frames/img.%03d.png, folders of videos, or globs.")],
    fixation: Annotated[str | None, typer.Option("--fixation", metavar="X,Y|auto",
                                                 help="X,Y pixel of a point on the rotation axis, or "
                                                                    "'auto' to find the axis from the motion "
                                                                    "(required, except with --segment).")] = None,
    fps: Annotated[
        float | None, typer.Option("--fps", metavar="FPS",
                                   help="Frame rate; overrides the file's; for images without "
                                        "EXIF capture times (else from them).")
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
    tracker_kind: Annotated[str | None, typer.Option("--tracker", metavar="auto|klt|csrt|matched",
                                                     help="auto (default: klt for videos, matched for "
                                                          "image sequences; csrt with --track), klt, "
                                                          "csrt (automatic: 30 corners, about 5x "
                                                          "slower; videos only) or matched (SIFT "
                                                          "features matched photo to photo).")] = None,
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
    resume: Annotated[bool, typer.Option("--resume", metavar="",
                                         help="With --output-dir: skip the inputs whose reports are there "
                                              "already (a batch run again after an interrupt).")] = False,
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
        from rotrate_cli.batch import check_expectation, expand_inputs

        report = standard_output(output)
        form = output_format(report, fmt)
        check_format(form)
        check_method(method)
        config = _config(fixation=fixation, fps=fps, times=times, start=start, end=end, roi=roi, every=every,
                         method=method, fov=fov, focal_px=focal_px, axis_angle=axis_angle, angle_from=angle_from,
                         elevation=elevation, direction=direction, window=window, track=track,
                         tracker_kind=tracker_kind, segment=segment, blur=blur, keep_tracks=overlay is not None)
        outputs = _Outputs(report, series_csv_path, overlay, plot, force)
        outputs.check(window)  # before a long run, not after
        check_expectation(expect, tolerance)
        units = _units(scale, unit)
        sources = expand_inputs(videos)
        if len(videos) > 1 or sources != videos or output_dir is not None:  # a glob of one file is a batch too
            if outputs.pictures_or_series:
                raise InputError("--series-csv, --overlay and --plot take one input; with several, use --output-dir")
            return _batch(sources, config, expect, tolerance, jobs, scheduler, output_dir, form, report, force,
                          strict, quiet=quiet, resume=resume)
        if resume:
            raise InputError("--resume skips the inputs whose reports --output-dir holds: give --output-dir")
        if scheduler is not None:
            raise InputError("--scheduler is for several inputs (a batch); with one, drop it")
        return _one(sources[0], config, outputs, form, units, quiet, expect, tolerance, strict)

    code = run(debug, job)
    if code:
        raise typer.Exit(code)


def _config(*, fixation: str | None, fps: float | None, times: Path | None, start: float, end: float | None,
            roi: str | None, every: int | None, method: str, fov: str | None, focal_px: float | None,
            axis_angle: float | None, angle_from: str, elevation: float | None, direction: str | None,
            window: float | None, track: list[str] | None, tracker_kind: str | None, segment: bool,
            blur: float | None, keep_tracks: bool) -> AnalysisConfig:
    """The analysis's settings from the command's flags (the library checks them again)."""
    from rotrate_cli.analysis import AnalysisConfig
    from rotrate_cli.scene.focal import parse_fov
    from rotrate_cli.tracking.klt import Roi, TrackerConfig
    from rotrate_cli.video.clock import read_times

    if fixation is None and not segment:
        raise InputError("give --fixation X,Y (a pixel on the rotation axis) or --fixation auto")
    auto = fixation is None or fixation.strip().lower() == "auto"
    point = None if auto else numbers(fixation or "", 2, "--fixation", "640,360 (or auto)")
    if blur is not None and not (math.isfinite(blur) and 0 <= blur <= 20):
        raise InputError("--blur takes a sigma in pixels between 0 and 20")
    tracker = TrackerConfig(blur_sigma_px=blur)
    if roi is not None:
        x, y, w, h = numbers(roi, 4, "--roi", "100,50,400,300")
        tracker = replace(tracker, roi=Roi(int(x), int(y), int(w), int(h)))
    fov_deg, find_focal = parse_fov(fov, "--fov")
    if fov is not None and fov.strip().lower() == "auto" and (focal_px is not None or method == "paper"):
        raise InputError("--fov auto finds the lens from the tracks: drop --focal-px (a given lens) or use "
                         "--method fit (the paper's method is orthographic)")
    frame_times = None if times is None else tuple(float(t) for t in read_times(times))
    return AnalysisConfig(fixation_px=None if point is None else (point[0], point[1]), fps=fps, times_s=frame_times,
                          axis_angle_deg=axis_angle, angle_from=angle_from, elevation_deg=elevation,
                          direction=None if direction is None else direction.strip().lower(),
                          window_s=window, start_s=start, end_s=end, every=every,
                          method=method, fov_deg=fov_deg, focal_px=focal_px, find_focal=find_focal,
                          tracker=tracker, segment=segment, keep_tracks=keep_tracks,
                          points_px=tuple((x, y) for x, y in (numbers(t, 2, "--track", "320,180")
                                                              for t in track or [])),
                          tracker_kind=tracker_kind or ("csrt" if track else "auto"))


@dataclass(frozen=True)
class _Outputs:
    """The files one analysis writes besides its report."""

    report: Path | None
    series_csv: Path | None
    overlay: Path | None
    plot: Path | None
    force: bool

    @property
    def pictures_or_series(self) -> bool:
        return self.series_csv is not None or self.overlay is not None or self.plot is not None

    def check(self, window_s: float | None) -> None:
        """Fail before any frame is read where an output could not be written."""
        if self.report is not None:
            check_output_path(self.report, self.force)
        if self.series_csv is not None:
            if window_s is None:
                raise InputError("--series-csv needs --window SECONDS")
            check_output_path(self.series_csv, self.force)
        for picture in (self.overlay, self.plot):
            if picture is not None:
                check_output_path(picture, self.force)
        if self.plot is not None:
            from rotrate_cli.cli.plots import check_plot

            check_plot(self.plot)
        if self.overlay is not None and self.overlay.suffix.lower() not in OVERLAY_SUFFIXES:
            # OpenCV wrote a stream of JPEG frames under an image's name (out.png): a broken picture
            raise InputError(f"--overlay writes a video: give it a name ending in {', '.join(OVERLAY_SUFFIXES[1:])}"
                             f" (got {self.overlay.name}; --plot draws a picture)")


def _one(source: str, config: AnalysisConfig, outputs: _Outputs, form: str, units: tuple[float, str] | None,
         quiet: bool, expect: float | None, tolerance: float | None, strict: bool) -> int:
    """Measure one input, write its files, then its report; 0, or 1 where a CI check fails."""
    import numpy as np

    from rotrate_cli.analysis import analyze
    from rotrate_cli.batch import check_expected, weak_message
    from rotrate_cli.cli.report import series_csv, with_units

    with progress_bar(quiet) as (progress, stage):
        analysis = said(analyze(source, config, progress, stage))
    # the files first, the report on stdout last: a reader that stops early (| head) costs no file
    if outputs.series_csv is not None:
        write_text(outputs.series_csv, series_csv(analysis), outputs.force)
    if outputs.overlay is not None:
        with progress_bar(quiet) as (progress, stage):
            if stage is not None:
                stage("writing the overlay")
            _write_overlay(source, config.fps, config.start_s, config.end_s, analysis, outputs.overlay, outputs.force,
                           None if config.times_s is None else np.asarray(config.times_s), progress)
    shown = analysis if units is None else with_units(analysis, *units)
    if outputs.plot is not None:
        from rotrate_cli.cli.plots import write_plot

        write_plot(shown, outputs.plot, outputs.force)
    emit(shown, form, outputs.report, outputs.force)
    for warning in analysis.warnings:
        console(stderr=True, soft_wrap=True).print(f"rotrate: warning: {warning}", markup=False, highlight=False)
    if expect is not None and tolerance is not None:
        miss = check_expected(analysis.omega_rad_s, expect, tolerance)
        if miss:
            raise fail(miss, 1)
    if strict and analysis.quality == "weak":
        raise fail(weak_message(analysis), 1)
    return 0


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
                   path: Path, force: bool, times_s: np.ndarray | None = None,
                   progress: Callable[[int, int | None], None] | None = None) -> None:
    """The overlay video of a finished analysis (see :func:`rotrate_cli.output.overlay.write_overlay`):
    the running rate of the tracks, or, where the rate is the clip's repetition or the picture's
    turning (not the tracks'), the reported rate throughout."""
    import numpy as np

    from rotrate_cli.fitting.series import running_rate
    from rotrate_cli.output.overlay import write_overlay
    from rotrate_cli.runtime.lazy import pandas as pd
    from rotrate_cli.stages.fits import running_measure
    from rotrate_cli.video.decode import FrameSource

    headline = analysis.rate_from in ("repetition", "turning")  # not the tracks' rate: the headline throughout
    running = (running_rate(analysis.offsets.iloc[:0], lambda _: None) if headline  # type: ignore[arg-type,return-value]
               else running_rate(analysis.offsets, running_measure(analysis.method, analysis.rejection,
                                                                    analysis.camera)))
    times = running["time_s"].to_numpy()

    def at(time_s: float) -> tuple[float, float, float]:
        if headline:
            return analysis.omega_rad_s, analysis.omega_low_rad_s, analysis.omega_high_rad_s
        index = int(np.searchsorted(times, time_s + 1e-9, side="right")) - 1
        if index < 0:
            return math.nan, math.nan, math.nan
        row = running.iloc[index]
        return float(row.omega_rad_s), float(row.omega_low_rad_s), float(row.omega_high_rad_s)

    features = analysis.features
    inliers = set(features.loc[features["inlier"], "track"].astype(int))
    tracks = analysis.tracks
    if tracks is None:  # no point was followed at all (the picture's turning alone): none to draw
        tracks = pd.DataFrame({"frame": pd.Series(dtype=int), "time_s": pd.Series(dtype=float),
                               "track": pd.Series(dtype=int), "x_px": pd.Series(dtype=float),
                               "y_px": pd.Series(dtype=float)})
    named = {int(track): str(reason) for track, reason in zip(features["track"], features["reason"], strict=True)
             if reason in ("reflection", "slides", "other_motion")}
    # the headline's quality where the headline is what is written (the tracks' running rate has its own)
    tag = "weak" if headline and analysis.quality == "weak" else ""
    write_overlay(FrameSource(source, fps=fps, times_s=times_s), path, tracks, inliers, analysis.fixation_px,
                  analysis.axis_angle_deg, at, start, end, force, named, progress, analysis.camera_path, tag)


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
           strict: bool = False, quiet: bool = False, resume: bool = False) -> int:
    """Analyse several inputs; one summary row each; the worst input's exit code. Each input's
    report is written as soon as it finishes, with a progress line (unless ``quiet``); with
    ``resume``, the inputs whose reports are there already are skipped."""
    from rotrate_cli.batch import Job, Outcome, batch_exit_code, run_batch
    from rotrate_cli.cli.report import render, render_summary, summary_text

    if resume and output_dir is None:
        raise InputError("--resume skips the inputs whose reports --output-dir holds: give --output-dir")
    details: dict[str, Path] = {}
    skipped: dict[str, Outcome] = {}
    if output_dir is not None:
        make_folder(output_dir)
        for source, path in zip(sources, _detail_paths(sources, output_dir, ".csv" if fmt == "csv" else ".json"),
                                strict=True):
            if resume and path.exists():
                skipped[source] = Outcome(source, "skipped", None, f"its report {path} is there already (--resume)")
                continue
            check_output_path(path, force)  # before a long run, not after
            details[source] = path
    todo = [source for source in sources if source not in skipped]
    line = batch_line(quiet, len(sources), len(skipped))

    def done(outcome: Outcome) -> None:
        """Keep a finished input's report at once (an interrupt later loses nothing) and say so."""
        if outcome.analysis is not None and outcome.source in details:
            write_text(details[outcome.source], render(said(outcome.analysis), "csv" if fmt == "csv" else "json"),
                       force)
        line(outcome)

    ran = said_outcomes(run_batch([Job(source, config, expect, tolerance, strict) for source in todo], jobs,
                                  done=done, scheduler=scheduler))
    by_source = {outcome.source: outcome for outcome in ran} | skipped
    outcomes = [by_source[source] for source in sources]
    if output is not None:
        write_text(output, summary_text(outcomes, fmt), force)
    elif fmt == "table":
        render_summary(outcomes, wide_console())
    else:
        sys.stdout.write(summary_text(outcomes, fmt))
        sys.stdout.flush()
    return batch_exit_code(outcomes)
