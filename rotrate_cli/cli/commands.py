"""The commands beside ``analyze``: ``check`` (a regression manifest), ``frame`` (a still with a
grid and the axis found), ``omega`` (a rate from a tracks file) and ``synth`` (a clip of known rate)."""

from __future__ import annotations

import math
import sys
from pathlib import Path
from typing import Annotated

import typer

from rotrate_cli.cli import (
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
    in_flags,
    run,
    said_outcomes,
    standard_output,
    wide_console,
)
from rotrate_cli.errors import InputError, RotrateError, SettingError
from rotrate_cli.output.files import check_output_path, output_format, write_text
from rotrate_cli.runtime.choices import PROJECTIONS, SHAPES


@app.command("check")
def check_command(
    manifest: Annotated[Path, typer.Argument(metavar="MANIFEST",
                                             help="CSV: file, expected_omega, tolerance_pct, and optional "
                                                  "per-row fixation, fov, focal_px, fps, axis_angle, every, "
                                                  "method, start, end.")],
    junit: Annotated[Path | None, typer.Option("--junit", metavar="PATH",
                                               help="Also write JUnit XML here, for CI.")] = None,
    jobs: Annotated[int, typer.Option("--jobs", "-j", metavar="N", help="Rows analysed at once (processes).")] = 1,
    scheduler: SchedulerOption = None,
    fmt: Annotated[str | None, typer.Option("--format", "-f", metavar="FORMAT",
                                            help="table (pass/fail), csv or json (one row per file).")] = None,
    force: Annotated[bool, typer.Option("--force", metavar="", help="Replace an existing --junit file.")] = False,
    quiet: QuietOption = False,
    debug: DebugOption = False,
) -> None:
    """Run a regression manifest: pass when every file's omega is within its tolerance. A line on
    stderr tells each file as it finishes."""

    def job() -> int:
        from rotrate_cli.analysis import AnalysisConfig
        from rotrate_cli.batch import read_manifest, run_batch
        from rotrate_cli.cli.report import junit_xml, render_check, summary_text

        form = fmt or "table"
        check_format(form)
        if junit is not None:
            check_output_path(junit, force)
        jobs_list = read_manifest(manifest, AnalysisConfig(fixation_px=None))
        outcomes = said_outcomes(run_batch(jobs_list, jobs, done=batch_line(quiet, len(jobs_list)),
                                           scheduler=scheduler))
        expected = [(j.expected_rad_s or math.nan, j.tolerance_pct or 0.0) for j in jobs_list]
        if junit is not None:
            write_text(junit, junit_xml(outcomes, expected, manifest.stem), force)
        if form == "table":
            render_check(outcomes, expected, wide_console())
        else:
            sys.stdout.write(summary_text(outcomes, form))
        failed = sum(o.status != "ok" for o in outcomes)
        if failed:
            raise fail(f"{failed} of {len(outcomes)} manifest rows failed", 1)
        return 0

    run(debug, job)


@app.command("frame")
def frame_command(
    video: Annotated[str, typer.Argument(metavar="VIDEO", help="Video file, image folder, or printf pattern.")],
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
        import cv2

        from rotrate_cli.analysis import AnalysisConfig, analyze
        from rotrate_cli.output.overlay import draw_axis, draw_grid, frame_at, write_image
        from rotrate_cli.video.decode import FrameSource

        if not cv2.haveImageWriter(str(output)):  # before any frame is read
            raise InputError(f"-o writes a picture: give it a name ending in .png or .jpg (got {output.name})")

        if not 5 <= grid <= 10_000:
            raise InputError("--grid takes a spacing in pixels, 5 or more")
        source = FrameSource(video, fps=fps)
        frame = frame_at(source, at)
        image = draw_grid(frame.image, grid)
        message: str | None = None
        try:  # the axis from the motion around that time
            analysis = analyze(video, AnalysisConfig(fixation_px=None, fps=fps, start_s=max(0.0, at - 3.0),
                                                     end_s=at + 3.0, angle_from=angle_from))
        except SettingError as exc:
            if exc.setting == "angle_from":
                raise
            message = f"no axis found ({in_flags(str(exc))}); read --fixation X,Y off the grid"
        except RotrateError as exc:
            message = f"no axis found ({in_flags(str(exc))}); read --fixation X,Y off the grid"
        if message is None:
            x, y = analysis.fixation_px
            if math.isfinite(x) and math.isfinite(y):
                draw_axis(image, (x, y), analysis.axis_angle_deg, f"{x:.1f},{y:.1f}")
                hint = "" if angle_from == "auto" else f" --angle-from {angle_from}"
                message = (f"axis found through {x:.1f},{y:.1f} ({analysis.axis_angle_deg:+.1f} deg from vertical; "
                           f"omega {analysis.omega_rad_s:.4f} rad/s): try --fixation {x:.1f},{y:.1f}{hint}")
            else:  # no track: the rate is the picture's return alone, about no axis
                message = (f"no axis found (no track gave a rate; omega {analysis.omega_rad_s:.4f} rad/s is the "
                           "picture's return alone); read --fixation X,Y off the grid")
        write_image(output, image, force)
        console(highlight=False, soft_wrap=True).print(f"wrote {output} (frame {frame.index}, {frame.time_s:.3f} s); "
                                                       f"{message}", markup=False)
        return 0

    run(debug, job)


@app.command("omega")
def omega_command(
    tracks: Annotated[Path, typer.Argument(
        metavar="TRACKS", help="Tracks CSV: track (or feature), frame, optional time_s, position.")],
    fixation: Annotated[float, typer.Option("--fixation", metavar="POSITION",
                                            help="The axis's position along the position column, in its "
                                                 "units (one number).")],
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

        report = standard_output(output)
        form = output_format(report, fmt)
        check_format(form)
        check_method(method)
        table = read_tracks(tracks, position_column)
        unit = position_column.rsplit("_", 1)[1] if "_" in position_column else "units"
        analysis = analyze_tracks(table, fixation, source=str(tracks), fps=fps, every=every, method=method,
                                  position_unit=unit)
        emit(analysis, form, report, force)
        return 0

    run(debug, job)


@app.command("synth")
def synth_command(
    output: Annotated[Path, typer.Argument(metavar="OUTPUT",
                                           help="Video to write (.mp4); the truth goes beside it as .json.")],
    shape: Annotated[str, typer.Option("--shape", metavar="NAME", help=f"One of {', '.join(SHAPES)}.")] = "box",
    omega: Annotated[
        float, typer.Option("--omega", metavar="RAD_S", help="Rate in rad/s; negative turns clockwise seen from above.")
    ] = 0.5,
    fps: Annotated[float, typer.Option("--fps", metavar="FPS", help="Frames per second.")] = 30.0,
    duration: Annotated[float, typer.Option("--duration", metavar="SECONDS", help="Length, s.")] = 5.0,
    size: Annotated[str, typer.Option("--size", metavar="WxH", help="WIDTHxHEIGHT in pixels.")] = "640x360",
    projection: Annotated[str, typer.Option("--projection", metavar="NAME",
                                            help=f"One of {', '.join(PROJECTIONS)}.")] = "orthographic",
    fov: Annotated[float, typer.Option("--fov", metavar="DEG",
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
        console(highlight=False).print(
            f"wrote {output} ({scene.frame_count} frames); truth: omega {abs(omega):g} rad/s, "
            f"fixation {fx:g},{fy:g}", markup=False)
        return 0

    run(debug, job)
