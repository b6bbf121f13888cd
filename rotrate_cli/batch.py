"""Many inputs in one run: one outcome per input, a bad input never stops the others.

:func:`expand_inputs` turns what the user typed (files, folders of videos, globs; a folder of
images stays one image-sequence input) into sources; :func:`run_batch` analyses each, in
parallel processes when asked, and returns an :class:`Outcome` per source in the order given,
whatever the order they finished in. :func:`check_expected` is the CI regression rule, and
:func:`read_manifest` reads the manifest of ``rotrate check``.
"""

from __future__ import annotations

import glob
import math
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, replace
from pathlib import Path

from rotrate_cli.analysis import Analysis, AnalysisConfig, analyze
from rotrate_cli.errors import InputError, NoResultError, RotrateError
from rotrate_cli.runtime.lazy import pandas as pd
from rotrate_cli.runtime.pools import available_cores
from rotrate_cli.scene.focal import parse_fov

VIDEO_SUFFIXES = frozenset({".mp4", ".mov", ".avi", ".mkv", ".m4v", ".webm", ".mpg", ".mpeg", ".wmv"})
SUMMARY_COLUMNS = ("file", "status", "omega", "omega_low", "omega_high", "rpm", "direction", "tracks_used",
                   "quality", "error", "warnings")
#: Outcome statuses and the exit code each stands for (a batch exits with the largest).
STATUS_CODES = {"ok": 0, "skipped": 0, "weak": 1, "off_target": 1, "no_result": 1, "bad_input": 2, "failed": 3}


@dataclass(frozen=True)
class Outcome:
    """What one input gave.

    Attributes:
        source: the input as expanded.
        status: ``ok``, ``skipped`` (its report was there already: a batch resumed), ``weak``
            (weak evidence, with ``--strict``), ``off_target`` (outside
            ``--expect``'s band), ``no_result`` (read, but
            no trustworthy rate), ``bad_input`` or ``failed`` (an unexpected error).
        analysis: the analysis when there was one (``ok`` and ``off_target``), else None.
        error: one line saying what went wrong ("" when nothing did).
    """

    source: str
    status: str
    analysis: Analysis | None
    error: str = ""

    @property
    def exit_code(self) -> int:
        """The exit code this outcome alone would give."""
        return STATUS_CODES[self.status]


def expand_inputs(items: Sequence[str]) -> list[str]:
    """Sources from what the user typed: a glob becomes its matches (sorted), a folder holding
    videos becomes those videos, anything else (a video, a folder of images, a printf pattern,
    a path that does not exist) stays as it is, to be analysed or reported. Duplicates are
    dropped, the first kept."""
    sources: list[str] = []
    for item in items:
        path = Path(item)
        if not path.exists() and any(c in item for c in "*?["):
            matches = sorted(glob.glob(item))
            sources.extend(matches if matches else [item])
        elif path.is_dir():
            videos = sorted(str(p) for p in path.iterdir() if p.is_file() and p.suffix.lower() in VIDEO_SUFFIXES)
            sources.extend(videos if videos else [item])
        else:
            sources.append(item)
    return list(dict.fromkeys(sources))


def check_expected(omega_rad_s: float, expected_rad_s: float, tolerance_pct: float) -> str:
    """"" when ``omega_rad_s`` lies within ``tolerance_pct`` percent of ``expected_rad_s``,
    else one line saying by how much it misses.

    The rule is the point estimate's distance, not an overlap of the 95% interval with the band:
    a CI check is there to catch drift, and a run whose interval widened (fewer tracks, a noisy
    clip) would pass an overlap rule while its estimate wandered off.
    """
    error_pct = 100.0 * (omega_rad_s / expected_rad_s - 1.0) if expected_rad_s else math.inf
    if math.isfinite(error_pct) and abs(error_pct) <= tolerance_pct:
        return ""
    return (f"omega {omega_rad_s:.6g} rad/s is {error_pct:+.2f}% from the expected {expected_rad_s:g} "
            f"(tolerance {tolerance_pct:g}%)")


def check_expectation(expected_rad_s: float | None, tolerance_pct: float | None) -> None:
    """Raise InputError unless the ``--expect``/``--tolerance`` pair is usable."""
    if expected_rad_s is None and tolerance_pct is None:
        return
    if expected_rad_s is None or tolerance_pct is None:
        raise InputError("`expected_rad_s` and `tolerance_pct` go together: give both or neither")
    if not (math.isfinite(expected_rad_s) and expected_rad_s > 0):
        raise InputError("`expected_rad_s` takes the expected rate in rad/s, a positive number")
    if not (math.isfinite(tolerance_pct) and tolerance_pct >= 0):
        raise InputError("`tolerance_pct` takes a percentage, 0 or more")


@dataclass(frozen=True)
class Job:
    """One input of a batch: the source, its configuration, and an optional expected rate."""

    source: str
    config: AnalysisConfig
    expected_rad_s: float | None = None
    tolerance_pct: float | None = None
    strict: bool = False


