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
from typer.core import TyperCommand, TyperGroup

from rotrate_cli.errors import InputError, NoResultError, OutputError, RotrateError
from rotrate_cli.output.files import write_text

# Only what --help needs is imported here: typer and rich. The library's stages (OpenCV,
# pandas, SciPy: most of a second) are imported by the commands that run them.
from rotrate_cli.runtime.choices import FORMATS, METHODS

if TYPE_CHECKING:
    from rich.console import Console
    from rich.progress import Progress, TaskID

    from rotrate_cli.analysis import Analysis
    from rotrate_cli.batch import Outcome

class _HelpFlag:
    """A command whose ``--help`` is shown as the flag it is (typer showed it as ``--help <bool>``)."""

    def get_help_option(self, ctx: typer.Context):  # type: ignore[no-untyped-def]
        option = super().get_help_option(ctx)  # type: ignore[misc]
        if option is not None:
            option.metavar = ""
        return option


class _Group(_HelpFlag, TyperGroup):
    pass


class _Command(_HelpFlag, TyperCommand):
    def collect_usage_pieces(self, ctx: typer.Context) -> list[str]:
        """The usage line as most command-line tools write it: ``VIDEO...``, ``[OPTIONS]``.

        Typer marks a required argument with braces (``{VIDEO}...``), which reads as a literal.
        """
        pieces = [self.options_metavar] if self.options_metavar else []
        for param in self.get_params(ctx):
            if param.param_type_name != "argument":
                pieces.extend(param.get_usage_pieces(ctx))
                continue
            name = str(param.display_name_raw)
            name = name if param.required else f"[{name}]"
            pieces.append(name + ("..." if param.nargs != 1 else ""))
        return pieces


class _Typer(typer.Typer):
    """The app, its commands made as :class:`_Command`."""

    def command(self, *args, cls=None, **kwargs):  # type: ignore[no-untyped-def]
        return super().command(*args, cls=cls or _Command, **kwargs)


