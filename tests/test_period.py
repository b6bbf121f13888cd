"""The rate from the clip's repetition (:mod:`rotrate_cli.stages.period`) and how it is weighed with
the tracks' (:mod:`rotrate_cli.stages.verdict`), on pictures of a turning texture with known periods."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from rotrate_cli.fitting.outliers import Combined
from rotrate_cli.stages.period import Period, Thumbnails, find_period
from rotrate_cli.stages.verdict import judge, turns_between
from rotrate_cli.video.frames import Frame


def _turning(times_s: np.ndarray, period_s: float, symmetry: int = 1, size: int = 96, seed: int = 7) -> Thumbnails:
    """A textured disk turning about the picture's centre, one frame per time, in thumbnails.
    ``symmetry``: the texture repeats that many times a turn."""
    rng = np.random.default_rng(seed)
    base = cv2.GaussianBlur(rng.uniform(0, 255, (size, size)).astype(np.float32), (0, 0), 2.0)
    if symmetry > 1:
        centre = ((size - 1) / 2.0, (size - 1) / 2.0)
        base = sum(cv2.warpAffine(base, cv2.getRotationMatrix2D(centre, 360.0 * k / symmetry, 1.0), (size, size))
                   for k in range(symmetry)) / symmetry
    yy, xx = np.mgrid[:size, :size]
    disk = (xx - (size - 1) / 2.0) ** 2 + (yy - (size - 1) / 2.0) ** 2 <= (0.45 * size) ** 2
    thumbnails = Thumbnails()
    frames = []
    for index, time_s in enumerate(times_s):
        matrix = cv2.getRotationMatrix2D(((size - 1) / 2.0, (size - 1) / 2.0), 360.0 * time_s / period_s, 1.0)
        turned = cv2.warpAffine(base, matrix, (size, size), flags=cv2.INTER_LINEAR)
        image = np.where(disk, turned, 90.0).clip(0, 255).astype(np.uint8)
        frames.append(Frame(index, float(time_s), image))
    for _ in thumbnails.tap(iter(frames)):
        pass
    return thumbnails


@pytest.mark.parametrize(("period_s", "duration_s"), [(1.7696, 8.0), (2.9, 7.0)])
def test_several_turns_of_a_video(period_s: float, duration_s: float) -> None:
    times = np.arange(0.0, duration_s, 1 / 23.976)
    thumbnails = _turning(times, period_s)
    found = find_period(thumbnails.times_s, thumbnails.images)
    assert found is not None
    assert found.period_s == pytest.approx(period_s, rel=0.003)
    assert found.period_low_s <= period_s <= found.period_high_s
    assert found.repeats >= 2


def test_one_turn_of_photographs_at_irregular_moments() -> None:
    """A turntable photographed by hand: 100 pictures of one turn at irregular times (as the EPFL
    cars); the turn closes between the last picture and the first, and the times place it."""
    rng = np.random.default_rng(3)
    steps = rng.uniform(0.6, 1.6, 100)
    times = np.r_[0.0, np.cumsum(steps)]
    period_s = float(times[-1])  # the 101st picture would be back at the start
    thumbnails = _turning(times[:-1], period_s)
    found = find_period(thumbnails.times_s, thumbnails.images)
    assert found is not None
    assert found.repeats == 1
    assert found.period_s == pytest.approx(period_s, rel=0.01)
    assert found.period_low_s <= period_s <= found.period_high_s


def test_under_a_turn_has_no_repetition() -> None:
    times = np.arange(0.0, 6.0, 1 / 30)
    thumbnails = _turning(times, 10.0)  # 0.6 turn
    assert find_period(thumbnails.times_s, thumbnails.images) is None


def test_nothing_moving_has_no_repetition() -> None:
    times = np.arange(0.0, 4.0, 1 / 30)
    thumbnails = _turning(times, 1e9)
    assert find_period(thumbnails.times_s, thumbnails.images) is None


def test_a_symmetric_object_takes_the_number_of_repeats_from_the_tracks() -> None:
    """Three-fold texture: the picture repeats three times a turn. Tracks saying about the turn's
    rate (with an interval) pick three repeats a turn; without tracks the repeat is reported."""
    period_s = 3.0
    times = np.arange(0.0, 7.0, 1 / 30)
    thumbnails = _turning(times, period_s, symmetry=3)
    found = find_period(thumbnails.times_s, thumbnails.images)
    assert found is not None
    assert found.period_s == pytest.approx(period_s / 3, rel=0.01)
    omega = 2 * math.pi / period_s
    verdict = judge(Combined(omega * 1.02, omega * 0.98, omega * 1.05, 40), found, 40)
    assert verdict.repeats_per_turn == 3
    assert verdict.omega_rad_s == pytest.approx(omega, rel=0.01)
    assert verdict.rate_from == "repetition" and verdict.quality == "good"
    alone = judge(None, found)  # nothing tells a third of a turn from a turn: weak, every count held
    assert alone.omega_rad_s == pytest.approx(3 * omega, rel=0.01) and alone.quality == "weak"
    assert alone.omega_low_rad_s < omega < alone.omega_high_rad_s
    assert "k = 3: " in alone.weak_because[0]


def test_verdict_on_tracks_alone() -> None:
    good = judge(Combined(0.6, 0.598, 0.603, 300), None, 300)
    assert (good.quality, good.rate_from, good.weak_because) == ("good", "tracks", ())
    wide = judge(Combined(0.6, 0.5, 0.7, 300), None, 300)
    assert wide.quality == "weak" and "wider than" in wide.weak_because[0]
    few = judge(Combined(0.6, 0.598, 0.603, 2), None, 2)
    assert few.quality == "weak" and "2 track" in few.weak_because[0]
    doubted = judge(Combined(0.6, 0.598, 0.603, 300), None, 300, ("the fixation is off",))
    assert doubted.quality == "weak"


def test_tracks_near_a_whole_number_of_repeats_tell_the_count_far_off() -> None:
    """A checker of 16 columns comes back every 1/16 of a turn: tracks at 1/16 of the return's
    rate are its turn, not tracks gone astray (the return read 16 times too fast, good, before)."""
    times = np.arange(0.0, 8.0, 1 / 30)
    found = find_period(*_arrays(_turning(times, 2.0)))
    assert found is not None
    verdict = judge(Combined(0.2, 0.196, 0.204, 50), found, 50)
    assert verdict.rate_from == "repetition" and verdict.repeats_per_turn == 16
    assert verdict.omega_rad_s == pytest.approx(math.pi / 16, rel=0.005) and verdict.quality == "good"


def test_tracks_between_whole_numbers_of_repeats_make_the_result_weak() -> None:
    """Tracks that fit no whole number of repeats: the two disagree, the result is weak, and the
    interval holds both readings (never one rate in a warning and another reported as good)."""
    times = np.arange(0.0, 8.0, 1 / 30)
    found = find_period(*_arrays(_turning(times, 2.0)))
    verdict = judge(Combined(1.2566, 1.245, 1.268, 50), found, 50)  # the return's 3.14 is 2.5 of them
    assert verdict.quality == "weak" and "not a whole number" in verdict.weak_because[0]
    assert verdict.omega_low_rad_s <= 1.245 and verdict.omega_high_rad_s >= math.pi


def _arrays(thumbnails: Thumbnails) -> tuple[np.ndarray, np.ndarray]:
    return thumbnails.times_s, thumbnails.images


def _single_closing(excess: float, frames: int = 50, lag_frames: float = 49.0):
    """A repetition seen once: a clip of ``frames`` photographs whose last comes back to the
    first after ``lag_frames`` (period 49 s at 1 frame/s)."""
    from rotrate_cli.stages.period import Period

    return Period(49.0, 48.5, 49.5, 1, frames, 0.2, 0.9, 0.0, excess, lag_frames)


def test_a_single_inexact_return_of_the_picture_is_not_a_sure_turn() -> None:
    # a car half a turn on looks like itself: the picture comes back once, not exactly
    alike = judge(None, _single_closing(excess=0.25))
    assert alike.quality == "weak" and any("comes back only once" in why for why in alike.weak_because)
    exact = judge(Combined(2 * math.pi / 49, 0.125, 0.131, 40), _single_closing(excess=0.03), 40)
    assert exact.quality == "good"  # a turntable's full turn of photographs, the tracks' count one
    # tracks that turn under two thirds of a turn in the period doubt even an exact return...
    slow_tracks = Combined(0.05, 0.045, 0.06, 20)  # a turn in 49 s is 0.128 rad/s
    doubted = judge(slow_tracks, _single_closing(excess=0.03), 20)
    assert doubted.quality == "weak" and any("turn only 39% of a turn" in why for why in doubted.weak_because)
    # ...and informative tracks that agree settle it
    agreeing = Combined(0.127, 0.124, 0.130, 20)
    assert judge(agreeing, _single_closing(excess=0.25), 20).quality == "good"
    # a clip that holds several returns is not doubted as a look-alike, but tracks that fit half or
    # a third of its repeat leave the count open: weak
    several = judge(slow_tracks, _single_closing(excess=0.25, frames=250), 20)
    assert several.quality == "weak" and not any("only once" in why for why in several.weak_because)


def test_an_exact_return_is_doubted_by_the_sense_the_near_side_travels() -> None:
    """Tracks whose fits through the lens did not tell the sense: their interval holds the other
    sense's rate too (0.092 rad/s), high enough to pass an exact return for a turn, while the
    sense their near side's travel shows turns under half a turn in the period (the first 50
    photographs of EPFL car 02: the picture back half a turn on, read as a good +90%)."""
    seen = Combined(0.053, 0.041, 0.143, 20, (0.092, 0.053), -1, (0.044, 0.061))
    doubted = judge(seen, _single_closing(excess=0.03), 20)
    assert doubted.quality == "weak" and any("turn only 41% of a turn" in why for why in doubted.weak_because)
    assert doubted.omega_low_rad_s <= 0.041 and doubted.omega_high_rad_s >= 2 * math.pi / 49.0


def test_a_doubted_return_gives_an_interval_that_holds_both_readings() -> None:
    """A single return doubted as a look-alike view: the interval spans the repetition's rate (a
    turn) and the tracks' interval (a look-alike view). An inexact one gives way to the tracks'
    rate (the EPFL cars' first 50-70 photographs: +91% to +99% by the repetition, -1% to -53% by
    the tracks), and so does an exact one whose tracks rule a turn out (their interval's top well
    under the return's rate: EPFL car 02's 45th-94th photographs, +99% -> -5.6%)."""
    slow_tracks = Combined(0.05, 0.045, 0.06, 20)
    turn = 2 * math.pi / 49.0
    exact = judge(slow_tracks, _single_closing(excess=0.03), 20)
    assert exact.quality == "weak" and exact.rate_from == "tracks"
    assert exact.omega_rad_s == pytest.approx(0.05)
    assert exact.omega_low_rad_s <= 0.045 and exact.omega_high_rad_s >= turn
    assert any("spans both readings" in note and "well under a turn" in note for note in exact.notes)
    inexact = judge(slow_tracks, _single_closing(excess=0.25), 20)
    assert inexact.quality == "weak" and inexact.rate_from == "tracks"
    assert inexact.omega_rad_s == pytest.approx(0.05)
    assert inexact.omega_low_rad_s <= 0.045 and inexact.omega_high_rad_s >= 0.06
    # without tracks to weigh, nothing tells the count: the interval holds every one
    alone = judge(None, _single_closing(excess=0.25))
    assert alone.rate_from == "repetition" and alone.quality == "weak"
    assert alone.omega_low_rad_s <= turn / 16 and alone.omega_high_rad_s >= turn


@pytest.mark.parametrize("step_deg", [29.0, 150.0])
def test_a_turn_too_fast_for_the_frame_rate_is_counted_from_every_return(step_deg: float) -> None:
    """A wheel turning tens of degrees a frame: its closest return spans several turns (at 29
    degrees a frame, 5 turns after 62 frames are 2 degrees off, 1 turn after 12 frames 12). The
    turn is the one that describes the differences at every lag; the result is weak all the same."""
    period_s = 360.0 / (step_deg * 30.0)
    thumbnails = _turning(np.arange(0.0, 3.0, 1 / 30), period_s)
    closest = find_period(thumbnails.times_s, thumbnails.images)
    assert closest is not None
    assert closest.far_apart and closest.turns_guess > 1
    found = turns_between(closest, None)  # no track: the lag profile's count
    assert found.turns_between == closest.turns_guess
    assert found.period_s == pytest.approx(period_s, rel=0.01)
    assert found.period_low_s <= period_s <= found.period_high_s
    assert found.step_deg == pytest.approx(step_deg, rel=0.01)
    verdict = judge(None, found)
    assert verdict.quality == "weak"
    assert any("wagon wheel" in reason for reason in verdict.weak_because)
    # the count is a guess: the interval holds every count, from one repeat to half a turn a frame
    assert verdict.omega_low_rad_s <= 2 * math.pi / closest.period_s
    assert verdict.omega_high_rad_s >= 0.99 * math.pi * 30


def test_frames_close_on_the_turn_are_not_far_apart() -> None:
    thumbnails = _turning(np.arange(0.0, 6.0, 1 / 30), 2.4)  # 5 degrees a frame
    found = find_period(thumbnails.times_s, thumbnails.images)
    assert found is not None
    assert not found.far_apart and found.turns_between == 1
    assert turns_between(found, Combined(0.5, 0.49, 0.51, 20), 20) is found
    turn = 2 * math.pi / 2.4
    assert judge(Combined(turn, 0.97 * turn, 1.03 * turn, 20), found, 20).quality == "good"
    assert judge(None, found).quality == "weak"  # a return alone does not tell a turn from a part


def test_where_frames_differ_wholly_the_tracks_count_the_turns() -> None:
    """A fine texture changes wholly from one frame to the next although it turns 6 degrees a
    frame (rendered spheres and cylinders at 3 rad/s): the lag profile alone may count two turns
    for one; the tracks, followed by small steps, count one."""
    closest = Period(2.0, 1.99, 2.01, 3, 180, 0.1, 0.8, lag_frames=60.0, far_apart=True, turns_guess=2)
    tracks = Combined(2 * math.pi / 2.0 * 1.02, 3.0, 3.3, 40)  # one turn in 2 s, as the tracks say
    assert turns_between(closest, tracks, 40).period_s == pytest.approx(2.0)
    assert turns_between(closest, None).period_s == pytest.approx(1.0)
    seven = turns_between(closest, Combined(7 * math.pi, 21.0, 23.0, 40), 40)
    assert seven.turns_between == 7 and seven.period_s == pytest.approx(2.0 / 7)


def test_a_fast_box_is_measured_from_its_returns_and_marked_weak(tmp_path) -> None:
    """A rendered box at 15 rad/s filmed at 30 fps (29 degrees a frame): no track lives beyond
    two frames, and its picture is most alike after 88 frames, 7 turns. Read as one turn that
    was 2.14 rad/s, called good."""
    from rotrate_cli.analysis import AnalysisConfig, analyze
    from rotrate_cli.video.synth import Renderer, SceneConfig

    scene = SceneConfig(shape="box", omega_rad_s=15.0, fps=30.0, duration_s=3.0, supersample=1, seed=3)
    renderer = Renderer(scene)
    clip = tmp_path / "fast_box.mp4"
    writer = cv2.VideoWriter(str(clip), cv2.VideoWriter_fourcc(*"mp4v"), scene.fps, (scene.width_px, scene.height_px))
    for frame in renderer.frames(range(scene.frame_count)):
        writer.write(frame)
    writer.release()
    result = analyze(clip, AnalysisConfig(fixation_px=None))
    assert result.omega_rad_s == pytest.approx(15.0, rel=0.01)
    assert result.verdict.quality == "weak"
    assert result.omega_low_rad_s <= 15.0 <= result.omega_high_rad_s


def test_a_light_flickering_with_the_mains_is_not_taken_for_the_turn() -> None:
    """50 Hz lights seen at 30 frames/s flicker at 10 Hz: the picture's brightness repeats every
    3 frames. At 15% that was taken for the turn (62.8 rad/s for 2)."""
    times = np.arange(0.0, 8.0, 1 / 30)
    clean = _turning(times, 3.1416)
    flickering = Thumbnails(steady_light=True)
    frames = [Frame(k, float(t), np.clip(image.reshape(64, 64).astype(np.float32)
                                         * (1 + 0.15 * math.sin(2 * math.pi * 10 * t)), 0, 255).astype(np.uint8))
              for k, (t, image) in enumerate(zip(clean.times_s, clean.images, strict=True))]
    for _ in flickering.tap(iter(frames)):
        pass
    found = find_period(flickering.times_s, flickering.images)
    assert found is not None
    assert found.period_s == pytest.approx(3.1416, rel=0.005)


@pytest.mark.parametrize("fixation_px", [(319.5, 179.5), None])
def test_the_first_fit_does_not_wait_for_the_clips_repetition(monkeypatch, fixation_px) -> None:
    """The repetition, worked out in its own thread, is first waited for where the lens is
    sought (not with --fov ortho or a lens given), else where a found axis is moved, after the
    first fit: that fit runs beside it. The repetition here waits (at most 20 s) for the first fit
    to start; had the fit waited for it, the two would have sat out the 20 s."""
    import threading
    from pathlib import Path

    from rotrate_cli import analysis
    from rotrate_cli.stages import fits

    fitting = threading.Event()
    fit_first = fits.rates_from_offsets

    def noted(*args, **kwargs):
        fitting.set()
        return fit_first(*args, **kwargs)

    find_first = analysis.find_period

    def waiting(*args, **kwargs):
        assert fitting.wait(timeout=20.0), "the first fit waited for the repetition"
        return find_first(*args, **kwargs)

    monkeypatch.setattr(analysis, "find_period", waiting)
    monkeypatch.setattr("rotrate_cli.stages.geometry.rates_from_offsets", noted)
    clip = Path(__file__).resolve().parents[1] / "sample_videos" / "box_ortho.mp4"
    result = analysis.analyze(clip, analysis.AnalysisConfig(fixation_px=fixation_px, find_focal=False))
    assert fitting.is_set()
    assert result.omega_rad_s == pytest.approx(0.6, rel=0.02)


def _rotor_thumbnails(scene) -> Thumbnails:
    from rotrate_cli.video.rotor import rotor_frames
    thumbnails = Thumbnails(steady_light=True)
    frames = (Frame(index, index / scene.fps, image) for index, image in enumerate(rotor_frames(scene)))
    for _ in thumbnails.tap(frames):
        pass
    return thumbnails


def test_a_return_buried_in_slow_change_is_found_once_the_change_is_taken_out() -> None:
    """A marked disc seen nearly edge on (80 degrees), 7.8 turns in 14 s, behind a rainy window:
    the light swings across the picture, drops run down the glass and the camera drifts 4 px. The
    frames' plain differences show no return; less their running mean they show it exactly."""
    from rotrate_cli.stages.period import _search
    from rotrate_cli.video.rotor import RotorScene
    scene = RotorScene(kind="checker", symmetry=1, omega_rad_s=3.5, fps=30, duration_s=14, width_px=320,
                       height_px=240, radius_px=80, tilt_deg=80, weather=2.0, texture=0.3, seed=3, mark=True)
    thumbnails = _rotor_thumbnails(scene)
    assert _search(thumbnails.times_s, thumbnails.images, 0.0) is None  # the case holds: no plain return
    found = find_period(thumbnails.times_s, thumbnails.images)
    truth_s = 2 * math.pi / 3.5
    assert found is not None and found.detrended
    assert found.period_s == pytest.approx(truth_s, rel=0.002)
    assert found.period_low_s <= truth_s <= found.period_high_s
    assert found.period_high_s - found.period_low_s < 0.02 * truth_s