def run_one(job: Job) -> Outcome:
    """Analyse one input; every failure becomes an outcome, never an exception (except an
    interrupt, which stops the batch)."""
    try:
        analysis = analyze(job.source, job.config)
    except InputError as exc:
        return Outcome(job.source, "bad_input", None, str(exc))
    except NoResultError as exc:
        return Outcome(job.source, "no_result", None, str(exc))
    except RotrateError as exc:
        return Outcome(job.source, "bad_input", None, str(exc))  # OutputError: a file it could not write
    except MemoryError:
        return Outcome(job.source, "failed", None, "ran out of memory; try `end_s` or `every` to analyse less")
    except Exception as exc:  # noqa: BLE001 - one bad input must not stop the batch
        return Outcome(job.source, "failed", None, f"unexpected {type(exc).__name__}: {exc}")
    if job.expected_rad_s is not None and job.tolerance_pct is not None:
        miss = check_expected(analysis.omega_rad_s, job.expected_rad_s, job.tolerance_pct)
        if miss:
            return Outcome(job.source, "off_target", analysis, miss)
    if job.strict and analysis.quality == "weak":
        return Outcome(job.source, "weak", analysis, weak_message(analysis))
    return Outcome(job.source, "ok", analysis)


def weak_message(analysis: Analysis) -> str:
    """The one line ``--strict`` fails with on a weak result."""
    reasons = "; ".join(analysis.verdict.weak_because) if analysis.verdict is not None else ""
    return f"weak evidence ({reasons}); the result is not trusted with `strict`"


def run_batch(
    jobs: Sequence[Job], workers: int = 1, done: Callable[[Outcome], None] | None = None,
    scheduler: str | None = None,
) -> list[Outcome]:
    """Run ``jobs`` and return their outcomes in the order of ``jobs``: here, in ``workers``
    processes when more than 1, or on the Dask cluster whose scheduler is at ``scheduler``
    (the ``dask`` extra). ``done`` is called as each finishes (in the order they finish, in
    processes; in the order given, on Dask).

    Raises:
        InputError: ``workers`` below 1, Dask not installed, or the scheduler unreachable.
    """
    if workers < 1:
        raise InputError("`workers` takes a number of processes, 1 or more")
    if scheduler is not None:
        return _run_on_dask(jobs, scheduler, done)
    outcomes: list[Outcome] = []
    if workers == 1 or len(jobs) <= 1:
        for job in jobs:
            outcomes.append(run_one(job))
            if done is not None:
                done(outcomes[-1])
        return outcomes
    finished: dict[int, Outcome] = {}
    with ProcessPoolExecutor(max_workers=min(workers, len(jobs), available_cores())) as pool:
        futures = {pool.submit(run_one, job): index for index, job in enumerate(jobs)}
        for future in as_completed(futures):  # ``done`` as each finishes: its report is kept at once
            finished[futures[future]] = future.result()
            if done is not None:
                done(finished[futures[future]])
    return [finished[index] for index in range(len(jobs))]


def _run_on_dask(jobs: Sequence[Job], scheduler: str, done: Callable[[Outcome], None] | None) -> list[Outcome]:
    """The jobs on a Dask distributed cluster (each job is one task; the cluster's workers need
    rotrate installed and the inputs at the same paths)."""
    try:
        from dask.distributed import Client
    except ImportError:
        raise InputError("`scheduler` needs Dask: pip install 'rotrate[dask]'") from None
    try:
        client = Client(scheduler, timeout="10s", set_as_default=False)
    except (OSError, TimeoutError, ValueError) as exc:
        raise InputError(f"could not reach the Dask scheduler at {scheduler} ({type(exc).__name__}); "
                         "check the address (tcp://HOST:8786)") from None
    # paths as this machine resolves them: a worker started elsewhere has another working folder
    sent = [replace(job, source=str(Path(job.source).resolve())) if Path(job.source).exists() else job for job in jobs]
    try:
        futures = client.map(run_one, sent, pure=False)
        outcomes = []
        for job, future in zip(jobs, futures, strict=True):  # in the order given, whatever order they finish in
            outcome = replace(future.result(), source=job.source)
            if outcome.status == "bad_input" and Path(job.source).exists() and "no such file" in outcome.error:
                outcome = replace(outcome, error=f"the Dask worker cannot see {Path(job.source).resolve()}, which "
                                                 "this machine has: the cluster's workers need the inputs at the "
                                                 "same paths (a shared folder)")
            outcomes.append(outcome)
            if done is not None:
                done(outcomes[-1])
        return outcomes
    finally:
        client.close()


