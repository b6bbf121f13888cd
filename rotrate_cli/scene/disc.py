"""A turning plane seen by a pinhole camera (a record, a wheel, a fan, a turntable seen from above),
unrolled about its axis: the picture resampled on circles of the plane, so that the body's turn is
a shift along the angle.

The plane's picture is a homography of it: the point ``radius, angle`` of the plane lies at
``X0 + radius (cos(angle) e1 + sin(angle) e2)`` in the camera's frame, where ``X0`` is the axis's
point on the ray through :attr:`DiscView.centre_px` (at depth 1), ``e1`` the direction of the circles'
long axes and ``e2`` that direction tilted away by :attr:`DiscView.tilt_deg`. With a long lens the
circles are ellipses about the axis's point (the affine view); close up, the near side is larger,
and a model without perspective turns the picture unevenly (the shared record close-up read 3%
slow over 0.3 of a turn through the affine view, 0.7% through this one).

The view is found from the picture itself (:func:`fitted_view`): the one that makes the changes of
the picture from frame to frame line up best when shifted along the angle.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import cv2
import numpy as np

#: Angles and rings of the unrolled picture while the view is sought (coarse: a search).
SEARCH_ANGLES = 256
SEARCH_RINGS = 64
#: Rings whose picture changes less than this from frame to frame (grey levels, on average)
#: carry nothing.
MOVING_LEVELS = 1.0
#: Where fewer rings than this move so, those whose rms change stands this many times above the
#: quietest quarter of the rings' (the picture's noise) move.
FEWEST_RINGS = 3
SPARSE_MOVING = 3.0
#: Where the rings that move so change by under NEAR_LEVELS times MOVING_LEVELS (their median),
#: the rings whose change is at least ALONG_SHARE of theirs move too, where it stands SPARSE_MOVING
#: times above the quietest quarter's: a body turning slowly between frames changes its rings by
#: about MOVING_LEVELS, some above and some below. (A real photograph on a disc turning 0.25
#: degrees a frame, 60 frames/s: 7 of its 22 rings counted, which lined the changes up through a
#: wrong view, tilted 33 degrees and 7 px off, better than through the right one; its tracks'
#: plane then read -0.8%, its interval missing, good.) Where the moving rings change by more, the
#: rule is as it was. (It narrows some readings through wrong views too: a flat six-spoked wheel's,
#: through a view tilted 57 degrees, 1.48 times too fast, from +-24% to +-5%; such a reading tells
#: no count of returns: :data:`rotrate_cli.stages.verdict.COUNT_SCORE`.)
ALONG_SHARE = 0.5
NEAR_LEVELS = 2.0
#: Starts refined besides the best about the given centre (apart from it and each other): the
#: record at half size played backwards, 0.6 of a turn, refined its two best coarse starts to views
#: that told no rate (its sliding tracks then read -74%), its third to the spindle (-0.55%).
REFINED_STARTS = 3
#: Times a refinement's simplex search is started again from where it stopped (and gained).
RESTARTS = 2
#: The longest focal length tried, in picture widths (beyond, the view is affine).
LONGEST_FOCAL = 20.0


@dataclass(frozen=True)
class DiscView:
    """Where a turning plane lies in the picture.

    Attributes:
        centre_px: where its axis meets it, in the picture's pixels.
        long_axis_deg: the direction of its circles' long axes in the picture (degrees from the
            image's x axis, y down).
        tilt_deg: how far it is tilted from facing the camera (0: face on; 90: edge on).
        focal_px: the camera's focal length, pixels (the principal point at the picture's centre).
    """

    centre_px: tuple[float, float]
    long_axis_deg: float
    tilt_deg: float
    focal_px: float

    def scaled(self, factor: float) -> DiscView:
        """The same view in a picture ``factor`` times as large."""
        return replace(self, centre_px=(self.centre_px[0] * factor, self.centre_px[1] * factor),
                       focal_px=self.focal_px * factor)


@dataclass(frozen=True)
class Unrolled:
    """The maps that unroll a picture about the axis (rows: angles, columns: rings), and which
    of their samples fall inside the picture."""

    map_x: np.ndarray
    map_y: np.ndarray
    inside: np.ndarray

    def of(self, image: np.ndarray) -> np.ndarray:
        """``image`` (grey, float32) unrolled."""
        return cv2.remap(image, self.map_x, self.map_y, cv2.INTER_LINEAR)


def unrolled(shape_px: tuple[int, int], view: DiscView, angles: int, rings: int | None = None) -> Unrolled:
    """The maps of a picture ``shape_px`` (height, width) through ``view`` at ``angles`` angles a
    turn and ``rings`` rings from the axis out to the farthest point of the plane the picture
    shows (None: a ring a pixel near the axis, at most 1.5 picture sides)."""
    height, width = shape_px
    principal = np.array([width / 2.0, height / 2.0])
    focal = view.focal_px
    axis_point = np.array([(view.centre_px[0] - principal[0]) / focal, (view.centre_px[1] - principal[1]) / focal, 1.0])
    ray = axis_point / np.linalg.norm(axis_point)
    across = np.array([1.0, 0.0, 0.0]) - ray[0] * ray
    across /= np.linalg.norm(across)
    down = np.cross(ray, across)
    phi, tilt = math.radians(view.long_axis_deg), math.radians(view.tilt_deg)
    e1 = math.cos(phi) * across + math.sin(phi) * down
    e2 = math.cos(tilt) * (-math.sin(phi) * across + math.cos(phi) * down) - math.sin(tilt) * ray
    normal = np.cross(e1, e2)
    largest = _largest_radius(width, height, principal, focal, axis_point, normal, e1, e2)
    count = rings if rings is not None else int(min(largest * focal, 1.5 * max(width, height)))
    radius = np.linspace(2.0 / focal, largest, max(count, 8))
    angle = np.arange(angles) * (2.0 * math.pi / angles)
    cos, sin = np.cos(angle)[:, None, None], np.sin(angle)[:, None, None]
    points = axis_point[None, None, :] + radius[None, :, None] * (cos * e1[None, None, :] + sin * e2[None, None, :])
    depth = points[..., 2]
    ahead = depth > 1e-6
    safe = np.where(ahead, depth, 1.0)
    map_x = principal[0] + focal * points[..., 0] / safe
    map_y = principal[1] + focal * points[..., 1] / safe
    inside = ahead & (map_x >= 1) & (map_x < width - 2) & (map_y >= 1) & (map_y < height - 2)
    return Unrolled(np.where(inside, map_x, -10.0).astype(np.float32),
                    np.where(inside, map_y, -10.0).astype(np.float32), inside)


@dataclass(frozen=True)
class PlaneMap:
    """A turning plane's picture as its tracks tell it (:mod:`rotrate_cli.scene.plane_turn`),
    through no camera model: the picture taken through the plane's horizon to infinity
    (``x / (a x + b y + 1)``, :attr:`horizon`) is an affine view of it, in which its circles about
    the axis are the ellipses ``centre + metric (cos, sin) r``.

    Attributes:
        horizon: ``a, b`` (per px) of the horizon ``a x + b y + 1 = 0``.
        centre: the axis's point, in the picture taken through the horizon.
        metric: 2 x 2, a circle's radius to the picture taken through the horizon.
        largest: the largest radius of the plane the tracks reached (in the metric's units).
    """

    horizon: tuple[float, float]
    centre: tuple[float, float]
    metric: tuple[tuple[float, float], tuple[float, float]]
    largest: float

    def unrolled(self, shape_px: tuple[int, int], scale: float, angles: int, rings: int) -> Unrolled:
        """The maps that unroll a picture ``shape_px`` (height, width; ``scale`` times the
        tracks' picture) on ``rings`` circles out to 1.2 times :attr:`largest`."""
        height, width = shape_px
        radius = np.linspace(0.02, 1.2, max(rings, 8)) * self.largest
        angle = np.arange(angles) * (2.0 * math.pi / angles)
        metric = np.array(self.metric)
        circle = np.stack([np.cos(angle), np.sin(angle)], axis=1) @ metric.T  # (angles, 2)
        flat = np.array(self.centre)[None, None, :] + circle[:, None, :] * radius[None, :, None]
        away = 1.0 - flat @ np.array(self.horizon)
        ahead = away > 1e-3
        picture = flat / np.where(ahead, away, 1.0)[..., None] * scale
        map_x, map_y = picture[..., 0], picture[..., 1]
        inside = ahead & (map_x >= 1) & (map_x < width - 2) & (map_y >= 1) & (map_y < height - 2)
        return Unrolled(np.where(inside, map_x, -10.0).astype(np.float32),
                        np.where(inside, map_y, -10.0).astype(np.float32), inside)


def _largest_radius(width: int, height: int, principal: np.ndarray, focal: float, axis_point: np.ndarray,
                    normal: np.ndarray, e1: np.ndarray, e2: np.ndarray) -> float:
    """The largest radius of the plane the picture shows (its border's points met on the plane),
    at most three picture sides."""
    largest = 0.0
    border = [(0, 0), (width, 0), (0, height), (width, height), (width / 2, 0), (width / 2, height), (0, height / 2),
              (width, height / 2)]
    for x, y in border:
        ray = np.array([(x - principal[0]) / focal, (y - principal[1]) / focal, 1.0])
        facing = float(ray @ normal)
        along = float(axis_point @ normal) / facing if abs(facing) > 1e-9 else -1.0
        if along <= 0:  # past the horizon: the plane runs out of the picture there
            largest = max(largest, 3.0 * max(width, height) / focal)
            continue
        offset = along * ray - axis_point
        largest = max(largest, math.hypot(float(offset @ e1), float(offset @ e2)))
    return min(largest, 3.0 * max(width, height) / focal)


def moving_weight(changes: list[np.ndarray], inside: np.ndarray) -> np.ndarray:
    """The rings where the unrolled picture changes from frame to frame (``changes``: unrolled
    differences of consecutive frames), by more than :data:`MOVING_LEVELS` on average over their
    part inside the picture: 1 there (wherever inside the picture), 0 elsewhere. Whole rings, as
    the body's texture passes every angle of its rings in time (a wheel's one sticker), and what
    stays still within them (a reflection) changes nothing and counts for nothing; where those
    change by about that threshold, with them the rings that change at least :data:`ALONG_SHARE`
    as much, clearly above the picture's noise (see :data:`NEAR_LEVELS`). Where
    fewer than :data:`FEWEST_RINGS` rings move so, those whose rms change stands :data:`SPARSE_MOVING`
    times above the quietest quarter of the rings' (a thin hand on a still face)."""
    mean = np.mean([np.abs(change) for change in changes], axis=0)
    seen = inside.sum(axis=0)
    wide = seen >= 0.1 * inside.shape[0]
    ring_mean = (mean * inside).sum(axis=0) / np.maximum(seen, 1)
    moving = (ring_mean > MOVING_LEVELS) & wide
    typical = float(np.median(ring_mean[moving])) if moving.sum() >= FEWEST_RINGS else math.inf
    if typical < NEAR_LEVELS * MOVING_LEVELS:  # the body changes by about the threshold: its rings
        quiet = float(np.percentile(ring_mean[wide], 25))  # that change a little less count too
        moving |= wide & (ring_mean >= ALONG_SHARE * typical) & (ring_mean > SPARSE_MOVING * quiet)
    if moving.sum() < FEWEST_RINGS and wide.any():
        # nothing moves over much of a ring: a thin moving part (a clock's hand, a few spokes) moves
        # few of each ring's pixels by much, which the rings' rms tells from the picture's noise
        # where their mean does not (a rendered second hand sweeping a still face: its rings' mean
        # changed 0.13 grey levels, the still face's 0.1; their rms 0.8-1.1 against 0.1-0.25)
        ring_rms = np.sqrt((np.mean([change * change for change in changes], axis=0) * inside).sum(axis=0)
                           / np.maximum(seen, 1))
        moving = (ring_rms > SPARSE_MOVING * float(np.percentile(ring_rms[wide], 25))) & wide
    return (inside & moving[None, :]).astype(np.float32)


class RingCorrelations:
    """The normalised correlation of any two of ``unrolled`` pictures (rows: angles) for every
    shift of the second along the angle (``upsample`` samples a row), over the samples ``weight``
    marks in both. Each ring's mean is taken out first: a ring alike at every angle (a record's
    grooves, a plain rim) says nothing of the angle. Shifts where the two overlap on less than a
    fifth of the most score -1. Each picture's spectra along the angle are computed once, not once
    a pair (a chain compares each key change with several; the view's variations dozens of pairs)."""

    def __init__(self, unrolled: list[np.ndarray], weight: np.ndarray, upsample: int = 8,
                 taper: float = 12.0) -> None:
        self._unrolled = unrolled
        self._weight = weight
        self._weight_spectrum = np.fft.rfft(weight, axis=0)
        self._overlap = (np.conj(self._weight_spectrum) * self._weight_spectrum).sum(axis=1)
        angles = weight.shape[0]
        frequency = np.arange(angles // 2 + 1)
        self._smooth = np.exp(-0.5 * (frequency / (angles / taper)) ** 2)
        self._length = angles * upsample
        self._spectra: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    def _of(self, index: int) -> tuple[np.ndarray, np.ndarray]:
        """The ``index``-th picture's spectra: of it less its rings' means, and of that squared."""
        if index not in self._spectra:
            ringless = _ringless(self._unrolled[index], self._weight)
            self._spectra[index] = (np.fft.rfft(ringless, axis=0), np.fft.rfft(ringless * ringless, axis=0))
        return self._spectra[index]

    def __call__(self, first: int, second: int) -> np.ndarray:
        """The correlation of the ``first`` and the ``second`` picture."""
        first_spectrum, first_square = self._of(first)
        second_spectrum, second_square = self._of(second)
        spectra = (self._overlap, (np.conj(first_spectrum) * second_spectrum).sum(axis=1),
                   (np.conj(first_square) * self._weight_spectrum).sum(axis=1),
                   (np.conj(self._weight_spectrum) * second_square).sum(axis=1))
        overlap, product, first_power, second_power = (np.fft.irfft(spectrum * self._smooth, n=self._length)
                                                       for spectrum in spectra)
        correlation = product / np.sqrt(np.maximum(first_power, 1e-9) * np.maximum(second_power, 1e-9))
        correlation[overlap < 0.2 * overlap.max()] = -1.0
        return correlation


def _ringless(unrolled_image: np.ndarray, weight: np.ndarray) -> np.ndarray:
    total = weight.sum(axis=0)
    mean = (unrolled_image * weight).sum(axis=0) / np.maximum(total, 1e-6)
    return (unrolled_image - mean[None, :]) * weight


def _cross(first: np.ndarray, second: np.ndarray) -> np.ndarray:
    """The spectrum of the circular cross-correlation along the angle, summed over the rings."""
    return (np.conj(np.fft.rfft(first, axis=0)) * np.fft.rfft(second, axis=0)).sum(axis=1)


def shift_deg(correlation: np.ndarray, near_deg: float | None = None, within_deg: float = 180.0) -> tuple[float, float]:
    """The shift (degrees, in (-180, 180]) where ``correlation`` peaks, searched within
    ``within_deg`` of ``near_deg`` (None: everywhere), refined between samples; and the peak's height."""
    count = len(correlation)
    shifts = (np.arange(count) * (360.0 / count) + 180.0) % 360.0 - 180.0
    if near_deg is None:
        index = int(np.argmax(correlation))
    else:
        off = (shifts - near_deg + 180.0) % 360.0 - 180.0
        index = int(np.argmax(np.where(np.abs(off) <= within_deg, correlation, -np.inf)))
    before, at, after = correlation[index - 1], correlation[index], correlation[(index + 1) % count]
    curve = before - 2.0 * at + after
    step = 0.5 * (before - after) / curve if curve < 0 else 0.0
    return float(shifts[index] + step * 360.0 / count), float(at)


def second_peak(correlation: np.ndarray, best_deg: float, apart_deg: float) -> tuple[float, float]:
    """The other shift that fits best, more than ``apart_deg`` from ``best_deg`` (degrees, in
    (-180, 180]), and its correlation (-1 where there is none)."""
    count = len(correlation)
    shifts = (np.arange(count) * (360.0 / count) + 180.0) % 360.0 - 180.0
    off = np.abs((shifts - best_deg + 180.0) % 360.0 - 180.0)
    others = np.where(off > apart_deg, correlation, -np.inf)
    index = int(np.argmax(others))
    return (float(shifts[index]), float(others[index])) if np.isfinite(others[index]) else (best_deg, -1.0)


def view_score(pairs: list[tuple[np.ndarray, np.ndarray]], view: DiscView, lags: tuple[int, ...],
               per_lag: int = 2) -> float:
    """How much of the picture's change (``pairs`` of consecutive frames, grey float32, in time
    order) lines up when shifted along the angle through ``view``: for a few changes ``lags``
    apart in the list, the best covariance over the shifts, each sample weighted by the area of the
    picture it stands for, over the two changes' energy in the whole picture (at most about 1). A
    view that lines up a small part of the picture well scores little: normalised over the rings
    it unrolled alone, a corner of the wheel's picture scored above the wheel."""
    count = len(pairs)
    starts = {lag: list(range(0, count - lag, max(1, (count - lag) // per_lag)))[:per_lag] for lag in lags
              if count - lag > 0}
    wanted = sorted({i for lag, firsts in starts.items() for s in firsts for i in (s, s + lag)})
    if not wanted:
        return -1.0
    maps = unrolled(pairs[0][0].shape, view, SEARCH_ANGLES, SEARCH_RINGS)
    area = _sample_area(maps)
    changes = {i: maps.of(pairs[i][1] - pairs[i][0]) for i in wanted}  # (the unrolling is linear)
    energy = {i: float(np.sum((pairs[i][1] - pairs[i][0]) ** 2)) for i in wanted}
    weight = moving_weight(list(changes.values()), maps.inside)
    if weight.sum() < 50:
        return -1.0
    frequency = np.arange(SEARCH_ANGLES // 2 + 1)
    smooth = np.exp(-0.5 * (frequency / (SEARCH_ANGLES / 12.0)) ** 2)
    scores = []
    for lag, firsts in starts.items():
        for first in firsts:
            a = _ringless(changes[first], weight) * area
            b = _ringless(changes[first + lag], weight)
            covariance = np.fft.irfft(_cross(a, b) * smooth, n=SEARCH_ANGLES * 4) * 4
            scores.append(float(covariance.max()) / max(math.sqrt(energy[first] * energy[first + lag]), 1e-9))
    return float(np.mean(scores))


def _sample_area(maps: Unrolled) -> np.ndarray:
    """The picture's area (pixels) each sample of the unrolled picture stands for: the cross
    product of its steps along the angle and along the radius; 0 outside the picture."""
    x, y = maps.map_x.astype(np.float64), maps.map_y.astype(np.float64)
    along_x, along_y = np.gradient(x, axis=0), np.gradient(y, axis=0)
    out_x, out_y = np.gradient(x, axis=1), np.gradient(y, axis=1)
    area = np.abs(along_x * out_y - along_y * out_x)
    return np.where(maps.inside, np.minimum(area, 16.0), 0.0)


@dataclass(frozen=True)
class Candidate:
    """A view found, its score (:func:`view_score`), and whether it was sought about the axis's
    point given or found from the tracks (independent evidence of where the axis is)."""

    view: DiscView
    score: float
    about_given: bool


#: The changes a view lines up are compared this share of the clip's changes apart (and next to
#: each other): a quarter and a half, which pin a short turn's view; an eighth and a quarter, which
#: line a turn's up where a half compares opposite sides of the body, lit and seen differently
#: (the record's 0.95 turn: the view through the farther ones 56 px off its spindle, -2.1% weak;
#: through the nearer, 20 px and +0.3% good; its third of a turn, +6.5% through the nearer).
LAG_SHARES = ((0.25, 0.5), (0.125, 0.25))


#: The start with its other side nearer is taken where it scores this many times as well.
FLIPPED_BETTER = 1.1


def fitted_views(pairs: list[tuple[np.ndarray, np.ndarray]], start: DiscView, step_px: float, search_tilt: bool,
                 search_centre: bool = False, budget: int = 100,
                 lag_shares: tuple[float, ...] = LAG_SHARES[0]) -> list[Candidate]:
    """The views that line the changes of the picture up best (:func:`view_score`), sought from
    ``start`` (moving its centre by about ``step_px``): the best about the given centre, tilted
    freely and face on, and where ``search_centre``, the best few elsewhere (apart from each
    other); each refined, best first. ``search_tilt``: try several tilts and directions first
    (where the tracks tell no view); ``search_centre``: centres over the whole picture (where the
    axis was found, not given: a found axis can lie far from a disc's, the record close-up's 600 px);
    ``lag_shares``: how far apart the changes compared lie (see :data:`LAG_SHARES`)."""
    count = len(pairs)
    lags = tuple(sorted({lag for lag in (1, *(max(2, int(count * share)) for share in lag_shares))
                         if lag < count})) or (1,)
    width = pairs[0][0].shape[1]
    starts = [start]
    if search_tilt:
        starts += [replace(start, tilt_deg=tilt, long_axis_deg=phi) for tilt in (35.0, 55.0, 70.0)
                   for phi in (0.0, 60.0, 120.0)]
    if search_centre:
        height = pairs[0][0].shape[0]
        starts += [replace(start, centre_px=(float(x), float(y)), tilt_deg=tilt, long_axis_deg=phi)
                   for x in np.linspace(0.1, 0.9, 5) * width for y in np.linspace(0.1, 0.9, 3) * height
                   for tilt, phi in ((0.0, 0.0), (55.0, 0.0), (55.0, 60.0), (55.0, 120.0))]
    scored = [(view_score(pairs, view, lags), view) for view in starts]
    near = max((pair for pair in scored if pair[1].centre_px == start.centre_px), key=lambda pair: pair[0])
    if near[1].tilt_deg > 0.0:
        # the other side nearer: through a lens the two are different views, and a search started
        # on the wrong side cannot turn it round, only flatten the lens until the sides look alike
        # (a disc tilted 50 degrees before a 45-degree lens: +1.1% through an orthographic view,
        # its interval missing; through the other side and the lens, -0.0% +-0.6%)
        # (taken where it lines the changes up clearly better: the two score nearly alike where the
        # lens shows the sides alike, and a face-on disc whose paths told a 20-degree tilt, started
        # from the other side on a 6% better score, refined to 8.6 degrees and read +1.5%, missing)
        flipped = replace(near[1], long_axis_deg=near[1].long_axis_deg + 180.0)
        flipped_score = view_score(pairs, flipped, lags)
        if flipped_score > FLIPPED_BETTER * near[0]:
            near = (flipped_score, flipped)
    found = [Candidate(*_refined(pairs, near[1], near[0], step_px, lags, budget), True)]
    if search_tilt:  # the plane face on about the given centre: its centre alone sought
        face_on = replace(start, tilt_deg=0.0, long_axis_deg=0.0)
        found.append(Candidate(*_refined(pairs, face_on, view_score(pairs, face_on, lags), step_px, lags, budget,
                                         face_on=True), True))
    if search_centre:
        # a start that scores best coarsely is not always the one that refines best
        chosen: list[tuple[float, DiscView]] = []
        for score, view in sorted(scored, key=lambda pair: -pair[0]):
            if len(chosen) >= REFINED_STARTS:
                break
            if all(math.dist(view.centre_px, other.centre_px) > 0.1 * width
                   for other in [near[1]] + [v for _, v in chosen]):
                chosen.append((score, view))
        found += [Candidate(*_refined(pairs, view, score, step_px, lags, budget), False) for score, view in chosen]
        if search_tilt:
            # and the plane face on about the best centre elsewhere, its centre alone sought: the
            # freely refined ones can lean away (the rolled wheel's found axis lay 290 px off its
            # hub; refined freely from the grid, 50 degrees tilted and 0.13; face on, at the hub)
            score, view = max(((score, view) for score, view in scored
                               if view.tilt_deg == 0.0 and view.centre_px != start.centre_px), key=lambda pair: pair[0])
            found.append(Candidate(*_refined(pairs, view, score, step_px, lags, budget, face_on=True), False))
    return sorted(found, key=lambda candidate: -candidate.score)


def _refined(pairs: list[tuple[np.ndarray, np.ndarray]], best: DiscView, best_score: float, step_px: float,
             lags: tuple[int, ...], budget: int, face_on: bool = False) -> tuple[DiscView, float]:
    """``best`` refined by a simplex search over its centre, direction, tilt and lens (its centre
    alone, ``face_on``)."""
    from scipy.optimize import minimize  # a well-kept simplex search; imported where used (start-up)

    width = pairs[0][0].shape[1]

    def unpack(x: np.ndarray) -> DiscView:
        if face_on:
            return replace(best, centre_px=(float(x[0]), float(x[1])))
        focal = width * min(math.exp(x[4]), LONGEST_FOCAL)
        return DiscView((float(x[0]), float(x[1])), float(x[2]), float(np.clip(x[3], 0.0, 85.0)), focal)

    x0 = np.array([best.centre_px[0], best.centre_px[1], best.long_axis_deg, best.tilt_deg,
                   math.log(min(best.focal_px / width, LONGEST_FOCAL))])
    steps = (step_px, step_px, 10.0, 10.0, 0.5)
    if face_on:
        x0, steps = x0[:2], steps[:2]
    score, x = best_score, x0
    for _ in range(RESTARTS):  # a simplex search restarted where it stopped: its first can stall
        simplex = [x] + [x + np.eye(len(x))[i] * size for i, size in enumerate(steps)]
        found = minimize(lambda x: -view_score(pairs, unpack(x), lags), x, method="Nelder-Mead",
                         options={"initial_simplex": simplex, "xatol": 0.3, "fatol": 5e-4, "maxfev": budget})
        if not -found.fun > score + 1e-3:
            break
        score, x = float(-found.fun), found.x
    return (unpack(x), score) if score > best_score else (best, best_score)
