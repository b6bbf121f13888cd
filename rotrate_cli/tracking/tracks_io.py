"""Reading point tracks from a tidy CSV file (hand-tracked points, other trackers' output).

Columns: a track id (``track`` or ``feature``), ``frame``, optional ``time_s``, and the horizontal
position column named by the caller (default ``x``). Lines starting with ``#`` are comments.
"""

from __future__ import annotations

import csv
import io
import warnings
from pathlib import Path

import numpy as np

from rotrate_cli.errors import InputError
from rotrate_cli.runtime.lazy import pandas as pd

MAX_BYTES = 512 * 1024 * 1024


def read_tracks(path: str | Path, position_column: str = "x") -> pd.DataFrame:
    """Read a tracks file into ``track, frame, time_s, position`` (``time_s`` may be all NaN).

    Raises:
        InputError: missing file or columns, non-numeric or missing values, duplicate rows.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"no such file: {path}" if not path.exists() else f"not a regular file: {path}")
    if path.stat().st_size > MAX_BYTES:
        raise InputError(f"{path} is larger than {MAX_BYTES // 2**20} MiB; is it a tracks table?")
    raw = path.read_bytes()
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InputError(f"{path} is not a UTF-8 text table (CSV)") from exc
    if "\x00" in text:
        raise InputError(f"{path} is not a text table (CSV)")
    try:
        with warnings.catch_warnings():
            # a row longer than the header would lose its extra values with only a warning
            warnings.simplefilter("error", pd.errors.ParserWarning)
            table = pd.read_csv(io.StringIO(text), comment="#", skipinitialspace=True, dtype=str,
                                keep_default_na=False, quoting=csv.QUOTE_MINIMAL, index_col=False)
    except pd.errors.ParserWarning as exc:
        raise InputError(f"could not read {path} as CSV: a row has more values than the header has names") from exc
    except (pd.errors.ParserError, pd.errors.EmptyDataError, csv.Error, ValueError) as exc:
        first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise InputError(f"could not read {path} as CSV: {first}") from exc
    table.columns = [str(c).strip() for c in table.columns]
    id_column = "track" if "track" in table.columns else "feature" if "feature" in table.columns else None
    missing = [name for name, present in (("track or feature", id_column), ("frame", "frame" in table.columns),
                                          (position_column, position_column in table.columns)) if not present]
    if missing:
        found = ", ".join(table.columns) or "none"
        raise InputError(f"{path} lacks the column(s) {', '.join(missing)} (found: {found}); "
                         "see `position_column`")
    if table.empty:
        raise InputError(f"{path} has no rows of tracks")
    columns = {"track": id_column, "frame": "frame", "position": position_column}
    if "time_s" in table.columns:
        columns["time_s"] = "time_s"
    out = pd.DataFrame(index=table.index)
    for name, source in columns.items():
        values = pd.to_numeric(table[source].str.strip(), errors="coerce")
        bad = values.isna() | ~np.isfinite(values.to_numpy(dtype=float, na_value=np.nan))
        if bad.any():
            first = int(np.argmax(bad.to_numpy()))  # by position: the index may not be 0..n-1
            raise InputError(f"{path}: column {source!r} has a missing or non-numeric value "
                             f"({table[source].iloc[first]!r}, data row {first + 1})")
        out[name] = values.astype(float)
    if "time_s" not in out:
        out["time_s"] = np.nan
    if not (out["frame"] == np.round(out["frame"])).all() or not (out["track"] == np.round(out["track"])).all():
        raise InputError(f"{path}: 'frame' and the track id must be whole numbers")
    out["frame"] = out["frame"].astype(np.int64)
    out["track"] = out["track"].astype(np.int64)
    duplicated = out.duplicated(["track", "frame"])
    if duplicated.any():
        row = out[duplicated].iloc[0]
        raise InputError(f"{path}: track {int(row.track)} has frame {int(row.frame)} more than once")
    return out.sort_values(["track", "frame"], kind="stable").reset_index(drop=True)