def test_slow_change_under_a_turn_is_no_return() -> None:
    """The same weather over 0.8 of a turn: taking the slow change out finds no return that is not there."""
    from rotrate_cli.video.rotor import RotorScene
    scene = RotorScene(kind="checker", symmetry=1, omega_rad_s=0.5, fps=30, duration_s=10, width_px=320,
                       height_px=240, radius_px=80, tilt_deg=60, weather=2.0, texture=0.3, seed=4, mark=True)
    thumbnails = _rotor_thumbnails(scene)
    assert find_period(thumbnails.times_s, thumbnails.images) is None


def _stepping_hand(fps: float, offset_s: float, size: int = 128) -> tuple[Thumbnails, float]:
    """A clock face whose second hand steps 3 degrees every half second (a turn in 60 s), filmed
    for one turn at ``fps``, the first step ``offset_s`` into its hold; with the turn's time."""
    rng = np.random.default_rng(1)
    face = cv2.GaussianBlur(rng.uniform(0, 255, (size, size)).astype(np.float32), (0, 0), 3) * 0.3 + 150
    c = (size - 1) / 2
    thumbnails = Thumbnails()
    frames = []
    turn_s, hold_s = 60.0, 0.5
    for index in range(int(round(turn_s * fps))):
        time_s = index / fps
        angle = math.radians(3.0 * math.floor((time_s + offset_s) / hold_s) - 90)
        image = face.copy()
        cv2.line(image, (int(c), int(c)), (int(c + 0.85 * c * math.cos(angle)), int(c + 0.85 * c * math.sin(angle))),
                 20, 3, cv2.LINE_AA)
        image += rng.normal(0, 1.5, image.shape)
        frames.append(Frame(index, time_s, np.clip(image, 0, 255).astype(np.uint8)))
    for _ in thumbnails.tap(iter(frames)):
        pass
    return thumbnails, turn_s


