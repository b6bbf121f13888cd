"""A hand-held camera's shake or roll, taken out of the tracks (:func:`find_shake`).

A camera held in the hand moves the whole picture by a few pixels from frame to frame. Every
tracked point carries that motion on top of its own, and a fit of a turn to an offset that
jumps by 2 px in a 6-second clip fails outright (a rendered box at 0.5 rad/s, its picture
shaken by 2 px and 0.2 degrees: 0.01 rad/s, weak, its interval missing the truth).

The still background shows the shake alone. Its points are the long tracks that move together:
the camera's path is the median step of those tracks frame by frame, summed, and a track is
background where, less that path, it stands still. The two are found in turn, from all long
tracks. On a tripod the tracker has already let go of still points (they say nothing about the
turn), so no background is left and nothing changes; where the tracks that move together do not
stand still once the path is taken out (the body's own points, a close-up with no background),
nothing changes either. Where the still half of the long tracks is the body's (a textured disc
that fills most of the picture holds most of them), the two are found again from the tracks that
move least: a camera that rolls moves its background less than the body turns.

A camera that rolls or pans smoothly (on a tripod head, or slowly in the hand) does not jolt, and
a smooth path is also what a body's own points give where they turn together as one picture (the
top of a cylinder seen from above). It is the camera's where the still points lie all over the
picture (:data:`BROAD`), not in one patch, and other points still move once it is taken out:
the body turning in front of the background. The shared wheel rolled 3 degrees a second: 30
still points across the whole picture, turned 39.6 degrees over the clip's 41.6.

A camera held in the hand also comes nearer and goes back: its picture zooms as well as turning
and shifting, and no turn and shift leaves the background within a pixel (a clock filmed in the
hand, rolling 2 degrees a second and coming 4% nearer and back: 15 of 252 long tracks still,
the rate from the tracks 7 times the truth, weak). Where a turn and shift find no background, or
a turn, zoom and shift leaves at least :data:`ZOOM_GAIN` times as many long tracks still, the
camera's path is that (124 still, the rate from the clock's hand within 1%), where its zoom
moves the still points by several pixels (:func:`_zoom_tells`): a zoom fitted where the camera
did not zoom gathers the body's points that move least. Its views are
fitted frame by frame to the still tracks' places in the first frame's picture, not composed
from frame to frame, whose errors add up; a zoom beyond :data:`MAX_ZOOM` is no hand's.
A camera that also leans by a few degrees keystones the picture: that is not taken out.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from rotrate_cli.runtime.lazy import pandas as pd

#: A background track lasts at least this fraction of the clip's frames (and
#: :data:`MIN_FRAMES`): short tracks cannot tell a still point from a slow one.
LONG_FRACTION = 0.5
MIN_FRAMES = 10
#: At least this many background tracks, or nothing is taken out.
MIN_BACKGROUND = 12
#: Less the camera's path, a background track stays within this many tracking pixels rms of its
#: mean position.
STILL_PX = 1.0
#: A camera path whose rms about its mean is under this many tracking pixels is no shake.
SHAKE_PX = 0.3
#: ... nor one whose frame-to-frame change of step (rms, tracking pixels) is under this: a hand's
#: shake jolts, while points of a turning body move smoothly together.
JOLT_PX = 0.15
#: ... and the jolts must stand this many times above the path's own noise, and be this share of
#: the path's rms at least. Points of a turning body that move together (the top of a cylinder
#: seen from 60 degrees above turns as one picture) give a smooth path, 10-19 px rms, whose
#: jolts are its noise (0.16 px, 0.01 of its rms): on two such renders the shake "found" took
#: the body's turn out. A hand's: a rendered 2-7 px shake, 0.9 of its rms.
JOLT_NOISE = 3.0
JOLT_SHARE = 0.05
#: The rms of a two-dimensional normal error over the median of its sizes: sqrt(2) / sqrt(2 ln 2).
RMS_PER_MEDIAN = 1.0 / math.sqrt(math.log(2.0))
#: A smooth path is the camera's where the still points' mean positions span at least this share
#: of the picture's width and of its height ...
BROAD = 0.5
#: ... and at least this many other tracks (of :data:`MIN_FRAMES` or more) move by more than
#: :data:`MOVING_PX` (rms about their mean, tracking pixels) once it is taken out (the rolled
#: wheel: 9, its thin spokes hold few long tracks).
MIN_MOVING = 5
MOVING_PX = 5.0
#: ... or its shifts lie this far (rms, tracking pixels) from a turn about one point: a body turning
#: as one picture turns about its axis, a hand's wobble shifts the picture as it turns (a clock
#: filmed rolling 3 degrees a second with a 12-px wobble: 11.5 px; a body filling the picture,
#: turning unevenly about its axis: 0.06).
OFF_ONE_POINT_PX = 2.0
#: ... or, its still points spanning this share of :data:`BROAD` (a strip of a bare wall), this
#: far: a body's points in one patch, turning in perspective, keep within a few pixels of a turn
#: about one point (a box's top seen from 30 degrees above: 3.5 px), a hand's wobble and zoom do
#: not (clocks filmed in the hand: 11-34 px, their still points spanning 21-41% of the width); a
#: body's face that nears a wide lens as it turns zooms far from one point too, but its still
#: points lie along one edge (2% of the width).
OFF_ONE_POINT_ALONE_PX = 8.0
ALONE_SPAN = 0.2
#: A camera that turned less than this over the clip (degrees), and shook less than
#: :data:`SHAKE_PX`, is still.
ROLL_DEG = 0.3
#: Rounds of (path, background) found in turn.
ROUNDS = 4
#: A turn, zoom and shift is taken for the camera's path where it leaves this many times as many
#: long tracks still as a turn and shift does (see the module's notes)...
ZOOM_GAIN = 1.5
#: ... and it zooms them by this many times the still tracks' bound (:data:`STILL_PX`) at their reach ...
ZOOM_MOVES = 4.0
#: ... each frame's fitted to at least this many still tracks (else that frame keeps the first
#: guess's) ...
VIEW_MIN_POINTS = 8
#: ... and its zoom within this factor either way.
MAX_ZOOM = 1.3
#: Where the still half after the median step holds no background, the rounds start again from
#: this many tracks that move least.
LEAST_MOVING = MIN_BACKGROUND


@dataclass(frozen=True)
class Shake:
    """The camera's own motion as the still background showed it.

    Attributes:
        rms_px: the camera path's rms about its mean, full-resolution pixels.
        largest_px: its largest distance from its mean.
        jolt_px: its typical change of step from one frame to the next, as an rms (the median
            of their sizes, scaled; see :func:`_typical_jolt`).
        background_tracks: tracks that showed it.
        turned_deg: how far the camera turned (rolled) over the clip, degrees (signed:
            anticlockwise as the picture shows it).
        turn_deg_s: its rate of turning, a line fitted to its angle over time, degrees a second
            (NaN where the tracks carry no times).
        smooth: the path does not jolt: a camera that rolls or pans (see the module's notes).
    """

    rms_px: float
    largest_px: float
    jolt_px: float
    background_tracks: int
    turned_deg: float = 0.0
    turn_deg_s: float = math.nan
    smooth: bool = False


def find_shake(tracks: pd.DataFrame, frames: int, pixel_px: float = 1.0,
               size_px: tuple[int, int] | None = None) -> tuple[CameraPath, Shake] | None:
    """The camera's motion and its size, from ``tracks`` (``frame, track, x_px, y_px``, sorted by
    track then frame) over ``frames`` frames; None where no shake shows (see the module's notes).
    ``pixel_px``: a tracking-image pixel in the tracks' pixels; ``size_px``: the picture's width
    and height, without which a smooth path (a roll, a pan) is not taken for the camera's."""
    if tracks.empty:
        return None
    track = tracks["track"].to_numpy()
    frame = tracks["frame"].to_numpy()
    long_ids = _long_ids(track, frames)
    if len(long_ids) < MIN_BACKGROUND:
        return None
    rows = np.isin(track, long_ids)
    sub_track, sub_frame = track[rows], frame[rows]
    x = tracks["x_px"].to_numpy(dtype=np.float64)[rows]
    y = tracks["y_px"].to_numpy(dtype=np.float64)[rows]
    first, last = int(frame.min()), int(frame.max())
    # steps within a track between consecutive frames, by the frame they end on
    same = (sub_track[1:] == sub_track[:-1]) & (sub_frame[1:] == sub_frame[:-1] + 1)
    steps = _Steps(sub_frame[1:][same] - first, x[:-1][same], y[:-1][same], x[1:][same], y[1:][same],
                   last - first + 1, first)
    step_index = np.searchsorted(long_ids, sub_track[1:][same])
    # first the median step of all long tracks (the background is most of them where there is
    # one), then in turn the picture's turn and shift from the still ones and the still ones
    path = steps.median_shift()
    spread = _spread(sub_track, *path.undo(sub_frame, x, y))
    still_px = STILL_PX * pixel_px

    def settled(background: np.ndarray) -> tuple[CameraPath, np.ndarray, np.ndarray] | None:
        """The camera's path and the still tracks found in turn from a first guess of them."""
        return _in_turn(lambda still: steps.rigid(still[step_index]), background, sub_track, sub_frame, x, y,
                        still_px, ROUNDS)

    # the still half after the median step (the background is most of the long tracks where there
    # is one); else the tracks that move least as they are: a body that fills most of the picture
    # holds most of the long tracks, and a camera that rolls moves its background less than the
    # body turns (a textured disc turning 86 degrees a second, the camera rolling 2: 21 of 294
    # long tracks on the background; from the median the rounds found no still point, and the
    # roll was added to the rate, +2.3% and good)
    found = settled(spread <= float(np.median(spread)))
    if found is None:
        moved = _spread(sub_track, x, y)
        found = settled(moved <= np.sort(moved)[min(len(moved), LEAST_MOVING) - 1])
    seed = found[0] if found is not None else path
    viewed = _zoomed(sub_track, sub_frame, x, y, steps, step_index, seed, still_px, size_px)
    if viewed is not None:
        _, inverse, counts = np.unique(sub_track, return_inverse=True, return_counts=True)
        held_x, held_y = viewed[0].undo(sub_frame, x, y)
        places = np.bincount(inverse, held_x) / counts, np.bincount(inverse, held_y) / counts
        if _zoom_tells(found, viewed, places, still_px):
            found = viewed
    if found is None:
        return None
    path, spread, background = found
    present = np.zeros(last - first + 1, bool)
    present[np.unique(frame) - first] = True
    centre = np.array([float(np.mean(x)), float(np.mean(y))])
    shifted = path.moved(centre)[present]  # where the camera's motion took the picture's middle
    shifted -= shifted.mean(axis=0)
    distance = np.hypot(shifted[:, 0], shifted[:, 1])
    rms = float(np.sqrt(np.mean(distance ** 2)))
    # a hand's shake jolts from frame to frame; a patch of the body moves smoothly with its turn
    jolt = _typical_jolt(shifted)
    # the path's own noise, from the background's scatter about it, jolts too (sqrt 6 for a second
    # difference of independent errors)
    noise = math.sqrt(6.0) * float(np.median(spread[background])) / math.sqrt(background.sum())
    angles = -np.degrees(path.angle_rad[present])  # anticlockwise as shown (the path's turns are y down)
    if rms < SHAKE_PX * pixel_px and float(np.ptp(angles)) < ROLL_DEG:
        return None
    smooth = jolt < max(JOLT_PX * pixel_px, JOLT_NOISE * noise, JOLT_SHARE * rms)
    if smooth and not _camera_s(tracks, path, long_ids[background], size_px, pixel_px):
        return None
    rate = math.nan
    if "time_s" in tracks:
        times = tracks.groupby("frame")["time_s"].first().reindex(np.arange(first, last + 1)).to_numpy()[present]
        if len(times) >= 2 and np.ptp(times) > 0:
            rate = float(np.polyfit(np.asarray(times, np.float64), angles, 1)[0])
    return path, Shake(rms, float(distance.max()), jolt, int(background.sum()), float(angles[-1] - angles[0]),
                       rate, smooth)


def _zoomed(track: np.ndarray, frame: np.ndarray, x: np.ndarray, y: np.ndarray, steps: _Steps,
            step_index: np.ndarray, seed: CameraPath, still_px: float,
            size_px: tuple[int, int] | None) -> tuple[CameraPath, np.ndarray, np.ndarray] | None:
    """The camera's path as a turn, zoom and shift and the long tracks it leaves still, found in
    turn from the still half under ``seed`` (a turn and shift); None where fewer than
    :data:`MIN_BACKGROUND` stay still or it zooms beyond :data:`MAX_ZOOM`.
    ``track, frame, x, y``: the long tracks' positions, sorted by track then frame; ``steps``
    their steps from frame to frame, of the tracks ``step_index`` (in order of their numbers).

    The first path is the views of their steps composed frame by frame (right at the start,
    adding up errors as it goes), then each frame's view is fitted anew to the still tracks'
    places in the first frame's picture (:func:`_fitted_views`)."""
    if size_px is None:
        return None  # as for a smooth path: without the picture's size, nothing is taken for the camera's
    spread = _spread(track, *seed.undo(frame, x, y))
    background = spread <= float(np.median(spread))
    ids = np.unique(track)
    last = [steps.composed_views(background[step_index])]  # the views fitted last, each round's start

    def fitted(still: np.ndarray) -> CameraPath:
        last[0] = _fitted_views(track, frame, x, y, np.isin(track, ids[still]), seed.first_frame, last[0])
        return CameraPath.from_warps(seed.first_frame, last[0])

    # these rounds gather the still tracks more slowly than a turn's
    found = _in_turn(fitted, background, track, frame, x, y, still_px, ROUNDS + 2)
    if found is None:
        return None
    zoom = np.sqrt(np.abs(np.linalg.det(last[0][:, :2, :2])))
    return None if zoom.max() > MAX_ZOOM or zoom.min() < 1.0 / MAX_ZOOM else found


def _in_turn(fit: Callable[[np.ndarray], CameraPath], background: np.ndarray, track: np.ndarray, frame: np.ndarray,
             x: np.ndarray, y: np.ndarray, still_px: float,
             rounds: int) -> tuple[CameraPath, np.ndarray, np.ndarray] | None:
    """The camera's path (``fit`` from the still tracks, a boolean per long track) and the still
    tracks (within ``still_px`` rms once it is taken out) found in turn from a first guess of
    them, ``rounds`` at most: the path, each long track's spread and the still ones; None where
    fewer than :data:`MIN_BACKGROUND` stay still."""
    for _ in range(rounds):
        path = fit(background)
        spread = _spread(track, *path.undo(frame, x, y))
        updated = spread <= still_px
        if updated.sum() < MIN_BACKGROUND:
            return None
        if (updated == background).all():
            break
        background = updated
    return path, spread, background


def _zoom_tells(still: tuple[CameraPath, np.ndarray, np.ndarray] | None,
                zoomed: tuple[CameraPath, np.ndarray, np.ndarray], places: tuple[np.ndarray, np.ndarray],
                still_px: float) -> bool:
    """True where the zoom is the camera's (see the module's notes): it moves the still
    background's far points by :data:`ZOOM_MOVES` times ``still_px`` or more over the clip (its
    range times their rms distance from their middle; ``places``: each long track's mean place),
    and, where a turn and shift found a background too (``still``: path, spreads, still tracks),
    it leaves :data:`ZOOM_GAIN` times as many long tracks still. A zoom fitted to a camera that
    did not zoom gathers a few of the body's points that move least (a rendered cylinder, its
    picture shaken 5 px: 53 still against 27, the zoom 1%, 2 px at their reach; the rate, from the
    tracks, +3.6% -> +12%); a camera coming 4% nearer and back moves them 16 px."""
    path, _, background = zoomed
    if still is not None and background.sum() < ZOOM_GAIN * still[2].sum():
        return False
    warp = path.warps()
    zoom = np.sqrt(np.abs(np.linalg.det(warp[:, :2, :2])))
    x, y = places[0][background], places[1][background]
    reach = math.sqrt(float(np.mean((x - x.mean()) ** 2 + (y - y.mean()) ** 2)))
    return float(np.ptp(zoom)) * reach >= ZOOM_MOVES * still_px


def _fitted_views(track: np.ndarray, frame: np.ndarray, x: np.ndarray, y: np.ndarray, chosen: np.ndarray,
                  first_frame: int, warp: np.ndarray) -> np.ndarray:
    """Each frame's view (``warp``, frames x 3 x 3, from the first frame's picture) fitted anew by
    least squares to the ``chosen`` rows: from each chosen track's mean place under ``warp``, in
    the first frame's picture, to where it is seen. Frames with fewer than
    :data:`VIEW_MIN_POINTS` chosen tracks keep theirs."""
    at = np.clip(frame[chosen] - first_frame, 0, len(warp) - 1)
    seen_x, seen_y = x[chosen], y[chosen]
    held_x, held_y = _apply(np.linalg.inv(warp)[at], seen_x, seen_y)
    _, inverse, counts = np.unique(track[chosen], return_inverse=True, return_counts=True)
    mean_x, mean_y = np.bincount(inverse, held_x) / counts, np.bincount(inverse, held_y) / counts
    views = _least_squares_views(at, mean_x[inverse], mean_y[inverse], seen_x, seen_y, len(warp))
    fitted = np.where((np.bincount(at, minlength=len(warp)) >= VIEW_MIN_POINTS)[:, None, None], views, warp)
    # the first frame's picture is where the path starts: its own view is none
    fitted = fitted @ np.linalg.inv(fitted[0])
    return fitted / fitted[:, 2:3, 2:3]


def _least_squares_views(frame: np.ndarray, from_x: np.ndarray, from_y: np.ndarray, to_x: np.ndarray,
                         to_y: np.ndarray, frames: int) -> np.ndarray:
    """Each frame's view (3x3: a turn, a zoom and a shift) that best carries ``from`` onto ``to``
    at the rows of that ``frame`` (least squares, all frames at once; none where a frame has
    fewer than two rows)."""
    count = np.bincount(frame, minlength=frames).astype(np.float64)
    weight = np.maximum(count, 1.0)

    def mean(values: np.ndarray) -> np.ndarray:
        return np.bincount(frame, values, frames) / weight

    ax, ay, bx, by = mean(from_x), mean(from_y), mean(to_x), mean(to_y)
    u0, v0, u1, v1 = from_x - ax[frame], from_y - ay[frame], to_x - bx[frame], to_y - by[frame]
    size = np.bincount(frame, u0 * u0 + v0 * v0, frames)
    usable = (count >= 2) & (size > 0)
    size = np.where(usable, size, 1.0)
    along = np.where(usable, np.bincount(frame, u0 * u1 + v0 * v1, frames) / size, 1.0)
    across = np.where(usable, np.bincount(frame, u0 * v1 - v0 * u1, frames) / size, 0.0)
    views = np.zeros((frames, 3, 3))
    views[:, 0, 0], views[:, 0, 1], views[:, 1, 0], views[:, 1, 1] = along, -across, across, along
    views[:, 0, 2] = np.where(usable, bx - (along * ax - across * ay), 0.0)
    views[:, 1, 2] = np.where(usable, by - (across * ax + along * ay), 0.0)
    views[:, 2, 2] = 1.0
    return views


def _apply(warp: np.ndarray, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Points ``x, y`` carried by views ``warp`` (one 3x3 per point, or one for all)."""
    depth = warp[..., 2, 0] * x + warp[..., 2, 1] * y + warp[..., 2, 2]
    return ((warp[..., 0, 0] * x + warp[..., 0, 1] * y + warp[..., 0, 2]) / depth,
            (warp[..., 1, 0] * x + warp[..., 1, 1] * y + warp[..., 1, 2]) / depth)


def still_background(tracks: pd.DataFrame, frames: int, pixel_px: float = 1.0) -> bool:
    """True where at least :data:`MIN_BACKGROUND` long tracks stay still (within :data:`STILL_PX`
    rms of their mean): a background that vouches for a still camera. Where none is seen, a camera
    that turns or moves cannot be told from the body (``tracks`` as for :func:`find_shake`)."""
    if tracks.empty:
        return False
    track = tracks["track"].to_numpy()
    long_ids = _long_ids(track, frames)
    if len(long_ids) < MIN_BACKGROUND:
        return False
    rows = np.isin(track, long_ids)
    spread = _spread(track[rows], tracks["x_px"].to_numpy(dtype=np.float64)[rows],
                     tracks["y_px"].to_numpy(dtype=np.float64)[rows])
    return int((spread <= STILL_PX * pixel_px).sum()) >= MIN_BACKGROUND


def _long_ids(track: np.ndarray, frames: int) -> np.ndarray:
    """The tracks long enough to tell a still point from a slow one (see :data:`LONG_FRACTION`)."""
    return np.flatnonzero(np.bincount(track) >= max(MIN_FRAMES, LONG_FRACTION * frames))


def _camera_s(tracks: pd.DataFrame, path: CameraPath, still_ids: np.ndarray, size_px: tuple[int, int] | None,
              pixel_px: float) -> bool:
    """True where a smooth ``path`` is the camera's (see the module's notes): the still tracks
    ``still_ids`` lie all over the picture, and other tracks still move once it is taken out or
    the path does not turn the picture about one point; or, the still tracks spanning part of the
    picture, the path is far from a turn about one point (:data:`OFF_ONE_POINT_ALONE_PX`)."""
    if size_px is None:
        return False
    # a body's turn, its points one picture, turns it about one point (the top of a cylinder); a
    # camera held in the hand shifts and zooms it as it turns (a clock filmed so, its stepping
    # hand's tracks still between steps: four moved)
    off_px = _off_one_point(path)
    track = tracks["track"].to_numpy()
    x, y = path.undo(tracks["frame"].to_numpy(), tracks["x_px"].to_numpy(dtype=np.float64),
                     tracks["y_px"].to_numpy(dtype=np.float64))
    ids, inverse, counts = np.unique(track, return_inverse=True, return_counts=True)
    mean_x, mean_y = np.bincount(inverse, x) / counts, np.bincount(inverse, y) / counts
    still = np.isin(ids, still_ids)
    width, height = size_px
    span = min(np.ptp(mean_x[still]) / width, np.ptp(mean_y[still]) / height)
    if span >= ALONE_SPAN * BROAD and off_px > OFF_ONE_POINT_ALONE_PX * pixel_px:
        return True
    if span < BROAD:
        return False
    spread = _spread(track, x, y)
    moving = (~still) & (counts >= MIN_FRAMES) & (spread > MOVING_PX * pixel_px)
    return int(moving.sum()) >= MIN_MOVING or off_px > OFF_ONE_POINT_PX * pixel_px


def _off_one_point(path: CameraPath) -> float:
    """How far (rms, px) the path's shifts lie from those of a turn (and zoom) about one fixed
    point (``shift_k = (I - A_k) c``, ``A_k`` the turn, ``c`` fitted)."""
    warp = path.warps()
    design = (np.eye(2) - warp[:, :2, :2] / warp[:, 2:3, 2:3]).reshape(-1, 2)
    shifts = (warp[:, :2, 2] / warp[:, 2:3, 2]).reshape(-1)
    point = np.linalg.lstsq(design, shifts, rcond=None)[0]
    misfit = (shifts - design @ point).reshape(-1, 2)
    return float(np.sqrt(np.mean(np.sum(misfit ** 2, axis=1))))


@dataclass(frozen=True)
class CameraPath:
    """The camera's motion: at each frame from ``first_frame`` on, the turn and shift that carry
    the first frame's picture onto it (``p_k = R(angle_k) p_0 + shift_k``, the tracks' pixels)."""

    first_frame: int
    angle_rad: np.ndarray
    shift_px: np.ndarray  # frames x 2
    #: where the camera also zoomed (came nearer and went back): each frame's view, a turn, zoom
    #: and shift from the first frame's picture (frames x 3 x 3), of which ``angle_rad`` and
    #: ``shift_px`` are the turn and the shift of the picture's origin
    warp: np.ndarray | None = None

    @classmethod
    def from_warps(cls, first_frame: int, warp: np.ndarray) -> CameraPath:
        """The path of views ``warp`` (frames x 3 x 3, affine, from the first frame's picture)."""
        angle = np.arctan2(warp[:, 1, 0] - warp[:, 0, 1], warp[:, 0, 0] + warp[:, 1, 1])
        shift = warp[:, :2, 2] / warp[:, 2, 2, None]
        return cls(first_frame, angle, shift, warp)

    def warps(self) -> np.ndarray:
        """Each frame's view from the first frame's picture (frames x 3 x 3)."""
        if self.warp is not None:
            return self.warp
        cos, sin = np.cos(self.angle_rad), np.sin(self.angle_rad)
        warp = np.zeros((len(cos), 3, 3))
        warp[:, 0, 0], warp[:, 0, 1], warp[:, 1, 0], warp[:, 1, 1] = cos, -sin, sin, cos
        warp[:, :2, 2], warp[:, 2, 2] = self.shift_px, 1.0
        return warp

    def _at(self, frame: np.ndarray | int) -> np.ndarray | int:
        return np.clip(np.asarray(frame) - self.first_frame, 0, len(self.angle_rad) - 1)

    def undo(self, frame: np.ndarray, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Positions seen at frames ``frame`` carried back to the first frame's picture."""
        at = self._at(frame)
        if self.warp is not None:
            return _apply(self._inverse()[at], x, y)
        angle, shift = self.angle_rad[at], self.shift_px[at]
        cos, sin = np.cos(angle), np.sin(angle)
        dx, dy = x - shift[..., 0], y - shift[..., 1]
        return cos * dx + sin * dy, -sin * dx + cos * dy

    def redo(self, frame: np.ndarray, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Steadied positions at frames ``frame`` where the shaken camera saw them (undoes
        :meth:`undo`)."""
        at = self._at(frame)
        if self.warp is not None:
            return _apply(self.warp[at], x, y)
        angle, shift = self.angle_rad[at], self.shift_px[at]
        cos, sin = np.cos(angle), np.sin(angle)
        return cos * x - sin * y + shift[..., 0], sin * x + cos * y + shift[..., 1]

    def _inverse(self) -> np.ndarray:
        assert self.warp is not None
        cached = self.__dict__.get("_inverse_warp")
        if cached is None:
            cached = np.linalg.inv(self.warp)
            object.__setattr__(self, "_inverse_warp", cached)
        return cached

    def seen(self, tracks: pd.DataFrame) -> pd.DataFrame:
        """Steadied ``tracks`` (``frame, x_px, y_px``) where the shaken camera saw them: on its
        own frames (an overlay draws them there)."""
        x, y = self.redo(tracks["frame"].to_numpy(), tracks["x_px"].to_numpy(dtype=np.float64),
                         tracks["y_px"].to_numpy(dtype=np.float64))
        return tracks.assign(x_px=x.astype(tracks["x_px"].dtype), y_px=y.astype(tracks["y_px"].dtype))

    def steady(self, tracks: pd.DataFrame) -> pd.DataFrame:
        """``tracks`` (``frame, x_px, y_px``) as the camera saw them from where it stood at the
        first analysed frame (where ``--fixation`` and ``--points`` are read)."""
        x, y = self.undo(tracks["frame"].to_numpy(), tracks["x_px"].to_numpy(dtype=np.float64),
                         tracks["y_px"].to_numpy(dtype=np.float64))
        return tracks.assign(x_px=x.astype(tracks["x_px"].dtype), y_px=y.astype(tracks["y_px"].dtype))

    def between(self, frame_a: int, frame_b: int, scale: float = 1.0) -> np.ndarray:
        """The 2x3 affine matrix carrying positions in frame ``frame_a``'s picture to frame
        ``frame_b``'s, in pixels ``scale`` times the tracks' (a tracking image's)."""
        a, b = int(self._at(frame_a)), int(self._at(frame_b))
        if self.warp is not None:
            scaling = np.diag([scale, scale, 1.0])
            view = scaling @ self.warp[b] @ self._inverse()[a] @ np.linalg.inv(scaling)
            return view[:2] / view[2, 2]
        turn = float(self.angle_rad[b] - self.angle_rad[a])
        c, s = math.cos(turn), math.sin(turn)
        rotation = np.array([[c, -s], [s, c]])
        shift = self.shift_px[b] - rotation @ self.shift_px[a]
        return np.hstack([rotation, (scale * shift)[:, None]])

    def steady_image(self, image: np.ndarray, frame: int, scale: float, fill: np.ndarray) -> np.ndarray:
        """``image`` (frame ``frame``'s, ``scale`` times the tracks' pixels) as the camera saw it
        from where it stood at the first frame; what it did not see there is ``fill`` (the first
        frame's own image: still, as the background is once steadied)."""
        out = fill.copy()
        return self.carry(image, frame, self.first_frame, scale, out=out)

    def carry(self, image: np.ndarray, frame_a: int, frame_b: int, scale: float,
              out: np.ndarray | None = None) -> np.ndarray:
        """``image`` (frame ``frame_a``'s, ``scale`` times the tracks' pixels) as frame
        ``frame_b``'s camera saw it: into ``out`` where given (what falls outside keeps ``out``),
        else the edge repeated."""
        import cv2
        height, width = image.shape[:2]
        matrix = self.between(frame_a, frame_b, scale)
        if out is None:
            return cv2.warpAffine(image, matrix, (width, height), flags=cv2.INTER_LINEAR,
                                  borderMode=cv2.BORDER_REPLICATE)
        cv2.warpAffine(image, matrix, (width, height), dst=out, flags=cv2.INTER_LINEAR,
                       borderMode=cv2.BORDER_TRANSPARENT)
        return out

    def moved(self, point: np.ndarray) -> np.ndarray:
        """Where the first frame's ``point`` lies in every frame (frames x 2)."""
        if self.warp is not None:
            return np.stack(_apply(self.warp, point[0], point[1]), axis=1)
        cos, sin = np.cos(self.angle_rad), np.sin(self.angle_rad)
        return np.stack([cos * point[0] - sin * point[1], sin * point[0] + cos * point[1]], axis=1) + self.shift_px


@dataclass(frozen=True)
class _Steps:
    """Tracks' steps from one frame to the next: the frame each ends on (from the first, 0),
    where it starts and where it ends."""

    frame: np.ndarray
    x0: np.ndarray
    y0: np.ndarray
    x1: np.ndarray
    y1: np.ndarray
    frames: int
    first_frame: int

    def median_shift(self) -> CameraPath:
        """The camera's motion as the median step into each frame, summed (no turn)."""
        shift = np.stack([_median_by(self.frame, self.x1 - self.x0, self.frames),
                          _median_by(self.frame, self.y1 - self.y0, self.frames)], axis=1)
        return CameraPath(self.first_frame, np.zeros(self.frames), np.cumsum(shift, axis=0))

    def composed_views(self, chosen: np.ndarray) -> np.ndarray:
        """The camera's views from the first frame's picture (frames x 3 x 3): into each frame,
        the turn, zoom and shift that best carry the ``chosen`` steps' starts onto their ends, composed
        frame by frame (a frame with fewer than :data:`VIEW_MIN_POINTS` steps: none)."""
        frame = self.frame[chosen]
        views = _least_squares_views(frame, self.x0[chosen], self.y0[chosen], self.x1[chosen], self.y1[chosen],
                                     self.frames)
        views[np.bincount(frame, minlength=self.frames) < VIEW_MIN_POINTS] = np.eye(3)
        warp = np.empty_like(views)
        warp[0] = np.eye(3)
        for k in range(1, self.frames):
            warp[k] = views[k] @ warp[k - 1]
            warp[k] /= warp[k, 2, 2]
        return warp

    def rigid(self, chosen: np.ndarray) -> CameraPath:
        """The camera's motion from the ``chosen`` steps: into each frame, the turn and shift that
        best carry their starts onto their ends (least squares), composed frame by frame."""
        frame = self.frame[chosen]
        x0, y0, x1, y1 = self.x0[chosen], self.y0[chosen], self.x1[chosen], self.y1[chosen]
        count = np.bincount(frame, minlength=self.frames).astype(np.float64)
        has = count > 0
        weight = np.maximum(count, 1.0)

        def mean(values: np.ndarray) -> np.ndarray:
            return np.bincount(frame, values, self.frames) / weight

        ax, ay, bx, by = mean(x0), mean(y0), mean(x1), mean(y1)
        u0, v0, u1, v1 = x0 - ax[frame], y0 - ay[frame], x1 - bx[frame], y1 - by[frame]
        along = np.bincount(frame, u0 * u1 + v0 * v1, self.frames)
        across = np.bincount(frame, u0 * v1 - v0 * u1, self.frames)
        step_angle = np.where(has & (count >= 2), np.arctan2(across, along), 0.0)
        cos, sin = np.cos(step_angle), np.sin(step_angle)
        step_shift = np.stack([bx - (cos * ax - sin * ay), by - (sin * ax + cos * ay)], axis=1)
        step_shift[~has] = 0.0
        angle = np.cumsum(step_angle)
        shift = np.zeros((self.frames, 2))
        for k in range(1, self.frames):  # p_k = R_k p_(k-1) + s_k, from p_0
            c, s = cos[k], sin[k]
            shift[k] = (c * shift[k - 1, 0] - s * shift[k - 1, 1] + step_shift[k, 0],
                        s * shift[k - 1, 0] + c * shift[k - 1, 1] + step_shift[k, 1])
        return CameraPath(self.first_frame, angle, shift)


def _typical_jolt(path_px: np.ndarray) -> float:
    """The path's typical change of step from one frame to the next, as an rms: the median of
    its sizes times :data:`RMS_PER_MEDIAN`. A hand jolts the picture all through a clip; where a
    body's points pass for the background, the path jumps only where those points come and go
    (a box's top seen from 60 degrees above, 0.2 rad/s: jolts of 1.3-4 px in the first 3 frames,
    where 8 of its 38 points were followed, and 0.02-0.18 px after; their rms, 0.81 px, read as a
    hand's shake, whose taking out turned the rate to -33%)."""
    if len(path_px) < 3:
        return 0.0
    sizes = np.hypot(*np.diff(path_px, 2, axis=0).T)
    return RMS_PER_MEDIAN * float(np.median(sizes))


def _median_by(frame: np.ndarray, values: np.ndarray, frames: int) -> np.ndarray:
    """The median of ``values`` at each frame (0 where there are none)."""
    order = np.lexsort((values, frame))
    ordered_frame, ordered = frame[order], values[order]
    counts = np.bincount(ordered_frame, minlength=frames)
    starts = np.r_[0, np.cumsum(counts)[:-1]]
    median = np.zeros(frames)
    has = counts > 0
    low = starts[has] + (counts[has] - 1) // 2
    high = starts[has] + counts[has] // 2
    median[has] = 0.5 * (ordered[low] + ordered[high])
    return median


def _spread(track: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Each track's rms distance from its own mean position, one value per distinct track in
    order of their numbers."""
    _, inverse, counts = np.unique(track, return_inverse=True, return_counts=True)
    mean_x = np.bincount(inverse, x) / counts
    mean_y = np.bincount(inverse, y) / counts
    squares = np.bincount(inverse, (x - mean_x[inverse]) ** 2 + (y - mean_y[inverse]) ** 2) / counts
    return np.sqrt(squares)
