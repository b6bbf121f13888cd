"""Outlier rejection and the combined estimate.

Every track gets a verdict with a reason, in this order: too few samples (``short``), too
little motion (``static``: background), no real rate (``no_fit``: the track curves away from the
axis, omega^2 < 0), a sinusoid that does not describe it (``poor_fit``: points sliding along an
outline, tracker slips), and finally disagreement with the majority (``disagrees``). The
survivors are combined by a random-effects weighted mean, whose 95% interval widens when the
tracks disagree by more than their own standard errors say they should.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rotrate_cli.fitting.estimators import TrackFit
from rotrate_cli.fitting.stats import student_t_975, weighted_median
from rotrate_cli.runtime.lazy import pandas as pd

FEATURE_COLUMNS = (
    "track", "samples", "omega_rad_s", "omega_se_rad_s", "rms_residual", "amplitude", "arc_rad", "sense",
    "range", "inlier", "reason",
)


@dataclass(frozen=True)
class RejectionConfig:
    """Thresholds for rejecting tracks and samples. Lengths are in the positions' own units
    (pixels for videos).

    Attributes:
        min_samples: a track needs at least this many samples.
        min_range: a track must move at least this far horizontally (0 disables the check).
        min_motion_ratio: ... and at least this many times its own rms misfit (on the sample
            box the trusted tracks move 10 to 2200 times theirs; 0 disables the check).
        max_residual_ratio: a track's rms misfit may be at most this multiple of the median
            track's (and ``residual_floor``, whichever is larger).
        residual_floor: misfit that is always acceptable (tracker precision), same units.
        disagreement_z: a track whose omega differs from the weighted median by more than this
            many combined standard deviations is rejected.
        singular_fraction: per-sample closed-form values where ``|y|`` is below this fraction
            of the track's amplitude are flagged ``near_singular``.
    """

    min_samples: int = 8
    min_range: float = 1.0
    min_motion_ratio: float = 8.0
    max_residual_ratio: float = 4.0
    residual_floor: float = 0.15
    disagreement_z: float = 3.5
    singular_fraction: float = 0.2


@dataclass(frozen=True)
class Combined:
    """The combined rate of the inlier tracks.

    Attributes:
        omega_rad_s: the weighted mean rate, rad/s.
        omega_low_rad_s, omega_high_rad_s: its 95% interval, rad/s.
        tracks_used: how many tracks went into it.
        senses_rad_s: through a pinhole, where the tracks' fits do not tell the sense of
            rotation, the rates of the two senses (anticlockwise, clockwise), which the interval
            holds; None otherwise.
        seen_sense: where ``senses_rad_s`` is set, +1 or -1 when the rate is that sense's, as
            the near side's travel shows it (:func:`rotrate_cli.stages.fits.rates_from_offsets`); 0
            when it is midway between the two.
        seen_interval_rad_s: with ``seen_sense``, that sense's own 95% interval (the interval
            above also holds the other sense's); None otherwise.
    """

    omega_rad_s: float
    omega_low_rad_s: float
    omega_high_rad_s: float
    tracks_used: int
    senses_rad_s: tuple[float, float] | None = None
    seen_sense: int = 0
    seen_interval_rad_s: tuple[float, float] | None = None



def judge_fits(samples: pd.DataFrame, fits: dict[int, TrackFit], config: RejectionConfig) -> pd.DataFrame:
    """One row per track with its fitted rate and a verdict (``inlier``, ``reason``).

    ``samples`` has columns ``track, offset_px``; ``fits`` holds each track's sinusoid fit.
    """
    sizes = samples.groupby("track", sort=False)["offset_px"].agg(["size", "min", "max"])
    track_fits = [fits[int(track)] for track in sizes.index]
    table = pd.DataFrame({
        "track": sizes.index.astype(int),
        "samples": sizes["size"].to_numpy(dtype=int),
        **{name: np.array([getattr(fit, name) for fit in track_fits], dtype=float)
           for name in ("omega_rad_s", "omega_se_rad_s", "rms_residual", "amplitude", "arc_rad", "sense")},
        "range": (sizes["max"] - sizes["min"]).to_numpy(dtype=float),
    })
    reason = pd.Series("", index=table.index, dtype=object)
    reason[table["samples"] < config.min_samples] = "short"
    # static: it hardly moves, or its motion does not stand out from its own misfit (a chosen
    # background pixel followed by CSRT: 2.5 px of jitter, 0.34 px misfit, "0.018 rad/s")
    still = (table["range"] < config.min_range) | (table["range"] < config.min_motion_ratio * table["rms_residual"])
    reason[(reason == "") & still] = "static"
    unfit = ~np.isfinite(table["omega_rad_s"]) | ~np.isfinite(table["omega_se_rad_s"]) | (table["omega_rad_s"] <= 0)
    reason[(reason == "") & unfit] = "no_fit"
    candidates = reason == ""
    if candidates.any():
        typical = float(table.loc[candidates, "rms_residual"].median())
        limit = max(config.max_residual_ratio * typical, config.residual_floor)
        reason[candidates & (table["rms_residual"] > limit)] = "poor_fit"
    reason = _reject_disagreeing(table, reason, config.disagreement_z)
    table["inlier"] = reason == ""
    table["reason"] = reason
    return table


def _reject_disagreeing(table: pd.DataFrame, reason: pd.Series, z_limit: float) -> pd.Series:
    reason = reason.copy()
    candidates = reason == ""
    if candidates.sum() < 3:
        return reason
    omega = table.loc[candidates, "omega_rad_s"].to_numpy()
    se = np.maximum(table.loc[candidates, "omega_se_rad_s"].to_numpy(), 1e-12)
    centre = weighted_median(omega, 1.0 / se**2)
    spread = 1.4826 * float(np.median(np.abs(omega - centre)))
    z = np.abs(omega - centre) / np.sqrt(se**2 + spread**2)
    index = table.index[candidates]
    reason[index[z > z_limit]] = "disagrees"
    return reason


def combine(omega_rad_s: np.ndarray, se_rad_s: np.ndarray) -> Combined:
    """Random-effects (DerSimonian-Laird) mean of per-track rates with a 95% t interval.

    With one track, its own standard error gives the interval.
    """
    omega = np.asarray(omega_rad_s, dtype=float)
    se = np.maximum(np.asarray(se_rad_s, dtype=float), 1e-12)
    k = len(omega)
    if k == 0:
        return Combined(math.nan, math.nan, math.nan, 0)
    if k == 1:
        half = 1.96 * float(se[0])
        return Combined(float(omega[0]), max(float(omega[0]) - half, 0.0), float(omega[0]) + half, 1)
    weights = 1.0 / se**2
    fixed = float(weights @ omega / weights.sum())
    q = float(weights @ (omega - fixed) ** 2)
    scale = float(weights.sum() - (weights**2).sum() / weights.sum())
    tau2 = max(0.0, (q - (k - 1)) / scale) if scale > 0 else 0.0
    weights = 1.0 / (se**2 + tau2)
    mean = float(weights @ omega / weights.sum())
    standard_error = math.sqrt(1.0 / float(weights.sum()))
    # Hartung-Knapp style rescaling keeps the interval honest when the tracks scatter.
    spread = float(weights @ (omega - mean) ** 2) / (k - 1)
    standard_error *= math.sqrt(max(spread, 1.0))
    half = student_t_975(k - 1) * standard_error
    return Combined(mean, max(mean - half, 0.0), mean + half, k)


def combine_plain(values: np.ndarray) -> Combined:
    """Mean of equally weighted values with a 95% t interval (the paper method's summary)."""
    values = np.asarray(values, dtype=float)
    k = len(values)
    if k == 0:
        return Combined(math.nan, math.nan, math.nan, 0)
    mean = float(values.mean())
    if k == 1:
        return Combined(mean, math.nan, math.nan, 1)
    half = student_t_975(k - 1) * float(values.std(ddof=1)) / math.sqrt(k)
    return Combined(mean, mean - half, mean + half, k)


def flag_samples(rates: pd.DataFrame, features: pd.DataFrame, config: RejectionConfig) -> pd.DataFrame:
    """Add ``inlier`` and ``reason`` to per-sample rates (fit method).

    A sample inherits its track's rejection; otherwise its own closed-form value is flagged
    ``no_derivative`` (too near a track end), ``near_singular`` or ``negative_omega2``.
    """
    table = rates.copy()
    verdict = features.set_index("track")
    reason = table["track"].map(verdict["reason"]).fillna("short").astype(object)
    amplitude = table["track"].map(verdict["amplitude"]).astype(float)
    ok = reason == ""
    reason[ok & table["omega2"].isna()] = "no_derivative"
    ok = reason == ""
    reason[ok & (table["offset_px"].abs() < config.singular_fraction * amplitude)] = "near_singular"
    ok = reason == ""
    reason[ok & (table["omega2"] <= 0)] = "negative_omega2"
    table["inlier"] = reason == ""
    table["reason"] = reason
    return table


def judge_paper(rates: pd.DataFrame) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The paper's own rule: a sample counts where omega^2 > 0; a feature's omega is the mean.

    Returns the per-sample table with ``inlier, reason`` and a per-feature table.
    """
    table = rates.copy()
    reason = pd.Series("", index=table.index, dtype=object)
    reason[table["d2y_dt2"].isna()] = "no_derivative"
    reason[(reason == "") & (table["omega2"] <= 0)] = "negative_omega2"
    reason[(reason == "") & table["omega_rad_s"].isna()] = "no_derivative"
    table["inlier"] = reason == ""
    table["reason"] = reason
    rows = []
    for track, group in table.groupby("track", sort=False):
        good = group.loc[group["inlier"], "omega_rad_s"].to_numpy()
        k = len(good)
        omega = float(good.mean()) if k else math.nan
        se = float(good.std(ddof=1) / math.sqrt(k)) if k > 1 else math.nan
        offsets = group["offset_px"]
        rows.append((int(track), len(group), omega, se, math.nan, float(offsets.abs().max()), math.nan, math.nan,
                     float(offsets.max() - offsets.min()), k > 0, "" if k else "no_valid_sample"))
    features = pd.DataFrame(rows, columns=list(FEATURE_COLUMNS))
    return table, features
