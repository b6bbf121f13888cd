"""The picture's own turning angle (rotrate_cli.scene.picture_angle): a textured disc turned by a
known angle a frame, face on and tilted, part of a turn, against a still background with a
still reflection on the disc; and how the verdict weighs it against the tracks."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from rotrate_cli.fitting.outliers import Combined
from rotrate_cli.scene.angle_frames import AngleFrames
from rotrate_cli.scene.disc import DiscView, moving_weight
from rotrate_cli.scene.picture_angle import PictureAngle, measure_angle
from rotrate_cli.stages.verdict import judge
from rotrate_cli.video.frames import Frame

FPS = 30.0


def _texture(size: int, seed: int = 3) -> np.ndarray:
    rng = np.random.default_rng(seed)
    noise = rng.random((size // 8, size // 8)).astype(np.float32)
    return (cv2.resize(noise, (size, size), interpolation=cv2.INTER_CUBIC) * 200 + 20).clip(0, 255).astype(np.uint8)


def _frames(deg_per_frame: float, count: int, tilt_deg: float = 0.0, size: int = 320) -> tuple[list[Frame],
                                                                                                   tuple[float, float]]:
    """A disc of texture turning ``deg_per_frame`` about its centre, squashed by ``cos(tilt)``
    vertically (a long lens: the affine view), over a still textured background, with a still
    bright patch on the disc (a reflection)."""
    disc = _texture(size)
    background = _texture(size, seed=9)
    centre = (size * 0.5, size * 0.5)
    yy, xx = np.mgrid[:size, :size]
    inside = (xx - centre[0]) ** 2 + (yy - centre[1]) ** 2 < (0.42 * size) ** 2
    squash = np.array([[1.0, 0.0, 0.0], [0.0, math.cos(math.radians(tilt_deg)), 0.0]])
    squash[1, 2] = centre[1] * (1 - squash[1, 1])
    frames = []
    for index in range(count):
        turn = cv2.getRotationMatrix2D(centre, deg_per_frame * index, 1.0)
        turned = np.where(inside, cv2.warpAffine(disc, turn, (size, size), flags=cv2.INTER_CUBIC), background)
        seen = cv2.warpAffine(turned.astype(np.uint8), squash, (size, size), flags=cv2.INTER_LINEAR)
        cv2.circle(seen, (int(size * 0.62), int(size * 0.45)), 12, 250, -1)  # a reflection: stays put
        frames.append(Frame(index, index / FPS, cv2.cvtColor(seen, cv2.COLOR_GRAY2BGR)))
    return frames, centre


def _measured(frames: list[Frame], start: DiscView, search_tilt: bool) -> PictureAngle | None:
    kept = AngleFrames()
    for _ in kept.tap(iter(frames)):
        pass
    return measure_angle(kept.frames, start, kept.width_px, search_tilt=search_tilt)


@pytest.mark.parametrize(("tilt_deg", "deg_per_frame"), [(0.0, 4.0), (0.0, -9.0), (55.0, 5.0)])
def test_a_third_of_a_turn_reads_the_rate_within_half_a_percent(tilt_deg: float, deg_per_frame: float) -> None:
    count = int(round(120 / abs(deg_per_frame))) + 2  # about a third of a turn
    frames, centre = _frames(deg_per_frame, count, tilt_deg)
    truth = math.radians(abs(deg_per_frame)) * FPS
    # the centre given 4 px off, face on: the view is found from the picture
    angle = _measured(frames, DiscView((centre[0] + 4, centre[1] - 3), 0.0, 0.0, 320.0), search_tilt=tilt_deg > 0)
    assert angle is not None
    assert abs(angle.omega_rad_s / truth - 1) < 0.005
    assert angle.omega_low_rad_s <= truth <= angle.omega_high_rad_s
    assert angle.turned_deg > 90


def test_the_sense_follows_the_turn() -> None:
    one, centre = _frames(5.0, 20)
    other, _ = _frames(-5.0, 20)
    start = DiscView(centre, 0.0, 0.0, 320.0)
    assert _measured(one, start, False).sense == -_measured(other, start, False).sense


def test_a_still_picture_tells_no_rate() -> None:
    frames, centre = _frames(0.0, 20)
    assert _measured(frames, DiscView(centre, 0.0, 0.0, 320.0), False) is None


def _angle(omega: float, half: float = 0.01) -> PictureAngle:
    return PictureAngle(omega, omega * (1 - half), omega * (1 + half), 1, np.zeros(8), np.zeros(8), 100.0, 0.9,
                        DiscView((0.0, 0.0), 0.0, 0.0, 100.0))


def test_the_verdict_reports_the_turning_and_notes_loose_tracks() -> None:
    loose = Combined(0.44, 0.0, 0.88, 12)  # tracks that slide: far off, and loose
    verdict = judge(loose, None, 12, angle=_angle(3.55))
    assert verdict.rate_from == "turning"
    assert verdict.quality == "good"
    assert verdict.omega_rad_s == pytest.approx(3.55)
    assert any("do not stand behind" in note for note in verdict.notes)


def test_informative_tracks_that_disagree_make_it_weak_and_the_interval_holds_both() -> None:
    tight = Combined(1.80, 1.75, 1.85, 20)
    verdict = judge(tight, None, 20, angle=_angle(3.55))
    assert verdict.quality == "weak"
    assert verdict.rate_from == "tracks" and verdict.omega_rad_s == pytest.approx(1.80)
    assert verdict.omega_low_rad_s <= 1.75 and verdict.omega_high_rad_s >= 3.55 * 1.01


def test_a_first_step_that_fits_two_ways_is_weak_with_both_readings() -> None:
    angle = PictureAngle(3.0, 2.97, 3.03, 1, np.zeros(8), np.zeros(8), 100.0, 0.9,
                         DiscView((0.0, 0.0), 0.0, 0.0, 100.0), alike_deg=-25.0, first_step_deg=35.0)
    verdict = judge(None, None, 0, angle=angle)
    assert verdict.quality == "weak"
    assert verdict.omega_high_rad_s >= 3.0 and verdict.omega_low_rad_s <= 3.0 * 25 / 35


def test_a_view_whose_changes_line_up_worse_change_by_change_is_told_apart() -> None:
    """Two views' chains over the same changes: one whose peaks fall short of the other's in
    nearly every change, by more than chance allows, is clearly worse; one that falls short on
    average but as often exceeds it (their scatter) is not; nor are too few changes shared."""
    from rotrate_cli.scene.picture_angle import _clearly_short_of

    rng = np.random.default_rng(5)
    times = np.arange(31) / FPS
    best = 0.8 + 0.05 * rng.standard_normal(30)
    shortfall = 0.1 + 0.05 * rng.standard_normal(30)  # the record's 0.9 turn from 5 s: -0.11 +- 0.02
    assert _clearly_short_of(times, best - shortfall, times, best)
    assert not _clearly_short_of(times, best, times, best - shortfall)  # the better one is not short
    scattered = best - 0.01 + 0.15 * rng.standard_normal(30)
    assert not _clearly_short_of(times, scattered, times, best)
    assert not _clearly_short_of(times[:5], (best - shortfall)[:4], times, best)  # too few shared


def _perspective_frames(deg_per_frame: float, count: int, tilt_deg: float, size: int = 320) -> list[Frame]:
    """A textured disc turning ``deg_per_frame``, its plane tilted ``tilt_deg`` and seen through a
    45-degree lens from 1.2 picture widths: its lower side farther, and so smaller."""
    disc = _texture(size)
    background = _texture(size, seed=9)
    radius = 0.27 * size
    plane = np.float32([[0, 0], [size, 0], [size, size], [0, size]]) - size / 2
    focal = 1.2 * size
    c, s = math.cos(math.radians(tilt_deg)), math.sin(math.radians(tilt_deg))
    seen = np.float32([[size / 2 + focal * u * radius / (size / 2) / (focal + v * radius / (size / 2) * s),
                        size / 2 + focal * v * radius / (size / 2) * c / (focal + v * radius / (size / 2) * s)]
                       for u, v in plane])
    warp = cv2.getPerspectiveTransform(plane + size / 2, seen)
    yy, xx = np.mgrid[:size, :size]
    inside = ((xx - size / 2) ** 2 + (yy - size / 2) ** 2 < (0.49 * size) ** 2).astype(np.uint8) * 255
    frames = []
    for index in range(count):
        turn = cv2.getRotationMatrix2D((size / 2, size / 2), deg_per_frame * index, 1.0)
        layer = cv2.warpPerspective(cv2.warpAffine(disc, turn, (size, size), flags=cv2.INTER_CUBIC), warp, (size, size))
        mask = cv2.warpPerspective(inside, warp, (size, size))
        picture = np.where(mask > 128, layer, background).astype(np.uint8)
        frames.append(Frame(index, index / FPS, cv2.cvtColor(picture, cv2.COLOR_GRAY2BGR)))
    return frames


def test_an_oblique_disc_through_a_lens_is_sought_with_either_side_nearer() -> None:
    """A disc tilted 50 degrees through a 45-degree lens, its lower side farther, the start's
    direction the other way round (its upper side farther): a search from there could not turn
    the view round, only flatten the lens, and read +1.1% with an interval that missed (a real
    photograph's texture turned so). Both sides are tried: within 0.5%, the interval holding it."""
    deg_per_frame = 3.5
    frames = _perspective_frames(deg_per_frame, int(round(110 / deg_per_frame)) + 2, 50.0)
    truth = math.radians(deg_per_frame) * FPS
    angle = _measured(frames, DiscView((160.0, 160.0), 0.0, 50.0, 320.0), search_tilt=False)
    assert angle is not None
    assert abs(angle.omega_rad_s / truth - 1) < 0.005
    assert angle.omega_low_rad_s <= truth <= angle.omega_high_rad_s


def _hand_frames(deg_per_frame: float, count: int, size: int = 320) -> tuple[list[Frame], tuple[float, float]]:
    """A thin dark hand sweeping about the middle of a still face (drawn to a sixteenth of a pixel),
    with a little noise: a clock's second hand, all else still."""
    face = np.full((size, size), 225, np.uint8)
    centre = (size * 0.5, size * 0.5)
    rng = np.random.default_rng(4)
    for k in range(12):  # the hour marks: still
        a = math.radians(30 * k)
        cv2.line(face, (int(centre[0] + 0.40 * size * math.sin(a)), int(centre[1] - 0.40 * size * math.cos(a))),
                 (int(centre[0] + 0.46 * size * math.sin(a)), int(centre[1] - 0.46 * size * math.cos(a))), 30, 3)
    frames = []
    for index in range(count):
        a = math.radians(20.0 + deg_per_frame * index)
        seen = face.copy()
        tip = (centre[0] + 0.42 * size * math.sin(a), centre[1] - 0.42 * size * math.cos(a))
        tail = (centre[0] - 0.08 * size * math.sin(a), centre[1] + 0.08 * size * math.cos(a))
        cv2.line(seen, (round(16 * tail[0]), round(16 * tail[1])), (round(16 * tip[0]), round(16 * tip[1])), 20, 1,
                 cv2.LINE_AA, shift=4)
        noisy = np.clip(seen + rng.normal(0.0, 1.5, seen.shape), 0, 255).astype(np.uint8)
        frames.append(Frame(index, index / FPS, cv2.cvtColor(noisy, cv2.COLOR_GRAY2BGR)))
    return frames, centre


def test_a_thin_hand_sweeping_a_still_face_is_measured() -> None:
    """Its rings' mean change is the noise's; their rms stands well above it (the moving weight's
    second rule): a hundred degrees read within its interval (before: no measurement at all)."""
    frames, centre = _hand_frames(-0.6, 170)  # 100 degrees
    truth = math.radians(0.6) * FPS
    angle = _measured(frames, DiscView(centre, 0.0, 0.0, 320.0), search_tilt=False)
    assert angle is not None
    assert abs(angle.omega_rad_s / truth - 1) < 0.03
    assert angle.omega_low_rad_s <= truth <= angle.omega_high_rad_s


def _ring_changes(ring_levels: np.ndarray, count: int = 6, angles: int = 64, seed: int = 5) -> list[np.ndarray]:
    """Unrolled changes (rows: angles, columns: rings) whose rings change by ``ring_levels`` on
    average (grey levels, their sign at random)."""
    rng = np.random.default_rng(seed)
    return [ring_levels[None, :] * np.sign(rng.standard_normal((angles, len(ring_levels)))) for _ in range(count)]


def test_a_body_changing_by_about_a_grey_level_counts_all_its_rings() -> None:
    """A body turning slowly between frames changes its rings by about MOVING_LEVELS, some a
    little above it, some below (a real photograph turning 0.25 degrees a frame at 60 frames/s:
    7 of its 22 rings counted, and the view found from them was wrong). Its rings that change at
    least half as much count too; the still rings (noise) do not. A body changing its rings by
    several levels keeps the rule as it was: those under a level do not count."""
    slow = np.r_[np.full(6, 0.6), np.full(6, 1.1), np.full(6, 0.8), np.full(30, 0.01)]  # then the still picture
    inside = np.ones((64, len(slow)), dtype=bool)
    weight = moving_weight(_ring_changes(slow), inside)
    assert weight[:, :18].all() and not weight[:, 18:].any()
    fast = np.r_[np.full(6, 0.6), np.full(6, 4.0), np.full(6, 0.8), np.full(30, 0.01)]
    weight = moving_weight(_ring_changes(fast), inside)
    assert weight[:, 6:12].all() and not weight[:, :6].any() and not weight[:, 12:].any()


def test_far_shifts_that_are_no_peak_or_lie_far_off_the_others_line_are_left_out() -> None:
    """What stays still while the body turns behind it (a tonearm, the picture's edge) peaks at no
    shift; far apart, its slope reached into the search for the body's shift: a record rendered
    with its axis below the frame read -14% from such shifts, its chained angles right."""
    from rotrate_cli.scene.picture_angle import _rate_of, _with_offset

    rng = np.random.default_rng(2)
    rate = 200.0  # degrees a second
    spans = np.linspace(0.1, 0.7, 40)
    rows = [(span, rate * span + 0.5 + rng.normal(0, 0.1)) for span in spans]
    clean, _ = _with_offset(rows, 40)
    assert clean == pytest.approx(rate, rel=0.002)
    wrong = rows + [(0.57, rate * 0.57 - 12.6), (0.53, rate * 0.53 - 4.7)]
    assert _with_offset(wrong, 40)[0] == pytest.approx(clean, rel=0.001)

    class _Change:  # what _rate_of reads of a change: its time and its place in the list
        def __init__(self, index: int, time_s: float) -> None:
            self.index, self.time_s = index, time_s

    count, angles = 720, 40
    changes = [_Change(i, i / 30.0) for i in range(angles)]
    times = np.array([change.time_s for change in changes])
    chained = rate * times
    shifts = (np.arange(count) * (360.0 / count) + 180.0) % 360.0 - 180.0

    def correlate(i: int, k: int) -> np.ndarray:
        true = chained[k] - chained[i]
        still = np.exp(-0.5 * (shifts / 80.0) ** 2)  # what does not turn: a broad peak at no shift
        body = (0.2 if true > 100 else 1.0) * np.exp(-0.5 * (((shifts - true + 180) % 360 - 180) / 1.5) ** 2)
        return body + (2.0 if true > 100 else 0.0) * still

    found, _ = _rate_of(changes, correlate, times, chained)
    assert found == pytest.approx(rate, rel=0.005)


def test_frames_turned_back_together_change_nowhere_the_camera_alone_turned() -> None:
    """A still scene filmed by a rolling camera: its two frames, turned back by their rolls, show
    the same picture; the frame's edges, turned by different rolls, are cut to what both show,
    so that nothing changes between them (each turned back alone, the edges changed)."""
    from rotrate_cli.scene.angle_frames import turned_back, turned_back_together

    rng = np.random.default_rng(2)
    scene = cv2.GaussianBlur(rng.uniform(0, 255, (400, 560)).astype(np.float32), (0, 0), 3.0)
    centre = (279.5, 199.5)
    frames, rolls = [], [10.0, 11.5]
    for roll in rolls:  # the camera turned anticlockwise by ``roll``: the picture as it saw it
        matrix = cv2.getRotationMatrix2D(centre, roll, 1.0)
        frames.append(cv2.warpAffine(scene, matrix, (560, 400), flags=cv2.INTER_LINEAR)[80:320, 100:460].copy())
    together = turned_back_together(frames, rolls)
    alone = [turned_back(frame, roll) for frame, roll in zip(frames, rolls, strict=True)]
    assert np.percentile(np.abs(together[1] - together[0]), 99.5) < 3.0
    assert np.percentile(np.abs(alone[1] - alone[0]), 99.5) > 20.0
