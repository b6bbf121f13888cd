"""Reports of an :class:`~rotrate_cli.analysis.Analysis`: Table I CSV, JSON, and a rich table.

The CSV has one row per feature per sample, in the reference paper's Table I layout:
``feature, frame, time_s, y_<unit>, dy_dt, d2y_dt2, omega2, omega, inlier, reason`` where ``y`` is
the horizontal offset from the fixation point (the paper's y), ``omega`` in rad/s.
"""

from __future__ import annotations

import io
import json
import math
from collections import Counter
from dataclasses import replace
from pathlib import Path
from typing import Any
from xml.etree import ElementTree as ET

from rich.console import Console
from rich.table import Table

from rotrate_cli.analysis import Analysis
from rotrate_cli.batch import Outcome, summary_frame
from rotrate_cli.runtime.choices import FORMATS  # noqa: F401 - re-exported
from rotrate_cli.runtime.lazy import pandas as pd

TABLE_ROWS = 25  # features listed in the terminal table; the CSV and JSON have them all


def _elevation_text(analysis: Analysis) -> str:
    """The camera's found elevation: its sign is told only where perspective was seen."""
    if analysis.focal is not None and math.isfinite(analysis.focal.focal_px):
        looking = "down on" if analysis.elevation_deg >= 0 else "up at"
        return f"; camera looks {looking} it by {abs(analysis.elevation_deg):.0f} deg"
    return f"; camera elevation {analysis.elevation_deg:.0f} deg, up or down"


def _elevation_in_view(analysis: Analysis) -> bool:
    """True when the elevation is the view's own (said in the view row) and no lens told its sign."""
    lens = analysis.focal is not None and math.isfinite(analysis.focal.focal_px)
    return analysis.view is not None and not lens and analysis.elevation_deg == analysis.view.elevation_deg


def _view_text(analysis: Analysis) -> str:
    """The view read from the tracks' paths, in words."""
    view = analysis.view
    if view is None and analysis.camera_turn_deg_s:
        return "unknown: the tracks' paths carry the camera's own turn"
    if view is None:
        return "unknown: too few tracks follow a turning path at the reported rate"
    lens = " (its elevation with the lens found)" if analysis.focal is not None and math.isfinite(
        analysis.focal.focal_px) else ""
    return (f"{view.name}: the axis {view.elevation_deg:.0f} deg out of the image plane (0 side, 90 frontal); "
            f"turning centre {view.centre_px[0]:.0f}, {view.centre_px[1]:.0f} px, from {view.tracks} tracks' "
            f"paths{lens}")


def _rate_from_text(analysis: Analysis) -> str:
    """Where the reported rate comes from, in words."""
    period = analysis.period
    if analysis.rate_from == "turning":
        if analysis.verdict is not None and analysis.verdict.thin_part:
            return "the picture's turning: a thin part's angle (a hand, a needle) against the still picture"
        if analysis.verdict is not None and analysis.verdict.plane_changes:
            return ("the picture's turning: its changes unrolled through the plane the tracks turn as one, "
                    "through any view")
        if analysis.verdict is not None and analysis.verdict.plane:
            return "the picture's turning: the tracks as one plane turning about its axis, through any view"
        return "the picture's turning: its angle about the axis, frame by frame"
    if analysis.rate_from != "repetition" or period is None:
        return "the tracks' fits"
    per_turn = analysis.verdict.repeats_per_turn if analysis.verdict is not None else 1
    told = analysis.verdict.repeats_told_by if analysis.verdict is not None else ""
    if not told:
        turn = "; a turn or a part of one: nothing tells"
    else:
        turn = f"; {'a turn' if per_turn == 1 else f'{per_turn} repeats a turn'}, as {told} tells"
    slow = "; found once the picture's slow change was taken out" if period.detrended else ""
    return (f"the clip's repetition: the picture repeats every {period.period_s:.4g} s "
            f"(seen {period.repeats} time(s){turn}{slow})")


def _number(value: float, digits: int = 6) -> float | None:
    return None if value is None or not math.isfinite(value) else round(float(value), digits)


def samples_frame(analysis: Analysis) -> pd.DataFrame:
    """The per-sample table with the report's column names."""
    table = analysis.samples
    offset_column = f"y_{analysis.position_unit}"
    out = pd.DataFrame(
        {
            "feature": table["track"].astype(int),
            "frame": table["frame"].astype(int),
            "time_s": table["time_s"],
            offset_column: table["offset_px"],
            "dy_dt": table["dy_dt"],
            "d2y_dt2": table["d2y_dt2"],
            "omega2": table["omega2"],
            "omega": table["omega_rad_s"],
            "inlier": table["inlier"].astype(bool),
            "reason": table["reason"],
        }
    )
    return out.sort_values(["feature", "frame"], kind="stable").reset_index(drop=True)


