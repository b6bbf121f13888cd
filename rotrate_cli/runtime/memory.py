"""Handing freed memory back to the operating system between stages.

A long clip's stages each build and drop arrays of tens of megabytes. glibc's allocator keeps
much of what is freed inside the process (its heap top is pinned by small live objects, and
its mmap threshold rises after the first large free), so the resident size ratchets up stage
after stage although the live data does not grow. ``malloc_trim(0)`` returns those free pages;
Dask's workers do the same for the same reason. Elsewhere (macOS, Windows, musl) this is a
no-op.
"""

from __future__ import annotations

import ctypes
import ctypes.util
from functools import cache


@cache
def _trim() -> object | None:
    """glibc's ``malloc_trim``, or None where there is no such function."""
    try:
        library = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        function = library.malloc_trim
    except (OSError, AttributeError):
        return None
    function.argtypes = [ctypes.c_size_t]
    function.restype = ctypes.c_int
    return function


def release_free_memory() -> None:
    """Return the allocator's free memory to the operating system, where it can."""
    trim = _trim()
    if trim is not None:
        trim(0)  # type: ignore[operator]
