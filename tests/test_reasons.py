"""Rejected tracks named by where they are (rotrate_cli.scene.reasons): reflections stand still on the
turning body, slides move on it at the wrong rate, other motion happens off it."""

from __future__ import annotations

import numpy as np
import pandas as pd

from rotrate_cli.scene.reasons import name_rejections, track_places


def _case() -> tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame]:
    """A body 200 px wide about x = 300 (accepted tracks 1-20 sweep it), and four rejected
    tracks: 21 still on the body 60 px off its axis for 2 s, 22 still near the axis, 23 moving
    on the body at the wrong rate, 24 moving far off it."""
    rows, offsets = [], []
    for k in range(1, 21):
        phase = 2 * np.pi * k / 20
        for frame in range(60):
            t = frame / 30.0
            x = 300 + 100 * np.cos(0.8 * t + phase)
            rows.append((k, t, x, 100 + 10 * ((7 * k) % 20)))  # heights not in step with phases
            offsets.append((k, frame, t, x - 300))
    for k, x, y in ((21, 360.0, 200.0), (22, 303.0, 200.0)):
        for frame in range(60):
            rows.append((k, frame / 30.0, x, y))
            offsets.append((k, frame, frame / 30.0, x - 300))
    for frame in range(60):
        t = frame / 30.0
        rows.append((23, t, 300 + 50 * np.cos(2.0 * t), 220.0))
        offsets.append((23, frame, t, 50 * np.cos(2.0 * t)))
        rows.append((24, t, 900 + 30 * t, 500.0))
        offsets.append((24, frame, t, 600 + 30 * t))
    tracks = pd.DataFrame(rows, columns=["track", "time_s", "x_px", "y_px"]).sort_values(["track", "time_s"])
    features = pd.DataFrame({
        "track": list(range(1, 25)),
        "inlier": [True] * 20 + [False] * 4,
        "reason": [""] * 20 + ["static", "static", "disagrees", "poor_fit"],
        "range": [200.0] * 20 + [0.02, 0.02, 100.0, 60.0],
    })
    offsets_table = pd.DataFrame(offsets, columns=["track", "frame", "time_s", "offset_px"])
    # track_places numbers tracks from 1 given tracks numbered from 0
    return features, track_places(tracks.assign(track=tracks["track"] - 1)), offsets_table


def test_rejections_are_named_by_place() -> None:
    features, places, offsets = _case()
    named = name_rejections(features, places, (300.0, 200.0), 0.0, 0.8, offsets)
    reason = dict(zip(named["track"], named["reason"], strict=True))
    assert reason[21] == "reflection"  # still, on the body, 60 px off its axis for 1.6 rad of turn
    assert reason[22] == "static"  # still, but on the axis: points there hardly move
    assert reason[23] == "slides"
    assert reason[24] == "other_motion"
    assert (named.loc[named["inlier"], "reason"] == "").all()


def test_a_still_point_that_the_body_does_not_cover_stays_static() -> None:
    # the body's accepted tracks all sit right of x = 330 in these frames: 21 is not on it then
    features, places, offsets = _case()
    offsets.loc[(offsets["track"] <= 20) & (offsets["offset_px"] < 70), "offset_px"] = 70.0
    named = name_rejections(features, places, (300.0, 200.0), 0.0, 0.8, offsets)
    assert named.loc[named["track"] == 21, "reason"].item() == "static"


def test_nothing_is_renamed_without_a_body() -> None:
    features, places, offsets = _case()
    features["inlier"] = False
    assert name_rejections(features, places, (300.0, 200.0), 0.0, 0.8, offsets)["reason"].equals(features["reason"])