def to_csv(analysis: Analysis) -> str:
    """Table I layout, one row per feature per sample."""
    return samples_frame(analysis).to_csv(index=False, float_format="%.6g", lineterminator="\n")


def to_dict(analysis: Analysis) -> dict[str, Any]:
    """The JSON report as a dictionary (omega in rad/s; NaN becomes None)."""
    features = []
    for row in analysis.features.itertuples(index=False):
        features.append(
            {
                "feature": int(row.track),
                "omega": _number(row.omega_rad_s),
                "omega_se": _number(row.omega_se_rad_s),
                "inlier": bool(row.inlier),
                "reason": row.reason,
                "samples": int(row.samples),
            }
        )
    reasons = Counter(r for r in analysis.features["reason"] if r)
    return {
        "video": analysis.source,
        "method": analysis.method,
        "fps": _number(analysis.fps),
        "frames": analysis.frames,
        "duration_s": _number(analysis.duration_s),
        "fixation": [_number(v, 3) for v in analysis.fixation_px],
        "axis": {
            "angle_deg": _number(analysis.axis_angle_deg, 3),
            "point_px": [_number(v, 3) for v in analysis.fixation_px],
            "found": analysis.axis_found and math.isfinite(analysis.fixation_px[0]),
            "angle_found": analysis.axis_angle_found,
            "angle_from": analysis.axis_angle_from if analysis.axis_angle_found else None,
            "elevation_deg": _number(analysis.elevation_deg, 2),
        },
        "view": None if analysis.view is None else {
            "name": analysis.view.name,
            "elevation_deg": _number(analysis.view.elevation_deg, 2),
            "centre_px": [_number(v, 2) for v in analysis.view.centre_px],
            "centre_spread_px": _number(analysis.view.centre_spread_px, 2),
            "tracks": analysis.view.tracks,
        },
        "camera": None if analysis.focal is None else {
            "found": True,
            "focal_px": _number(analysis.focal.focal_px, 1) if math.isfinite(analysis.focal.focal_px) else None,
            "fov_deg": _number(analysis.focal.fov_deg, 2),
            "orthographic": not math.isfinite(analysis.focal.focal_px),
            "tracks": analysis.focal.tracks,
        },
        "omega": _number(analysis.omega_rad_s),
        "omega_low": _number(analysis.omega_low_rad_s),
        "omega_high": _number(analysis.omega_high_rad_s),
        "rpm": _number(analysis.rpm, 4),
        "quality": analysis.quality,
        "weak_because": list(analysis.verdict.weak_because) if analysis.verdict is not None else [],
        "rate_from": analysis.rate_from,
        "clock": analysis.clock,
        "repetition": None if analysis.period is None else {
            "period_s": _number(analysis.period.period_s),
            "period_low_s": _number(analysis.period.period_low_s),
            "period_high_s": _number(analysis.period.period_high_s),
            "repeats_seen": analysis.period.repeats,
            "repeats_per_turn": analysis.verdict.repeats_per_turn if analysis.verdict is not None else 1,
            "likeness": _number(analysis.period.likeness, 4),
            "far_apart": analysis.period.far_apart,
            "turns_between": analysis.period.turns_between,
            "detrended": analysis.period.detrended,
            "roll_deg_s": _number(analysis.period.roll_deg_s, 3),
            "sway_deg": _number(analysis.period.sway_deg, 1),
            "zoom_share": _number(analysis.period.zoom_share, 3),
        },
        "shake": None if analysis.shake is None else {
            "rms_px": _number(analysis.shake.rms_px, 3), "largest_px": _number(analysis.shake.largest_px, 3),
            "background_tracks": analysis.shake.background_tracks,
            "turned_deg": _number(analysis.shake.turned_deg, 3), "turn_deg_s": _number(analysis.shake.turn_deg_s, 4),
            "smooth": analysis.shake.smooth,
        },
        "camera_turn_deg_s": _number(analysis.camera_turn_deg_s, 3),
        "other_body": None if analysis.other_body is None else {
            "omega": _number(analysis.other_body.omega_rad_s, 4),
            "centre_px": [_number(v, 1) for v in analysis.other_body.centre_px],
            "tracks": analysis.other_body.tracks,
            "along": analysis.other_body.along,
        },
        "direction": analysis.direction,
        "direction_seen": _direction_seen(analysis),
        "tracks_total": analysis.tracks_total,
        "tracks_used": analysis.tracks_used,
        "rejected": dict(sorted(reasons.items())),
        "warnings": list(analysis.warnings),
        "features": features,
        **({} if analysis.bodies is None else {"bodies": [
            {"omega": _number(body.omega_rad_s), "omega_low": _number(body.omega_low_rad_s),
             "omega_high": _number(body.omega_high_rad_s), "rpm": _number(body.omega_rad_s * 30.0 / math.pi, 4),
             "axis_px": [_number(v, 3) for v in body.axis_px], "direction": body.direction,
             "tracks": body.tracks_used, "tracks_total": body.tracks_total}
            for body in analysis.bodies
        ]}),
        **({} if analysis.series is None else {"series": [
            {"time_s": _number(row.time_s, 6), "omega": _number(row.omega_rad_s),
             "omega_low": _number(row.omega_low_rad_s), "omega_high": _number(row.omega_high_rad_s),
             "tracks_used": int(row.tracks_used), "rate_from": getattr(row, "rate_from", "tracks"),
             "quality": getattr(row, "quality", "good")}
            for row in analysis.series.itertuples(index=False)
        ]}),
    }


