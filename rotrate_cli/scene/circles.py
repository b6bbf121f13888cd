"""A turning plane's view from its circles: a record's grooves, bands, label and rim, a wheel's rim
and tyre, a clock's bezel, a platter's edge. Circles about the axis, seen through the right view,
unroll to straight rings: the picture's profile along the radius is the same at every angle. So the
view (the axis's point, the tilt and its direction, the lens) is the one through which the
derivative along the radius, averaged over the angles, keeps most of its energy
(:func:`coherence`, 1 where every angle's profile is the same).

The picture's changes (:mod:`rotrate_cli.scene.picture_angle`) hold a view loosely under a turn:
a rendered record tilted 50 degrees, a third of a turn, was read through a view tilted 48 degrees
through a 392-px lens (the truth 1,152), and its rate's interval was +-16%. Its circles held the
tilt to 0.02 degrees and the lens to 3%, and the changes lined up better through that view (0.94
against 0.82). Where the circles do not tell one view (a close-up that shows a short arc of the
record: several views nearly as coherent, whose rates differ), none is taken.

What is unrolled is the mean of the frames kept: what turns with the body (a label's print, dust)
is smeared along its circles and what stays put (the circles) is kept. How closely the circles
hold the view: as far as they line up within :data:`DROP` of the best, along each principal
direction of the coherence's curvature.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import cv2
import numpy as np

from rotrate_cli.scene.disc import DiscView, unrolled

#: The picture is unrolled at this many angles a turn and rings.
ANGLES = 120
RINGS = 200
#: The picture is smoothed first by this share of its width (a pixel of the 320-px frames kept).
SMOOTHING_SHARE = 1.0 / 320.0
#: Rings seen at fewer than this share of the angles are left out.
SEEN_SHARE = 0.1
#: A view whose coherence is under this tells nothing (a textured disc with no circle: 0.05-0.2;
#: the rendered records 0.9, the shared record and wheel 0.5).
MIN_COHERENCE = 0.5
#: Other starts' views as coherent as this share of the best are its rivals: the circles do not
#: tell one view where their rates differ.
RIVALS = 0.85
#: The lenses the search starts from besides the one given, in picture widths (a 45-degree lens,
#: a long one): the coherence has separate peaks along the lens (from the record's 392 px, a peak
#: at 0.41 and the truth's at 0.79).
START_FOCAL_WIDTHS = (1.2, 3.0)
#: The lenses searched, in picture widths (as :mod:`rotrate_cli.scene.picture_angle` reads a view
#: through: the shared record's circles lined up best through a 34-px lens, 160 degrees across),
#: and the most tilt.
SHORTEST_FOCAL = 0.3
LONGEST_FOCAL = 20.0
MOST_TILT_DEG = 80.0
#: The search's first moves: the axis's point (px), the tilt's two components (degrees), the lens
#: (its logarithm); and its tolerance and most evaluations.
SIMPLEX = (2.0, 2.0, 2.0, 2.0, 0.2)
TOLERANCE = 0.01
MOST_EVALUATIONS = 300
#: Every start is searched coarsely first (angles, rings; evaluations), and the best again in
#: full; the others whose coarse coherence comes near it (:data:`RIVALS`) are its rivals.
COARSE = (60, 150)
COARSE_EVALUATIONS = 120
#: How far the circles hold the view: to where they line up this share less well than through the
#: view found, along each principal direction of the coherence's curvature (measured by central
#: differences of these steps: the axis's point, px of the picture searched; the tilt's
#: components, degrees; the lens's logarithm), at most this many steps.
DROP = 0.15
HESSIAN_STEPS = (0.25, 0.25, 0.25, 0.25, 0.02)
FARTHEST = 16.0


#: Where nothing else tells a view to start from, the circles' pictures do: ellipses fitted to the
#: edges of the picture (contours at least this share of its width long, their points within this
#: many pixels of the ellipse, its short axis at least this share of the width and this share of
#: its long one: a plane tilted 80 degrees at most), the longest this many.
ELLIPSE_LENGTH_SHARE = 0.1
ELLIPSE_WITHIN_PX = 1.0
ELLIPSE_SHORTEST_SHARE = 0.03
ELLIPSE_FLATTEST = math.cos(math.radians(MOST_TILT_DEG))
ELLIPSE_STARTS = 3


@dataclass(frozen=True)
class CircleView:
    """The view the circles tell, and how closely.

    Attributes:
        view: the view (the picture's pixels, as searched).
        coherence: how well its circles line up (1 at best).
        held: the view moved each way as far as the circles hold it (:func:`_held`).
        rivals: other views nearly as coherent (:data:`RIVALS`), found coarsely from other starts.
    """

    view: DiscView
    coherence: float
    held: tuple[DiscView, ...]
    rivals: tuple[DiscView, ...]


def _unrolled_derivative(image: np.ndarray, view: DiscView, angles: int = ANGLES,
                         rings_: int = RINGS) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """The picture unrolled through ``view``, differenced along the radius: the derivative, where
    it is seen, and which rings are seen widely enough; None where none is."""
    maps = unrolled(image.shape, view, angles, rings_)
    flat = cv2.remap(image, maps.map_x, maps.map_y, cv2.INTER_LINEAR)
    seen = maps.inside[:, 1:] & maps.inside[:, :-1]
    derivative = np.where(seen, np.diff(flat, axis=1), 0.0)
    rings = seen.sum(axis=0) >= SEEN_SHARE * angles
    if not rings.any():
        return None
    return derivative[:, rings], seen[:, rings], rings


def coherence(image: np.ndarray, view: DiscView, coarse: bool = False) -> float:
    """How alike the picture's profile along the radius is at every angle through ``view``: the
    energy of the angles' mean derivative over the mean energy of theirs (1: every angle alike;
    about 1/angles where nothing is circular). ``coarse``: at fewer angles and rings
    (:data:`COARSE`)."""
    unrolled_ = _unrolled_derivative(image, view, *(COARSE if coarse else (ANGLES, RINGS)))
    if unrolled_ is None:
        return 0.0
    derivative, seen, _ = unrolled_
    counts = seen.sum(axis=0)
    sums = derivative.sum(axis=0)
    energy = float((derivative ** 2).sum())
    return float((sums ** 2 / np.maximum(counts, 1)).sum()) / energy if energy > 0 else 0.0


def _view_of(params: np.ndarray) -> DiscView:
    """The view of the search's unknowns: the axis's point, the tilt's components along the
    picture's x and y (degrees), the lens's logarithm."""
    x, y, a, b, log_focal = (float(value) for value in params)
    return DiscView((x, y), math.degrees(math.atan2(b, a)) if (a or b) else 0.0, math.hypot(a, b), math.exp(log_focal))


def _params_of(view: DiscView) -> np.ndarray:
    phi = math.radians(view.long_axis_deg)
    return np.array([view.centre_px[0], view.centre_px[1], view.tilt_deg * math.cos(phi),
                     view.tilt_deg * math.sin(phi), math.log(view.focal_px)])


def _search(image: np.ndarray, start: DiscView, coarse: bool = False) -> tuple[DiscView, float]:
    """The most coherent view near ``start`` (Nelder-Mead), and its coherence; ``coarse``: in
    fewer steps, at fewer angles and rings."""
    from scipy.optimize import minimize  # imported here: it weighs on every run's start otherwise

    shortest, longest = math.log(SHORTEST_FOCAL * image.shape[1]), math.log(LONGEST_FOCAL * image.shape[1])

    def cost(params: np.ndarray) -> float:
        if not shortest <= params[4] <= longest or math.hypot(params[2], params[3]) > MOST_TILT_DEG:
            return 0.0  # no lens a camera has, or a plane edge on
        return -coherence(image, _view_of(params), coarse)

    first = _params_of(start)
    first[4] = min(max(first[4], shortest), longest)
    simplex = np.array([first] + [first + np.eye(5)[k] * step for k, step in enumerate(SIMPLEX)])
    found = minimize(cost, first, method="Nelder-Mead",
                     options={"initial_simplex": simplex, "xatol": TOLERANCE, "fatol": 1e-4,
                              "maxfev": COARSE_EVALUATIONS if coarse else MOST_EVALUATIONS})
    return _view_of(found.x), float(-found.fun)


def _held(image: np.ndarray, view: DiscView, best: float) -> tuple[DiscView, ...]:
    """The views at the ends of the region about ``view`` (coherence ``best``) where the circles
    line up within :data:`DROP` of it: along each principal direction of the coherence's curvature
    (so along the valleys where the axis's point, the tilt and the lens trade off), or
    :data:`FARTHEST` steps along those in which it does not fall."""
    first = _params_of(view)
    steps = np.array(HESSIAN_STEPS)

    def value(units: np.ndarray) -> float:
        return coherence(image, _view_of(first + units * steps))

    count = len(first)
    hessian = np.zeros((count, count))
    for i in range(count):
        unit_i = np.eye(count)[i]
        hessian[i, i] = value(unit_i) - 2.0 * best + value(-unit_i)
        for j in range(i):
            unit_j = np.eye(count)[j]
            hessian[i, j] = hessian[j, i] = 0.25 * (value(unit_i + unit_j) - value(unit_i - unit_j)
                                                    - value(unit_j - unit_i) + value(-unit_i - unit_j))
    curvature, directions = np.linalg.eigh(-hessian)
    held = []
    for k in range(count):
        extent = math.sqrt(2.0 * DROP * best / curvature[k]) if curvature[k] > 0 else FARTHEST
        for sign in (1.0, -1.0):
            held.append(_view_of(first + sign * min(extent, FARTHEST) * directions[:, k] * steps))
    return tuple(held)


@dataclass(frozen=True)
class Start:
    """A view to start the circles' search from; ``in_picture``: only views whose axis lies in the
    picture are taken from it (a start from an ellipse: see :func:`circle_view`)."""

    view: DiscView
    in_picture: bool = False


#: The screened views searched in full, at most (the next where the first breaks its start's rule
#: or lines no circle up).
FULL_SEARCHES = 2


def circle_view(image: np.ndarray, starts: list[Start]) -> CircleView | None:
    """The view ``image`` (grey, float32: the mean of a clip's frames) shows its circles through:
    every start searched coarsely, from it and through other lenses (:data:`START_FOCAL_WIDTHS`),
    and the most coherent view so screened searched again in full; None where no view lines
    circles up (:data:`MIN_COHERENCE`). The other screened views nearly as coherent
    (:data:`RIVALS`) are its rivals. Screening every start before one full search costs a quarter
    less than searching each in full (four starts on a rendered record's third of a turn: 1.99 ->
    1.56 s)."""
    rows, columns = image.shape
    width = columns
    # fine grooves sampled by the rings alias: the coherence then rises and falls along the lens
    # every 15% (a rendered record's 3-px grooves: peaks at 800 and 920 px, the truth 768)
    image = cv2.GaussianBlur(image, (0, 0), SMOOTHING_SHARE * width)

    def allowed(view: DiscView, start: Start) -> bool:
        return not start.in_picture or (0 <= view.centre_px[0] <= columns - 1 and 0 <= view.centre_px[1] <= rows - 1)

    screened: list[tuple[DiscView, float, Start]] = []
    for start in starts:
        first = start.view
        lenses = [first.focal_px] + [widths * width for widths in START_FOCAL_WIDTHS
                                     if abs(math.log(widths * width / first.focal_px)) > 0.2]
        # the tilt either way about its long axis: seen from far off, a circle tilted towards the
        # camera at its top and one tilted at its bottom look alike, and the search does not cross
        # from one to the other (the rendered record's changes told the wrong one; through it its
        # circles lined up at 0.58 against 0.90, and the rate read +12%)
        for focal in lenses:
            for turn in (0.0, 180.0):
                view, value = _search(image, replace(first, focal_px=focal, long_axis_deg=first.long_axis_deg + turn),
                                      coarse=True)
                if allowed(view, start):
                    screened.append((view, value, start))
    screened.sort(key=lambda item: -item[1])
    for top_view, top, start in screened[:FULL_SEARCHES]:
        best, best_coherence = _search(image, top_view)
        if best_coherence < MIN_COHERENCE or not allowed(best, start):
            continue
        rivals = tuple(view for view, value, _ in screened if view is not top_view and value >= RIVALS * top)
        return CircleView(best, best_coherence, _held(image, best, best_coherence), rivals)
    return None


def ellipse_starts(image: np.ndarray) -> list[DiscView]:
    """Views to start :func:`circle_view` from where nothing else tells one: each of the longest
    ellipses the picture's edges draw (:data:`ELLIPSE_STARTS`), seen as a circle tilted by the
    arc cosine of its short axis over its long one, about its long axis, through a 45-degree lens
    (the search moves the axis's point off the ellipse's centre, where the lens draws it off).
    ``image``: grey, float32 (the mean of a clip's frames)."""
    width = image.shape[1]
    smooth = cv2.GaussianBlur(image, (0, 0), 1.0)
    levels = cv2.normalize(smooth, None, 0, 255, cv2.NORM_MINMAX).astype(np.uint8)
    contours, _ = cv2.findContours(cv2.Canny(levels, 30, 90), cv2.RETR_LIST, cv2.CHAIN_APPROX_NONE)
    found = []
    for contour in contours:
        if len(contour) < ELLIPSE_LENGTH_SHARE * width:
            continue
        (x, y), (first, second), angle = cv2.fitEllipse(contour)
        long_, short = max(first, second) / 2.0, min(first, second) / 2.0
        if short < ELLIPSE_SHORTEST_SHARE * width or short < ELLIPSE_FLATTEST * long_ or long_ > 3.0 * width:
            continue
        along = math.radians(angle if first >= second else angle + 90.0)
        points = contour[:, 0, :].astype(np.float64) - (x, y)
        u = points[:, 0] * math.cos(along) + points[:, 1] * math.sin(along)
        v = -points[:, 0] * math.sin(along) + points[:, 1] * math.cos(along)
        if float(np.median(np.abs(np.hypot(u / long_, v / short) - 1.0))) * short > ELLIPSE_WITHIN_PX:
            continue  # no ellipse: a contour that only roughly closes
        found.append((len(contour), DiscView((x, y), math.degrees(along) % 180.0,
                                             math.degrees(math.acos(min(1.0, short / long_))),
                                             START_FOCAL_WIDTHS[0] * width)))
    found.sort(key=lambda item: -item[0])
    return [view for _, view in found[:ELLIPSE_STARTS]]