@pytest.mark.parametrize(("fps", "offset_s"), [(25.0, 0.3), (10.0, 0.25)])
def test_a_stepped_hand_s_single_return_is_placed_no_finer_than_its_step(fps: float, offset_s: float) -> None:
    """Where the hand stands still between steps, its return can be placed only within the half
    second a step is held: the interval holds that (one step is 0.83% of the turn)."""
    thumbnails, turn_s = _stepping_hand(fps, offset_s)
    found = find_period(thumbnails.times_s, thumbnails.images)
    assert found is not None
    assert found.period_low_s <= turn_s <= found.period_high_s
    assert found.period_high_s - found.period_low_s >= 0.5 / turn_s * turn_s  # at least one step's width


def test_a_smooth_turn_holds_no_step_and_a_stepped_one_its_own() -> None:
    from rotrate_cli.stages.period import _hold_s, pixel_differences
    times = np.arange(0.0, 8.0, 1 / 23.976)
    smooth = _turning(times, 1.7696)
    assert _hold_s(pixel_differences(smooth.images).diagonal(1), smooth.times_s) == 0.0
    stepped, _ = _stepping_hand(25.0, 0.3)
    assert _hold_s(pixel_differences(stepped.images).diagonal(1), stepped.times_s) == pytest.approx(0.5, abs=0.05)
