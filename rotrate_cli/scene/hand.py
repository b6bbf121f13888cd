"""A thin part turning over a still picture (a clock's hand, a gauge's needle, a pointer): its angle
frame by frame, against the clip's own still picture.

The picture's changes from one frame to the next (:mod:`rotrate_cli.scene.picture_angle`) say
little here: a hand one or two pixels wide changes few pixels, and a hand that steps once a second
changes none between most frames. Its picture against the clip's median picture does: where the
hand sweeps a wide enough arc, the median is the still face without it, and each frame less the
median is the hand alone, wherever it is then.

Each frame's difference is a line (:data:`NEEDLE_ELONGATION`); the lines of every frame meet at
the axis (their least-squares crossing, robust to a few that miss it); each frame's angle is its
line's direction from the axis, towards the hand's far end. A hand on a plane seen obliquely is
foreshortened: its image turns unevenly and its length changes with its angle, both by the same
stretch of the plane's picture. So the angles and the lengths are fitted together: one rate,
one start, the stretch (two numbers, zero face on) and the hand's length. The interval is the fit's
(the angles' scatter, a ticking hand's steps included, and the stretch as far as the lengths
leave it open).

Nothing else may move against the still picture: where the differences are not one line through
one point in most frames (a textured body turning, a camera the steadying did not hold, a swinging
pendulum), this tells nothing and the caller keeps the picture's changes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from rotrate_cli.scene.disc import DiscView
from rotrate_cli.scene.picture_angle import PictureAngle

#: Frames used at most (evenly over those kept).
MOST_FRAMES = 64
#: A frame's difference counts where it stands this many noise levels above the still picture and
#: this share of the frame's strongest differences (:data:`STRONGEST_QUANTILE`): a hand's edge,
#: not the codec's ripples along the face's marks.
NOISE_LEVELS = 6.0
STRONGEST_SHARE = 0.3
STRONGEST_QUANTILE = 99.9
#: ... and it must count this many pixels.
MIN_PIXELS = 8
#: A frame's difference is a needle where its spread along its main direction is this many times
#: its spread across (a hand 1 px wide and 70 long: about 20; a textured body: 1-3).
NEEDLE_ELONGATION = 6.0
#: ... in this many frames, and this share of them at least.
MIN_FRAMES = 8
NEEDLE_SHARE = 0.6
#: The needles' lines must pass this close to their crossing (median, of the hand's length).
THROUGH_SHARE = 0.03
#: Once the axis is first placed, the needles' pixels within this share of the hand's reach of it are
#: let go, and the axis placed again.
HUB_SHARE = 0.2
#: A steadied frame is shifted onto the still picture where their phase correlation peaks at least
#: this high (lower peaks: a frame whose steadying left the picture's edges far from the first
#: frame's, shifted by them), by at most this much (px of the frames used).
LINED_UP = 0.3
LINED_UP_MOST_PX = 12.0
#: The most rounds of OpenCV's ECC in lining a frame up as a plane's view (:func:`_lined_up`).
LINED_UP_ROUNDS = 50
#: A frame's grey levels are matched to the still picture's on about this many of its pixels.
LEVEL_SAMPLES = 10000
#: The face is lined up with the still picture at this many angles a turn, over rings from the first
#: to the second share of the hand's reach, the hand's own angle left out (within this, degrees);
#: where its unrolled pictures are alike to less than this (their normalised correlation, median),
#: or turned by more than this (degrees: no steadying leaves that), nothing is taken out.
FACE_ANGLES = 720
FACE_RINGS = (0.3, 1.1)
FACE_HAND_DEG = 12.0
FACE_ALIKE = 0.5
FACE_MOST_DEG = 5.0
#: A needle is told from its other end by its centroid lying this far from the axis (of its length):
#: a bar through its axis (a propeller's two blades) has no far end to tell.
OFF_AXIS_SHARE = 0.2
#: Only the difference within this of the needle's direction (degrees) counts towards its angle
#: and length: another part that moves a little (a clock's minute hand) is left out.
WEDGE_DEG = 8.0
#: The hand must turn this far over the clip (degrees), and its angles keep this close to a steady
#: turn (a robust rms, of the angle turned, and degrees): a swinging pendulum does not, nor a
#: needle taken for another from frame to frame (a ticking hand's steps of 6 degrees: 1.7).
MIN_TURNED_DEG = 15.0
MOST_SCATTER_SHARE = 0.1
MOST_SCATTER_DEG = 8.0
#: The needles are sought again within this share of the hand's reach of the axis first placed...
AROUND_REACH = 1.3
#: ... where a frame whose difference holds a second piece this long (of the longest) shows several parts
#: alike (six spokes: one taken for another from frame to frame read three times too fast).
RIVAL_SHARE = 0.6
#: Frames whose angle or length misfits a steady turn by more than this many (robust) scatters are
#: left out.
OUTLYING = 4.0
#: ... but no more than this share of them.
MOST_LEFT_OUT = 0.2
#: The lengths are read as this quantile of the needle's pixels along it.
LENGTH_QUANTILE = 98.0
#: A needle's direction is read to about this much (px of the frames used) at its tip, whatever its
#: scatter says: the pixel grid's errors follow the angle, not the frame (a drawn hand whose ends
#: were rounded to whole pixels read 0.17% apart from two sets of its frames, each within +-0.15%).
READ_PX = 0.5
#: The plane's stretch counts where it stands this many standard errors from none, and tells a tilt
#: of this much at least (degrees; less turns a hand's angles by under 0.6 degrees).
TOLD_TILT_DEG = 12.0
TOLD_STRETCH = 3.0


@dataclass(frozen=True)
class _Needle:
    """One frame's difference as a line: its centroid, direction and the pixels it holds."""

    centroid: np.ndarray
    direction: np.ndarray
    x: np.ndarray
    y: np.ndarray
    weight: np.ndarray