def series_csv(analysis: Analysis) -> str:
    """omega(t) as CSV: ``time_s,omega,omega_low,omega_high,tracks_used`` (rad/s), and ``rate_from``,
    ``quality`` per window."""
    series = analysis.series if analysis.series is not None else pd.DataFrame(
        columns=["time_s", "omega_rad_s", "omega_low_rad_s", "omega_high_rad_s", "tracks_used"])
    table = series.rename(columns={"omega_rad_s": "omega", "omega_low_rad_s": "omega_low",
                                   "omega_high_rad_s": "omega_high"})
    return table.to_csv(index=False, float_format="%.6g", lineterminator="\n")


def to_json(analysis: Analysis) -> str:
    """The JSON report as text, one object."""
    return json.dumps(to_dict(analysis), indent=2, allow_nan=False) + "\n"


#: How a found axis angle is named in the table (``Analysis.axis_angle_from``).
_ANGLE_FOUND = {"motion": "from the motion", "paths": "from the paths", "lens": "with the lens, from the tracks"}


def render_table(analysis: Analysis, console: Console) -> None:
    """A summary and per-feature rows, for the terminal."""
    interval = (
        f"[{analysis.omega_low_rad_s:.4f}, {analysis.omega_high_rad_s:.4f}]"
        if math.isfinite(analysis.omega_low_rad_s) else "n/a"
    )
    summary = Table(title=f"rotrate: {analysis.source}", show_header=False, title_justify="left")
    summary.add_column("quantity", style="bold")
    summary.add_column("value")
    summary.add_row("omega", f"{analysis.omega_rad_s:.4f} rad/s  ({analysis.rpm:.3f} rpm)")
    summary.add_row("95% interval", f"{interval} rad/s")
    summary.add_row("quality", analysis.quality)
    summary.add_row("rate from", _rate_from_text(analysis))
    summary.add_row("direction", analysis.direction + ("" if analysis.direction == "unknown"
                                                       else f"  ({_direction_seen(analysis)})"))
    fx, fy = analysis.fixation_px
    if math.isnan(fx):  # no axis: the rate is the picture's return alone (no track gave one)
        summary.add_row("fixation", "none found (no track gave a rate)")
    else:
        summary.add_row("fixation", f"{fx:.1f}" + ("" if math.isnan(fy) else f", {fy:.1f}")
                        + (f" {analysis.position_unit}" if math.isnan(fy) else " px")
                        + (f"  (found from {_fixation_from(analysis)})" if analysis.axis_found else ""))
    if not math.isnan(fy):
        summary.add_row("axis", f"{analysis.axis_angle_deg:+.2f} deg from vertical (top end "
                        f"{'right' if analysis.axis_angle_deg >= 0 else 'left'})"
                        + (f"  (found {_ANGLE_FOUND.get(analysis.axis_angle_from, 'from the tracks')})"
                           if analysis.axis_angle_found else "")
                        + ("" if math.isnan(analysis.elevation_deg) or _elevation_in_view(analysis)
                           else _elevation_text(analysis)))
    summary.add_row("view", _view_text(analysis))
    if analysis.focal is not None:
        summary.add_row("camera", "no perspective seen: orthographic" if not math.isfinite(analysis.focal.focal_px)
                        else f"found: focal {analysis.focal.focal_px:.0f} px (field of view "
                        f"{analysis.focal.fov_deg:.1f} deg), from {analysis.focal.tracks} tracks")
    summary.add_row("frames", f"{analysis.frames} over {analysis.duration_s:.2f} s at {analysis.fps:g} fps"
                    f"  (clock: {analysis.clock})")
    reasons = Counter(r for r in analysis.features["reason"] if r)
    rejected = ", ".join(f"{n} {why}" for why, n in reasons.most_common()) or "none"
    summary.add_row("features", f"{analysis.tracks_used} used of {analysis.tracks_total}; rejected: {rejected}")
    summary.add_row("method", analysis.method)
    for warning in analysis.warnings:
        summary.add_row("warning", warning)
    console.print(summary)
    if analysis.bodies is not None:
        bodies = Table(title="bodies (the first is the summary above)", title_justify="left")
        for name in ("body", "omega rad/s", "95% interval", "rpm", "axis px", "direction", "tracks used"):
            bodies.add_column(name, justify="left" if name in ("axis px", "direction") else "right")
        for number, body in enumerate(analysis.bodies, start=1):
            low, high = body.omega_low_rad_s, body.omega_high_rad_s
            bodies.add_row(str(number), f"{body.omega_rad_s:.4f}",
                           f"[{low:.4f}, {high:.4f}]" if math.isfinite(low) else "n/a",
                           f"{body.omega_rad_s * 30.0 / math.pi:.3f}",
                           f"{body.axis_px[0]:.1f}, {body.axis_px[1]:.1f}", body.direction,
                           f"{body.tracks_used} of {body.tracks_total}")
        console.print(bodies)

    features = analysis.features.copy()
    features["weight"] = 1.0 / features["omega_se_rad_s"].where(features["omega_se_rad_s"] > 0) ** 2
    features = features.sort_values(["inlier", "weight"], ascending=[False, False], na_position="last")
    rows = Table(title="features", title_justify="left")
    for name in ("feature", "samples", "omega rad/s", "± s.e.", f"range {analysis.position_unit}", "used", "reason"):
        rows.add_column(name, justify="right" if name not in ("used", "reason") else "left")
    for row in features.head(TABLE_ROWS).itertuples(index=False):
        rows.add_row(
            str(int(row.track)), str(int(row.samples)),
            "" if not math.isfinite(row.omega_rad_s) else f"{row.omega_rad_s:.4f}",
            "" if not math.isfinite(row.omega_se_rad_s) else f"{row.omega_se_rad_s:.4f}",
            f"{row.range:.1f}", "yes" if row.inlier else "no", row.reason,
        )
    console.print(rows)
    if len(features) > TABLE_ROWS:
        console.print(f"... {len(features) - TABLE_ROWS} more features (all of them with --format csv or json)")


