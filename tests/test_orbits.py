"""Another body turning in the picture (rotrate_cli.fitting.orbits, rotrate_cli.stages.bodies):
tracks on two discs side by side, turning at different rates, are told apart by their own orbits,
and a result whose axis was found says that another body turns and is weak for it; one body, seen
face on, from the side or shaken in place, shows no other."""

from __future__ import annotations

import math
import re

import numpy as np
import pandas as pd
import pytest

from rotrate_cli.fitting.orbits import another_body, turning_groups
from tests.conftest import blob_texture, write_grey_clip

SIZE = (1280, 720)


def _disc_tracks(rng: np.random.Generator, first_id: int, omega: float, centre: tuple[float, float], radius: float,
                 count: int = 40, frames: int = 90, fps: float = 30.0, squash: float = 1.0) -> pd.DataFrame:
    """``count`` points of a disc turning ``omega`` about ``centre``, seen tilted (``squash``: its
    circles' short axis over their long), followed with 0.3 px of noise."""
    rows = []
    times = np.arange(frames) / fps
    for k in range(count):
        r = radius * math.sqrt(rng.uniform(0.15, 1.0))
        phase = rng.uniform(0, 2 * math.pi)
        x = centre[0] + r * np.cos(omega * times + phase) + rng.normal(0, 0.3, frames)
        y = centre[1] + squash * r * np.sin(omega * times + phase) + rng.normal(0, 0.3, frames)
        rows.append(pd.DataFrame({"frame": np.arange(frames), "time_s": times, "track": first_id + k,
                                  "x_px": x, "y_px": y}))
    return pd.concat(rows, ignore_index=True)


def test_two_discs_turning_at_different_rates_are_two_groups_and_each_is_the_others_other_body() -> None:
    rng = np.random.default_rng(3)
    tracks = pd.concat([_disc_tracks(rng, 0, 1.0, (340, 360), 200), _disc_tracks(rng, 100, 1.6, (940, 360), 180,
                                                                                   squash=0.6)],
                       ignore_index=True)
    groups = turning_groups(tracks, SIZE)
    assert len(groups) == 2
    rates = sorted(group.omega_rad_s for group in groups)
    assert rates == [pytest.approx(1.0, rel=0.02), pytest.approx(1.6, rel=0.02)]
    slow = next(group for group in groups if group.omega_rad_s < 1.3)
    assert math.dist(slow.centre_px, (340, 360)) < 5
    # measured the fast disc about its axis: the slow one is another body, and the other way round
    other = another_body(groups, 1.6, (940, 360))
    assert other is not None and other.omega_rad_s == pytest.approx(1.0, rel=0.02)
    assert another_body(groups, 1.0, (340, 360)).omega_rad_s == pytest.approx(1.6, rel=0.02)
    # where the measured axis is unknown, the group at the measured rate stands for it
    assert another_body(groups, 1.0, (math.nan, math.nan)).omega_rad_s == pytest.approx(1.6, rel=0.02)


def test_one_disc_shows_no_other_body_even_measured_at_a_slid_rate_or_about_a_point_off_its_axis() -> None:
    rng = np.random.default_rng(4)
    tracks = _disc_tracks(rng, 0, 2.0, (640, 360), 250, squash=0.45)
    groups = turning_groups(tracks, SIZE)
    assert len(groups) == 1
    assert another_body(groups, 2.0, (640, 360)) is None
    # the rate 40% slow (tracks sliding along grooves) about a point 100 px off: still inside its orbits
    assert another_body(groups, 1.2, (700, 440)) is None


def test_a_patch_shaking_in_place_is_no_turning_group() -> None:
    rng = np.random.default_rng(5)
    frames, times = 90, np.arange(90) / 30.0
    shaking = pd.concat([pd.DataFrame({"frame": np.arange(frames), "time_s": times, "track": 200 + k,
                                       "x_px": 100 + 3 * k + 4 * np.cos(6 * times), "y_px": 600 + 4 * np.sin(6 * times)
                                       + rng.normal(0, 0.2, frames)}) for k in range(30)], ignore_index=True)
    assert turning_groups(shaking, SIZE) == ()


def _side_tracks(rng: np.random.Generator, first_id: int, omega: float, axis_x: float, radius: float,
                 count: int = 40, frames: int = 90, fps: float = 30.0) -> pd.DataFrame:
    """``count`` points of a body turning ``omega`` about a vertical axis at ``axis_x``, seen from the
    side (their paths lines across the picture, each at its own height), each followed while it
    faces the camera (half a turn at most), with 0.3 px of noise."""
    rows = []
    for k in range(count):
        r = radius * rng.uniform(0.3, 1.0)
        phase = rng.uniform(0, 2 * math.pi)
        times = np.arange(frames) / fps
        angle = omega * times + phase
        facing = np.cos(angle) > 0  # on the near side
        if facing.sum() < 20:
            continue
        times = times[facing]
        rows.append(pd.DataFrame({"frame": np.flatnonzero(facing), "time_s": times, "track": first_id + k,
                                  "x_px": axis_x + r * np.sin(angle[facing]) + rng.normal(0, 0.3, len(times)),
                                  "y_px": rng.uniform(200, 520) + rng.normal(0, 0.3, len(times))}))
    return pd.concat(rows, ignore_index=True)


