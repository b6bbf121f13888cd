"""The joint fit: one rate shared by many tracks (analytic tracks with known truth)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from rotrate_cli.fitting import estimators
from rotrate_cli.fitting.camera import Camera
from rotrate_cli.fitting.joint import joint_fit
from rotrate_cli.fitting.outliers import combine


def _short_noisy_tracks(rng: np.random.Generator, omega: float, tracks: int, samples: int,
                        step_s: float, noise_px: float, camera: Camera | None = None) -> pd.DataFrame:
    """Tracks of ``samples`` samples each, radius 20..150 px, random phase and start."""
    rows = []
    for track in range(tracks):
        time_s = rng.uniform(0, 10) + np.arange(samples) * step_s
        radius_px = rng.uniform(20, 150)
        angle = omega * time_s + rng.uniform(0, 2 * np.pi)
        if camera is None:
            offset = radius_px * np.sin(angle)
        else:
            r = radius_px / camera.focal_px
            offset = (camera.axis_n + r * np.sin(angle)) / (1 - r * np.cos(angle)) * camera.focal_px \
                - camera.axis_n * camera.focal_px
        rows.append(pd.DataFrame({"track": track, "frame": np.arange(samples), "time_s": time_s,
                                  "offset_px": offset + rng.normal(0, noise_px, samples)}))
    return pd.concat(rows, ignore_index=True)


def test_joint_fit_removes_the_small_track_bias_of_averaging(rng: np.random.Generator) -> None:
    # like the dinosaur's published tracks: 6 views 10 degrees apart, 1.5 px noise (averaging
    # per-track rates is measured 2-4% high here, the joint fit under 1%)
    omega = 0.1745
    samples = _short_noisy_tracks(rng, omega, tracks=400, samples=6, step_s=1.0, noise_px=1.5)
    fits = estimators.fit_tracks(samples, min_samples=5)
    good = {k: f for k, f in fits.items() if np.isfinite(f.omega_rad_s) and np.isfinite(f.omega_se_rad_s)}
    pooled = combine(np.array([f.omega_rad_s for f in good.values()]),
                     np.array([f.omega_se_rad_s for f in good.values()]))
    used = samples[samples["track"].isin(list(good))]
    result = joint_fit(used, {k: 1.5 for k in good}, pooled.omega_rad_s)
    assert abs(result.omega_rad_s / omega - 1) < 0.01
    assert abs(result.omega_rad_s / omega - 1) < abs(pooled.omega_rad_s / omega - 1)
    assert result.omega_low_rad_s <= omega <= result.omega_high_rad_s
    assert result.tracks_used == len(good)


@pytest.mark.parametrize("sense", [1, -1])
def test_joint_fit_with_a_pinhole_camera(rng: np.random.Generator, sense: int) -> None:
    camera = Camera(900.0, 0.05)
    samples = _short_noisy_tracks(rng, sense * 0.8, tracks=60, samples=40, step_s=1 / 30, noise_px=0.2,
                                  camera=camera)
    result = joint_fit(samples, dict.fromkeys(range(60), 0.2), 0.75, camera=camera, sense=sense)
    assert result.omega_rad_s == pytest.approx(0.8, rel=0.003)
    assert result.omega_low_rad_s <= 0.8 <= result.omega_high_rad_s
    orthographic = joint_fit(samples, dict.fromkeys(range(60), 0.2), 0.75)
    assert abs(orthographic.omega_rad_s / 0.8 - 1) > 0.005  # what ignoring perspective costs


def test_joint_fit_finds_a_rate_outside_its_first_window(rng: np.random.Generator) -> None:
    samples = _short_noisy_tracks(rng, 1.3, tracks=20, samples=60, step_s=1 / 30, noise_px=0.1)
    result = joint_fit(samples, dict.fromkeys(range(20), 0.1), 0.9, span=0.1)
    assert result.omega_rad_s == pytest.approx(1.3, rel=0.002)


def test_one_track_gets_an_interval_from_its_own_misfit(rng: np.random.Generator) -> None:
    samples = _short_noisy_tracks(rng, 0.6, tracks=1, samples=90, step_s=1 / 30, noise_px=0.3)
    result = joint_fit(samples, {0: 0.3}, 0.62)
    assert result.omega_rad_s == pytest.approx(0.6, rel=0.02)
    assert result.omega_low_rad_s < 0.6 < result.omega_high_rad_s
    assert result.omega_high_rad_s - result.omega_low_rad_s < 0.1


def test_no_tracks_or_no_guess_gives_nan() -> None:
    empty = pd.DataFrame({"track": [], "frame": [], "time_s": [], "offset_px": []})
    assert np.isnan(joint_fit(empty, {}, 0.5).omega_rad_s)


def test_ragged_tracks_sum_and_split_like_a_group_by(rng: np.random.Generator) -> None:
    from rotrate_cli.fitting.ragged import Ragged

    samples = _short_noisy_tracks(rng, 0.5, tracks=30, samples=7, step_s=0.1, noise_px=1.0)
    samples = samples[samples.index % 5 != 0]  # uneven lengths
    tracks = Ragged.from_samples(samples, np.arange(3, 30))
    expected = samples[samples["track"] >= 3].groupby("track")["offset_px"].sum()
    assert tracks.ids.tolist() == expected.index.tolist()
    assert np.allclose(tracks.sums(tracks.offset), expected.to_numpy())
    assert np.allclose(tracks.time_s, samples.loc[samples["track"] >= 3, "time_s"].to_numpy())
    seen = []
    for part, block in tracks.blocks(10):
        assert block.counts.sum() <= max(10, block.counts[0])
        assert np.allclose(block.sums(block.offset), expected.to_numpy()[part])
        seen.extend(block.ids.tolist())
    assert seen == tracks.ids.tolist()


def test_leave_one_out_in_chunks_matches_the_whole_table(monkeypatch):
    """The delete-one-track minima are taken a chunk of tracks at a time (memory on long
    clips): the same numbers as from the whole tracks x grid table, across chunk edges."""
    from rotrate_cli.fitting import joint

    rng = np.random.default_rng(5)
    grid = np.linspace(0.9, 1.1, 25)
    weighted = (grid[None, :] - rng.uniform(0.95, 1.05, (2500, 1))) ** 2 * rng.uniform(0.5, 2.0, (2500, 1))
    whole = joint._parabola_minimum(grid, weighted.sum(0)[None, :] - weighted)
    monkeypatch.setattr(joint, "_CHUNK_TRACKS", 1000)
    chunked = joint._leave_one_out(grid, weighted)
    assert chunked.shape == (2500,)
    np.testing.assert_array_equal(chunked, whole)
    assert np.isfinite(chunked).all() and not np.allclose(chunked, chunked[0])