def measure_hand(kept: list[tuple[int, float, np.ndarray]], width_px: int,
                 steadied: bool = False) -> PictureAngle | None:
    """The turning of a thin part over a still picture (see the module's notes) in the frames
    ``kept`` (``(index, time_s, grey image)``, in order; the first of each run of consecutive
    ones is used), whose picture is ``width_px`` wide; None where the picture holds no such part.
    ``steadied``: the frames are a moving camera's, steadied: the angles are read against the
    face the hand turns over (:func:`_face_turns`).
    The reading's view is the plane's as the hand's stretch tells it, about the axis found (in the
    picture's own pixels); its score, the share of the frames whose difference was the needle."""
    chosen = _one_per_run(kept)
    if len(chosen) < MIN_FRAMES:
        return None
    if len(chosen) > MOST_FRAMES:
        chosen = [chosen[i] for i in np.unique(np.linspace(0, len(chosen) - 1, MOST_FRAMES).round().astype(int))]
    times = np.array([time_s for time_s, _ in chosen])
    images = np.stack([cv2.GaussianBlur(image.astype(np.float32), (0, 0), 1.0) for _, image in chosen])
    still = np.median(images, axis=0)
    if steadied:
        # a moving camera's frames, steadied from its background's tracks, may still sit a few
        # pixels off (a rolling, wobbling camera's first frames: 4 px): each is lined up with the
        # still picture again where the two clearly match
        images = _lined_up(images, still)
        still = np.median(images, axis=0)
    needed = max(MIN_FRAMES, NEEDLE_SHARE * len(chosen))
    placed = _needles_and_axis(images, still, needed)
    if placed is None:
        return None
    found, lines, centre = placed
    read = [_angle_and_length(needle, centre) for needle in lines]
    good = np.array([reading is not None for reading in read])
    if good.sum() < needed:
        return None
    angles = np.unwrap(np.array([reading[0] for reading in read if reading is not None]))
    lengths = np.array([reading[1] for reading in read if reading is not None])
    frames = np.array(found)[good]
    times = times[frames]
    # the angles against the face the hand turns over: the steady turn that a moving camera's
    # steadying left (the face turned with it) is taken out, and how well it is known kept
    face = _face_turns(images[frames], still, centre, float(np.median(lengths)), angles) if steadied else None
    face_se = 0.0
    if face is not None:
        t = times - times.mean()
        line = np.polyfit(t, face, 1)
        face_se = float(np.std(face - np.polyval(line, t), ddof=2)) / math.sqrt(float(np.sum(t ** 2)))
        angles = angles - float(line[0]) * t
    if float(np.median([_off_line(line, centre) for line in lines])) > THROUGH_SHARE * float(np.median(lengths)):
        return None  # the lines do not meet in one point: not a part turning about an axis
    return _fitted(times, angles, lengths, centre, width_px / still.shape[1], len(found) / len(chosen), face_se)


