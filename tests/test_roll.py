"""The clip's repetition with a camera's steady roll taken out (:mod:`rotrate_cli.stages.roll`), on
pictures of a textured disc seen obliquely, its picture turned by a rolling camera."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from rotrate_cli.stages.period import Thumbnails, find_period
from rotrate_cli.stages.roll import rolled_period, unsteady_camera_period, zoomed_period
from rotrate_cli.video.frames import Frame

FPS = 24.0


def _filmed(period_s: float, roll_deg_s: float, tilt_deg: float, duration_s: float = 15.0,
            centre: tuple[float, float] = (150.0, 70.0), seed: int = 3) -> Thumbnails:
    """A textured disc turning once in ``period_s`` about ``centre`` (a 256x144 picture), seen
    tilted by ``tilt_deg`` (its circles squashed across), by a camera rolling ``roll_deg_s``
    (anticlockwise as shown) about the picture's centre; in thumbnails. The disc fills the
    picture: nothing in it stands still."""
    rng = np.random.default_rng(seed)
    side = 900
    texture = 6.0 * cv2.GaussianBlur(rng.uniform(0, 255, (side, side)).astype(np.float32), (0, 0), 10.0)
    squash = math.cos(math.radians(tilt_deg))
    thumbnails = Thumbnails()
    frames = []
    for index in range(int(duration_s * FPS)):
        time_s = index / FPS
        turn = cv2.getRotationMatrix2D((side / 2.0, side / 2.0), 360.0 * time_s / period_s, 1.0)
        # the plane's view: its middle to the axis's place, squashed across
        view = np.array([[1.0, 0.0, centre[0] - side / 2.0], [0.0, squash, centre[1] - squash * side / 2.0]])
        camera = cv2.getRotationMatrix2D((127.5, 71.5), roll_deg_s * time_s, 1.0)
        matrix = _then(camera, _then(view, turn))
        image = cv2.warpAffine(texture, matrix, (256, 144), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
        frames.append(Frame(index, time_s, (image - image.mean() + 128.0).clip(0, 255).astype(np.uint8)))
    for _ in thumbnails.tap(iter(frames)):
        pass
    return thumbnails


def _then(second: np.ndarray, first: np.ndarray) -> np.ndarray:
    """The affine map ``first`` then ``second`` (2x3 each)."""
    return (np.vstack([second, [0.0, 0.0, 1.0]]) @ np.vstack([first, [0.0, 0.0, 1.0]]))[:2]


@pytest.mark.parametrize("roll_deg_s", [3.0, -4.0])
def test_a_rolling_camera_s_roll_is_found_and_the_return_times_the_turn(roll_deg_s: float) -> None:
    """Seen tilted 65 degrees, the disc's picture comes back each turn turned by the camera's roll
    over it: no return. Turned back by the roll found, it comes back at the disc's own rate."""
    thumbnails = _filmed(3.0, roll_deg_s, 65.0)
    assert thumbnails.shape is not None
    assert find_period(thumbnails.times_s, thumbnails.images) is None
    found = rolled_period(thumbnails.times_s, thumbnails.images, thumbnails.shape)
    assert found is not None
    assert found.roll_deg_s == pytest.approx(roll_deg_s, abs=0.5)
    assert found.period_s == pytest.approx(3.0, rel=0.005)
    assert found.period_low_s <= 3.0 <= found.period_high_s


def test_a_disc_face_on_about_the_middle_tells_no_roll() -> None:
    """Face on about the picture's centre, the camera's turn and the disc's are one: turned back by
    any roll the picture comes back, at another rate. No roll is pinned, and none is taken (the
    plain return reads the two turns together)."""
    thumbnails = _filmed(3.0, 3.0, 0.0, centre=(127.5, 71.5))
    assert thumbnails.shape is not None
    assert rolled_period(thumbnails.times_s, thumbnails.images, thumbnails.shape) is None


def test_a_picture_under_a_turn_has_no_rolled_return() -> None:
    thumbnails = _filmed(20.0, 3.0, 65.0, duration_s=8.0)
    assert thumbnails.shape is not None
    assert rolled_period(thumbnails.times_s, thumbnails.images, thumbnails.shape) is None


def _swaying(period_s: float, tilt_deg: float, roll_deg_s: float = 0.0, duration_s: float = 15.0,
             nearer: float = 0.0) -> Thumbnails:
    """:func:`_filmed`'s disc, the camera also swaying as a hand does (1.5 and 0.4 degrees at 0.9
    and 2.3 Hz about the picture's centre), with ``roll_deg_s`` of steady roll; ``nearer``: a
    camera coming nearer and going back instead of swaying (the picture ``1.05 (1 + nearer sin(2 pi
    0.2 t))`` times as large about its centre)."""
    rng = np.random.default_rng(5)
    side = 900
    texture = 6.0 * cv2.GaussianBlur(rng.uniform(0, 255, (side, side)).astype(np.float32), (0, 0), 10.0)
    squash = math.cos(math.radians(tilt_deg))
    centre = (150.0, 70.0)
    thumbnails = Thumbnails()
    frames = []
    for index in range(int(duration_s * FPS)):
        time_s = index / FPS
        sway = 1.5 * math.sin(2 * math.pi * 0.9 * time_s) + 0.4 * math.sin(2 * math.pi * 2.3 * time_s + 1.0)
        scale = 1.0
        if nearer:
            sway, scale = 0.0, 1.05 * (1.0 + nearer * math.sin(2 * math.pi * 0.2 * time_s))
        turn = cv2.getRotationMatrix2D((side / 2.0, side / 2.0), 360.0 * time_s / period_s, 1.0)
        view = np.array([[1.0, 0.0, centre[0] - side / 2.0], [0.0, squash, centre[1] - squash * side / 2.0]])
        camera = cv2.getRotationMatrix2D((127.5, 71.5), roll_deg_s * time_s + sway, scale)
        image = cv2.warpAffine(texture, _then(camera, _then(view, turn)), (256, 144), flags=cv2.INTER_LINEAR,
                               borderMode=cv2.BORDER_REFLECT)
        frames.append(Frame(index, time_s, (image - image.mean() + 128.0).clip(0, 255).astype(np.uint8)))
    for _ in thumbnails.tap(iter(frames)):
        pass
    return thumbnails


