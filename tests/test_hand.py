"""A thin part turning over a still picture (rotrate_cli.scene.hand): a clock's second hand, sweeping
or stepping once a second, face on and on a tilted face, with the minute hand creeping beside it;
and what is not one (a textured disc turning, a swinging pendulum) tells nothing here."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from rotrate_cli.scene.angle_frames import AngleFrames
from rotrate_cli.scene.hand import measure_hand, window_rates
from rotrate_cli.video.frames import Frame

FPS = 15.0
SIZE = 480
CENTRE = (250.0, 230.0)
RADIUS = 170.0


def _face() -> np.ndarray:
    """A clock face (ticks and a textured ring) over a textured wall."""
    rng = np.random.default_rng(4)
    wall = cv2.resize(rng.random((SIZE // 10, SIZE // 10)).astype(np.float32), (SIZE, SIZE)) * 120 + 40
    face = wall.copy()
    cv2.circle(face, (int(CENTRE[0]), int(CENTRE[1])), int(RADIUS), 230, -1, cv2.LINE_AA)
    for k in range(60):
        a = math.radians(6 * k)
        inner = RADIUS - (22 if k % 5 == 0 else 10)
        cv2.line(face, (int(CENTRE[0] + inner * math.sin(a)), int(CENTRE[1] - inner * math.cos(a))),
                 (int(CENTRE[0] + (RADIUS - 4) * math.sin(a)), int(CENTRE[1] - (RADIUS - 4) * math.cos(a))),
                 30, 3 if k % 5 == 0 else 1, cv2.LINE_AA)
    return face


def _hand(image: np.ndarray, clock_deg: float, length: float, width: int, grey: float) -> None:
    """A hand from a little behind the centre out to ``length``, at ``clock_deg`` (clockwise from 12)."""
    a, s = math.radians(clock_deg), 16
    tail = (int(s * (CENTRE[0] - 0.15 * length * math.sin(a))), int(s * (CENTRE[1] + 0.15 * length * math.cos(a))))
    cv2.line(image, tail,
             (int(s * (CENTRE[0] + length * math.sin(a))), int(s * (CENTRE[1] - length * math.cos(a)))),
             grey, width, cv2.LINE_AA, shift=4)


def _clock(seconds: float, deg_per_s: float = 6.0, ticking: bool = False, tilt_deg: float = 0.0,
           minute_deg_s: float = 0.1) -> list[Frame]:
    """A second hand turning clockwise ``deg_per_s`` (each second at once where ``ticking``) and a
    minute hand creeping, the whole face seen tilted ``tilt_deg`` about a line 30 degrees from x."""
    face = _face()
    b = math.radians(30.0)
    rotation = np.array([[math.cos(b), -math.sin(b)], [math.sin(b), math.cos(b)]])
    squash = rotation @ np.diag([1.0, math.cos(math.radians(tilt_deg))]) @ rotation.T
    warp = np.hstack([squash, (np.array(CENTRE) - squash @ np.array(CENTRE))[:, None]])
    rng = np.random.default_rng(7)
    frames = []
    for index in range(int(seconds * FPS)):
        time_s = index / FPS
        image = face.copy()
        _hand(image, 300.0 + minute_deg_s * time_s, 0.6 * RADIUS, 6, 20)
        _hand(image, 40.0 + deg_per_s * (math.floor(time_s) if ticking else time_s), 0.92 * RADIUS, 2, 90)
        if tilt_deg:
            image = cv2.warpAffine(image, warp, (SIZE, SIZE), flags=cv2.INTER_LINEAR)
        image = np.clip(image + rng.normal(0.0, 2.0, image.shape), 0, 255).astype(np.uint8)
        frames.append(Frame(index, time_s, image))
    return frames


def _measured(frames: list[Frame]):
    kept = AngleFrames()
    for _ in kept.tap(iter(frames)):
        pass
    return measure_hand(kept.frames, kept.width_px)


@pytest.fixture(scope="module")
def sweeping() -> list[Frame]:
    return _clock(20.0)


def test_a_sweeping_second_hand_reads_its_rate_and_its_axis(sweeping: list[Frame]) -> None:
    truth = math.radians(6.0)
    angle = _measured(sweeping)
    assert angle is not None and angle.thin_part
    assert angle.omega_rad_s == pytest.approx(truth, rel=0.005)
    assert angle.omega_low_rad_s <= truth <= angle.omega_high_rad_s
    assert angle.sense == -1  # clockwise as shown
    assert math.dist(angle.view.centre_px, CENTRE) < 1.5
    assert angle.view.tilt_deg == 0.0 and angle.turned_deg > 100
    # omega(t): every 8-s window holds the rate
    windows = window_rates(angle, np.array([5.0, 10.0, 15.0]), 8.0)
    assert all(w is not None and w[1] <= truth <= w[2] for w in windows)


def test_a_hand_that_steps_once_a_second_reads_its_rate() -> None:
    """Between most frames nothing changes: the picture's changes tell nothing, the hand does."""
    truth = math.radians(6.0)
    angle = _measured(_clock(20.0, ticking=True))
    assert angle is not None
    assert angle.omega_rad_s == pytest.approx(truth, rel=0.02)
    assert angle.omega_low_rad_s <= truth <= angle.omega_high_rad_s