def _needles_and_axis(images: np.ndarray, still: np.ndarray,
                      needed: float) -> tuple[list[int], list[_Needle], np.ndarray] | None:
    """The frames whose difference from ``still`` is a needle, their needles (the hub's pixels let
    go) and the axis where their lines cross; None where fewer than ``needed`` frames show one, or
    the lines do not cross. Twice: the axis first placed from each frame's longest piece, then the
    needles sought again within the hand's reach of it (:data:`AROUND_REACH`), where a second
    piece alike tells several parts (:data:`RIVAL_SHARE`), and what lies farther off (a steadied
    frame's edges, someone passing) does not count."""
    differences = np.abs(images - still)
    noise = 1.4826 * float(np.median(differences)) + 1e-6
    region = None
    for _ in range(2):
        needles = [_needle(difference, noise, region) for difference in differences]
        found = [k for k, needle in enumerate(needles) if needle is not None]
        if len(found) < needed:
            return None
        centre = _crossing([needles[k] for k in found])
        if centre is None:
            return None
        reach = float(np.median([np.max(np.hypot(needles[k].x - centre[0], needles[k].y - centre[1])) for k in found]))
        region = (centre, AROUND_REACH * reach)
    # again without the hub (its cap, a counterweight, and where a hand that turns little lies in
    # the still picture too): the lines' far parts place the axis
    beyond = [(k, _beyond(needles[k], centre, HUB_SHARE * reach)) for k in found]
    found = [k for k, line in beyond if line is not None]
    lines = [line for _, line in beyond if line is not None]
    centre = _crossing(lines) if len(lines) >= needed else None
    return None if centre is None else (found, lines, centre)


def _one_per_run(kept: list[tuple[int, float, np.ndarray]]) -> list[tuple[float, np.ndarray]]:
    """The first frame of each run of consecutive ones."""
    chosen, last = [], None
    for index, time_s, image in kept:
        if last is None or index != last + 1:
            chosen.append((time_s, image))
        last = index
    return chosen


def _needle(difference: np.ndarray, noise: float,
            region: tuple[np.ndarray, float] | None = None) -> _Needle | None:
    """The frame's difference from the still picture as a line, or None where it is no needle.
    ``region``: only within this far of this point, and no second piece alike there."""
    if region is not None:
        (cx, cy), radius = region
        rows_at, columns_at = np.ogrid[:difference.shape[0], :difference.shape[1]]
        difference = np.where((columns_at - cx) ** 2 + (rows_at - cy) ** 2 <= radius ** 2, difference, 0.0)
    strongest = float(np.percentile(difference, STRONGEST_QUANTILE))
    mask = (difference > max(NOISE_LEVELS * noise, STRONGEST_SHARE * strongest)).astype(np.uint8)
    if int(mask.sum()) < MIN_PIXELS:
        return None
    # the longest piece (joined across a pixel's gap): another part that moved a little (a clock's
    # minute hand, a sliver along its edge) lies apart from the hand, unless they cross
    joined = cv2.dilate(mask, np.ones((3, 3), np.uint8))
    count, labels, stats, _ = cv2.connectedComponentsWithStats(joined, connectivity=8)
    if count < 2:
        return None
    extents = np.hypot(stats[1:, cv2.CC_STAT_WIDTH], stats[1:, cv2.CC_STAT_HEIGHT])
    order = np.argsort(-extents)
    if region is not None and len(order) > 1 and extents[order[1]] >= RIVAL_SHARE * extents[order[0]]:
        return None  # several parts alike (spokes, blades): which is which is not told frame to frame
    rows, columns = np.nonzero(mask.astype(bool) & (labels == 1 + int(order[0])))
    if len(rows) < MIN_PIXELS:
        return None
    x, y = columns.astype(np.float64), rows.astype(np.float64)
    weight = difference[rows, columns].astype(np.float64)
    line = _line(x, y, weight)
    for _ in range(2):  # pixels off the line let go (another part joined to the hand at the axis)
        away = np.abs((x - line[0][0]) * line[1][1] - (y - line[0][1]) * line[1][0])
        near = away <= 3.0 * float(np.median(away)) + 1.0
        if near.sum() < MIN_PIXELS:
            return None
        x, y, weight = x[near], y[near], weight[near]
        line = _line(x, y, weight)
    centroid, direction, values = line
    if values[1] < NEEDLE_ELONGATION ** 2 * max(values[0], 1e-3):
        return None
    return _Needle(centroid, direction, x, y, weight)


