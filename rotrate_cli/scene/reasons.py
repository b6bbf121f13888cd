"""Why tracks on real footage were rejected, named by where they are.

The fits reject a track for what it does alone: too short, not moving (``static``), not a
sinusoid, or a rate that disagrees with the others. Where it lies says more: the body is where
the accepted tracks are (the convex hull of their mean positions). So:

* ``reflection``: still, yet on the body and well off its axis, where every point of the surface
  moves: a highlight, or the mirror image of the room in glossy paint, standing still while the
  surface turns under it (the record's glints; a car's windows);
* ``slides``: on the body and moving, at a rate the body does not have: a point slipping along a
  texture that looks the same after a turn (grooves, a rim, spokes, a fence of similar bars);
* ``other_motion``: moving off the body (people walking behind, a hand, a tonearm).

The rest keep the fits' names. With fewer than three accepted tracks there is no body to place
them on, and nothing is renamed.
"""

from __future__ import annotations

import math

import numpy as np

from rotrate_cli.runtime.lazy import pandas as pd
from rotrate_cli.scene.axis import unit_offset

#: A reflection moves this many times less than the least a point of the body there would.
STILLER = 4.0
#: The body's outline is grown by this fraction of its size before a track is placed in it.
MARGIN = 0.05
#: A still track is a reflection only this far across the axis, as a fraction of the body's
#: half-width across it: points near the axis hardly move, and are rightly still.
OFF_AXIS = 0.25


def track_places(tracks: pd.DataFrame) -> pd.DataFrame:
    """Each track's mean position and how long it lasted, ``track, x_px, y_px, span_s`` (tracks
    numbered as the features: from 1), from a tracks table ``track, time_s, x_px, y_px`` sorted
    by track (numbered from 0) then time."""
    track = tracks["track"].to_numpy()
    if len(track) == 0:
        return pd.DataFrame({"track": pd.Series(dtype=int), "x_px": pd.Series(dtype=float),
                             "y_px": pd.Series(dtype=float), "span_s": pd.Series(dtype=float)})
    starts = np.flatnonzero(np.r_[True, track[1:] != track[:-1]])
    counts = np.diff(np.r_[starts, len(track)])
    x = np.add.reduceat(tracks["x_px"].to_numpy(dtype=np.float64), starts) / counts
    y = np.add.reduceat(tracks["y_px"].to_numpy(dtype=np.float64), starts) / counts
    time_s = tracks["time_s"].to_numpy(dtype=np.float64)
    return pd.DataFrame({"track": track[starts] + 1, "x_px": x, "y_px": y,
                         "span_s": time_s[starts + counts - 1] - time_s[starts]})


def _covered(offsets: pd.DataFrame, features: pd.DataFrame, candidates: np.ndarray, margin_px: float) -> np.ndarray:
    """For each candidate track (a boolean per feature row), whether accepted tracks lay on both
    sides of it across the axis, by ``margin_px``, in most of its frames: the body was there
    then. (The hull of the accepted tracks over the whole clip is not enough: a box's outline
    narrows as it turns, and the background shows inside its widest extent.)"""
    covered = np.zeros(len(features), bool)
    if not candidates.any():
        return covered
    accepted = set(features.loc[features["inlier"].to_numpy(dtype=bool), "track"].to_numpy().tolist())
    track = offsets["track"].to_numpy()
    frame = offsets["frame"].to_numpy()
    offset = offsets["offset_px"].to_numpy(dtype=np.float64)
    inlier = np.isin(track, list(accepted))
    frames = int(frame.max()) + 1 if len(frame) else 0
    low = np.full(frames, np.inf)
    high = np.full(frames, -np.inf)
    np.minimum.at(low, frame[inlier], offset[inlier])
    np.maximum.at(high, frame[inlier], offset[inlier])
    wanted = features.loc[candidates, "track"].to_numpy()
    rows = np.isin(track, wanted)
    for number, group in pd.DataFrame({"track": track[rows], "frame": frame[rows], "offset": offset[rows]}).groupby(
            "track", sort=False):
        f, d = group["frame"].to_numpy(), group["offset"].to_numpy()
        inside = (low[f] < d - margin_px) & (high[f] > d + margin_px)
        covered[np.flatnonzero(features["track"].to_numpy() == number)] = inside.mean() >= 0.8
    return covered


