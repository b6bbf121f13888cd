"""The libraries' own thread pools, sized for this pipeline while an analysis runs.

An analysis already keeps the machine busy with threads of its own: the decoder (and FFmpeg's
threads behind it) in the background, the tracker in the foreground, and the fits' two batches.
The libraries underneath add pools of their own that wait for work by spinning: OpenBLAS (NumPy's
and SciPy's linear algebra) and OpenCV's ``parallel_for_``. Our matrices are small (3x3 normal
equations, a few hundred tracks), so BLAS threads only spin between calls; and OpenCV's pool,
given the cores the pipeline's own threads already use, takes processor time from the decoder
rather than adding any. Measured on the 720p bench clip on a 2-core machine: the spinning was
14% of all processor samples (OpenBLAS's ``blas_thread_server``) plus the kernel's scheduling of
it, and the run's processor time fell from 0.80-0.87 s to 0.64 s with BLAS at one thread and
OpenCV's pool at one, its time not longer.

:func:`pipeline_threads` sets them for the length of a run and puts back what it found: BLAS at
one thread, OpenCV at the cores the pipeline's own two busy threads leave (at least one, which
is OpenCV running serially in the caller's thread). Nested and concurrent runs in one process
share one setting; the last to leave restores it.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import cv2

#: Threads the pipeline keeps busy itself (the decoder's and the tracker's).
PIPELINE_THREADS = 2

_lock = threading.Lock()
_depth = 0
_saved: tuple[int, Any] | None = None


def available_cores() -> int:
    """Cores this process may run on."""
    if hasattr(os, "sched_getaffinity"):
        return max(1, len(os.sched_getaffinity(0)))
    return max(1, os.cpu_count() or 1)


def opencv_threads(cores: int) -> int:
    """OpenCV's pool size while a run uses ``cores``: those its own threads leave, at least 1."""
    return max(1, cores - PIPELINE_THREADS)


def _limit_blas() -> Any:
    """BLAS at one thread; the limiter to restore it, or None without threadpoolctl."""
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:  # an optional speed-up: without it, runs are as before
        return None
    return threadpool_limits(limits=1, user_api="blas")


@contextmanager
def pipeline_threads() -> Iterator[None]:
    """Within: BLAS at one thread and OpenCV's pool at :func:`opencv_threads` (see the module's
    notes); what was set before is put back when the last run in the process leaves."""
    global _depth, _saved
    with _lock:
        if _depth == 0:
            before = cv2.getNumThreads()
            cv2.setNumThreads(opencv_threads(available_cores()))
            _saved = (before, _limit_blas())
        _depth += 1
    try:
        yield
    finally:
        with _lock:
            _depth -= 1
            if _depth == 0 and _saved is not None:
                before, blas = _saved
                cv2.setNumThreads(before)
                if blas is not None:
                    blas.restore_original_limits()
                _saved = None
