"""The tracker on rendered frames: it follows the object, not the background or the outline."""

from __future__ import annotations

import numpy as np
import pytest

from rotrate_cli.decode import Frame
from rotrate_cli.synth import Renderer, SceneConfig
from rotrate_cli.tracking import Roi, TrackerConfig, track_frames, tracking_image


@pytest.fixture(scope="module")
def sphere() -> tuple[Renderer, list[Frame]]:
    scene = SceneConfig(shape="sphere", omega_rad_s=0.8, duration_s=2.0, width_px=320, height_px=180,
                        supersample=1, seed=5)
    renderer = Renderer(scene)
    frames = [Frame(k, k / scene.fps, tracking_image(renderer.render(k), 1.0)) for k in range(scene.frame_count)]
    return renderer, frames


def test_points_start_on_the_object_and_move(sphere: tuple[Renderer, list[Frame]]) -> None:
    renderer, frames = sphere
    run = track_frames(frames, (320, 180), TrackerConfig())
    assert run.frames == 60
    assert run.last_time_s == pytest.approx(59 / 30)
    tracks = run.tracks
    assert tracks["track"].nunique() > 30
    fx, fy = renderer.fixation_px
    radius_px = 0.7 * 180 / 2  # the sphere's radius on screen
    first = tracks.groupby("track").first()
    distance = np.hypot(first["x_px"] - fx, first["y_px"] - fy)
    assert (distance < radius_px).all()  # nothing seeded on the static background
    # points are dropped as their window reaches the background (checked every few frames)
    distance = np.hypot(tracks["x_px"] - fx, tracks["y_px"] - fy)
    assert (distance < radius_px + 1.0).all()
    assert (distance > radius_px - 1.0).mean() < 0.02
    ranges = tracks.groupby("track")["x_px"].agg(lambda x: x.max() - x.min())
    long_tracks = tracks.groupby("track").size() >= 20
    assert (ranges[long_tracks] > 1.0).all()


def test_roi_limits_seeding(sphere: tuple[Renderer, list[Frame]]) -> None:
    _, frames = sphere
    roi = Roi(160, 40, 60, 100)
    run = track_frames(frames, (320, 180), TrackerConfig(roi=roi))
    first = run.tracks.groupby("track").first()
    assert len(first) > 5
    # sub-pixel corner refinement may move a corner on the border by under a pixel
    assert first["x_px"].between(roi.x_px - 1, roi.x_px + roi.width_px + 1).all()
    assert first["y_px"].between(roi.y_px - 1, roi.y_px + roi.height_px + 1).all()


def test_reduced_tracking_image_reports_full_resolution(sphere: tuple[Renderer, list[Frame]]) -> None:
    renderer, _ = sphere
    scene = renderer.scene
    config = TrackerConfig(track_width_px=160)
    frames = [Frame(k, k / scene.fps, tracking_image(renderer.render(k), 0.5)) for k in range(30)]
    run = track_frames(frames, (320, 180), config)
    assert run.tracks["x_px"].max() > 160  # positions are scaled back to the 320-px frame
