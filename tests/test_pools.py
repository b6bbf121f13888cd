"""The libraries' thread pools while an analysis runs (rotrate_cli/runtime/pools.py)."""

from __future__ import annotations

import threading

import cv2
import pytest
import threadpoolctl  # a runtime dependency (pyproject): its absence is a failure, not a skip

from rotrate_cli.runtime.pools import available_cores, opencv_threads, pipeline_threads


def test_pools_are_sized_for_the_run_and_put_back() -> None:
    before = cv2.getNumThreads()
    blas_before = [info["num_threads"] for info in threadpoolctl.threadpool_info() if info["user_api"] == "blas"]
    with pipeline_threads():
        assert cv2.getNumThreads() == opencv_threads(available_cores())
        blas = [info["num_threads"] for info in threadpoolctl.threadpool_info() if info["user_api"] == "blas"]
        assert all(count == 1 for count in blas)
        with pipeline_threads():  # a nested run keeps the setting, and leaving it does not undo it
            pass
        assert cv2.getNumThreads() == opencv_threads(available_cores())
    assert cv2.getNumThreads() == before
    assert [info["num_threads"] for info in threadpoolctl.threadpool_info()
            if info["user_api"] == "blas"] == blas_before


def test_concurrent_runs_share_one_setting() -> None:
    before = cv2.getNumThreads()
    inside, leave = threading.Event(), threading.Event()

    def other_run() -> None:
        with pipeline_threads():
            inside.set()
            leave.wait(5)

    worker = threading.Thread(target=other_run)
    worker.start()
    assert inside.wait(5)
    with pipeline_threads():
        pass  # this run leaves first: the other is still running, so nothing is put back yet
    assert cv2.getNumThreads() == opencv_threads(available_cores())
    leave.set()
    worker.join(5)
    assert cv2.getNumThreads() == before


@pytest.mark.parametrize(("cores", "threads"), [(1, 1), (2, 1), (4, 2), (16, 14)])
def test_opencv_gets_the_cores_the_pipeline_leaves(cores: int, threads: int) -> None:
    assert opencv_threads(cores) == threads


def _blas_threads_after_main(environment: dict[str, str]) -> str:
    """The BLAS pools' sizes in a process that ran the command's entry point and then loaded
    NumPy and SciPy's linear algebra, as a stage does."""
    import os
    import subprocess
    import sys

    code = ("import sys\nfrom rotrate_cli import cli\nsys.argv = ['rotrate', '--version']\n"
            "try:\n    cli.main()\nexcept SystemExit:\n    pass\n"
            "import numpy, scipy.linalg, threadpoolctl\n"
            "print(sorted({i['num_threads'] for i in threadpoolctl.threadpool_info() if i['user_api'] == 'blas'}))")
    env = {key: value for key, value in os.environ.items() if key != "OPENBLAS_NUM_THREADS"} | environment
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                          env=env).stdout.strip().splitlines()[-1]


def test_the_command_starts_blas_at_one_thread_unless_told_otherwise() -> None:
    """Each BLAS copy starts a spinning thread per core as it loads (see cli._one_blas_thread):
    the command sets one thread before they load, and keeps a user's own setting."""
    assert _blas_threads_after_main({}) == "[1]"
    assert _blas_threads_after_main({"OPENBLAS_NUM_THREADS": "2"}) == "[2]"
