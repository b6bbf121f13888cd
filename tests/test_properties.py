"""Properties of the estimators and the readers, not just examples (hypothesis).

The rate of a rigid body does not depend on where the camera puts it (a shift of positions with
the fixation point), on the image's scale, or on which way it turns; time scaled by ``c`` scales
the rate by ``1/c``. Any bytes given as a tracks file give tracks or a clean InputError. The same
input and options give byte-identical reports.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from rotrate_cli.analysis import analyze_tracks
from rotrate_cli.cli import app
from rotrate_cli.errors import InputError
from rotrate_cli.tracking.tracks_io import read_tracks
from tests.conftest import SAMPLES

PROPERTY = settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def _tracks(seed: int, omega: float, tracks: int = 24) -> pd.DataFrame:
    """Noisy tracks of one body (radius 30-150, 20-60 frames at 30 fps), positions in pixels
    about an axis at 0."""
    rng = np.random.default_rng(seed)
    rows = []
    for k in range(tracks):
        n = int(rng.integers(20, 60))
        frame = int(rng.integers(0, 60)) + np.arange(n)
        angle = omega * frame / 30.0 + rng.uniform(0, 2 * np.pi)
        rows.append(pd.DataFrame({"track": k, "frame": frame, "time_s": frame / 30.0,
                                  "position": rng.uniform(30, 150) * np.sin(angle) + rng.normal(0, 0.3, n)}))
    return pd.concat(rows, ignore_index=True)


def _omega(tracks: pd.DataFrame, fixation: float = 0.0) -> float:
    return analyze_tracks(tracks, fixation).omega_rad_s


@PROPERTY
@given(seed=st.integers(0, 10_000), omega=st.floats(0.3, 3.0), shift=st.floats(-500, 500),
       scale=st.floats(0.05, 20.0))
def test_omega_is_unchanged_by_a_shift_with_the_fixation_and_by_scale(seed: int, omega: float, shift: float,
                                                                      scale: float) -> None:
    tracks = _tracks(seed, omega)
    base = _omega(tracks)
    moved = tracks.assign(position=tracks["position"] * scale + shift)
    assert _omega(moved, fixation=shift) == pytest.approx(base, rel=1e-6)


@PROPERTY
@given(seed=st.integers(0, 10_000), omega=st.floats(0.3, 3.0), factor=st.floats(0.2, 5.0))
def test_omega_scales_inversely_with_time(seed: int, omega: float, factor: float) -> None:
    tracks = _tracks(seed, omega)
    slower = tracks.assign(time_s=tracks["time_s"] * factor)
    assert _omega(slower) == pytest.approx(_omega(tracks) / factor, rel=1e-6)


@PROPERTY
@given(seed=st.integers(0, 10_000), omega=st.floats(0.3, 3.0))
def test_omega_is_the_same_either_way_round(seed: int, omega: float) -> None:
    tracks = _tracks(seed, omega)
    mirrored = tracks.assign(position=-tracks["position"])  # the same motion turning the other way
    forward, backward = analyze_tracks(tracks, 0.0), analyze_tracks(mirrored, 0.0)
    assert backward.omega_rad_s == pytest.approx(forward.omega_rad_s, rel=1e-9)
    assert {forward.direction, backward.direction} <= {"ccw", "cw", "unknown"}
    if forward.direction != "unknown":
        assert backward.direction == {"ccw": "cw", "cw": "ccw"}[forward.direction]


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.one_of(
    st.binary(max_size=400),
    st.text(max_size=400).map(str.encode),
    st.lists(st.tuples(st.integers(-3, 3), st.integers(-2, 5),
                       st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=4))),
             max_size=12).map(lambda rows: ("track,frame,x\n"
                                            + "".join(f"{a},{b},{c}\n" for a, b, c in rows)).encode()),
))
def test_any_bytes_as_a_tracks_file_give_tracks_or_a_clean_error(tmp_path_factory: pytest.TempPathFactory,
                                                                  data: bytes) -> None:
    path = tmp_path_factory.mktemp("fuzz") / "tracks.csv"
    path.write_bytes(data)
    try:
        tracks = read_tracks(path)
    except InputError as exc:
        assert str(exc) and "\n" not in str(exc)
        return
    assert sorted(tracks.columns) == ["frame", "position", "time_s", "track"]
    assert np.isfinite(tracks["position"]).all() and not tracks.duplicated(["track", "frame"]).any()
    try:
        analyze_tracks(tracks, 0.0, fps=30.0)
    except InputError:
        pass
    except Exception as exc:  # noqa: BLE001 - the only other allowed outcome is NoResultError
        assert type(exc).__name__ == "NoResultError", repr(exc)


@pytest.mark.parametrize("fmt", ["json", "csv"])
def test_same_input_same_options_byte_identical_reports(tmp_path: Path, fmt: str) -> None:
    runner = CliRunner()
    outputs = []
    for run in range(2):
        target = tmp_path / f"report{run}.{fmt}"
        result = runner.invoke(app, ["analyze", str(SAMPLES / "box_ortho.mp4"), "--fixation", "auto", "--format", fmt,
                                     "--end", "3", "-o", str(target)])
        assert result.exit_code == 0, result.output
        outputs.append(target.read_bytes())
    assert outputs[0] == outputs[1] and len(outputs[0]) > 1000
    assert math.isfinite(len(outputs[0]))