def test_a_swaying_camera_s_picture_comes_back_each_turn_once_the_sway_is_allowed() -> None:
    """A hand's sway of a degree or two spoils the plain return: the pictures a turn apart differ
    by the sway. Allowed a small turn of the whole picture, they come back each turn, at the
    disc's own rate, and the sway is said (its ``sway_deg``); with no sway, nothing changes."""
    thumbnails = _swaying(2.5, 65.0)
    assert thumbnails.shape is not None
    plain = find_period(thumbnails.times_s, thumbnails.images)
    found = unsteady_camera_period(thumbnails.times_s, thumbnails.images, thumbnails.shape, 0.0, plain)
    assert plain is None or plain.period_s > 1.5 * 2.5  # plainly, back only where the sway lines up too
    assert found is not None and found.sway_deg > 0 and found.roll_deg_s == 0
    assert found.period_s == pytest.approx(2.5, rel=0.005)
    assert found.period_low_s <= 2.5 <= found.period_high_s
    assert found.repeats >= 4
    still = _filmed(2.5, 0.0, 65.0)
    plain = find_period(still.times_s, still.images)
    assert unsteady_camera_period(still.times_s, still.images, still.shape, 0.0, plain) is plain


def test_a_camera_coming_nearer_and_going_back_is_allowed_for_and_said() -> None:
    """A camera coming 3% nearer and going back once in five seconds: the pictures a turn apart
    differ in size. Allowed a few percent larger or smaller about the centre, the picture comes
    back each turn at the disc's own rate, and the zoom is said (its ``zoom_share``), where the
    plain return comes back less often. (Here a small steady roll taken out, tried before the
    zoom, brings it back too, and is taken: the shared record so filmed needed the zoom.)"""
    thumbnails = _swaying(2.5, 65.0, nearer=0.03)
    assert thumbnails.shape is not None
    plain = find_period(thumbnails.times_s, thumbnails.images)
    zoomed = zoomed_period(thumbnails.times_s, thumbnails.images, thumbnails.shape)
    assert zoomed is not None and zoomed.zoom_share > 0 and zoomed.sway_deg == 0 and zoomed.roll_deg_s == 0
    assert plain is None or plain.repeats < zoomed.repeats
    assert zoomed.period_s == pytest.approx(2.5, rel=0.005)
    assert zoomed.period_low_s <= 2.5 <= zoomed.period_high_s
    assert zoomed.repeats >= 4
    found = unsteady_camera_period(thumbnails.times_s, thumbnails.images, thumbnails.shape, 0.0, plain)
    assert found is not None and found.period_low_s <= 2.5 <= found.period_high_s


def test_a_rolling_and_swaying_camera_s_roll_is_found() -> None:
    thumbnails = _swaying(2.5, 65.0, roll_deg_s=3.0)
    assert thumbnails.shape is not None
    found = unsteady_camera_period(thumbnails.times_s, thumbnails.images, thumbnails.shape, 0.0,
                                   find_period(thumbnails.times_s, thumbnails.images))
    assert found is not None
    assert found.roll_deg_s == pytest.approx(3.0, abs=0.5)
    assert found.period_s == pytest.approx(2.5, rel=0.005)
    assert found.period_low_s <= 2.5 <= found.period_high_s


def test_tracks_are_turned_back_as_the_pictures_are() -> None:
    """A point's position turned back by a camera's roll lands where the picture turned back by the
    same roll shows it: the tracks' paths and the pictures stay in one frame (the rolled record's
    view was sought from paths the roll had turned)."""
    import pandas as pd

    from rotrate_cli.scene.angle_frames import turned_back as turned_back_picture
    from rotrate_cli.stages.roll import turned_back_positions

    size = (320, 180)
    points = [(250.0, 40.0, 2.0), (60.0, 150.0, 5.0)]  # x, y, time since the start
    tracks = pd.DataFrame({"track": [0, 1], "time_s": [t for _, _, t in points],
                           "x_px": [x for x, _, _ in points], "y_px": [y for _, y, _ in points]})
    turned = turned_back_positions(tracks, 4.0, 0.0, size)
    for (x, y, time_s), (_, row) in zip(points, turned.iterrows(), strict=True):
        image = np.zeros((size[1], size[0]), np.uint8)
        cv2.circle(image, (round(x), round(y)), 3, 255, -1)
        back = turned_back_picture(image, 4.0 * time_s).astype(float)
        rows, columns = np.mgrid[:size[1], :size[0]]
        seen = (float((back * columns).sum() / back.sum()), float((back * rows).sum() / back.sum()))
        assert math.hypot(seen[0] - row["x_px"], seen[1] - row["y_px"]) < 0.5
        assert math.hypot(x - row["x_px"], y - row["y_px"]) > 2.0  # (it did move)