def test_bodies_seen_from_the_side_are_grouped_along_their_lines_and_told_apart() -> None:
    rng = np.random.default_rng(6)
    one = _side_tracks(rng, 0, 1.0, 400, 200, frames=150)
    groups = turning_groups(one, SIZE)
    assert len(groups) >= 1 and groups[0].along == "x"
    assert groups[0].omega_rad_s == pytest.approx(1.0, rel=0.05) and abs(groups[0].centre_px[0] - 400) < 10
    # one body seen from the side, measured about its axis, even 30% slow or 40 px off: no other body
    assert another_body(groups, 1.0, (400, 360)) is None
    assert another_body(groups, 0.7, (440, 300)) is None
    # two side by side, at 1.0 and 1.8 rad/s: each is the other's other body
    two = pd.concat([one, _side_tracks(rng, 100, 1.8, 950, 160, frames=150)], ignore_index=True)
    groups = turning_groups(two, SIZE)
    other = another_body(groups, 1.0, (400, 360))
    assert other is not None and other.along == "x" and other.omega_rad_s == pytest.approx(1.8, rel=0.05)
    assert abs(other.centre_px[0] - 950) < 10 and 200 < other.centre_px[1] < 520
    assert another_body(groups, 1.8, (950, 360)).omega_rad_s == pytest.approx(1.0, rel=0.05)


def test_the_two_bodies_sample_seen_from_the_side_names_the_other(tmp_path) -> None:
    """sample_videos/two_bodies.mp4: a box (0.5 rad/s, axis at x 160) and a cylinder (-1.2 rad/s,
    axis at x 480) side by side, seen from the side. Measured with the axis found, the result
    names the other body and is weak; about the cylinder's axis, given, it names the box; a single
    box seen from the side names none."""
    from pathlib import Path

    from rotrate_cli.analysis import analyze
    from rotrate_cli.config import AnalysisConfig
    from rotrate_cli.tracking.klt import Roi, TrackerConfig

    samples = Path(__file__).resolve().parents[1] / "sample_videos"
    two = analyze(samples / "two_bodies.mp4", AnalysisConfig(fixation_px=None))
    assert two.other_body is not None and two.other_body.along == "x"
    measured_box = abs(two.fixation_px[0] - 160) < 20
    assert abs(two.other_body.centre_px[0] - (480 if measured_box else 160)) < 20
    assert two.verdict.quality == "weak"
    assert any(warning.startswith("another body turns in the picture") for warning in two.warnings)
    from rotrate_cli.cli.report import to_dict

    assert to_dict(two)["other_body"]["along"] == "x"
    # measured about the cylinder's axis (given), the box is the other body: said, not weak for it
    cylinder = analyze(samples / "two_bodies.mp4", AnalysisConfig(fixation_px=(479.0, 180.0)))
    assert cylinder.other_body is not None and abs(cylinder.other_body.centre_px[0] - 160) < 20
    assert cylinder.other_body.omega_rad_s == pytest.approx(0.5, rel=0.05)
    # as the advice says, `roi` around the one meant keeps the other's points out of its fits
    assert "`roi` around the one meant" in " ".join(cylinder.warnings)
    kept_out = analyze(samples / "two_bodies.mp4", AnalysisConfig(fixation_px=(479.0, 180.0),
                                                                   tracker=TrackerConfig(roi=Roi(380, 50, 200, 260))))
    assert kept_out.omega_rad_s == pytest.approx(1.2, rel=0.01) and kept_out.verdict.quality == "good"
    one = analyze(samples / "box_ortho.mp4", AnalysisConfig(fixation_px=None))
    assert one.other_body is None


