"""A picture of a measurement (``--plot out.png``): the tracks against their fitted model, each
feature's rate with its interval, and the rate over time.

matplotlib draws it; it is an optional extra (``pip install 'rotrate[plot]'``), imported only
here and only when a plot is asked for. The file is written through a temporary name.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from rotrate_cli.analysis import Analysis
from rotrate_cli.errors import InputError
from rotrate_cli.fitting.estimators import solve_two_columns
from rotrate_cli.fitting.series import running_rate
from rotrate_cli.output.files import check_output_path, replacing
from rotrate_cli.runtime.lazy import pandas as pd
from rotrate_cli.stages.fits import running_measure

if TYPE_CHECKING:
    from matplotlib.axes import Axes

#: Features drawn in the y(t) panel (the best-determined inliers).
TRACKS_DRAWN = 8
#: Size of the figure, pixels.
SIZE_PX = (1200, 1100)


#: The picture formats matplotlib writes (by the file's suffix), known without importing it.
PLOT_SUFFIXES = (".png", ".pdf", ".svg", ".svgz", ".jpg", ".jpeg", ".eps", ".ps", ".tif", ".tiff", ".webp")


def check_plot(path: Path) -> None:
    """Fail before any frame is read where ``--plot`` could not be drawn: matplotlib missing, or a
    format it does not write.

    Raises:
        InputError: either.
    """
    import importlib.util

    if importlib.util.find_spec("matplotlib") is None:
        raise InputError("--plot needs matplotlib: pip install 'rotrate[plot]'")
    if path.suffix.lower() not in PLOT_SUFFIXES:
        raise InputError(f"--plot draws a picture: give it a name ending in {', '.join(PLOT_SUFFIXES)} "
                         f"(got {path.name})")


def write_plot(analysis: Analysis, path: Path, force: bool = False) -> None:
    """Write the three-panel picture of ``analysis`` to ``path`` (PNG, or what the suffix says).

    Raises:
        InputError: matplotlib is not installed.
        OutputError: ``path`` exists (without ``force``) or cannot be written.
    """
    try:
        import matplotlib

        matplotlib.use("Agg")  # files only, no display
        from matplotlib import pyplot
    except ImportError:
        raise InputError("--plot needs matplotlib: pip install 'rotrate[plot]'") from None
    check_output_path(path, force)  # before drawing, not after

    dpi = 100
    figure, (top, middle, bottom) = pyplot.subplots(3, 1, figsize=(SIZE_PX[0] / dpi, SIZE_PX[1] / dpi), dpi=dpi,
                                                     gridspec_kw={"height_ratios": [1.3, 1.0, 1.0]})
    unit = analysis.position_unit
    _tracks_panel(top, analysis, unit)
    _features_panel(middle, analysis)
    _time_panel(bottom, analysis)
    figure.suptitle(f"{Path(analysis.source).name}: omega {analysis.omega_rad_s:.4f} rad/s "
                    f"[{analysis.omega_low_rad_s:.4f}, {analysis.omega_high_rad_s:.4f}] ({analysis.rpm:.2f} rpm), "
                    f"{analysis.direction}", fontsize=12)
    figure.tight_layout()
    try:
        with replacing(path, force, suffix=path.suffix or ".png") as temporary:
            figure.savefig(temporary, dpi=dpi)
    finally:
        pyplot.close(figure)


def _best_features(analysis: Analysis) -> pd.DataFrame:
    features = analysis.features[analysis.features["inlier"]].copy()
    features["weight"] = 1.0 / features["omega_se_rad_s"].where(features["omega_se_rad_s"] > 0) ** 2
    return features.sort_values("weight", ascending=False).head(TRACKS_DRAWN)


def _tracks_panel(axes: Axes, analysis: Analysis, unit: str) -> None:
    """Each drawn feature's offsets (dots) and its fitted sinusoid at the summary rate (line)."""
    offsets = analysis.offsets
    omega = analysis.omega_rad_s
    drawn = _best_features(analysis)["track"].astype(int)
    plane = analysis.verdict is not None and analysis.verdict.plane
    if len(drawn) == 0 or plane:
        # no track stands behind the rate (the picture's turning, or the return, gave it), or its
        # tracks stand behind it as one plane turning, not as sinusoids about one fixation
        text = (f"{analysis.tracks_used} tracks stand behind the rate as one plane turning (through any view),\n"
                "not as sinusoids about one fixation: see the overlay" if plane else
                f"no track stands behind the rate reported (from {analysis.rate_from})")
        axes.text(0.5, 0.5, text, ha="center", va="center", transform=axes.transAxes, fontsize=9)
        axes.set_axis_off()
        return
    for number, track in enumerate(drawn):
        part = offsets[offsets["track"] == track]
        time_s, y = part["time_s"].to_numpy(), part["offset_px"].to_numpy()
        c, s = np.cos(omega * time_s), np.sin(omega * time_s)
        a, b = solve_two_columns(np.array([c @ c]), np.array([s @ s]), np.array([c @ s]), np.array([c @ y]),
                                 np.array([s @ y]))
        dense = np.linspace(time_s.min(), time_s.max(), 200)
        colour = f"C{number % 10}"
        axes.plot(time_s, y, ".", color=colour, markersize=3, label=f"feature {track}")
        axes.plot(dense, a[0] * np.cos(omega * dense) + b[0] * np.sin(omega * dense), "-",
                  color=colour, linewidth=1)
    axes.set_xlabel("time (s)")
    axes.set_ylabel(f"offset y from the axis ({unit})")
    axes.set_title(f"the {TRACKS_DRAWN} best-determined features (dots) and y = a cos(wt) + b sin(wt) at the "
                   "summary rate (lines)", fontsize=10)
    axes.legend(fontsize=7, ncol=4, loc="upper right")
    axes.grid(alpha=0.3)


