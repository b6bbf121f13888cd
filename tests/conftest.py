"""Shared paths and helpers for the tests."""

from __future__ import annotations

import json
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


def need(path: Path, what: str) -> None:
    """Skip the test, saying why, when shared data is absent (a checkout outside the workplace)."""
    if not path.exists():
        pytest.skip(f"{what} not found at {path}: shared data is absent in this checkout")


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(12345)