def test_a_tilted_face_is_read_through_the_stretch_its_hand_shows() -> None:
    truth = math.radians(6.0)
    angle = _measured(_clock(20.0, tilt_deg=40.0))
    assert angle is not None
    assert angle.view.tilt_deg == pytest.approx(40.0, abs=5.0)
    assert angle.omega_rad_s == pytest.approx(truth, rel=0.01)
    assert angle.omega_low_rad_s <= truth <= angle.omega_high_rad_s


def test_a_textured_disc_turning_is_no_thin_part() -> None:
    rng = np.random.default_rng(3)
    disc = (cv2.resize(rng.random((40, 40)).astype(np.float32), (320, 320), interpolation=cv2.INTER_CUBIC)
            * 200 + 20).clip(0, 255).astype(np.uint8)
    frames = [Frame(k, k / FPS, cv2.cvtColor(cv2.warpAffine(disc, cv2.getRotationMatrix2D((160, 160), 3.0 * k, 1.0),
                                                            (320, 320)), cv2.COLOR_GRAY2BGR)) for k in range(60)]
    assert _measured(frames) is None


def test_a_swinging_pendulum_is_no_steady_turn() -> None:
    face = _face()
    frames = []
    for index in range(int(12 * FPS)):
        image = face.copy()
        _hand(image, 180.0 + 25.0 * math.sin(2 * math.pi * index / FPS / 2.0), 0.9 * RADIUS, 3, 40)
        frames.append(Frame(index, index / FPS, image.astype(np.uint8)))
    assert _measured(frames) is None


def test_a_ticking_clock_clip_is_rated_by_its_hand(tmp_path) -> None:
    """Through the whole analysis: a clip of a clock whose second hand steps once a second gave no
    result before (no track lasts, and the picture's changes are mostly empty)."""
    from rotrate_cli.analysis import AnalysisConfig, analyze

    path = tmp_path / "clock.mp4"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), FPS, (SIZE, SIZE))
    for frame in _clock(16.0, ticking=True):
        writer.write(cv2.cvtColor(frame.image, cv2.COLOR_GRAY2BGR))
    writer.release()
    result = analyze(path, AnalysisConfig(fixation_px=None, window_s=8.0))
    truth = math.radians(6.0)
    assert result.rate_from == "turning" and result.verdict is not None and result.verdict.thin_part
    assert result.omega_rad_s == pytest.approx(truth, rel=0.02)
    assert result.omega_low_rad_s <= truth <= result.omega_high_rad_s
    assert math.dist(result.fixation_px, CENTRE) < 2.0
    # omega(t), no track standing behind it: each window rated by the hand, holding the truth
    series = result.series
    assert series is not None and len(series) >= 3 and set(series["rate_from"]) == {"turning"}
    assert ((series["omega_low_rad_s"] <= truth) & (truth <= series["omega_high_rad_s"])).all()


def test_a_steadied_camera_that_leaned_and_followed_the_light_is_lined_up_again(sweeping: list[Frame]) -> None:
    """A hand-held camera's frames, steadied by a turn, zoom and shift, still keystone by a few
    pixels (it leaned) and their exposure follows the light: the face's marks and the whole face
    differ from the still picture by more than the hand. Each is fitted to the still picture as a
    plane's view and brought to its grey levels; the hand reads as on a tripod."""
    rng = np.random.default_rng(3)
    leaned = []
    for frame in sweeping:
        view = np.eye(3)
        view[2, :2] = rng.normal(0.0, 2e-5, 2)  # a lean of a degree or so at a 700-px focal length
        view[:2, 2] = rng.normal(0.0, 1.0, 2)
        image = cv2.warpPerspective(frame.image.astype(np.float32), view, (SIZE, SIZE), flags=cv2.INTER_LINEAR,
                                    borderMode=cv2.BORDER_REPLICATE)
        light = 1.0 + 0.08 * math.sin(2 * math.pi * 0.2 * frame.time_s)
        leaned.append(Frame(frame.index, frame.time_s, np.clip(light * image, 0, 255).astype(np.uint8)))
    kept = AngleFrames()
    for _ in kept.tap(iter(leaned)):
        pass
    reading = measure_hand(kept.frames, kept.width_px, steadied=True)
    truth = math.radians(6.0)
    assert reading is not None
    assert reading.omega_rad_s == pytest.approx(truth, rel=0.01)
    assert reading.omega_low_rad_s <= truth <= reading.omega_high_rad_s


def test_lining_up_leaves_its_frames_as_they_were() -> None:
    """OpenCV's phase correlation applies its window to its inputs in place where their size
    needs no padding for the Fourier transform (320 x 240 does, 322 x 240 does not): the steadied
    frames were read faded to their edges at some sizes and not at others. They are faded by
    choice now, whatever their size, and the frames given are left as they were."""
    from rotrate_cli.scene.hand import _lined_up

    rng = np.random.default_rng(2)
    for width in (320, 322):
        base = cv2.GaussianBlur(rng.random((240, width)).astype(np.float32) * 255, (0, 0), 2.0)
        images = np.stack([np.roll(base, k, axis=1) for k in range(4)])
        given, still = images.copy(), base.copy()
        lined = _lined_up(images, still)
        assert np.array_equal(images, given) and np.array_equal(still, base)
        # faded to the edges, the same way at either size
        assert float(np.abs(lined[:, :, 0]).max()) < 1.0 and float(np.abs(lined[:, 120, width // 2]).min()) > 1.0