def with_units(analysis: Analysis, units_per_px: float, unit: str) -> Analysis:
    """The analysis with its offsets (and so the Table I columns ``y``, ``dy_dt``, ``d2y_dt2``)
    and per-feature lengths in physical units, as the paper's inches; rates are unchanged (the
    scale is applied to the results, after the measurement, so no pixel threshold moves)."""
    features = analysis.features.copy()
    for column in ("range", "rms_residual", "amplitude"):
        if column in features:
            features[column] = features[column] * units_per_px
    offsets = analysis.offsets.assign(offset_px=analysis.offsets["offset_px"] * units_per_px)
    return replace(analysis, offsets=offsets, features=features, position_unit=unit)


def render(analysis: Analysis, fmt: str) -> str:
    """The report in format ``fmt`` as text (the table without colour)."""
    if fmt == "csv":
        return to_csv(analysis)
    if fmt == "json":
        return to_json(analysis)
    buffer = io.StringIO()
    render_table(analysis, Console(file=buffer, width=110, color_system=None, force_terminal=False))
    return buffer.getvalue()


def summary_text(outcomes: list[Outcome], fmt: str) -> str:
    """A batch's summary, one row per input, as ``csv`` or ``json`` text (``table``: plain)."""
    table = summary_frame(outcomes)
    if fmt == "csv":
        return table.to_csv(index=False, float_format="%.6g", lineterminator="\n")
    if fmt == "json":
        rows = [{k: (_number(v) if isinstance(v, float) else v) for k, v in row.items()}
                for row in table.to_dict("records")]
        return json.dumps({"inputs": rows}, indent=2, allow_nan=False) + "\n"
    buffer = io.StringIO()
    render_summary(outcomes, Console(file=buffer, width=140, color_system=None, force_terminal=False))
    return buffer.getvalue()


