"""Several rigid bodies in one clip: with ``--segment``, the tracks grouped by rate and axis
(:mod:`rotrate_cli.fitting.segment`), each group measured as a body of its own (:mod:`rotrate_cli.stages.geometry`),
and groups that measure like a larger body folded into it; without it, what tells that a body other
than the one measured turns (:func:`another_body_seen`)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rotrate_cli.config import AnalysisConfig
from rotrate_cli.errors import NoResultError
from rotrate_cli.fitting.orbits import TurningGroup, another_body
from rotrate_cli.fitting.segment import Body, segment_tracks, unresolved
from rotrate_cli.runtime.lazy import pandas as pd
from rotrate_cli.scene import axis as axes
from rotrate_cli.stages.fits import RateResult
from rotrate_cli.stages.geometry import Geometry, axis_angle, locate, measure
from rotrate_cli.video.frames import VideoInfo


@dataclass(frozen=True)
class MeasuredBodies:
    """The bodies measured, the headline one (most tracks) first.

    Attributes:
        bodies: every body reported.
        geometry, result: the headline body's geometry and rates.
        notes: groups that gave no rate, or were folded into a larger body.
    """

    bodies: tuple[Body, ...]
    geometry: Geometry
    result: RateResult
    notes: tuple[str, ...]


def measure_bodies(tracks: pd.DataFrame, motion_angle_deg: float, config: AnalysisConfig,
                   info: VideoInfo) -> MeasuredBodies:
    """Group ``tracks`` (``frame, time_s, track, x_px, y_px`` sorted by track then frame) into
    rigid bodies and measure each.

    Raises:
        NoResultError: no group could be measured.
    """
    size_px = (info.width_px, info.height_px)
    angle = axis_angle(tracks, motion_angle_deg, config)[0]
    ux, uy = axes.unit_offset(angle)
    extent_px = abs(size_px[0] * ux) + abs(size_px[1] * uy)
    groups = segment_tracks(tracks, axes.offsets_along(tracks, (0.0, 0.0), angle), extent_px)
    track = tracks["track"].to_numpy()
    measured = []
    for ids in groups:
        part = tracks[np.isin(track, ids)].reset_index(drop=True)
        try:
            geometry, body = locate(part, motion_angle_deg, config, info, seek_lens=False)
            geometry, result = measure(body, geometry, config, size_px)
        except NoResultError:
            continue
        if result.combined.tracks_used > 0:
            measured.append((geometry, result, len(ids)))
    if not measured:
        raise NoResultError(f"no rigid body could be measured ({len(groups)} group(s) of tracks found); "
                            "try a longer clip or `roi` around one object")
    notes = []
    skipped = len(groups) - len(measured)
    if skipped:
        notes.append(f"{skipped} group(s) of tracks gave no trustworthy rate and are not reported")
    measured, folded = distinct_bodies(measured, ux, uy, extent_px)
    if folded:
        notes.append(f"{folded} smaller group(s) of tracks measured like a larger body (rate and axis within "
                     "the resolution) and are not reported as bodies of their own")
    bodies = tuple(
        Body(r.combined.omega_rad_s, r.combined.omega_low_rad_s, r.combined.omega_high_rad_s,
             g.fixation_px, r.direction, r.combined.tracks_used, total)
        for g, r, total in measured
    )
    geometry, result, _ = measured[0]
    return MeasuredBodies(bodies, geometry, result, tuple(notes))


def distinct_bodies(measured: list, ux: float, uy: float, extent_px: float) -> tuple[list, int]:
    """The measured bodies ``(geometry, result, tracks)`` (largest group first) without those whose
    measured rate and axis lie within the resolution of a larger one
    (:func:`rotrate_cli.fitting.segment.unresolved`), and how many were left out. Grouping works on each
    track's own rough estimates; a group of mis-tracks along an outline can look apart there and
    measure like the body it borders: seen on a 32 s 720p cylinder, 57 rim tracks (1% of them)
    measured 1.27 rad/s about an axis 8 px from the body's 1.57."""
    kept: list = []
    for entry in measured:
        fixation, result = entry[0].fixation_px, entry[1]
        axis_px = fixation[0] * ux + fixation[1] * uy
        if not any(unresolved(result.combined.omega_rad_s, axis_px, other[1].combined.omega_rad_s,
                              other[0].fixation_px[0] * ux + other[0].fixation_px[1] * uy, extent_px)
                   for other in kept):
            kept.append(entry)
    return kept, len(measured) - len(kept)


@dataclass(frozen=True)
class AnotherBody:
    """A body other than the one measured, seen turning at another rate about another axis.

    Attributes:
        group: its tracks' orbits (:class:`rotrate_cli.fitting.orbits.TurningGroup`).
        note: what the user is told.
        weak_because: why the result is weak for it ("" where the user gave the axis: the body
            measured is the one meant).
    """

    group: TurningGroup
    note: str
    weak_because: str


def another_body_seen(groups: tuple[TurningGroup, ...], omega_rad_s: float, fixation_px: tuple[float, float],
                      fixation_given: bool) -> AnotherBody | None:
    """Whether the tracks' orbits (``groups``, :func:`rotrate_cli.fitting.orbits.turning_groups`) show
    a body other than the one measured (``omega_rad_s`` about ``fixation_px``). Where the axis was
    found, not given, which of the two the user meant is not known: the result is weak for it
    (two discs side by side, 1.0 and 1.6 rad/s: the faster one's return read 1.600, good, with no
    word of the other). None where no other body shows."""
    other = another_body(groups, omega_rad_s, fixation_px)
    if other is None:
        return None
    x, y = other.centre_px
    measured = (f"the rate reported is the body's about ({fixation_px[0]:.0f}, {fixation_px[1]:.0f}) px"
                if all(math.isfinite(v) for v in fixation_px) else "the rate reported is another's")
    # `roi` keeps the other body's points out of the fits: seen from the side, its tracks' arcs about
    # an axis given at the other one fit slow rates that pass the rejection (the two-bodies sample
    # about the cylinder's axis: 0.30 rad/s, weak, for 1.2; with `roi` around it, 1.2006, good)
    note = (f"another body turns in the picture: about {other.omega_rad_s:.3g} rad/s about ({x:.0f}, {y:.0f}) px, "
            f"from {other.tracks} tracks going round it; {measured}; `roi` around the one meant keeps the "
            "other's points out, and `segment` measures each")
    because = "" if fixation_given else ("two bodies turn at different rates, and which one is meant is not "
                                         "known: give the axis of the one meant, and `roi` around it")
    return AnotherBody(other, note, because)