def _line(x: np.ndarray, y: np.ndarray, weight: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The weighted pixels' centroid, main direction and second moments (across, along)."""
    centroid = np.array([np.average(x, weights=weight), np.average(y, weights=weight)])
    dx, dy = x - centroid[0], y - centroid[1]
    moments = np.array([[np.average(dx * dx, weights=weight), np.average(dx * dy, weights=weight)],
                        [np.average(dx * dy, weights=weight), np.average(dy * dy, weights=weight)]])
    values, vectors = np.linalg.eigh(moments)
    return centroid, vectors[:, 1], values


def _lined_up(images: np.ndarray, still: np.ndarray) -> np.ndarray:
    """Each image lined up with the still picture and brought to its grey levels.

    First shifted onto ``still`` (phase correlation over the whole picture; the shift where it is
    clear: :data:`LINED_UP`; over the clock's face alone, mostly plain, the shifts were noisier:
    the rolling clocks' intervals three to ten times as wide), and faded to its edges (a Hanning
    window): where the camera's view came and went, a steadied frame's edges differ from the still
    picture in long straight strips, which pass for a needle (a clock filmed in the hand, leaning
    and zooming, found no hand unfaded; -0.16% faded). Then each is fitted to the shifted
    images' median as a plane's view (OpenCV's ECC, at most :data:`LINED_UP_ROUNDS` rounds), where
    that moves no corner by more than :data:`LINED_UP_MOST_PX`: a camera held in the hand leans as
    well as turning, and its steadying (a turn, zoom and shift) left the face's marks doubled by a
    few pixels. Last, each is scaled and offset to that median's grey levels: a camera's exposure
    follows the light, and a face 8% brighter differs from the still picture all over by more
    than the hand."""
    height, width = still.shape
    window = cv2.createHanningWindow((width, height), cv2.CV_32F)
    shifted = np.empty_like(images)
    for k, image in enumerate(images):
        # copies: OpenCV applies the window to its inputs in place where they need no padding
        (dx, dy), response = cv2.phaseCorrelate(still.copy(), image.copy(), window)
        if response < LINED_UP or math.hypot(dx, dy) > LINED_UP_MOST_PX:
            shifted[k] = image
            continue
        shift = np.array([[1.0, 0.0, -dx], [0.0, 1.0, -dy]])
        shifted[k] = cv2.warpAffine(image, shift, (width, height), flags=cv2.INTER_LINEAR,
                                    borderMode=cv2.BORDER_REPLICATE)
    shifted *= window
    still = np.median(shifted, axis=0)
    corners = np.array([[0.0, 0.0, 1.0], [width, 0.0, 1.0], [0.0, height, 1.0], [width, height, 1.0]]).T
    criteria = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, LINED_UP_ROUNDS, 1e-4)
    every = max(1, still.size // LEVEL_SAMPLES)
    lined = np.empty_like(images)
    for k, image in enumerate(shifted):
        try:
            _, view = cv2.findTransformECC(still, image, np.eye(3, dtype=np.float32), cv2.MOTION_HOMOGRAPHY,
                                           criteria, None, 5)
        except cv2.error:  # it did not converge: the shift stands
            view = None
        if view is not None:
            moved = view.astype(np.float64) @ corners
            if float(np.max(np.hypot(*(moved[:2] / moved[2] - corners[:2])))) <= LINED_UP_MOST_PX:
                image = cv2.warpPerspective(image, view, (width, height),
                                            flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                                            borderMode=cv2.BORDER_REPLICATE)
        gain, offset = np.polyfit(image.ravel()[::every], still.ravel()[::every], 1)
        lined[k] = gain * image + offset
    return lined


def _face_turns(images: np.ndarray, still: np.ndarray, centre: np.ndarray, reach_px: float,
                hand_rad: np.ndarray) -> np.ndarray | None:
    """How far each image's picture about ``centre`` is turned from the still picture's (radians,
    anticlockwise as shown), from the rings the hand sweeps (:data:`FACE_RINGS`, of its reach)
    less the hand's own angles (``hand_rad``, within :data:`FACE_HAND_DEG`); None where the face
    shows too little to line up by (a plain disc)."""
    angles = np.arange(FACE_ANGLES) * (2.0 * math.pi / FACE_ANGLES)
    radii = np.linspace(FACE_RINGS[0], FACE_RINGS[1], 32) * reach_px
    map_x = (centre[0] + radii[None, :] * np.cos(angles)[:, None]).astype(np.float32)
    map_y = (centre[1] - radii[None, :] * np.sin(angles)[:, None]).astype(np.float32)

    def unrolled(image: np.ndarray) -> np.ndarray:
        polar = cv2.remap(image, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        return polar - polar.mean(axis=0)

    reference = np.fft.rfft(unrolled(still), axis=0)
    energy = float(np.sum(np.abs(reference) ** 2))
    turns = np.zeros(len(images))
    heights = np.zeros(len(images))
    for k, (image, hand_angle) in enumerate(zip(images, hand_rad, strict=True)):
        polar = unrolled(image)
        near_hand = np.abs((angles - hand_angle + math.pi) % (2.0 * math.pi) - math.pi) < math.radians(FACE_HAND_DEG)
        polar[near_hand] = 0.0
        spectrum = np.fft.rfft(polar, axis=0)
        correlation = np.fft.irfft(np.sum(spectrum * np.conj(reference), axis=1), n=FACE_ANGLES)
        peak = int(np.argmax(correlation))
        before, at, after = correlation[peak - 1], correlation[peak], correlation[(peak + 1) % FACE_ANGLES]
        curvature = before - 2.0 * at + after
        offset = 0.5 * (before - after) / curvature if curvature < 0 else 0.0
        shift = (peak + offset + FACE_ANGLES / 2) % FACE_ANGLES - FACE_ANGLES / 2
        turns[k] = shift * 2.0 * math.pi / FACE_ANGLES
        heights[k] = at / max(math.sqrt(energy * float(np.sum(np.abs(spectrum) ** 2))), 1e-9) * FACE_ANGLES
    if float(np.median(heights)) < FACE_ALIKE or float(np.max(np.abs(turns))) > math.radians(FACE_MOST_DEG):
        return None
    return turns


def _beyond(needle: _Needle, centre: np.ndarray, radius_px: float) -> _Needle | None:
    """The needle's pixels farther than ``radius_px`` from ``centre``, as a line again."""
    far = np.hypot(needle.x - centre[0], needle.y - centre[1]) > radius_px
    if far.sum() < MIN_PIXELS:
        return None
    x, y, weight = needle.x[far], needle.y[far], needle.weight[far]
    centroid, direction, _ = _line(x, y, weight)
    return _Needle(centroid, direction, x, y, weight)


def _off_line(line: _Needle, point: np.ndarray) -> float:
    """How far ``point`` lies from the needle's line (px)."""
    offset = point - line.centroid
    return abs(float(line.direction[0] * offset[1] - line.direction[1] * offset[0]))


def _crossing(lines: list[_Needle]) -> np.ndarray | None:
    """The point nearest every line (least squares, the lines far from it weighed down in turn:
    a frame whose difference held more than the hand); None where the lines are near parallel."""
    weights = np.ones(len(lines))
    centre = None
    for _ in range(4):
        normal_sum, target = np.zeros((2, 2)), np.zeros(2)
        for line, weight in zip(lines, weights, strict=True):
            normal = np.array([-line.direction[1], line.direction[0]])
            projector = weight * np.outer(normal, normal)
            normal_sum += projector
            target += projector @ line.centroid
        if np.linalg.cond(normal_sum) > 1e6:
            return None
        centre = np.linalg.solve(normal_sum, target)
        distances = np.array([_off_line(line, centre) for line in lines])
        scale = max(1.4826 * float(np.median(distances)), 0.5)
        weights = 1.0 / (1.0 + (distances / (2.0 * scale)) ** 2)
    return centre


def _angle_and_length(needle: _Needle, centre: np.ndarray) -> tuple[float, float] | None:
    """The needle's angle about ``centre`` (radians, anticlockwise as shown) towards its far end,
    and its length, from its pixels within :data:`WEDGE_DEG` of its direction; None where its far
    end cannot be told."""
    dx, dy = needle.x - centre[0], needle.y - centre[1]
    direction = needle.direction
    if float(np.dot(needle.centroid - centre, direction)) < 0:
        direction = -direction
    for _ in range(2):  # the direction through the axis, from the pixels near it
        along = dx * direction[0] + dy * direction[1]
        across = dx * direction[1] - dy * direction[0]
        near = (along > 0) & (np.abs(across) <= np.tan(np.radians(WEDGE_DEG)) * along + 1.0)
        if near.sum() < MIN_PIXELS:
            return None
        w = needle.weight[near]
        moments = np.array([[np.sum(w * dx[near] ** 2), np.sum(w * dx[near] * dy[near])],
                            [np.sum(w * dx[near] * dy[near]), np.sum(w * dy[near] ** 2)]])
        vector = np.linalg.eigh(moments)[1][:, 1]
        direction = vector if float(vector @ direction) > 0 else -vector
    along = dx * direction[0] + dy * direction[1]
    length = float(np.percentile(along[near], LENGTH_QUANTILE))
    centroid_along = float(np.average(along[near], weights=needle.weight[near]))
    if centroid_along < OFF_AXIS_SHARE * length:
        return None
    return math.atan2(-direction[1], direction[0]), length


def _fitted(times: np.ndarray, angles: np.ndarray, lengths: np.ndarray, centre: np.ndarray, scale: float,
            share: float, face_se: float = 0.0) -> PictureAngle | None:
    """The rate from each frame's angle and length (see the module's notes); None where the angles
    do not follow a steady turn. ``face_se``: the standard error of the face's own turn taken out
    (radians a second), which the interval holds too."""
    turned = float(abs(angles[-1] - angles[0]))
    if math.degrees(turned) < MIN_TURNED_DEG or len(times) < MIN_FRAMES:
        return None
    t = times - times.mean()
    scatter = _robust_scale(angles - np.polyval(np.polyfit(t, angles, 1), t))
    if scatter > min(MOST_SCATTER_SHARE * turned, math.radians(MOST_SCATTER_DEG)):
        return None
    fitted = _stretched_fit(t, angles, lengths)
    if fitted is None:
        return None
    params, covariance, kept = fitted
    _, omega, e1, e2, _ = params
    half = _quantile(kept.sum() * 2 - len(params)) * math.sqrt(max(float(covariance[1, 1]), 0.0))
    rate, low, high = abs(float(omega)), abs(float(omega)) - half, abs(float(omega)) + half
    try:
        stretch_told = float(np.r_[e1, e2] @ np.linalg.solve(covariance[2:4, 2:4], np.r_[e1, e2]))
    except np.linalg.LinAlgError:
        stretch_told = 0.0
    if stretch_told < TOLD_STRETCH ** 2 or math.hypot(e1, e2) < _stretch_of(TOLD_TILT_DEG):
        # no stretch clearly seen: the hand's turn read face on, the interval holding the stretched
        # fit's too (the lengths' own small errors, a pixel's rounding or another hand moving
        # beside it, can feign a few degrees: a minute hand turning 1 degree a second, 8.4, +1.2%)
        e1 = e2 = 0.0
        line = np.polyfit(t[kept], angles[kept], 1)
        scatter = float(np.std(angles[kept] - np.polyval(line, t[kept]), ddof=2))
        face_half = _quantile(kept.sum() - 2) * scatter / math.sqrt(float(np.sum((t[kept] - t[kept].mean()) ** 2)))
        omega = float(line[0])
        rate = abs(omega)
        low, high = min(low, rate - face_half), max(high, rate + face_half)
    # the face's turn taken out, as far as it is known
    low, high = low - _quantile(len(t) - 2) * face_se, high + _quantile(len(t) - 2) * face_se
    # at least what reading the hand's direction to READ_PX at its tip allows over the turn seen
    floor = READ_PX / float(np.median(lengths)) / turned * rate
    low, high = min(low, rate - floor), max(high, rate + floor)
    stretch = min(math.hypot(e1, e2), 0.99)
    tilt = math.degrees(math.acos((1 - stretch) / (1 + stretch)))  # the inverse of _stretch_of
    axis = (float((centre[0] + 0.5) * scale - 0.5), float((centre[1] + 0.5) * scale - 0.5))
    view = DiscView(axis, -0.5 * math.degrees(math.atan2(e2, e1)), tilt, math.inf)
    return PictureAngle(rate, max(0.0, low), high, 1 if omega > 0 else -1, times, np.degrees(angles - angles[0]),
                        math.degrees(turned), share, view, thin_part=True)


def _stretch_of(tilt_deg: float) -> float:
    """The stretch a plane tilted ``tilt_deg`` shows its circles with (0 face on)."""
    ratio = math.cos(math.radians(tilt_deg))
    return (1.0 - ratio) / (1.0 + ratio)


def _quantile(dof: int) -> float:
    """A 95% two-sided t quantile, nearly (within 1% from 5 degrees of freedom)."""
    return 1.96 + 2.4 / max(dof, 1)


def _stretched_fit(t: np.ndarray, angles: np.ndarray,
                   lengths: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """One steady turn of a hand seen through a stretch of the plane's picture, fitted to the
    angles and lengths (each kind weighed by its own scatter), the frames whose angle or length
    lies far off it (:data:`OUTLYING`: the hand's tip lost over a dark mark, or crossing another
    hand) left out, up to :data:`MOST_LEFT_OUT` of them: the parameters (start, rate, the
    stretch's two numbers, the length), their covariance (widened by the misfit beyond the
    scatters), and which frames were kept; None where it cannot be had."""
    line = np.polyfit(t, angles, 1)
    start = np.r_[line[1], line[0], 0.0, 0.0, np.median(lengths)]
    # a robust fit first (each kind weighed by its robust scatter about the last fit), whose far-off
    # frames (OUTLYING times that scatter, or what the pixel grid allows: READ_PX, half of it either
    # way) are let go, the worst MOST_LEFT_OUT at most; then the plain fit of those kept
    floors = (0.5 * READ_PX / float(np.median(lengths)), 0.5 * READ_PX)
    params, scales = _weighed_fit(t, angles, lengths, start, "soft_l1")
    angle_misfit, length_misfit = _misfits(params, t, angles, lengths)
    off = np.maximum(np.abs(angle_misfit) / max(scales[0], floors[0]),
                     np.abs(length_misfit) / max(scales[1], floors[1]))
    kept = off <= OUTLYING
    if kept.sum() < (1 - MOST_LEFT_OUT) * len(t):
        kept = off <= np.quantile(off, 1 - MOST_LEFT_OUT)
    if kept.sum() < MIN_FRAMES:
        return None
    params, scales = _weighed_fit(t[kept], angles[kept], lengths[kept], params, "linear")
    fit_misfits = _misfits(params, t[kept], angles[kept], lengths[kept])
    normalised = np.r_[fit_misfits[0] / scales[0], fit_misfits[1] / scales[1]]
    jacobian = _jacobian(params, t[kept], angles[kept], lengths[kept], scales)
    dof = max(len(normalised) - len(params), 1)
    try:
        covariance = np.linalg.inv(jacobian.T @ jacobian) * max(float(normalised @ normalised) / dof, 1.0)
    except np.linalg.LinAlgError:
        return None
    return params, covariance, kept


def _weighed_fit(t: np.ndarray, angles: np.ndarray, lengths: np.ndarray, start: np.ndarray,
                 loss: str) -> tuple[np.ndarray, list[float]]:
    """The stretched turn fitted with each kind weighed by its robust scatter about the last fit
    (three times), by ``loss``: the parameters and the two scatters."""
    from scipy.optimize import least_squares  # imported here: it weighs on every run's start otherwise

    params = start
    angle_misfit, length_misfit = _misfits(params, t, angles, lengths)
    for _ in range(3):
        scales = [max(_robust_scale(angle_misfit), 1e-6), max(_robust_scale(length_misfit), 1e-3)]

        def residuals(values: np.ndarray, scales: list[float] = scales) -> np.ndarray:
            misfit = _misfits(values, t, angles, lengths)
            return np.r_[misfit[0] / scales[0], misfit[1] / scales[1]]

        params = least_squares(residuals, params, loss=loss, f_scale=1.0).x
        angle_misfit, length_misfit = _misfits(params, t, angles, lengths)
    return params, scales


def _jacobian(params: np.ndarray, t: np.ndarray, angles: np.ndarray, lengths: np.ndarray,
              scales: list[float]) -> np.ndarray:
    """The normalised misfits' derivatives by the parameters (central differences)."""
    columns = []
    for i in range(len(params)):
        step = np.zeros(len(params))
        step[i] = 1e-6 * max(1.0, abs(float(params[i])))
        plus, minus = _misfits(params + step, t, angles, lengths), _misfits(params - step, t, angles, lengths)
        columns.append(np.r_[(plus[0] - minus[0]) / scales[0], (plus[1] - minus[1]) / scales[1]] / (2 * step[i]))
    return np.stack(columns, axis=1)


def _misfits(params: np.ndarray, t: np.ndarray, angles: np.ndarray,
             lengths: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The angles' and the lengths' misfits (radians, px) to a steady turn seen through a stretch."""
    a, omega, e1, e2, length = params
    theta = a + omega * t
    c, s = np.cos(theta), np.sin(theta)
    x, y = (1 + e1) * c + e2 * s, e2 * c + (1 - e1) * s
    return (np.arctan2(y, x) - angles + np.pi) % (2 * np.pi) - np.pi, length * np.hypot(x, y) - lengths


def _robust_scale(values: np.ndarray) -> float:
    return 1.4826 * float(np.median(np.abs(values - np.median(values))))


def window_rates(angle: PictureAngle, centres_s: np.ndarray,
                 window_s: float) -> list[tuple[float, float, float] | None]:
    """omega(t) from a hand's angles (:func:`measure_hand`): per window (``centres_s``, ``window_s``
    long) a steady turn fitted to the angles inside it (its slope's 95% interval, and the clip's own
    interval's share for the stretch); None for a window with too few frames or too small a turn."""
    share = (angle.omega_high_rad_s - angle.omega_low_rad_s) / (2.0 * angle.omega_rad_s)
    rates: list[tuple[float, float, float] | None] = []
    for centre in centres_s:
        inside = np.abs(angle.times_s - centre) <= window_s / 2 + 1e-9
        times, angles = angle.times_s[inside], np.radians(angle.angles_deg[inside])
        if len(times) < MIN_FRAMES or math.degrees(abs(angles[-1] - angles[0])) < MIN_TURNED_DEG:
            rates.append(None)
            continue
        t = times - times.mean()
        line = np.polyfit(t, angles, 1)
        scatter = float(np.std(angles - np.polyval(line, t), ddof=2))
        omega = abs(float(line[0]))
        half = _quantile(len(t) - 2) * scatter / math.sqrt(float(np.sum(t ** 2))) + share * omega
        rates.append((omega, max(0.0, omega - half), omega + half))
    return rates