def render_summary(outcomes: list[Outcome], console: Console) -> None:
    """A batch's summary table for the terminal."""
    table = Table(title=f"rotrate: {len(outcomes)} inputs", title_justify="left")
    frame = summary_frame(outcomes)
    # the files' own names where they tell the inputs apart: a path broken over lines reads badly
    names = [Path(str(file)).name for file in frame["file"]]
    shown = names if len(set(names)) == len(names) else [str(file) for file in frame["file"]]
    for name in ("file", "status", "quality", "omega rad/s", "95% interval", "rpm", "direction", "tracks",
                 "message"):
        table.add_column(name, justify="right" if name in ("omega rad/s", "rpm", "tracks") else "left",
                         overflow="fold", no_wrap=name in ("file", "status", "quality", "omega rad/s"))
    for file, row in zip(shown, frame.itertuples(index=False), strict=True):
        ok = math.isfinite(row.omega)
        message = row.error or (f"{len(row.warnings.split('; '))} warning(s): see --format json" if row.warnings
                                else "")
        table.add_row(file, str(row.status), str(row.quality), f"{row.omega:.4f}" if ok else "",
                      f"[{row.omega_low:.4f}, {row.omega_high:.4f}]" if ok and math.isfinite(row.omega_low) else "",
                      f"{row.rpm:.3f}" if ok else "", str(row.direction), str(row.tracks_used) if ok else "",
                      message)
    console.print(table)


def render_check(outcomes: list[Outcome], expected: list[tuple[float, float]], console: Console) -> None:
    """``rotrate check``'s pass/fail table."""
    table = Table(title=f"rotrate check: {len(outcomes)} files", title_justify="left")
    for name in ("file", "expected", "omega rad/s", "error %", "tolerance %", "result", "message"):
        table.add_column(name, justify="left" if name in ("file", "result", "message") else "right",
                         overflow="fold")
    for outcome, (omega, tolerance) in zip(outcomes, expected, strict=True):
        measured = outcome.analysis.omega_rad_s if outcome.analysis is not None else math.nan
        error = 100.0 * (measured / omega - 1.0) if math.isfinite(measured) else math.nan
        table.add_row(outcome.source, f"{omega:g}", f"{measured:.4f}" if math.isfinite(measured) else "",
                      f"{error:+.2f}" if math.isfinite(error) else "", f"{tolerance:g}",
                      "pass" if outcome.status == "ok" else "FAIL", outcome.error)
    console.print(table)


def junit_xml(outcomes: list[Outcome], expected: list[tuple[float, float]], suite: str) -> str:
    """JUnit XML for CI systems: one test case per manifest row; ``expected`` holds each row's
    (expected omega, tolerance %)."""
    failures = sum(o.status in ("off_target", "no_result") for o in outcomes)
    errors = sum(o.status in ("bad_input", "failed") for o in outcomes)
    root = ET.Element("testsuite", name=suite, tests=str(len(outcomes)), failures=str(failures), errors=str(errors))
    for outcome, (omega, tolerance) in zip(outcomes, expected, strict=True):
        case = ET.SubElement(root, "testcase", classname=suite, name=outcome.source)
        measured = outcome.analysis.omega_rad_s if outcome.analysis is not None else math.nan
        ET.SubElement(case, "system-out").text = (
            f"expected {omega:g} rad/s +-{tolerance:g}%; measured {measured:.6g} rad/s")
        if outcome.status in ("off_target", "no_result"):
            ET.SubElement(case, "failure", message=outcome.error, type=outcome.status)
        elif outcome.status != "ok":
            ET.SubElement(case, "error", message=outcome.error, type=outcome.status)
    ET.indent(root)
    return '<?xml version="1.0" encoding="utf-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


def _direction_seen(analysis: Analysis) -> str:
    """Where the reported sense of turning is seen from."""
    if analysis.direction_in_picture:
        return "as seen in the picture"
    return "seen from the axis's top end"


def _fixation_from(analysis: Analysis) -> str:
    """Where a found fixation came from: the picture's turning gives its own axis point where it
    gives the rate (the view its changes line up through, or the plane's fixed point), else the
    tracks."""
    turning = analysis.verdict is not None and analysis.verdict.rate_from == "turning"
    return "the picture's turning" if turning else "the tracks"
