"""Heavy libraries imported when first used, not when rotrate starts.

``from rotrate_cli.runtime.lazy import pandas as pd`` gives a stand-in whose first attribute (``pd.DataFrame``)
imports pandas; after that it forwards to the real module. pandas and SciPy are needed only once
the tracks are in, so decoding starts 0.3 s sooner (0.33 s from the process's start to the first
720p frame, was 0.65 s). Importing them in a background thread while decoding was tried: the
whole run took no less (the imports hold the interpreter the tracker needs), so they load when
first used. (SciPy is imported where it is used: :func:`rotrate_cli.fitting.stats.student_t_975`,
the lens search and the renderer.)
"""

from __future__ import annotations

import importlib
import types
from typing import Any


class _Deferred(types.ModuleType):
    """A module imported on first attribute access (see the module's notes)."""

    def __getattr__(self, attribute: str) -> Any:
        value = getattr(importlib.import_module(self.__name__), attribute)
        setattr(self, attribute, value)  # later accesses do not come here
        return value


pandas: Any = _Deferred("pandas")
