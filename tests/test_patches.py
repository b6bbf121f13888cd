"""The lens fit's samples placed again by an affine patch match (rotrate_cli.scene.patches), on the
tracker's images kept evenly over the clip (rotrate_cli.tracking.keyframes)."""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import numpy as np
import pytest

from rotrate_cli import AnalysisConfig, analyze
from rotrate_cli.scene.patches import place_again
from rotrate_cli.tracking.keyframes import Keyframes
from rotrate_cli.video.frames import Frame


def test_keyframes_stay_within_their_budget_and_evenly_spread() -> None:
    image = np.zeros((100, 100), np.uint8)
    keyframes = Keyframes(scale=0.5, max_bytes=50 * image.nbytes)
    frames = (Frame(index, index / 30.0, image + np.uint8(index % 200)) for index in range(1000))
    assert sum(1 for _ in keyframes.tap(frames)) == 1000  # every frame passes through
    assert 25 <= len(keyframes) <= 50
    assert keyframes.step == 32
    assert keyframes.has(np.array([0, 32, 992, 1, 33])).tolist() == [True, True, True, False, False]
    assert int(keyframes.image(64)[0, 0]) == 64  # its own picture, not a later one's
    assert keyframes.indices().tolist() == list(range(0, 1000, 32))
    keyframes.keep_only(np.array([32, 64, 65]))
    assert keyframes.indices().tolist() == [32, 64]
    keyframes.clear()
    assert len(keyframes) == 0 and keyframes.step == 1


def _texture(seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return cv2.GaussianBlur(rng.uniform(0, 255, (240, 320)).astype(np.float32), (0, 0), 2.0)


def _kept(frames: list[Frame]) -> Keyframes:
    keyframes = Keyframes(scale=1.0)
    for _ in keyframes.tap(iter(frames)):
        pass
    return keyframes


def test_a_deforming_patch_is_placed_where_its_centre_went() -> None:
    """A surface patch that narrows, shears and dims as it turns away (as on a sphere), and a
    tracker whose positions drifted by up to 1.5 px: placed again within 0.1 px of where the
    patch's centre really went."""
    texture = _texture()
    centre = np.array([160.0, 120.0])
    pictures, truth, tracked = [], [], []
    for k in range(12):
        squeeze, shear, gain = 1.0 - 0.04 * k, 0.02 * k, 1.0 - 0.03 * k
        where = np.array([150.0 + 3.1 * k, 110.0 + 0.4 * k])
        linear = np.array([[squeeze, shear], [0.0, 1.0]])
        # the picture at frame k: texture point p appears at where + linear (p - centre)
        matrix = np.hstack([linear, (where - linear @ centre)[:, None]])
        picture = cv2.warpAffine(texture, matrix, (320, 240), flags=cv2.INTER_LINEAR) * gain + 10
        pictures.append(Frame(k, k / 30.0, np.clip(picture, 0, 255).astype(np.uint8)))
        truth.append(where)
        tracked.append(where + np.array([0.2 * k / 11, 1.5 * k / 11]))
    keyframes = _kept(pictures)
    truth_xy, tracked_xy = np.array(truth), np.array(tracked)
    x, y = place_again(keyframes, np.arange(12), tracked_xy[:, 0], tracked_xy[:, 1])
    assert np.isfinite(x).all()
    assert np.abs(x - truth_xy[:, 0]).max() < 0.1
    assert np.abs(y - truth_xy[:, 1]).max() < 0.1


def test_tracks_are_placed_again_every_one_at_fewer_frames_beyond_a_budget_of_samples() -> None:
    """Each track's samples placed again where its first patch went; beyond the budget of samples,
    every track at every second (third, ...) frame; samples at frames with no image left out."""
    import pandas as pd

    from rotrate_cli.scene.patches import place_tracks

    texture = _texture()
    pictures = []
    for k in range(6):  # the picture shifts 2 px right a frame
        matrix = np.array([[1.0, 0.0, 2.0 * k], [0.0, 1.0, 0.0]])
        pictures.append(Frame(k, k / 30.0, np.clip(cv2.warpAffine(texture, matrix, (320, 240)), 0, 255)
                              .astype(np.uint8)))
    keyframes = _kept(pictures[:5])  # the sixth frame's image is not kept
    rows = []
    for track, (x0, y0, frames) in enumerate([(100.0, 100.0, range(6)), (200.0, 80.0, range(3)),
                                              (150.0, 160.0, range(5))]):
        rows += [(k, k / 30.0, track, x0 + 2.0 * k + 0.6, y0 - 0.4) for k in frames]  # 0.7 px off where it went
    samples = pd.DataFrame(rows, columns=["frame", "time_s", "track", "x_px", "y_px"])
    every = place_tracks(keyframes, samples, most_samples=20)
    assert len(every) == 13 and 5 not in every["frame"].tolist()
    first = samples.groupby("track").first()
    went = first.loc[every["track"], "x_px"].to_numpy() + 2.0 * every["frame"].to_numpy()
    assert np.abs(every["x_px"].to_numpy() - went).max() < 0.1  # where the first patch went, off as it was
    fewer = place_tracks(keyframes, samples, most_samples=10)  # 13 samples: every second frame
    assert sorted(fewer["frame"].unique().tolist()) == [0, 2, 4]
    assert sorted(fewer["track"].unique().tolist()) == [0, 1, 2]
    assert len(place_tracks(keyframes, samples.iloc[:0], 10)) == 0


def test_a_patch_that_does_not_match_is_left_out() -> None:
    """Where the picture at the tracker's position is something else, no position is made up."""
    keyframes = _kept([Frame(index, index / 30.0, _texture(index).astype(np.uint8)) for index in (0, 1)])
    x, y = place_again(keyframes, np.array([0, 1]), np.array([160.0, 160.0]), np.array([120.0, 120.0]))
    assert x[0] == pytest.approx(160.0) and math.isnan(x[1]) and math.isnan(y[1])


def test_a_sphere_through_a_lens_is_measured_with_its_lens(tmp_path: Path) -> None:
    """A sphere through a 20-degree lens: the tracker's positions drift with the surface's
    deformation just as a pinhole's bob would, and the lens was found at 26.6-30.0 degrees on
    three renders (2.4-4.0% slow). Placed again on the kept frames, 19.6-20.7 degrees and
    within 0.6%."""
    from rotrate_cli.video.synth import SceneConfig, write_clip

    scene = SceneConfig(shape="sphere", omega_rad_s=0.7, duration_s=4.0, width_px=640, height_px=360,
                        projection="perspective", fov_deg=20.0, supersample=1, seed=2)
    path = tmp_path / "sphere.mp4"
    write_clip(scene, path)
    analysis = analyze(path, AnalysisConfig(fixation_px=None))
    assert analysis.focal is not None
    assert analysis.focal.fov_deg == pytest.approx(20.0, abs=1.5)
    assert analysis.omega_rad_s == pytest.approx(0.7, rel=0.01)
    assert analysis.omega_low_rad_s <= 0.7 <= analysis.omega_high_rad_s