def _features_panel(axes: Axes, analysis: Analysis) -> None:
    """Every feature's rate with its 95% interval, used in blue and rejected in red; the summary
    rate and its interval as a band."""
    features = analysis.features[np.isfinite(analysis.features["omega_rad_s"])]
    # on a plane's rate, the used tracks' own rates are their one-point fits, another model of them
    plane = analysis.verdict is not None and analysis.verdict.plane
    for used, colour, label in ((True, "C0", "on the plane; their one-point fits" if plane else "used"),
                                (False, "C3", "rejected")):
        part = features[features["inlier"] == used]
        if part.empty:
            continue
        half = 1.96 * part["omega_se_rad_s"].where(np.isfinite(part["omega_se_rad_s"]), np.nan)
        axes.errorbar(part["track"], part["omega_rad_s"], yerr=half, fmt="o", color=colour, markersize=2,
                      elinewidth=0.6, label=f"{label} ({len(part)})")
    axes.axhspan(analysis.omega_low_rad_s, analysis.omega_high_rad_s, color="C2", alpha=0.25,
                 label="summary 95% interval")
    axes.axhline(analysis.omega_rad_s, color="C2", linewidth=1.2)
    used = features.loc[features["inlier"], "omega_rad_s"]
    if len(used):
        low, high = np.percentile(used, [2, 98])
        margin = max(high - low, 0.1 * analysis.omega_rad_s)
        axes.set_ylim(low - margin, high + margin)
    axes.set_xlabel("feature")
    axes.set_ylabel("omega (rad/s)")
    axes.set_title("each feature's rate with its 95% interval" + (" (its one-point fit)" if plane else ""), fontsize=10)
    axes.legend(fontsize=8, loc="upper right")
    axes.grid(alpha=0.3)


def _time_panel(axes: Axes, analysis: Analysis) -> None:
    """omega(t) with its band: the sliding-window series when measured, else the running rate
    (everything up to each time)."""
    if analysis.series is not None:
        series, title = analysis.series, "omega(t) over the sliding window, with its 95% band"
    else:
        series = running_rate(analysis.offsets, running_measure(analysis.method, analysis.rejection, analysis.camera))
        title = "omega from the start up to each time, with its 95% band"
    if analysis.rate_from in ("repetition", "turning") and analysis.series is None:
        # the reported rate is not the tracks': their own rates are shown beside it
        source = "the clip's repetition" if analysis.rate_from == "repetition" else "the picture's turning"
        title = ("the tracks' " + title[0].lower() + title[1:] + f"; dashed: the reported rate, from {source}")
        axes.axhspan(analysis.omega_low_rad_s, analysis.omega_high_rad_s, color="C2", alpha=0.2)
    finite = series[np.isfinite(series["omega_rad_s"])]
    if len(finite):
        axes.fill_between(finite["time_s"], finite["omega_low_rad_s"], finite["omega_high_rad_s"], color="C0",
                          alpha=0.25)
        axes.plot(finite["time_s"], finite["omega_rad_s"], "-o", color="C0", markersize=3)
    axes.axhline(analysis.omega_rad_s, color="C2", linewidth=1, linestyle="--", label="summary")
    axes.set_xlabel("time (s)")
    axes.set_ylabel("omega (rad/s)")
    axes.set_title(title, fontsize=10)
    axes.grid(alpha=0.3)
    if len(finite) and math.isfinite(analysis.omega_rad_s):
        spread = finite["omega_high_rad_s"] - finite["omega_low_rad_s"]
        top = float(np.nanmax(finite["omega_rad_s"] + spread.clip(upper=analysis.omega_rad_s)))
        bottom = float(np.nanmin(finite["omega_rad_s"] - spread.clip(upper=analysis.omega_rad_s)))
        # the reported rate and its interval stay in view where the tracks read another (a plane's
        # rate, 3.09 rad/s, drawn off a panel of the tracks' one-point 4.1-4.6)
        top = max(top, 1.02 * analysis.omega_high_rad_s) if math.isfinite(analysis.omega_high_rad_s) else top
        bottom = min(bottom, 0.98 * analysis.omega_low_rad_s) if math.isfinite(analysis.omega_low_rad_s) else bottom
        axes.set_ylim(max(0.0, bottom), top)
