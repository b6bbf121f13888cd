"""The view from the tracks' paths (rotrate_cli.scene.view): elevation, turning centre and the rate
in both image coordinates, on paths computed exactly, with the kinds of false tracks real
footage has (still glints, points sliding a few pixels along a rim)."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from rotrate_cli.scene.view import keep_for_view, rate_from_paths, view_from_paths

CENTRE = (400.0, 250.0)


def _paths(elevation_deg: float, omega: float = 1.2, tracks: int = 40, noise_px: float = 0.2,
           seed: int = 0) -> pd.DataFrame:
    """Points of a flat disk about a vertical axis, seen orthographically from ``elevation_deg``
    above (0: edge on), each tracked for 1.5 s at 30 fps from its own start."""
    rng = np.random.default_rng(seed)
    rows = []
    squash = math.sin(math.radians(elevation_deg))
    for k in range(tracks):
        radius, phase, start = rng.uniform(40, 150), rng.uniform(0, 2 * math.pi), rng.uniform(0, 3)
        height = 0.0  # a flat disk: every path has the same centre
        time_s = start + np.arange(45) / 30.0
        x = CENTRE[0] + radius * np.cos(omega * time_s + phase) + rng.normal(0, noise_px, 45)
        y = CENTRE[1] - height + squash * radius * np.sin(omega * time_s + phase) + rng.normal(0, noise_px, 45)
        rows.append(pd.DataFrame({"track": k, "time_s": time_s, "x_px": x, "y_px": y}))
    return pd.concat(rows, ignore_index=True)


def _with_false_tracks(paths: pd.DataFrame, seed: int = 1) -> pd.DataFrame:
    """Add still glints and rim slides (a few px along x, wherever they are)."""
    rng = np.random.default_rng(seed)
    extra, first = [], (int(paths["track"].max()) + 1) if len(paths) else 0
    for k in range(30):
        time_s = np.arange(45) / 30.0
        x0, y0 = rng.uniform(0, 800), rng.uniform(0, 500)
        slide = 0.0 if k % 2 else rng.uniform(2, 5)
        extra.append(pd.DataFrame({"track": first + k, "time_s": time_s,
                                   "x_px": x0 + slide * np.sin(1.2 * time_s) + rng.normal(0, 0.1, 45),
                                   "y_px": y0 + rng.normal(0, 0.1, 45)}))
    return pd.concat([paths, *extra], ignore_index=True)


@pytest.mark.parametrize("elevation", [0.0, 25.0, 50.0, 85.0])
def test_elevation_and_centre_are_read_from_the_paths(elevation: float) -> None:
    view = view_from_paths(_with_false_tracks(_paths(elevation)), 1.2)
    assert view is not None
    assert view.elevation_deg == pytest.approx(elevation, abs=2.0)
    assert view.centre_px[0] == pytest.approx(CENTRE[0], abs=2.0)
    assert view.centre_px[1] == pytest.approx(CENTRE[1], abs=2.0)
    assert view.name == ("side" if elevation < 20 else "frontal" if elevation > 70 else "oblique")
    assert view.tracks >= 35  # the false tracks do not pass (a few rim slides may, with no weight)


def test_the_sign_of_the_rate_does_not_matter() -> None:
    paths = _paths(40.0)
    assert view_from_paths(paths, -1.2) == view_from_paths(paths, 1.2)


def test_false_tracks_alone_tell_no_view() -> None:
    false_only = _with_false_tracks(_paths(40.0).iloc[:0])
    assert view_from_paths(false_only, 1.2) is None
    assert math.isnan(rate_from_paths(false_only, 1.2))


def test_no_rate_no_view() -> None:
    assert view_from_paths(_paths(30.0), math.nan) is None
    assert view_from_paths(_paths(30.0).iloc[:0], 1.0) is None


@pytest.mark.parametrize("elevation", [0.0, 35.0, 70.0])
def test_rate_from_paths_finds_the_rate_from_a_first_guess(elevation: float) -> None:
    paths = _with_false_tracks(_paths(elevation, omega=0.9))
    for guess in (0.85, 0.9, 0.96):
        assert rate_from_paths(paths, guess) == pytest.approx(0.9, rel=0.003)


def test_keep_for_view_keeps_the_longest_tracks_thinned() -> None:
    paths = _paths(30.0)
    short = pd.DataFrame({"track": 999, "time_s": [0.0, 0.1], "x_px": [1.0, 2.0], "y_px": [1.0, 2.0]})
    kept = keep_for_view(pd.concat([paths, short], ignore_index=True))
    assert 999 not in set(kept["track"])
    assert kept.groupby("track").size().max() <= 48
    assert set(kept.columns) == {"track", "time_s", "x_px", "y_px"}


def test_through_a_lens_found_the_view_takes_the_lens_fits_elevation(monkeypatch) -> None:
    """The paths read their ellipses as seen from far away (50 degrees for a render 60 degrees
    above through a 65-degree lens); the lens's fit read 59, and the report said both, in two rows."""
    import rotrate_cli.stages.geometry as geometry_stage
    from rotrate_cli.scene.focal import FocalEstimate
    from rotrate_cli.scene.view import View
    from rotrate_cli.stages import view_at_rate
    from rotrate_cli.stages.camera import Lens

    paths = View(50.0, (232.0, 134.0), 3.0, 211, 137.0, 0.0)
    monkeypatch.setattr(view_at_rate, "view_from_paths", lambda tracks, omega: paths)
    estimate = FocalEstimate(518.0, 63.4, 1 / 518.0, 1e-4, -59.0, 153, 0.3)
    found = geometry_stage.Geometry(0.0, "lens", (228.5, 213.7), True, Lens(518.0, -59.0, "found", estimate), -59.0)
    assert view_at_rate.view_at_rate(found, pd.DataFrame(), 0.2, "tracks", (640, 360)).view.elevation_deg == 59.0
    orthographic = geometry_stage.Geometry(0.0, "paths", (228.5, 213.7), True, Lens(None), 50.0)
    assert view_at_rate.view_at_rate(orthographic, pd.DataFrame(), 0.2, "tracks", (640, 360)).view is paths
