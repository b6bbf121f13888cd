"""Shared paths and helpers for the tests."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
SAMPLES = ROOT / "sample_videos"
SHARED = ROOT.parent / "shared"
PAPER_TABLE = SHARED / "reference" / "paper_table1.csv"
DINOSAUR = SHARED / "data" / "dinosaur"


def truth_of(clip: Path) -> dict:
    """The truth JSON written beside a rendered clip."""
    return json.loads(clip.with_suffix(".json").read_text())


def direction_seen_as(truth: dict, reported_angle_deg: float) -> str:
    """The truth's direction as seen from the axis end that ``reported_angle_deg`` calls the top.

    An axis near horizontal has no natural top: rotrate folds angles into (-90, 90], so a clip
    rendered with its top end to the right (roll 90) may be reported with the top end to the
    left (-90), and then its sense is read from the other end.
    """
    flip = math.cos(math.radians(reported_angle_deg - truth.get("axis_angle_deg", 0.0))) < 0
    return {"ccw": "cw", "cw": "ccw"}[truth["direction"]] if flip else truth["direction"]


def blob_texture(generator: np.random.Generator, side: int, cells: tuple[int, ...]) -> np.ndarray:
    """A photograph-like texture, ``side`` px square: random grids of ``cells`` a side, each
    enlarged smoothly and summed (blobs at several scales), grey levels 20-240."""
    import cv2

    texture = np.zeros((side, side), np.float32)
    for count in cells:
        texture += cv2.resize(generator.random((count, count)).astype(np.float32), (side, side),
                              interpolation=cv2.INTER_CUBIC)
    return (texture - texture.min()) / np.ptp(texture) * 220 + 20


def write_grey_clip(path: Path, pictures, size: tuple[int, int], fps: float) -> None:
    """``pictures`` (grey, float, ``size`` = width, height) written as an MPEG-4 clip by OpenCV's
    own writer, clipped to 0-255."""
    import cv2

    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), fps, size)
    for picture in pictures:
        writer.write(cv2.cvtColor(np.clip(picture, 0, 255).astype(np.uint8), cv2.COLOR_GRAY2BGR))
    writer.release()


def need(path: Path, what: str) -> None:
    """Skip the test, saying why, when shared data is absent (a checkout outside the workplace)."""
    if not path.exists():
        pytest.skip(f"{what} not found at {path}: shared data is absent in this checkout")


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(12345)


@dataclass(frozen=True)
class Sample:
    """A bundled sample clip and its truth (the JSON ``rotrate synth`` wrote beside it)."""

    path: Path
    truth: dict

    @property
    def omega_rad_s(self) -> float:
        return abs(float(self.truth["omega_rad_s"]))

    @property
    def fixation_px(self) -> tuple[float, float]:
        x, y = self.truth["fixation_px"]
        return float(x), float(y)


def _sample_fixture(name: str):  # noqa: ANN202 - a pytest fixture
    def sample() -> Sample:
        path = SAMPLES / f"{name}.mp4"
        return Sample(path, truth_of(path))

    sample.__doc__ = f"sample_videos/{name}.mp4 and its truth."
    return pytest.fixture(name=name)(sample)


#: One fixture per bundled sample clip, named as the clip (``def test_x(box_ortho): ...``).
SAMPLE_NAMES = ("box_ortho", "box_perspective", "box_roll10", "box_spinup", "cylinder_horizontal",
                "cylinder_ortho", "sphere_ortho", "two_bodies")
for _name in SAMPLE_NAMES:
    globals()[_name] = _sample_fixture(_name)
