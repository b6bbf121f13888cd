"""Features matched from photograph to photograph (:mod:`rotrate_cli.tracking.matched`)."""

from __future__ import annotations

import math

import cv2
import numpy as np

from rotrate_cli.tracking.matched import match_frames
from rotrate_cli.video.frames import Frame


def _photographs(count: int, step_deg: float, size: int = 240) -> list[Frame]:
    """A textured disc turning ``step_deg`` a photograph about the picture's middle, before a
    still textured background."""
    rng = np.random.default_rng(3)
    texture = cv2.GaussianBlur(rng.uniform(0, 255, (size, size)).astype(np.float32), (0, 0), 1.5)
    texture = cv2.normalize(texture, None, 0, 255, cv2.NORM_MINMAX)
    background = cv2.normalize(cv2.GaussianBlur(rng.uniform(0, 255, (size, size)).astype(np.float32), (0, 0), 1.5),
                               None, 0, 255, cv2.NORM_MINMAX)
    yy, xx = np.mgrid[:size, :size]
    centre = (size - 1) / 2.0
    disc = (xx - centre) ** 2 + (yy - centre) ** 2 <= (0.4 * size) ** 2
    frames = []
    for index in range(count):
        matrix = cv2.getRotationMatrix2D((centre, centre), step_deg * index, 1.0)
        turned = cv2.warpAffine(texture, matrix, (size, size), flags=cv2.INTER_LINEAR)
        frames.append(Frame(index, float(index), np.where(disc, turned, background).astype(np.uint8)))
    return frames


def test_features_on_photographs_far_apart_are_followed_on_the_turning_body_alone() -> None:
    """10 degrees a photograph: tracks of several photographs, each point at one distance from
    the axis and turning 10 degrees a step; nothing on the still background."""
    run = match_frames(_photographs(8, 10.0), scale=1.0)
    tracks = run.tracks
    assert run.frames == 8
    lengths = tracks.groupby("track").size()
    assert (lengths >= 4).sum() >= 30
    centre = (240 - 1) / 2.0
    x, y = tracks["x_px"].to_numpy() - centre, tracks["y_px"].to_numpy() - centre
    radius = np.hypot(x, y)
    assert radius.max() <= 0.4 * 240 + 3  # on the disc: the still background is let go
    tracks = tracks.assign(radius=radius, angle=np.degrees(np.arctan2(y, x)))
    for _, track in tracks.groupby("track"):
        if len(track) < 4:
            continue
        assert np.ptp(track["radius"]) < 2.0
        steps = (np.diff(track["angle"].to_numpy()) + 180.0) % 360.0 - 180.0
        assert np.allclose(np.abs(steps), 10.0, atol=math.degrees(2.0 / max(track["radius"].mean(), 20.0)) + 0.5)