def name_rejections(features: pd.DataFrame, places: pd.DataFrame, fixation_px: tuple[float, float],
                    angle_deg: float, omega_rad_s: float, offsets: pd.DataFrame | None = None) -> pd.DataFrame:
    """``features`` with ``static`` tracks on the body renamed ``reflection``, ``disagrees``
    tracks on it ``slides`` and moving rejected tracks off it ``other_motion`` (see the module's
    notes); unchanged where fewer than three tracks were accepted or positions are unknown.

    A still track is a reflection only where a point of the body there would have moved, over
    the track's life at the body's rate ``omega_rad_s``, :data:`STILLER` times more than it did:
    at least ``d (1 - cos(w T))`` across the axis for a point ``d`` from it (its least motion,
    starting at the turn of its path). Short tracks at the turn of their path, on a matte body,
    are still for a moment and rightly ``static``."""
    import cv2  # for the hull: imported here, as the module is also used without video

    if features.empty or places.empty:
        return features
    where = features[["track"]].merge(places, on="track", how="left")
    x, y = where["x_px"].to_numpy(dtype=np.float64), where["y_px"].to_numpy(dtype=np.float64)
    inlier = features["inlier"].to_numpy(dtype=bool) & np.isfinite(x) & np.isfinite(y)
    if inlier.sum() < 3:
        return features
    hull = cv2.convexHull(np.column_stack([x[inlier], y[inlier]]).astype(np.float32))
    size = math.dist(hull.min(axis=(0, 1)), hull.max(axis=(0, 1)))
    if not size > 0:
        return features
    reason = features["reason"].to_numpy(dtype=object).copy()
    moving = np.isin(reason, ("disagrees", "poor_fit", "no_fit"))
    # how far inside the hull: asked only of the tracks renamed here (the record clip's 45,000
    # short tracks need no answer)
    asked = (moving | (reason == "static")) & np.isfinite(x) & np.isfinite(y)
    depth = np.full(len(x), -math.inf)
    depth[asked] = [cv2.pointPolygonTest(hull, (float(px), float(py)), True) for px, py in zip(x[asked], y[asked],
                                                                                             strict=True)]
    inside = depth >= -MARGIN * size
    # well inside: a still point on the outline is the outline's edge against the background,
    # which stands where the body's widest part passes (a rendered matte box: 120 such tracks)
    within = depth >= MARGIN * size
    ux, uy = unit_offset(angle_deg)
    across = (x - fixation_px[0]) * ux + (y - fixation_px[1]) * uy
    half_width = float(np.max(np.abs(across[inlier])))
    turn = np.minimum(abs(omega_rad_s) * where["span_s"].to_numpy(dtype=np.float64), math.pi)
    least_motion = np.abs(across) * (1.0 - np.cos(np.nan_to_num(turn)))
    still = features["range"].to_numpy(dtype=np.float64) * STILLER < least_motion
    off_axis = np.abs(across) > OFF_AXIS * half_width
    candidates = (reason == "static") & within & off_axis & still
    if offsets is not None:
        candidates &= _covered(offsets, features, candidates, MARGIN * half_width)
    reason[candidates] = "reflection"
    reason[(reason == "disagrees") & inside] = "slides"
    reason[moving & ~inside] = "other_motion"
    return features.assign(reason=reason)


#: A used track whose rate lies further than this (a fraction) from a rate measured otherwise is
#: not counted as used.
AGREE_WITHIN = 0.05


def against_rate(features: pd.DataFrame, omega_rad_s: float) -> pd.DataFrame:
    """The features measured against a rate that did not come from them (the picture's return):
    used tracks that read more than :data:`AGREE_WITHIN` slower are marked ``slides`` (points that
    slip along grooves and rims read slow), faster ``disagrees``; none of them is shown as used."""
    if not (math.isfinite(omega_rad_s) and omega_rad_s > 0) or features.empty:
        return features
    rate = np.abs(features["omega_rad_s"].to_numpy(dtype=float))
    used = features["inlier"].to_numpy(dtype=bool)
    out = used & ~(np.abs(rate / omega_rad_s - 1.0) <= AGREE_WITHIN)
    if not out.any():
        return features
    reason = features["reason"].to_numpy(dtype=object).copy()
    reason[out] = np.where(rate[out] < omega_rad_s, "slides", "disagrees")
    inlier = used & ~out
    return features.assign(inlier=inlier, reason=reason)


def on_plane(features: pd.DataFrame, tracks: tuple[int, ...], omega_rad_s: float) -> pd.DataFrame:
    """The features measured against the rate of the tracks ``tracks`` (numbered as the tracks
    table, from 0) read as one plane turning (:mod:`rotrate_cli.scene.plane_turn`): those are the
    ones used, whatever their one-point fits read (the paper's model, which a plane seen through
    a lens is not); the others are measured against the rate as against a return
    (:func:`against_rate`)."""
    if features.empty or not tracks:
        return against_rate(features, omega_rad_s)
    plane = np.isin(features["track"].to_numpy(dtype=int) - 1, np.asarray(tracks, dtype=int))
    others = against_rate(features.assign(inlier=features["inlier"].to_numpy(dtype=bool) & ~plane), omega_rad_s)
    reason = others["reason"].to_numpy(dtype=object).copy()
    reason[plane] = ""
    return others.assign(inlier=others["inlier"].to_numpy(dtype=bool) | plane, reason=reason)
