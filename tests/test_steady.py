"""A hand-held camera's shake taken out of the tracks (:mod:`rotrate_cli.tracking.steady`)."""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import numpy as np
import pandas as pd
import pytest

from rotrate_cli.tracking.steady import find_shake


def _shake(frames: int, amplitude_px: float, turn_deg: float, seed: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """A hand's smooth random shift (frames x 2, px) and turn (rad) about the picture's middle."""
    rng = np.random.default_rng(seed)

    def smooth(scale: float) -> np.ndarray:
        noise = np.convolve(rng.normal(0, 1, frames + 40), np.ones(9) / 9, "same")[20:20 + frames]
        return noise / noise.std() * scale

    return np.stack([smooth(amplitude_px), smooth(amplitude_px)], axis=1), np.radians(smooth(turn_deg))


def _tracks(frames: int, shift: np.ndarray, turn: np.ndarray, background: int = 60, body: int = 40,
            rng_seed: int = 2) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Background points standing still and body points swinging to and fro (a turning body seen
    from the side), seen through the shaken camera; and the same seen from where the camera stood
    at the first frame."""
    rng = np.random.default_rng(rng_seed)
    middle = np.array([320.0, 180.0])
    still = rng.uniform([0, 0], [640, 360], (background, 2))
    radius, phase, height = rng.uniform(10, 120, body), rng.uniform(0, 2 * math.pi, body), rng.uniform(80, 280, body)

    def seen(k: int, camera: int) -> np.ndarray:
        c, s = math.cos(turn[camera]), math.sin(turn[camera])
        swing = np.stack([320 + radius * np.sin(0.05 * k + phase), height], axis=1)
        return (np.vstack([still, swing]) - middle) @ np.array([[c, -s], [s, c]]).T + middle + shift[camera]

    def table(camera_at_first: bool) -> pd.DataFrame:
        rows = [(k, k / 30.0, track, x, y) for k in range(frames)
                for track, (x, y) in enumerate(seen(k, 0 if camera_at_first else k))]
        tracks = pd.DataFrame(rows, columns=["frame", "time_s", "track", "x_px", "y_px"])
        return tracks.sort_values(["track", "frame"], kind="stable").reset_index(drop=True)

    return table(False), table(True)


def test_the_shake_is_found_from_the_still_background_and_taken_out() -> None:
    frames = 150
    shift, turn = _shake(frames, 3.0, 0.3)
    tracks, steady_truth = _tracks(frames, shift, turn)
    found = find_shake(tracks, frames)
    assert found is not None
    path, shake = found
    assert shake.background_tracks == 60
    assert 2.0 < shake.rms_px < 8.0
    steadied = path.steady(tracks)
    # every point where the camera, held where it stood at the first frame, would have seen it
    error = np.hypot(steadied["x_px"] - steady_truth["x_px"], steadied["y_px"] - steady_truth["y_px"])
    assert error.max() < 0.05
    # and back on the shaken camera's own frames (where an overlay draws them)
    seen = path.seen(steadied)
    assert np.abs(seen[["x_px", "y_px"]].to_numpy() - tracks[["x_px", "y_px"]].to_numpy()).max() < 1e-3


def test_no_shake_on_a_tripod_or_without_a_background() -> None:
    frames = 150
    none = (np.zeros((frames, 2)), np.zeros(frames))
    tracks, _ = _tracks(frames, *none)
    assert find_shake(tracks, frames) is None  # still: nothing to take out
    shift, turn = _shake(frames, 3.0, 0.3)
    body_only, _ = _tracks(frames, shift, turn, background=0, body=60)
    assert find_shake(body_only, frames) is None  # the body's points do not stand still together


def test_a_shaken_render_is_measured_as_from_a_tripod(tmp_path: Path) -> None:
    """A rendered box at 0.5 rad/s whose picture shakes by 3 px and 0.3 degrees: without the
    shake taken out it read 0.01 to 0.31 rad/s, weak."""
    from rotrate_cli.analysis import AnalysisConfig, analyze
    from rotrate_cli.video.synth import Renderer, SceneConfig

    scene = SceneConfig(shape="box", omega_rad_s=0.5, fps=30.0, duration_s=4.0, supersample=1, seed=5)
    renderer = Renderer(scene)
    shift, turn = _shake(scene.frame_count, 3.0, 0.3)
    clip = tmp_path / "shaken.mp4"
    size = (scene.width_px, scene.height_px)
    writer = cv2.VideoWriter(str(clip), cv2.VideoWriter_fourcc(*"mp4v"), scene.fps, size)
    for k, frame in enumerate(renderer.frames(range(scene.frame_count))):
        matrix = cv2.getRotationMatrix2D((size[0] / 2, size[1] / 2), math.degrees(turn[k]), 1.0)
        matrix[:, 2] += shift[k]
        writer.write(cv2.warpAffine(frame, matrix, size, borderMode=cv2.BORDER_REPLICATE))
    writer.release()
    result = analyze(clip, AnalysisConfig(fixation_px=None))
    assert result.omega_rad_s == pytest.approx(0.5, rel=0.01)
    assert result.omega_low_rad_s <= 0.5 <= result.omega_high_rad_s
    assert any("camera shook" in note for note in result.warnings)
    assert result.shake is not None and result.shake.rms_px > 1.0


def test_a_face_turning_as_one_picture_is_not_taken_for_a_shaking_camera() -> None:
    """The top of a cylinder seen from high above turns as one picture: its points stand still
    once that turn is taken out, as a shaken background would. Its path is smooth (a rendered
    one jolted only by its noise, 0.16 px in 19 px rms), a hand's is not."""
    tracks, frames = _cylinder_top()
    assert find_shake(tracks, frames) is None


def _cylinder_top() -> tuple[pd.DataFrame, int]:
    """Points of a cylinder's top seen from high above, turning as one picture (sorted by track
    then frame), and the frames."""
    rng = np.random.default_rng(4)
    frames, points = 60, 30
    radius, phase = rng.uniform(20, 150, points), rng.uniform(0, 2 * math.pi, points)
    rows = []
    for k in range(frames):
        angle = phase + 0.2 * k / 30.0
        x = 300 + radius * np.cos(angle) + rng.normal(0, 0.3, points)
        y = 200 + radius * np.sin(angle) + rng.normal(0, 0.3, points)
        rows += [(k, k / 30.0, track, x[track], y[track]) for track in range(points)]
    tracks = pd.DataFrame(rows, columns=["frame", "time_s", "track", "x_px", "y_px"])
    return tracks.sort_values(["track", "frame"], kind="stable").reset_index(drop=True), frames



@pytest.mark.slow  # renders a clip (about 10 s): make test-slow keeps make test under 4 minutes
def test_a_face_whose_points_come_late_is_not_taken_for_a_shaking_camera(tmp_path: Path) -> None:
    """A box's top seen from 60 degrees above (orthographic, 0.2 rad/s, 2 s, noisy) turns as one
    picture, its points standing still once that turn is taken out. Most of them are first
    followed some frames in, and as they come the path they give jumps (1.3-4 px over 3 frames,
    0.02-0.18 px after: their rms, 0.81 px, was a hand's jolt). Taken for a shake, the turn was
    taken out and the rate read -33%, its interval missing the truth."""
    from rotrate_cli.analysis import AnalysisConfig, analyze
    from rotrate_cli.video.synth import SceneConfig, write_clip

    clip = tmp_path / "top.mp4"
    write_clip(SceneConfig(shape="box", omega_rad_s=0.2, fps=24.0, duration_s=2.0, elevation_deg=60.0,
                           noise_sigma=2.0, start_angle_rad=5.8891234540184, seed=8014), clip)
    result = analyze(clip, AnalysisConfig(fixation_px=None))
    assert result.shake is None
    assert result.omega_rad_s == pytest.approx(0.2, rel=0.03)
    assert result.omega_low_rad_s <= 0.2 <= result.omega_high_rad_s


def test_a_camera_that_rolls_smoothly_is_found_where_its_still_points_lie_all_round() -> None:
    """A camera rolling 3 degrees a second on a tripod head does not jolt as a hand does; still
    points all over the picture, and a body that goes on moving once the roll is taken out, tell
    it is the camera's. The turn is reported, anticlockwise as the picture shows it."""
    frames = 90
    turn = np.radians(-3.0 * np.arange(frames) / 30.0)  # anticlockwise on the screen (y down: a negative turn)
    tracks, steadied = _tracks(frames, np.zeros((frames, 2)), turn)
    assert find_shake(tracks, frames) is None  # smooth, and nothing said of the picture's size
    found = find_shake(tracks, frames, size_px=(640, 360))
    assert found is not None
    path, shake = found
    assert shake.smooth
    assert shake.turned_deg == pytest.approx(3.0 * (frames - 1) / 30.0, abs=0.05)
    assert shake.turn_deg_s == pytest.approx(3.0, rel=0.02)
    x, y = path.undo(tracks["frame"].to_numpy(), tracks["x_px"].to_numpy(), tracks["y_px"].to_numpy())
    assert np.allclose(x, steadied["x_px"].to_numpy(), atol=0.05) and np.allclose(y, steadied["y_px"].to_numpy(),
                                                                                   atol=0.05)


def test_a_smooth_turn_of_points_in_one_patch_is_not_taken_for_a_rolling_camera() -> None:
    """The cylinder's top of the test above, its picture's size now known: its points lie in one
    patch of the picture, not all over it."""
    tracks, frames = _cylinder_top()
    assert find_shake(tracks, frames, size_px=(1280, 720)) is None


def test_a_still_background_is_told_from_none() -> None:
    """A still background vouches for a still camera; where every long track moves (a record that
    fills the picture), nothing tells a camera's turn from the body's, and the report says it
    assumes a still camera (:data:`rotrate_cli.stages.tracks.NO_BACKGROUND_NOTE`)."""
    from rotrate_cli.tracking.steady import MIN_BACKGROUND, still_background

    frames = 120
    none = np.zeros((frames, 2)), np.zeros(frames)
    with_background, _ = _tracks(frames, *none, background=MIN_BACKGROUND, body=40)
    only_body, _ = _tracks(frames, *none, background=0, body=40)
    few_still, _ = _tracks(frames, *none, background=MIN_BACKGROUND - 1, body=40)
    assert still_background(with_background, frames)
    assert not still_background(only_body, frames)
    assert not still_background(few_still, frames)


def test_a_rolling_camera_is_found_where_a_turning_disc_holds_most_of_the_tracks() -> None:
    """A textured disc turning 86 degrees a second fills the middle and holds most of the long
    tracks; 20 still points lie around it; the camera rolls 2 degrees a second about the middle.
    The still half after the median step is the disc's: the rounds start again from the tracks
    that move least, and find the roll (it was added to the disc's rate, +2.3%, and called good)."""
    frames, fps = 64, 30.0
    rng = np.random.default_rng(5)
    middle = np.array([320.0, 200.0])
    angle = rng.uniform(0, 2 * math.pi, 20)
    still = middle + np.stack([np.cos(angle), np.sin(angle)], axis=1) * rng.uniform(200, 300, (20, 1)) * [1.0, 0.6]
    radius, phase = rng.uniform(20, 170, 250), rng.uniform(0, 2 * math.pi, 250)
    rows = []
    for k in range(frames):
        roll = math.radians(-2.0 * k / fps)  # anticlockwise on the screen (y down)
        c, s = math.cos(roll), math.sin(roll)
        turned = phase + 1.5 * k / fps
        disc = middle + np.stack([radius * np.cos(turned), radius * np.sin(turned)], axis=1)
        points = (np.vstack([still, disc]) - middle) @ np.array([[c, -s], [s, c]]).T + middle
        rows += [(k, k / fps, track, x, y) for track, (x, y) in enumerate(points)]
    tracks = pd.DataFrame(rows, columns=["frame", "time_s", "track", "x_px", "y_px"])
    tracks = tracks.sort_values(["track", "frame"], kind="stable").reset_index(drop=True)
    found = find_shake(tracks, frames, size_px=(640, 400))
    assert found is not None
    _, shake = found
    assert shake.smooth and shake.background_tracks >= 12
    assert shake.turn_deg_s == pytest.approx(2.0, rel=0.02)


def test_a_camera_that_rolls_and_wobbles_is_found_where_little_else_moves() -> None:
    """A clock filmed by a camera rolling 3 degrees a second and wobbling 12 px: still points all
    over the picture, but its stepping hand leaves few tracks that move. The picture does not turn
    about one point, as a body's points turning together do: the camera's. A body filling the
    picture, turning unevenly about its axis, is not taken for it."""
    frames = 120
    time_s = np.arange(frames) / 30.0
    turn = np.radians(-3.0 * time_s + 1.5 * np.sin(2 * np.pi * 0.7 * time_s))
    shift = np.stack([12 * np.sin(2 * np.pi * 0.4 * time_s + 1), 9 * np.sin(2 * np.pi * 0.55 * time_s)], axis=1)
    tracks, _ = _tracks(frames, shift, turn, body=3)  # three tracks move: too few to tell it so
    found = find_shake(tracks, frames, size_px=(640, 360))
    assert found is not None and found[1].smooth
    assert found[1].turned_deg == pytest.approx(-np.degrees(turn[-1]), abs=0.1)
    # a body filling the picture, turning unevenly about its own axis, as one picture
    rng = np.random.default_rng(4)
    radius, phase = rng.uniform(20, 400, 80), rng.uniform(0, 2 * math.pi, 80)
    rows = []
    for k in range(60):
        angle = phase + (0.2 + 0.1 * math.sin(k / 10)) * k / 30.0
        x, y = 320 + radius * np.cos(angle) + rng.normal(0, 0.3, 80), 180 + radius * np.sin(angle)
        rows += [(k, k / 30.0, t, x[t], y[t]) for t in range(80) if 0 <= x[t] < 640 and 0 <= y[t] < 360]
    body = pd.DataFrame(rows, columns=["frame", "time_s", "track", "x_px", "y_px"])
    assert find_shake(body.sort_values(["track", "frame"], kind="stable").reset_index(drop=True), 60,
                      size_px=(640, 360)) is None


def test_a_camera_that_comes_nearer_and_goes_back_is_taken_out_with_its_zoom() -> None:
    """A hand-held camera rolling 2 degrees a second, shifting 10 px and coming 4% nearer and back:
    no turn and shift leaves its background within a pixel (the edges move 13 px more), so the
    rate was the tracks', 7 times the truth. A turn, zoom and shift does: every background point
    comes back to where the first frame saw it, and the roll is the camera's."""
    frames = 150
    time_s = np.arange(frames) / 30.0
    turn = np.radians(-2.0 * time_s)
    zoom = 1.0 + 0.04 * np.sin(2 * np.pi * 0.1 * time_s + 1.0)
    shift = np.stack([10 * np.sin(2 * np.pi * 0.5 * time_s), 10 * np.sin(2 * np.pi * 0.37 * time_s + 2)], axis=1)
    rng = np.random.default_rng(7)
    still = rng.uniform([0, 0], [640, 360], (60, 2))
    middle = np.array([320.0, 180.0])
    rows = []
    for k in range(frames):
        c, s = math.cos(turn[k]), math.sin(turn[k])
        seen = zoom[k] * (still - middle) @ np.array([[c, -s], [s, c]]).T + middle + shift[k]
        rows += [(k, time_s[k], track, x, y) for track, (x, y) in enumerate(seen)]
        hand = middle + 100 * np.array([math.sin(0.1 * (k // 30)), -math.cos(0.1 * (k // 30))])
        rows.append((k, time_s[k], 60, *(zoom[k] * (hand - middle) @ np.array([[c, -s], [s, c]]).T + middle
                                          + shift[k])))
    tracks = pd.DataFrame(rows, columns=["frame", "time_s", "track", "x_px", "y_px"])
    tracks = tracks.sort_values(["track", "frame"], kind="stable").reset_index(drop=True)
    found = find_shake(tracks, frames, size_px=(640, 360))
    assert found is not None
    path, shake = found
    assert path.warp is not None and shake.background_tracks == 60
    assert shake.turn_deg_s == pytest.approx(2.0, rel=0.02)  # anticlockwise as the picture shows it (y down)
    background = tracks[tracks["track"] < 60]
    x, y = path.undo(background["frame"].to_numpy(), background["x_px"].to_numpy(), background["y_px"].to_numpy())
    seen_first = zoom[0] * (still - middle) + middle + shift[0]  # the first frame: no turn yet
    truth = seen_first[background["track"].to_numpy()]
    assert np.allclose(x, truth[:, 0], atol=0.05) and np.allclose(y, truth[:, 1], atol=0.05)
    # the views carry a picture as they carry its points
    image = np.zeros((90, 160), np.float32)
    image[40:50, 70:90] = 1.0
    carried = path.carry(image, 0, 100, 0.25)
    row, col = np.argwhere(carried > 0.5).mean(axis=0)
    ex, ey = path.redo(np.array([100]), *path.undo(np.array([0]), np.array([79.5 / 0.25]), np.array([44.5 / 0.25])))
    assert col == pytest.approx(ex[0] * 0.25, abs=0.5) and row == pytest.approx(ey[0] * 0.25, abs=0.5)


def test_a_patch_that_zooms_about_one_point_is_not_taken_for_the_camera() -> None:
    """Points in one patch that grow about one point as they turn (a body coming nearer as it
    turns, seen face on) give a smooth path about one point, in one patch: not the camera's."""
    frames, rows = 120, []
    rng = np.random.default_rng(8)
    points = rng.uniform([250, 120], [390, 240], (50, 2))
    for k in range(frames):
        a, zoom = 0.4 * k / 30.0, 1.0 + 0.003 * k
        c, s = math.cos(a), math.sin(a)
        seen = zoom * (points - [320.0, 180.0]) @ np.array([[c, -s], [s, c]]).T + [320.0, 180.0]
        rows += [(k, k / 30.0, track, x, y) for track, (x, y) in enumerate(seen)]
    tracks = pd.DataFrame(rows, columns=["frame", "time_s", "track", "x_px", "y_px"])
    assert find_shake(tracks.sort_values(["track", "frame"], kind="stable").reset_index(drop=True), frames,
                      size_px=(640, 360)) is None


def test_a_path_a_little_off_one_point_needs_its_still_points_all_round() -> None:
    """A smooth path whose still points lie in one patch is the camera's only where it is far from
    a turn about one point: a box's top seen from above, turning in perspective, keeps within a few
    pixels of one (it was taken for a rolling camera, and then no point could be tracked); a hand's
    wobble and zoom do not."""
    from rotrate_cli.tracking.steady import OFF_ONE_POINT_ALONE_PX, OFF_ONE_POINT_PX, CameraPath, _camera_s

    frames = 90
    angle = np.radians(np.linspace(0.0, 10.0, frames))
    rng = np.random.default_rng(3)
    patch = rng.uniform([200, 90], [440, 270], (30, 2))  # a part of the picture, not all of it
    rows = [(k, k / 30.0, track, x, y) for k in range(frames) for track, (x, y) in enumerate(patch)]
    tracks = pd.DataFrame(rows, columns=["frame", "time_s", "track", "x_px", "y_px"])
    about = np.array([320.0, 180.0])
    between = 0.5 * (OFF_ONE_POINT_PX + OFF_ONE_POINT_ALONE_PX)
    for off_px, camera in ((between, False), (2 * OFF_ONE_POINT_ALONE_PX, True)):
        turn = np.stack([np.cos(angle), np.sin(angle)], axis=1)
        shift = about - np.stack([turn[:, 0] * about[0] - turn[:, 1] * about[1],
                                  turn[:, 1] * about[0] + turn[:, 0] * about[1]], axis=1)
        shift[:, 0] += off_px * math.sqrt(2) * np.sin(np.linspace(0, 4 * math.pi, frames))  # off the one point
        path = CameraPath(0, angle, shift)
        assert _camera_s(tracks, path, np.arange(30), (640, 360), 1.0) is camera
    # still points along one edge (a box's face nearing a wide lens) are no wall, however far off
    edge = tracks.assign(x_px=300.0 + 0.05 * tracks["x_px"])
    assert not _camera_s(edge, path, np.arange(30), (640, 360), 1.0)
