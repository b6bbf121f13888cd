"""The sense of turning where the view is not the paper's side view: as the picture shows it.

Seen from the side, points swing to and fro along lines, and the sense of turning is told by
which way the near side travels (:func:`rotrate_cli.stages.fits.rates_from_offsets`): right means
anticlockwise seen from the axis's top end. That rule assumes the side view. Seen from above or
face on (a record, a wheel), points go round the turning centre in the picture, and the sense is
the one they go round in: on the bicycle wheel the side rule's answer was whichever way the
picture happened to be turned (the same clip turned upside down, or by a quarter turn, read the
other way), while every track that went round its axle went round it anticlockwise.

Each kept track's turn about the fixation is summed from the angles between its successive
offsets from it; tracks that turn far enough vote, weighted by how far they turn. The sense so
told is as the camera sees it: for a camera above the turning plane (a turntable, a record seen
from above), the same as seen from the axis's top end.
"""

from __future__ import annotations

import math

import numpy as np

from rotrate_cli.runtime.lazy import pandas as pd
from rotrate_cli.scene import axis as axes
from rotrate_cli.scene.view import SIDE_DEG, View

#: A track votes when it turns at least this far about the fixation (rad), and the sense is told
#: when the tracks turning one way carry at least SENSE_MAJORITY of the turning of all that vote,
#: and at least SENSE_MIN_TRACKS vote. On the bicycle wheel (about its true axle) 26 tracks turn
#: 0.3 rad or more, all anticlockwise; on the record 2,116, all but one clockwise.
SENSE_TURN_RAD = 0.3
SENSE_MAJORITY = 0.8
SENSE_MIN_TRACKS = 5
#: The kept tracks are thinned (:func:`rotrate_cli.scene.view.keep_for_view`): a step between two of
#: their samples counts only while the body turns less than this between them (rad), so that no
#: step's angle can wrap round (seen from 23 degrees above, the picture's angle moves up to
#: 1/sin(23) times faster than the body's: 1.3 rad).
SENSE_STEP_RAD = 0.5
#: Where no path tells the view, steps spreading across their main direction at least this much
#: (``sin^2`` of 30 degrees, :func:`rotrate_cli.scene.axis.steps_spread`) show that it is not a side
#: view: 0.46 on the bicycle wheel, 0.002 on the side-view bench clip, 0.13-0.17 from 25-27
#: degrees above.
NOT_SIDE_SPREAD = 0.25


def turning_in_picture(tracks: pd.DataFrame, fixation_px: tuple[float, float], omega_rad_s: float) -> float:
    """+1 when the tracks go round ``fixation_px`` anticlockwise as the picture shows it, -1
    clockwise, NaN when they do not say (see the module's notes). ``tracks``: ``track, time_s,
    x_px, y_px`` sorted by track then time; ``omega_rad_s``: the rate measured (its sign does
    not matter)."""
    fx, fy = fixation_px
    omega = abs(omega_rad_s)
    if len(tracks) < 2 or not (math.isfinite(fx) and math.isfinite(fy) and math.isfinite(omega)):
        return math.nan
    track = tracks["track"].to_numpy()
    x = tracks["x_px"].to_numpy(dtype=np.float64) - fx
    y = tracks["y_px"].to_numpy(dtype=np.float64) - fy
    same = track[1:] == track[:-1]
    same &= omega * np.diff(tracks["time_s"].to_numpy(dtype=np.float64)) <= SENSE_STEP_RAD
    # with y down, a positive angle from one offset to the next is clockwise on the screen
    step = np.arctan2(x[:-1] * y[1:] - y[:-1] * x[1:], x[:-1] * x[1:] + y[:-1] * y[1:])
    owner = np.cumsum(np.r_[0, track[1:] != track[:-1]])
    turn = np.bincount(owner[:-1], weights=np.where(same, step, 0.0), minlength=int(owner[-1]) + 1)
    voting = turn[np.abs(turn) >= SENSE_TURN_RAD]
    if len(voting) < SENSE_MIN_TRACKS:
        return math.nan
    anticlockwise = float(-voting[voting < 0].sum() / np.abs(voting).sum())
    if anticlockwise >= SENSE_MAJORITY:
        return 1.0
    if anticlockwise <= 1.0 - SENSE_MAJORITY:
        return -1.0
    return math.nan


def not_side_view(view: View | None, tracks: pd.DataFrame) -> bool:
    """True when the view is not the paper's side view: the paths say so (an elevation of
    :data:`rotrate_cli.scene.view.SIDE_DEG` or more), or, where they tell no view, the steps spread
    across their main direction (:data:`NOT_SIDE_SPREAD`)."""
    if view is not None:
        return view.elevation_deg >= SIDE_DEG
    spread = axes.steps_spread(tracks) if len(tracks) > 1 else math.nan
    return math.isfinite(spread) and spread >= NOT_SIDE_SPREAD


def sense_of_turning(direction: str, view: View | None, tracks: pd.DataFrame, fixation_px: tuple[float, float],
                     omega_rad_s: float) -> tuple[str, bool]:
    """The sense of turning to report, and whether it is as the picture shows it. ``direction``:
    the tracks' fits' (the side view's rule, or the lens's); ``view``, ``tracks`` (kept for the
    view), ``fixation_px`` and ``omega_rad_s``: as reported. In a side view the fits' sense
    stands. Otherwise the picture's, where its tracks tell one; where they do not, the fits' sense
    stands when the paths tell a view from above (a turntable's near side still travels as seen
    from the side), and is unknown when no path tells the view at all (its rule's premise fails:
    on the face-on wheel it was a coin's toss)."""
    if not not_side_view(view, tracks):
        return direction, False
    sense = turning_in_picture(tracks, fixation_px, omega_rad_s)
    if math.isfinite(sense):
        return ("ccw" if sense > 0 else "cw"), True
    return (direction if view is not None else "unknown"), False