app = _Typer(
    cls=_Group,
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


def console(**options: object) -> Console:
    """A rich console (rich is loaded here, when something is printed: not before the first frame
    where nothing is, which it delayed by 0.03 s)."""
    from rich.console import Console

    return Console(**options)  # type: ignore[arg-type]


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


def fail(message: str, code: int) -> typer.Exit:
    console(stderr=True, highlight=False, soft_wrap=True).print(f"rotrate: error: {in_flags(message)}", markup=False)
    return typer.Exit(code)


def run(debug: bool, job: Callable[[], T]) -> T:
    """Run ``job``, turning errors into one line and an exit code."""
    try:
        return job()
    except RotrateError as exc:
        if debug:
            traceback.print_exc()
        raise fail(str(exc), exit_code(exc)) from None
    except KeyboardInterrupt:
        raise fail("interrupted", 130) from None
    except BrokenPipeError:
        # the reader of stdout stopped early (| head): nothing to say; keep Python's exit flush quiet
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        raise typer.Exit(0) from None
    except typer.Exit:
        raise
    except Exception as exc:  # noqa: BLE001 - the user gets one line, the developer --debug
        if debug:
            traceback.print_exc()
        raise fail(f"unexpected {type(exc).__name__}: {exc} (rerun with --debug for details)", 3) from None


def numbers(text: str, count: int, option: str, example: str) -> list[float]:
    parts = [p.strip() for p in text.split(",")]
    try:
        values = [float(p) for p in parts]
    except ValueError:
        values = []
    if len(values) != count or not all(math.isfinite(v) for v in values):
        raise InputError(f"{option} takes {count} numbers separated by a comma, such as {example}; got {text!r}")
    return values


def check_format(fmt: str) -> None:
    if fmt not in FORMATS:
        raise InputError(f"--format must be one of {', '.join(FORMATS)}; got {fmt!r}")


def check_method(method: str) -> None:
    if method not in METHODS:
        raise InputError(f"--method must be one of {', '.join(METHODS)}; got {method!r}")


def standard_output(output: Path | None) -> Path | None:
    """``-o -`` is standard output, as in the tools people pipe: None (no file) for ``-``."""
    return None if output is not None and str(output) == "-" else output


def emit(analysis: Analysis, fmt: str, output: Path | None, force: bool) -> None:
    from rotrate_cli.cli.report import render, render_table

    if output is not None:
        write_text(output, render(analysis, fmt), force)
        return
    if fmt == "table":
        render_table(analysis, console(highlight=False))
    else:
        sys.stdout.write(render(analysis, fmt))
        sys.stdout.flush()


@contextmanager
def progress_bar(quiet: bool) -> Iterator[tuple[Callable[[int, int | None], None] | None,
                                                 Callable[[str], None] | None]]:
    """The frames' progress callback and the stage callback of :func:`rotrate_cli.analysis.analyze`
    (None, None when quiet or not on a terminal)."""
    if quiet or not (sys.stderr.isatty() or os.environ.get("FORCE_COLOR") or os.environ.get("TTY_COMPATIBLE") == "1"):
        yield None, None  # (decided before rich is loaded: a batch or a pipe needs none of it)
        return
    stderr = console(stderr=True)
    if not stderr.is_terminal:
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
    with Progress(*columns, console=stderr, transient=True) as progress:
        task = progress.add_task("frames", total=None)

        def update(done: int, total: int | None) -> None:
            progress.update(task, completed=done, total=total)

        yield update, lambda text: next_stage(progress, task, text)


def next_stage(progress: Progress, task: TaskID, text: str) -> None:
    """The bar moved on to a stage after the frames: it pulses (a stage's length is not known
    ahead) and its clock starts again (once the frames' bar was full, rich kept its time: the fits
    that followed showed a stopped clock)."""
    progress.reset(task, total=None, description=text)


def batch_line(quiet: bool, total: int, done_before: int = 0) -> Callable[[Outcome], None]:
    """A batch's ``done`` callback: one line on stderr as each input finishes (inputs done of
    ``total``, the input, its rate and quality or its failure, the time since the batch started);
    nothing when ``quiet``."""
    import time

    started, count = time.monotonic(), [done_before]
    stderr = console(stderr=True, highlight=False, soft_wrap=True)

    def line(outcome: Outcome) -> None:
        count[0] += 1
        if quiet:
            return
        if outcome.analysis is not None:
            told = (f"{outcome.analysis.omega_rad_s:.4g} rad/s, {outcome.analysis.quality}"
                    + ("" if outcome.status == "ok" else f" ({outcome.status})"))
        else:
            told = f"{outcome.status}: {in_flags(outcome.error)}"
        stderr.print(f"rotrate: [{count[0]}/{total}] {outcome.source}: {told} ({time.monotonic() - started:.0f} s)",
                      markup=False)

    return line


def wide_console() -> Console:
    """stdout, at least 140 columns wide when it is not a terminal (file names stay whole in logs)."""
    stdout = console(highlight=False)
    return stdout if stdout.is_terminal else console(highlight=False, width=max(stdout.width, 140))


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


# the commands, registered on ``app`` as their modules load (each imports only typer and rich at
# its top: the library's stages load when a command runs)
from rotrate_cli.cli import analyze as _analyze, commands as _commands  # noqa: E402, F401, I001


def main() -> None:
    """Console-script entry point. A usage error (an unknown option, a missing argument) is one
    line on standard error and exit 2, as every other error, not Click's framed box."""
    try:  # Typer 0.2x carries its own copy of Click
        from typer._click.exceptions import ClickException
    except ImportError:  # pragma: no cover - an older Typer on Click itself
        from click.exceptions import ClickException

    _one_blas_thread()
    if "--debug" not in sys.argv:
        _quiet_native_logs()
    try:
        code = app(standalone_mode=False)
    except ClickException as error:
        context = getattr(error, "ctx", None)
        where = f"rotrate {context.info_name} --help" if context is not None and context.parent else "rotrate --help"
        console(stderr=True, highlight=False, soft_wrap=True).print(
            f"rotrate: error: {error.format_message()} (see {where})", markup=False)
        sys.exit(error.exit_code)
    except typer.Abort:
        sys.exit(130)
    sys.exit(code if isinstance(code, int) else 0)