def _two_discs_clip(path, omegas: tuple[float, float], seconds: float = 2.0, fps: float = 30.0) -> None:
    """Two finely textured discs (radius 70 px) side by side, turning face on at ``omegas``, before a
    plain backdrop; 480x200."""
    import cv2

    rng = np.random.default_rng(11)
    size, radius = (480, 200), 70
    side = 2 * radius
    yy, xx = np.mgrid[:side, :side]
    disc = (((xx - radius + 0.5) ** 2 + (yy - radius + 0.5) ** 2) <= radius ** 2).astype(np.float32)
    textures = [blob_texture(rng, side, (6, 18, 48)) for _ in omegas]
    corners = [(40, 30), (300, 30)]

    def pictures():
        for frame in range(int(seconds * fps) + 1):
            picture = np.full((size[1], size[0]), 128.0, np.float32)
            for texture, omega, (x0, y0) in zip(textures, omegas, corners, strict=True):
                turn = cv2.getRotationMatrix2D((radius - 0.5, radius - 0.5), math.degrees(omega * frame / fps), 1.0)
                body = cv2.warpAffine(texture, turn, (side, side), flags=cv2.INTER_LINEAR)
                window = picture[y0:y0 + side, x0:x0 + side]
                picture[y0:y0 + side, x0:x0 + side] = window * (1 - disc) + body * disc
            yield picture + rng.normal(0, 1.0, picture.shape)

    write_grey_clip(path, pictures(), size, fps)


@pytest.mark.slow  # renders a clip and analyses it twice (about 10 s): make test-slow keeps make test under 4 minutes
def test_two_discs_side_by_side_found_axis_is_weak_and_names_the_other_given_axis_is_told(tmp_path) -> None:
    """Before: the faster disc's rate, good, with no word of the other (a found axis may land on
    either body; the user who meant the other got a confident wrong number)."""
    from rotrate_cli.analysis import analyze
    from rotrate_cli.config import AnalysisConfig

    clip = tmp_path / "two.mp4"
    _two_discs_clip(clip, (1.5, 2.6))
    found = analyze(clip, AnalysisConfig(fixation_px=None))
    told = [warning for warning in found.warnings if warning.startswith("another body turns")]
    assert found.quality == "weak" and len(told) == 1
    # the rate reported is one of the two, and the note names the other's
    reported, other = (1.5, 2.6) if abs(found.omega_rad_s - 1.5) < abs(found.omega_rad_s - 2.6) else (2.6, 1.5)
    assert found.omega_rad_s == pytest.approx(reported, rel=0.03)
    assert float(re.search(r"about ([0-9.]+) rad/s", told[0]).group(1)) == pytest.approx(other, rel=0.03)
    assert any("which one is meant" in reason for reason in found.verdict.weak_because)
    from rotrate_cli.cli.report import to_dict

    assert to_dict(found)["other_body"]["omega"] == pytest.approx(other, rel=0.03)
    given = analyze(clip, AnalysisConfig(fixation_px=(110.0, 100.0)))
    assert given.omega_rad_s == pytest.approx(1.5, rel=0.03)
    assert any(warning.startswith("another body turns") for warning in given.warnings)
    assert not any("which one is meant" in reason for reason in given.verdict.weak_because)



def _scattered_arcs(rng: np.random.Generator, count: int = 500, frames: int = 24) -> pd.DataFrame:
    """One body's side-view tracks that slid: arcs whose rates scatter 0.8-2.5 rad/s (log-evenly)
    about axis places spread 200 px, each on the near side, 0.3 px of noise."""
    times = np.arange(frames) / 30.0
    rows = []
    for k in range(count):
        omega, axis_x, radius = math.exp(rng.uniform(math.log(0.8), math.log(2.5))), 640 + rng.uniform(-100, 100), \
            rng.uniform(40, 200)
        angle = omega * times + rng.uniform(-0.5 * math.pi, 0.5 * math.pi - omega * times[-1])
        rows.append(pd.DataFrame({"frame": np.arange(frames), "time_s": times, "track": k,
                                  "x_px": axis_x + radius * np.sin(angle) + rng.normal(0, 0.3, frames),
                                  "y_px": rng.uniform(200, 520) + rng.normal(0, 0.3, frames)}))
    return pd.concat(rows, ignore_index=True)


@pytest.mark.parametrize("seed", range(4))
def test_one_bodys_arcs_scattered_in_rate_are_no_other_body(seed: int) -> None:
    """Seen from the side, tracks that slide (a drum of 16 checkers, each track jumping from
    checker to checker) read arcs whose rates scatter: its 500 lines fell into fragments alone (29,
    20 and 10 tracks at 1.07, 1.58 and 2.27 rad/s for 1.3, none at its own rate), the smallest was
    named another body and the right result weak. A side view's group now holds a tenth of the
    lines compared at least (with seed 3 here, a fragment of 17 was named before)."""
    groups = turning_groups(_scattered_arcs(np.random.default_rng(seed)), SIZE)
    assert another_body(groups, 1.3, (640, 360)) is None


def test_a_second_body_beside_scattered_arcs_is_still_named() -> None:
    rng = np.random.default_rng(3)
    beside = pd.concat([_scattered_arcs(rng), _side_tracks(rng, 1000, 1.8, 1100, 160, count=160, frames=150)],
                       ignore_index=True)
    other = another_body(turning_groups(beside, SIZE), 1.3, (640, 360))
    assert other is not None and other.omega_rad_s == pytest.approx(1.8, rel=0.05)
