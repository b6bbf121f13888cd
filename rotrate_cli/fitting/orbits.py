"""Each track's own orbit in the picture, and the groups of tracks that go round one centre at one
rate: what tells that more than one body turns in a clip, whichever measurement gave the rate.

A point of a body turning at ``omega`` (seen without much perspective) moves on an ellipse: its
image x and y are each a sinusoid of that rate about the ellipse's centre, the image of the axis.
The exact recurrence of :func:`rotrate_cli.fitting.segment.track_motion` gives each coordinate's
rate and centre on its own; a track whose two rates agree has an orbit: a rate, a centre and a
radius. Tracks that share the rate and the centre are one body's (:func:`turning_groups`).

Seen from the side, a point's path is a line: along it, its position is still a sinusoid of the
rate about the axis's place, and across it tells nothing. Such tracks are grouped apart, by their
rate and the axis's place along their line alone (the paper's own scene: boxes, cylinders, a car on
its turntable, side by side). A group must still go round its axis: points on both sides of it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rotrate_cli.fitting.segment import RATE_TOLERANCE, track_motion
from rotrate_cli.runtime.lazy import pandas as pd

#: Tracks with fewer samples than this tell no orbit (and are not looked at: a long clip's many short ones).
MIN_SAMPLES = 12
#: A track's shorter coordinate range must be at least this share of its longer: an ellipse, not a line.
MIN_OPENING = 0.25
#: Tracks whose centres lie within this share of the picture's longer side, and whose rates lie
#: within :data:`RATE_TOLERANCE` (in log), go round one axis.
CENTRE_TOLERANCE = 0.04
#: The fewest tracks that make a group; the most groups sought; the most tracks compared (a subset beyond).
MIN_GROUP = 10
MOST_GROUPS = 6
MOST_TRACKS = 2000
#: A group's orbits must be at least this share of the picture's longer side (a patch that shakes
#: in place is no body turning), and go round its centre: the tracks' directions from it spread
#: (their mean unit vector shorter than this).
MIN_RADIUS = 0.03
MOST_LOPSIDED = 0.7
#: Along a side view's lines a track's recurrence is read from an arc of a sinusoid only, and one
#: body's tracks scatter in rate (on rendered boxes seen from the side, 0.45-0.74 rad/s for 0.5-0.6):
#: they fall into several groups, the smaller ones (12-23 tracks, a quarter of the largest or less)
#: centred 45-55 px off the axis. A side view's group stands for a body only where it holds at least
#: this share of the largest one's tracks (the sample of two bodies side by side: 226 and 82 of 500).
LINE_SHARE = 0.3
#: ...and at least this share of the lines compared: where a body's arcs scatter widely (a drum of
#: 16 checkers seen from the side, its tracks sliding from checker to checker) they fall into
#: fragments alone (29, 20 and 10 of 500 lines, at 1.07, 1.58 and 2.27 rad/s for 1.3; none at its
#: own rate), and the smallest was named another body; the two bodies side by side: 226 and 82.
LINES_COMPARED_SHARE = 0.1
#: The most side-view tracks compared (an even subset beyond): a side view's tracks are nearly all
#: lines, and the grouping is quadratic (1,600 of them took 40 ms of a 1-s analysis; 500, 7 ms).
MOST_LINES = 500


@dataclass(frozen=True)
class TurningGroup:
    """Tracks that go round one centre at one rate.

    Attributes:
        omega_rad_s: their median rate (a magnitude), rad/s.
        centre_px: the median centre of their orbits (x, y), picture pixels.
        radius_px: how far out they go round it (the 90th percentile of their orbits' radii).
        tracks: how many.
    """

    omega_rad_s: float
    centre_px: tuple[float, float]
    radius_px: float
    tracks: int
    #: ``"both"`` for orbits opened into ellipses; ``"x"`` or ``"y"`` for a side view's lines along
    #: that coordinate, whose centre is known along it only (the other coordinate: their middle)
    along: str = "both"


def turning_groups(tracks: pd.DataFrame, size_px: tuple[int, int]) -> tuple[TurningGroup, ...]:
    """The groups of ``tracks`` (``frame, time_s, track, x_px, y_px``, sorted by track then frame)
    that go round one centre at one rate, the largest first (see the module's notes). Only tracks
    long enough and far enough are fitted: those opened into ellipses (at most :data:`MOST_TRACKS`,
    evenly), and a side view's lines (at most :data:`MOST_LINES`); a long clip's table is not copied."""
    longest = float(max(size_px))
    track = tracks["track"].to_numpy()
    if len(track) < MIN_SAMPLES or bool(np.any(np.diff(track) < 0)):
        return ()
    starts = np.r_[0, np.flatnonzero(np.diff(track)) + 1]
    counts = np.diff(np.r_[starts, len(track)])
    x, y = tracks["x_px"].to_numpy(dtype=float), tracks["y_px"].to_numpy(dtype=float)
    range_x = np.maximum.reduceat(x, starts) - np.minimum.reduceat(x, starts)
    range_y = np.maximum.reduceat(y, starts) - np.minimum.reduceat(y, starts)
    longer, shorter = np.maximum(range_x, range_y), np.minimum(range_x, range_y)
    chosen = (counts >= MIN_SAMPLES) & (shorter >= MIN_OPENING * longer) & (longer >= MIN_RADIUS * longest)
    lines = (counts >= MIN_SAMPLES) & (shorter < MIN_OPENING * longer) & (longer >= MIN_RADIUS * longest)
    found = _ellipses(tracks, chosen, starts, counts, x, y, range_x, range_y, longest)
    side: list[TurningGroup] = []
    for along, values, ranges, across in (("x", x, range_x, y), ("y", y, range_y, x)):
        picked = _evenly_at_most(lines & (ranges >= range_x) & (ranges >= range_y), MOST_LINES)
        side += [group for group in _lines(tracks, picked, starts, counts, values, across, 0.5 * ranges, along, longest)
                 if group.tracks >= LINES_COMPARED_SHARE * picked.sum()]
    most = max((group.tracks for group in side), default=0)
    found += [group for group in side if group.tracks >= LINE_SHARE * most]
    return tuple(sorted(found, key=lambda group: -group.tracks))


def _evenly_at_most(chosen: np.ndarray, most: int) -> np.ndarray:
    """``chosen``, or an even subset of at most ``most`` of its tracks (the grouping is quadratic)."""
    if chosen.sum() <= most:
        return chosen
    picked = np.flatnonzero(chosen)
    subset = np.zeros_like(chosen)
    subset[picked[np.linspace(0, len(picked) - 1, most).astype(int)]] = True
    return subset


def _motion(tracks: pd.DataFrame, chosen: np.ndarray, counts: np.ndarray, values: np.ndarray) -> pd.DataFrame:
    """The recurrence's rate and centre of each chosen track along ``values``, indexed by track."""
    rows = np.repeat(chosen, counts)
    table = pd.DataFrame({"track": tracks["track"].to_numpy()[rows], "frame": tracks["frame"].to_numpy()[rows],
                          "time_s": tracks["time_s"].to_numpy()[rows]})
    return track_motion(table, values[rows]).set_index("track")


def _ellipses(tracks: pd.DataFrame, chosen: np.ndarray, starts: np.ndarray, counts: np.ndarray, x: np.ndarray,
              y: np.ndarray, range_x: np.ndarray, range_y: np.ndarray, longest: float) -> list[TurningGroup]:
    """The groups of tracks whose paths open into ellipses (both coordinates' rates agree)."""
    chosen = _evenly_at_most(chosen, MOST_TRACKS)
    if chosen.sum() < MIN_GROUP:
        return []
    along_x, along_y = _motion(tracks, chosen, counts, x), _motion(tracks, chosen, counts, y)
    both = along_x.merge(along_y, left_index=True, right_index=True, suffixes=("_x", "_y"))
    if both.empty:
        return []
    track = tracks["track"].to_numpy()
    place = np.searchsorted(track[starts], both.index.to_numpy())
    rate_x, rate_y = both["omega_rad_s_x"].to_numpy(), both["omega_rad_s_y"].to_numpy()
    agreeing = np.abs(np.log(rate_x / rate_y)) <= RATE_TOLERANCE
    if agreeing.sum() < MIN_GROUP:
        return []
    place = place[agreeing]
    rate = np.where(range_x[place] >= range_y[place], rate_x[agreeing], rate_y[agreeing])
    centre = np.column_stack([both["axis_px_x"].to_numpy()[agreeing], both["axis_px_y"].to_numpy()[agreeing]])
    start = np.column_stack([x[starts[place]], y[starts[place]]])
    # each orbit's radius: half its longer range (the ellipse's long semi-axis, or the chord seen)
    radius = 0.5 * np.maximum(range_x[place], range_y[place])
    return [group for group, _ in _grouped(rate, centre, start, radius, longest)]


def _lines(tracks: pd.DataFrame, chosen: np.ndarray, starts: np.ndarray, counts: np.ndarray, values: np.ndarray,
           across: np.ndarray, radius: np.ndarray, along: str, longest: float) -> list[TurningGroup]:
    """The groups of a side view's tracks (lines along ``along``): by rate and the centre along it."""
    if chosen.sum() < MIN_GROUP:
        return []
    motion = _motion(tracks, chosen, counts, values)
    rate = motion["omega_rad_s"].to_numpy()
    fitted = np.isfinite(rate) & (rate > 0) & np.isfinite(motion["axis_px"].to_numpy())
    if fitted.sum() < MIN_GROUP:
        return []
    place = np.searchsorted(tracks["track"].to_numpy()[starts], motion.index.to_numpy())[fitted]
    middle_across = (np.maximum.reduceat(across, starts) + np.minimum.reduceat(across, starts))[place] / 2.0
    centre = np.column_stack([motion["axis_px"].to_numpy()[fitted], np.zeros(len(place))])
    start = np.column_stack([values[starts[place]], np.zeros(len(place))])
    # across their lines, the group is placed at its members' middle (for the report)
    return [TurningGroup(group.omega_rad_s, ((group.centre_px[0], float(np.median(middle_across[members])))
                                             if along == "x" else (float(np.median(middle_across[members])),
                                                                   group.centre_px[0])),
                         group.radius_px, group.tracks, along)
            for group, members in _grouped(rate[fitted], centre, start, radius[place], longest)]


def _grouped(rate: np.ndarray, centre: np.ndarray, start: np.ndarray, radius: np.ndarray,
             longest: float) -> list[tuple[TurningGroup, np.ndarray]]:
    """Mode seeking in (log rate, centre): the track with the most neighbours seeds a group of
    them, and the search repeats on the rest. Each group with its members' indices."""
    scaled_rate = np.log(rate) / RATE_TOLERANCE
    scaled_centre = centre / (CENTRE_TOLERANCE * longest)
    left = np.ones(len(rate), dtype=bool)
    found: list[tuple[TurningGroup, np.ndarray]] = []
    while len(found) < MOST_GROUPS and left.sum() >= MIN_GROUP:
        pool = np.flatnonzero(left)
        near = ((np.abs(scaled_rate[pool, None] - scaled_rate[None, pool]) <= 1.0)
                & (np.abs(scaled_centre[pool, None, 0] - scaled_centre[None, pool, 0]) <= 1.0)
                & (np.abs(scaled_centre[pool, None, 1] - scaled_centre[None, pool, 1]) <= 1.0))
        counts = near.sum(axis=1)
        seed = int(np.argmax(counts))
        if counts[seed] < MIN_GROUP:
            break
        members = pool[near[seed]]
        left[members] = False
        middle = np.median(centre[members], axis=0)
        away = start[members] - middle
        lengths = np.hypot(away[:, 0], away[:, 1])
        directions = away[lengths > 0] / lengths[lengths > 0, None]
        lopsided = float(np.hypot(*directions.mean(axis=0))) if len(directions) else 1.0
        spread = float(np.percentile(radius[members], 90))
        if spread < MIN_RADIUS * longest or lopsided > MOST_LOPSIDED:
            continue  # a patch shaking in place, or tracks on one side of a centre they do not go round
        found.append((TurningGroup(float(np.median(rate[members])), (float(middle[0]), float(middle[1])), spread,
                                   len(members)), members))
    return found


#: Two rates this far apart (in log: twice the per-track tolerance) are told apart.
RATES_APART = 2.0 * RATE_TOLERANCE
#: The measured body's axis lies outside a group's orbits where it is farther from the group's
#: centre than this many times their radius.
OUTSIDE = 1.2


def another_body(groups: tuple[TurningGroup, ...], omega_rad_s: float,
                 fixation_px: tuple[float, float]) -> TurningGroup | None:
    """The largest group that is another body than the one measured (``omega_rad_s`` about
    ``fixation_px``): its rate told apart from the measured one, and the measured axis outside its
    orbits (a rigid body's points go round its own axis). Where the measured axis is not known
    (NaN), a group at the measured rate stands for it. None where no group is another body."""
    if not (math.isfinite(omega_rad_s) and omega_rad_s > 0):
        return None
    axis = np.asarray(fixation_px, dtype=float)
    if not np.all(np.isfinite(axis)):
        alike = [group for group in groups if abs(math.log(group.omega_rad_s / omega_rad_s)) <= RATE_TOLERANCE]
        if not alike:
            return None
        axis = np.asarray(alike[0].centre_px)
    for group in groups:
        apart = abs(math.log(group.omega_rad_s / omega_rad_s)) > RATES_APART
        if group.along == "both":
            away = math.dist(axis, group.centre_px)
        else:  # a side view's lines tell the axis's place along them alone
            coordinate = 0 if group.along == "x" else 1
            away = abs(float(axis[coordinate]) - group.centre_px[coordinate])
        outside = away > OUTSIDE * group.radius_px
        if apart and outside:
            return group
    return None
