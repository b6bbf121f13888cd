"""The picture's own turning angle as a stage: where it is sought (not in the tracks' side view),
from which view of the plane, and omega(t) from it per window. The measurement itself is
:mod:`rotrate_cli.scene.picture_angle`; the verdict weighs it (:mod:`rotrate_cli.stages.verdict`)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace

import numpy as np

from rotrate_cli.fitting.outliers import Combined
from rotrate_cli.runtime.lazy import pandas as pd
from rotrate_cli.scene import hand
from rotrate_cli.scene.backdrop import backdrop_path
from rotrate_cli.scene.disc import DiscView
from rotrate_cli.scene.picture_angle import PictureAngle, measure_angle, rate_through_map, window_rates
from rotrate_cli.scene.plane_turn import keep_for_plane, placed_for_plane, plane_from
from rotrate_cli.scene.sense import not_side_view
from rotrate_cli.scene.view import view_from_paths
from rotrate_cli.stages.geometry import Geometry
from rotrate_cli.stages.tracks import Footage
from rotrate_cli.stages.verdict import MIN_TRACKS, WEAK_HALF_WIDTH
from rotrate_cli.stages.windows import AngleWindows


def picture_angle(footage: Footage, geometry: Geometry, view_tracks: pd.DataFrame | None,
                  tracks: Combined | None) -> PictureAngle | None:
    """The picture's own turning angle (:mod:`rotrate_cli.scene.picture_angle`), where the picture
    can turn: not in a side view as the tracks' paths tell it (where they tell no view, the
    picture's own changes decide: an edge-on plane is no measurement). Its plane's view is sought
    from the tracks' paths' (their centre and ellipse, at the tracks' rate) where they tell one,
    else from the fixation, every tilt tried."""
    rate = tracks.omega_rad_s if tracks is not None and 0 < tracks.omega_rad_s < math.inf else math.nan
    view = None
    if view_tracks is not None and len(view_tracks) > 0:
        view = view_from_paths(view_tracks, rate) if math.isfinite(rate) else None
        if view is not None and not not_side_view(view, view_tracks):
            # seen from the side (as the paths tell) the picture does not turn; a flat face seen
            # nearly edge on looks alike, and where the tracks do not hold, they may be one plane
            return None if _tracks_hold(tracks) else _tracks_plane(footage, footage.pairs.angle_frames.frames)
        if view is not None and view.elevation_deg < NEARER_SIDE_DEG and _tracks_hold(tracks):
            # nearer the side than face on, and the tracks agree closely: the paper's own case, where
            # the picture turns little (a cylinder seen from 15 degrees above: a search of 10 s
            # that found no plane)
            return None
    # (no track at all tells no view: the picture's own changes are the only evidence)
    width = footage.info.width_px
    kept = footage.pairs.angle_frames.frames
    # a thin part turning over a still picture (a clock's hand) first: quick, and where it reads a
    # rate closely, the picture's changes (a few hand pixels, or none between a ticking hand's
    # steps) have no more to say
    thin = hand.measure_hand(kept, width, steadied=footage.shake is not None)
    if thin is not None and _half_width(thin) <= WEAK_HALF_WIDTH:
        return thin
    middle = (width / 2.0, footage.info.height_px / 2.0)
    if view is not None:
        start = DiscView(view.centre_px, view.across_deg, 90.0 - view.elevation_deg, float(width))
    else:
        centre = geometry.fixation_px
        if not (math.isfinite(centre[0]) and math.isfinite(centre[1])):
            centre = middle
        start = DiscView(centre, 0.0, 0.0, float(width))
    # where nothing still shows the camera's own motion, the picture's turning is the body's and the
    # camera's: its circles would narrow that sum (the wheel under a camera rolling 3 degrees a
    # second, 0.3 of a turn: -2.5% within +-2.1%, good, missing)
    circles = not footage.background_unseen
    changes = measure_angle(kept, start, width, search_tilt=view is None,
                            search_centre=view is None and geometry.fixation_found, circles=circles)
    if (view is None and geometry.fixation_found and not _tracks_hold(tracks) and start.centre_px != middle
            and (changes is None or _half_width(changes) > WEAK_HALF_WIDTH)):
        # an axis found from tracks that do not hold together may lie anywhere (one track in a
        # corner of a wheel shrunk to 0.6 its size): where no view about it tells the rate closely,
        # the view is sought about the picture's middle too, face on and tilted, and the reading
        # through the view whose changes line up better is taken (that wheel, 0.9 of a turn from
        # 8 s: about its one track's axis no view told a rate, and the result was that track's,
        # 96% low, weak; about the middle -1.0%). (Sought wherever the tracks do not hold, the
        # search doubled the time of the wheel's first 2.5 s, read closely about its axis already.)
        about_middle = measure_angle(kept, DiscView(middle, 0.0, 0.0, float(width)), width, search_tilt=True,
                                     search_centre=True, circles=circles)
        changes = max((reading for reading in (changes, about_middle) if reading is not None),
                      key=lambda reading: reading.score, default=None)
    # the tracks as one plane turning, through no view (a printed face turning before a short
    # lens, its axis out of the frame, where the view found from the picture is loose)
    plane = _tracks_plane(footage, kept)
    if plane is not None and plane.camera_turn_deg_s:
        return plane  # the other readings are of the picture as the turning camera saw it
    readings = [reading for reading in (thin, changes, plane) if reading is not None]
    return min(readings, key=_half_width) if readings else None


def _tracks_plane(footage: Footage, kept: list[tuple[int, float, np.ndarray]]) -> PictureAngle | None:
    """The tracks as one plane turning (:func:`rotrate_cli.scene.plane_turn.plane_angle`), as the
    picture's changes bear it out (:func:`_weighed`); None where they show none.

    Where nothing in the picture stays still and its rim moves (``footage.background_unseen``),
    the picture around the plane tells whether the camera turned (:mod:`rotrate_cli.scene.backdrop`);
    where it did, the plane is read again with the camera's motion taken out of its tracks, and
    its changes with the camera's turn taken out of them."""
    samples = (footage.plane_tracks if footage.plane_tracks is not None
               else keep_for_plane(footage.tracks, footage.keyframes.indices()))
    placed = placed_for_plane(samples, footage.keyframes)
    plane = plane_from(samples, placed)
    if plane is None:
        return None
    if footage.background_unseen and plane.plane_map is not None and len(footage.keyframes) > 0:
        frames = samples.groupby("frame")["time_s"].first()
        frames = frames[footage.keyframes.has(frames.index.to_numpy())]
        path = backdrop_path(footage.keyframes, frames.index.to_numpy(), frames.to_numpy(), plane.plane_map)
        steadied = plane_from(samples, placed, path.steady) if path is not None else None
        if path is not None and steadied is not None:
            start_s = min(time_s for _, time_s, _ in kept) if kept else 0.0
            kept = footage.pairs.angle_frames.turned_back(path.turn_deg_s, start_s).frames
            plane = replace(steadied, camera_turn_deg_s=path.turn_deg_s)
    return _weighed(plane, kept, footage.info.width_px)


#: The plane's tracks slide on a turning picture (see :func:`_weighed`): its rate moved by 0.4-0.85%
#: on face-on renders of real photographs. Where its interval's half is narrower than this share of
#: its rate, the slide matters, and the picture's changes through it give the rate; where wider,
#: the interval holds the slide, and the plane is loosely known, so the changes through it are no
#: better (printed discs before a 45-degree lens, their axis out of the frame, tilted 45 and 60
#: degrees: their planes -0.17% within +-2.4% and -0.21% within +-1.4%, the changes through them
#: -1.1% and -2.0%).
SLIDING = 0.01

#: The picture's changes unrolled through the plane bear it out within this share of its rate,
#: however closely each is read: they are its check (that the tracks' plane is the body's), not its
#: measure. On 17 renders of real photographs turning face on and tilted, their rate lay 0.02-0.3%
#: from the plane's read from tracks placed again (:func:`rotrate_cli.scene.plane_turn.plane_angle`),
#: each reading's interval as narrow as +-0.01-0.1%; 1.9% where the axis lay 160 px below the frame.
#: Tracks that follow something else read 16% or more from them (see :func:`_weighed`).
BORNE_OUT = 0.03

#: Where the picture's changes through the plane turn at least this many times as far as its tracks
#: do (short tracks: dust on a record), theirs is the rate, within an interval holding both: a record
#: rendered tilted 30 degrees, 0.3 of a turn, its plane from tracks over 20 degrees read +0.77%
#: within +-0.5% (good, missing), its changes through it over 99 degrees -0.99% within +-0.3%; tilted
#: 50 degrees, 0.6 of a turn, its plane over 61 degrees -11.4% within +-11%, the changes over 212
#: degrees -0.6% within +-2.8%.
FARTHER_TURNED = 2.0

#: A plane the picture's changes bear out only loosely is still a reading (weak, its interval
#: holding theirs) where that interval's larger half is within this share of its rate: printed
#: discs tilted 40 and 65 degrees, +-11% and +-6.5%; an EPFL car's side on its turntable, whose
#: points fit a plane only loosely (the car is no plane; its one-point fits are the model), +-40%
#: and +-43% (its photographs 0-29 and 45-74: from the plane +1.1% and +22%, from the tracks
#: -1.2% and +0.4%).
LOOSE_PLANE = 0.25


def _weighed(plane: PictureAngle, kept: list[tuple[int, float, np.ndarray]], width_px: int) -> PictureAngle | None:
    """The tracks' plane as the picture's own changes, unrolled through it
    (:func:`rotrate_cli.scene.picture_angle.rate_through_map`), bear it out: as it is where they
    turn at its rate within the two intervals; where they turn at another rate, or tell one only
    loosely, a loose reading (weak) whose interval holds both; None where they tell none through
    it, or one too far off (:data:`LOOSE_PLANE`).

    Tracks can follow something other than the body and fit one plane turning all the same (a
    flat spoked wheel over a textured floor: its tracks, the floor's points dragged along by the
    thin spokes, read -16%, the picture through their plane 34% faster, within +-18%): too loose to
    be a reading (:data:`LOOSE_PLANE`). The changes are read no more closely than the plane they
    are unrolled through is known (its interval's half at least): a printed disc tilted 45
    degrees read +0.2% +-0.9% from its tracks, -0.75% +-0.1% from its changes through their plane.
    Changes that tell no rate of their own through the plane (their interval wider than the weak
    one) bear nothing out: a box seen from 60 degrees above, its top's tracks read -1.3% +-1.1%,
    missing, where the box's sides change the picture as no plane's turn. Where the other
    readings are looser still, a loose plane is the closest evidence there is: printed discs
    before a 45-degree lens, their axis out of the frame and tilted 40 and 65 degrees, read +1.0%
    and +0.2% from their planes (the changes through them -3.6% +-7% and -3.5% +-3%), against
    +43% and +34% from the picture's changes through the view their paths tell, intervals missing.

    Where the changes bear the plane out and tell its turn more closely, and the plane is known within
    :data:`SLIDING`, theirs is the rate (and the angles, for omega(t)), within the plane's interval (the
    view they are unrolled through is known no better): Lucas-Kanade follows a window by its translation
    alone, and on a turning picture each step misses by the turn times the offset of the window's
    texture from its centre, so the tracks slide (:mod:`rotrate_cli.scene.patches`). A car photograph
    turning face on, 0.4 of a turn at 1.2 rad/s: its tracks' steps about the true axis read a median
    -0.4% (-3% to +8% by radius), the plane's pairs -0.50% within [-0.89%, -0.11%] (missing, good), the
    changes through it +0.01% within +-0.08%."""
    if plane.plane_map is None:
        return None
    seen = rate_through_map(kept, plane.plane_map, width_px)
    if seen is None:
        return None
    rate, half = seen.omega_rad_s, seen.half_rad_s
    plane_half = 0.5 * (plane.omega_high_rad_s - plane.omega_low_rad_s)
    apart = max(math.hypot(max(half, plane_half), plane_half), BORNE_OUT * plane.omega_rad_s)
    borne_out = abs(rate - plane.omega_rad_s) <= apart
    if half <= WEAK_HALF_WIDTH * rate and seen.turned_deg >= FARTHER_TURNED * plane.turned_deg:
        # the changes through the plane see the body turn much farther than its tracks do: theirs
        # is the rate, read no more closely than the plane they are unrolled through is known, within
        # an interval that also holds the plane's reading
        wide = max(half, plane_half)
        low, high = min(plane.omega_low_rad_s, rate - wide), max(plane.omega_high_rad_s, rate + wide)
        farther = replace(plane, omega_rad_s=rate, omega_low_rad_s=max(0.0, low), omega_high_rad_s=high,
                          times_s=seen.times_s, angles_deg=seen.angles_deg, turned_deg=seen.turned_deg,
                          plane_changes=True)
        if not borne_out:
            farther = replace(farther, doubt=f"the plane the tracks turn as one, seen over {plane.turned_deg:.0f} "
                                             f"degrees, turns at {plane.omega_rad_s:.4g} rad/s: it bears out the "
                                             f"picture's own changes through it, over {seen.turned_deg:.0f}, only "
                                             "loosely")
        return farther if _half_width(farther) <= LOOSE_PLANE else None
    if half <= WEAK_HALF_WIDTH * rate and borne_out:
        if half < plane_half < SLIDING * plane.omega_rad_s and not plane.plane_placed:
            # they bear it out and tell its turn more closely, and the plane is known closely
            # enough for its tracks' slide to matter: theirs is the rate, the tracks' plane its
            # view (see below)
            return replace(plane, omega_rad_s=rate, omega_low_rad_s=max(0.0, rate - plane_half),
                           omega_high_rad_s=rate + plane_half, times_s=seen.times_s, angles_deg=seen.angles_deg,
                           turned_deg=seen.turned_deg, plane_changes=True)
        return plane
    low, high = min(plane.omega_low_rad_s, rate - half), max(plane.omega_high_rad_s, rate + half)
    loose = replace(plane, omega_low_rad_s=max(0.0, low), omega_high_rad_s=high,
                    doubt=f"the picture's own changes, unrolled through the plane the tracks turn as one, turn at "
                          f"{rate:.4g} rad/s within +-{half:.2g}: they bear out its {plane.omega_rad_s:.4g} rad/s only "
                          "loosely")
    return loose if _half_width(loose) <= LOOSE_PLANE else None


def _half_width(angle: PictureAngle) -> float:
    """The larger half of the reading's interval, as a share of its rate."""
    half = max(angle.omega_rad_s - angle.omega_low_rad_s, angle.omega_high_rad_s - angle.omega_rad_s)
    return half / angle.omega_rad_s


#: A view whose axis lies nearer the image plane than this (degrees out of it, as the paths tell)
#: is the tracks' where they agree (:func:`_tracks_hold`): the picture's angle is not sought there.
#: (At 45, a disc seen 45 degrees from face on, its paths telling 44.9, read -0.52% from its
#: tracks; its picture's turning reads +0.10% within +-0.2%. The dinosaur's photographs, whose
#: paths tell 27-29, stay with their tracks.)
NEARER_SIDE_DEG = 35.0


def _tracks_hold(tracks: Combined | None) -> bool:
    """True where the tracks' rate is good evidence by the verdict's rules: enough tracks, and an
    interval within :data:`rotrate_cli.stages.verdict.WEAK_HALF_WIDTH` of it."""
    if tracks is None or tracks.tracks_used < MIN_TRACKS or not 0 < tracks.omega_rad_s < math.inf:
        return False
    half = max(tracks.omega_rad_s - tracks.omega_low_rad_s, tracks.omega_high_rad_s - tracks.omega_rad_s)
    return half <= WEAK_HALF_WIDTH * tracks.omega_rad_s


def angle_windows(footage: Footage, angle: Callable[[], PictureAngle | None]) -> AngleWindows:
    """omega(t) per window from the picture's own angle (measured here if the verdict did not),
    for :func:`rotrate_cli.stages.windows.judged_series`."""

    def rates(centres_s: np.ndarray, window_s: float) -> list[tuple[float, float, float] | None]:
        measured = angle()
        if measured is None:
            return [None] * len(centres_s)
        if measured.thin_part or measured.plane:
            return hand.window_rates(measured, centres_s, window_s)
        return window_rates(footage.pairs.angle_frames.frames, measured, footage.info.width_px, centres_s, window_s)

    return rates