def summary_frame(outcomes: Sequence[Outcome]) -> pd.DataFrame:
    """One row per input: ``file, status, omega, omega_low, omega_high, rpm, direction,
    tracks_used, quality, error, warnings`` (rad/s; empty where there is no analysis; ``error``:
    why there is none, or why the result failed a check; ``warnings``: the analysis's, joined)."""
    rows = []
    for outcome in outcomes:
        a = outcome.analysis
        rows.append({
            "file": outcome.source, "status": outcome.status,
            "omega": a.omega_rad_s if a else math.nan,
            "omega_low": a.omega_low_rad_s if a else math.nan,
            "omega_high": a.omega_high_rad_s if a else math.nan,
            "rpm": a.rpm if a else math.nan,
            "direction": a.direction if a else "",
            "tracks_used": a.tracks_used if a else 0,
            "quality": a.quality if a else "",
            "error": outcome.error,
            # a result with a caveat (a file cut off, say) keeps it in the row
            "warnings": "; ".join(a.warnings) if a else "",
        })
    return pd.DataFrame(rows, columns=list(SUMMARY_COLUMNS))


def batch_exit_code(outcomes: Sequence[Outcome]) -> int:
    """0 when every input gave a result within its expectation, else the worst outcome's code."""
    return max((o.exit_code for o in outcomes), default=0)


#: Manifest columns: required, and optional per-row options (as on the command line).
MANIFEST_REQUIRED = ("file", "expected_omega", "tolerance_pct")
MANIFEST_OPTIONAL = ("fixation", "fov", "focal_px", "fps", "axis_angle", "angle_from", "elevation", "every", "method",
                     "start", "end")


def read_manifest(path: Path, base: AnalysisConfig) -> list[Job]:
    """The jobs of a ``rotrate check`` manifest: a CSV with ``file, expected_omega,
    tolerance_pct`` and optionally ``fixation`` (``X,Y`` or ``auto``, the default), ``fov`` (degrees or ``auto``),
    ``focal_px``, ``fps``, ``axis_angle``, ``angle_from``, ``elevation``, ``every``, ``method``,
    ``start``, ``end``. Files are relative to the manifest's folder.

    Raises:
        InputError: the manifest is missing, unreadable, or a row is malformed (saying which).
    """
    if not path.is_file():
        raise InputError(f"no such manifest: {path}")
    try:
        table = pd.read_csv(path, dtype=str, keep_default_na=False, skipinitialspace=True)
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
        raise InputError(f"could not read the manifest {path} as CSV ({type(exc).__name__})") from None
    table.columns = [str(c).strip() for c in table.columns]
    missing = [c for c in MANIFEST_REQUIRED if c not in table.columns]
    if missing:
        raise InputError(f"the manifest {path} lacks the column(s) {', '.join(missing)}; "
                         f"it needs {', '.join(MANIFEST_REQUIRED)}")
    unknown = [c for c in table.columns if c not in MANIFEST_REQUIRED + MANIFEST_OPTIONAL]
    if unknown:
        raise InputError(f"the manifest {path} has unknown column(s) {', '.join(unknown)}; "
                         f"optional ones are {', '.join(MANIFEST_OPTIONAL)}")
    if table.empty:
        raise InputError(f"the manifest {path} lists no file")
    jobs = []
    for number, row in enumerate(table.to_dict("records"), start=2):  # line 1 is the header
        jobs.append(_manifest_job(path, number, {k: str(v).strip() for k, v in row.items()}, base))
    return jobs


def _manifest_job(path: Path, line: int, row: dict[str, str], base: AnalysisConfig) -> Job:
    where = f"{path}, line {line}"

    def number(name: str, default: float | None = None) -> float | None:
        text = row.get(name, "")
        if text == "":
            return default
        try:
            value = float(text)
        except ValueError:
            raise InputError(f"{where}: {name} must be a number; got {text!r}") from None
        if not math.isfinite(value):
            raise InputError(f"{where}: {name} must be a finite number; got {text!r}")
        return value

    if not row["file"]:
        raise InputError(f"{where}: the file is empty")
    expected, tolerance = number("expected_omega"), number("tolerance_pct")
    if expected is None or tolerance is None:
        raise InputError(f"{where}: expected_omega and tolerance_pct are required")
    check_expectation(expected, tolerance)
    fixation_text = row.get("fixation", "") or "auto"
    fixation: tuple[float, float] | None = None
    if fixation_text.lower() != "auto":
        parts = fixation_text.split(",")
        try:
            fixation = (float(parts[0]), float(parts[1])) if len(parts) == 2 else None
        except ValueError:
            fixation = None
        if fixation is None:
            raise InputError(f"{where}: fixation must be X,Y or auto; got {fixation_text!r}")
    every = number("every", 1)
    end = number("end")
    fov_deg, find_focal = parse_fov(row.get("fov", "") or None, where)
    config = replace(
        base, fixation_px=fixation, fov_deg=fov_deg, find_focal=find_focal, focal_px=number("focal_px"),
        fps=number("fps"),
        axis_angle_deg=number("axis_angle"), angle_from=row.get("angle_from", "") or base.angle_from,
        elevation_deg=number("elevation"), every=int(every or 1), method=row.get("method", "") or base.method,
        start_s=number("start", 0.0) or 0.0, end_s=end,
    )
    source = Path(row["file"])
    if not source.is_absolute():
        source = path.parent / source
    return Job(str(source), config, expected, tolerance)
