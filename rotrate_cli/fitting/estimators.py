"""Rotation-rate estimators: per sample and per track.

The paper's relation: with ``offset_px`` the horizontal distance of a point from the fixation
point on the rotation axis (the paper's ``y``), orthographic projection and a constant rate,
``d2 offset / dt2 = -omega^2 * offset``.

Two families are offered:

* ``paper``: the reference paper's Table I, faithfully: backward differences at the sampling
  step (first derivative from consecutive samples, second derivative from consecutive first
  derivatives), ``omega^2 = -y''/y`` per sample, and a feature's omega is the mean of its
  per-sample omegas where ``omega^2 > 0``.
* ``fit`` (ours, the default): the solution of that differential equation is
  ``offset = a cos(omega t) + b sin(omega t)``; fitting it to all of a track's samples by least
  squares uses every sample at once, needs no numerical derivative, is exact at any sampling step,
  and weighs near-singular samples (offset ~ 0) correctly instead of dividing by them. The
  per-sample columns are then the exact discrete form of the same relation at a lag chosen for
  the noise, ``cos(omega m dt) = (y[k+m] + y[k-m]) / (2 y[k])``, for inspection.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, replace

import numpy as np

from rotrate_cli.fitting.camera import Camera
from rotrate_cli.runtime.choices import METHODS  # noqa: F401 - re-exported
from rotrate_cli.runtime.lazy import pandas as pd


@dataclass(frozen=True)
class TrackFit:
    """A sinusoid fitted to one track's offsets.

    Attributes:
        omega_rad_s: the fitted rate (magnitude), rad/s; NaN when the fit failed.
        omega_se_rad_s: its standard error from the fit's residuals, rad/s.
        rms_residual: root-mean-square misfit of the offsets, in their units.
        amplitude: the fitted amplitude ``sqrt(a^2 + b^2)``, in the offsets' units.
        arc_rad: the rotation angle the track spans, ``omega * duration``.
        sense: +1 anticlockwise seen from above, -1 clockwise, as the pinhole fit found it; NaN
            for orthographic fits, which cannot tell.
    """

    omega_rad_s: float
    omega_se_rad_s: float
    rms_residual: float
    amplitude: float
    arc_rad: float
    sense: float = math.nan


def solve_two_columns(
    a11: np.ndarray, a22: np.ndarray, a12: np.ndarray, b1: np.ndarray, b2: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Per track, the least-squares ``a, b`` of ``y ~ a first + b second`` from its normal
    equations (``a11 = first.first``, ``a22 = second.second``, ``a12 = first.second``,
    ``b1 = first.y``, ``b2 = second.y``); ``0, 0`` where the two columns are degenerate."""
    det = a11 * a22 - a12 * a12
    det = np.where(np.abs(det) > 1e-300, det, np.inf)
    return (a22 * b1 - a12 * b2) / det, (a11 * b2 - a12 * b1) / det


_FAILED = TrackFit(math.nan, math.nan, math.nan, math.nan, math.nan)


def recurrence_omega(time_s: np.ndarray, offset: np.ndarray) -> float:
    """Closed-form first guess from the exact three-term recurrence at the median step.

    ``y[k-1] + y[k+1] = 2 cos(omega dt) y[k]`` is solved for ``cos(omega dt)`` by least squares
    over the track (weights ``y[k]^2``, so near-singular samples count little). Returns NaN
    when the track curves away from the axis (no real solution).
    """
    if len(offset) < 3:
        return math.nan
    dt = float(np.median(np.diff(time_s)))
    middle = offset[1:-1]
    denominator = 2.0 * float(middle @ middle)
    if dt <= 0 or denominator <= 0:
        return math.nan
    cosine = float(middle @ (offset[:-2] + offset[2:])) / denominator
    if not -1.0 < cosine < 1.0:
        return math.nan if cosine >= 1.0 else math.pi / dt
    return math.acos(cosine) / dt


def fit_track(time_s: np.ndarray, offset: np.ndarray) -> TrackFit:
    """Fit ``offset = a cos(omega t) + b sin(omega t)`` to one track by Gauss-Newton.

    ``time_s`` may be unevenly spaced (centred internally). The start comes from the exact
    three-term recurrence (see :func:`recurrence_omega`) and a few trial rates around it; the
    standard error is the usual ``s^2 (J^T J)^-1`` one, infinite when the track does not
    determine omega.
    """
    time_s = np.asarray(time_s, dtype=float)[None, :]
    offset = np.asarray(offset, dtype=float)[None, :]
    return _fit_batch(time_s, offset, np.ones_like(time_s, dtype=bool))[0]


def paper_samples(samples: pd.DataFrame) -> pd.DataFrame:
    """The paper's per-sample derivatives and rates (Table I), per track.

    Input columns: ``track, frame, time_s, offset_px`` (sorted by track then time). Backward
    differences at the sampling step: ``dy_dt[k] = (y[k] - y[k-1]) / dt``,
    ``d2y_dt2[k] = (dy_dt[k] - dy_dt[k-1]) / dt``, ``omega2 = -d2y_dt2 / y`` and
    ``omega = sqrt(omega2)`` where ``omega2 > 0`` (NaN otherwise, as the paper left it blank).
    """
    table = samples.loc[:, ["track", "frame", "time_s", "offset_px"]].copy()
    grouped = table.groupby("track", sort=False)
    dt = grouped["time_s"].diff()
    table["dy_dt"] = grouped["offset_px"].diff() / dt
    table["d2y_dt2"] = table.groupby("track", sort=False)["dy_dt"].diff() / dt
    with np.errstate(divide="ignore", invalid="ignore"):
        table["omega2"] = -table["d2y_dt2"] / table["offset_px"]
    table["omega_rad_s"] = np.sqrt(table["omega2"].where(table["omega2"] > 0))
    return table


def local_lag(omega_dt_rad: float, n: int) -> int:
    """The lag (in samples) for per-sample second differences.

    The second difference grows as ``(omega m dt)^2`` while its noise stays ``~2 sigma``, so a
    longer lag is better until the three samples span a large arc: aim for half a radian, but
    keep at least half of the track's samples with a value.
    """
    if omega_dt_rad <= 0 or not math.isfinite(omega_dt_rad):
        return 1
    return int(max(1, min(round(0.5 / omega_dt_rad), (n - 1) // 4)))


def _track_slices(tracks: np.ndarray) -> list[slice]:
    """Slices of consecutive equal ids in a sorted id array."""
    if len(tracks) == 0:
        return []
    edges = np.flatnonzero(np.diff(tracks)) + 1
    bounds = np.concatenate([[0], edges, [len(tracks)]])
    return [slice(int(a), int(b)) for a, b in zip(bounds[:-1], bounds[1:], strict=True)]


def fit_samples(samples: pd.DataFrame, omega_rad_s: dict[int, float]) -> pd.DataFrame:
    """Per-sample values for the fit method: central differences at lag ``m`` and the exact
    discrete rate ``omega = arccos((y[k+m] + y[k-m]) / (2 y[k])) / (m dt)``.

    ``samples`` is sorted by track, then time; ``omega_rad_s`` holds each track's fitted rate,
    which sets its lag. ``dy_dt`` is the central difference at that lag
    and ``d2y_dt2 = -omega2 * y``, the second derivative of the sinusoid through the three
    samples; rows near a track's ends have NaN.
    """
    table = samples.loc[:, ["track", "frame", "time_s", "offset_px"]].reset_index(drop=True)
    tracks = table["track"].to_numpy()
    times = table["time_s"].to_numpy(dtype=float)
    offsets = table["offset_px"].to_numpy(dtype=float)
    n_all = len(table)
    dy = np.full(n_all, np.nan)
    omega2 = np.full(n_all, np.nan)
    for part in _track_slices(tracks):
        time_s, offset = times[part], offsets[part]
        n = len(offset)
        if n < 3:
            continue
        rate = omega_rad_s.get(int(tracks[part.start]), math.nan)
        lag = local_lag(rate * float(np.median(np.diff(time_s))), n)
        if n <= 2 * lag:
            continue
        k = np.arange(lag, n - lag)
        step_s = (time_s[k + lag] - time_s[k - lag]) / 2.0
        with np.errstate(divide="ignore", invalid="ignore"):
            cosine = (offset[k + lag] + offset[k - lag]) / (2.0 * offset[k])
            rate = np.arccos(np.clip(cosine, -1.0, 1.0)) / step_s
            # cos > 1 means the point curves away from the axis: a negative omega^2.
            rate2 = np.where(cosine > 1.0, -(np.arccosh(np.maximum(cosine, 1.0)) / step_s) ** 2, rate**2)
        dy[part.start + k] = (offset[k + lag] - offset[k - lag]) / (2.0 * step_s)
        omega2[part.start + k] = rate2
    table["dy_dt"] = dy
    table["d2y_dt2"] = -omega2 * offsets
    table["omega2"] = omega2
    table["omega_rad_s"] = np.sqrt(np.where(omega2 > 0, omega2, np.nan))
    return table


#: Elements per padded batch in :func:`fit_tracks`: bounds memory whatever the clip's length.
_BATCH_ELEMENTS = 10_000
#: Batches fitted at once (threads): memory is this many batches' temporaries.
_FIT_THREADS = 2


#: A batched model: ``(params, rows) -> (predicted, jacobian)`` for the given rows of the batch
#: (``params`` holds just those rows; ``rows`` is an index array or ``slice(None)`` for all).
Model = Callable[[np.ndarray, "np.ndarray | slice"], tuple[np.ndarray, np.ndarray]]

_ALL = slice(None)


def _orthographic(t: np.ndarray, weight: np.ndarray) -> Model:
    """``y = A cos(wt) + B sin(wt)``; params rows ``(A, B, w)``. Returns model and Jacobian."""

    def model(params: np.ndarray, rows: np.ndarray | slice) -> tuple[np.ndarray, np.ndarray]:
        a, b, w = params[:, 0:1], params[:, 1:2], params[:, 2:3]
        tr, weight_r = t[rows], weight[rows]
        c, s_ = np.cos(w * tr) * weight_r, np.sin(w * tr) * weight_r
        return a * c + b * s_, np.stack([c, s_, tr * (-a * s_ + b * c)], axis=2)

    return model


def _pinhole(t: np.ndarray, weight: np.ndarray, axis_n: float, depth_scale: float = 1.0) -> Model:
    """A pinhole camera aimed at the axis's depth, positions normalised by the focal length.

    With the camera at unit distance from the axis, a point at normalised radius r and angle th
    projects to ``(axis_n + r sin th) / (1 - k r cos th)``, ``k`` the cosine of the camera's
    elevation (``depth_scale``). Written with ``L = A cos(wt) + B sin(wt)`` (the orthographic
    offset) and its depth ``Z = -A sin(wt) + B cos(wt)``: ``x = (axis_n + L) / (1 - k Z)``.
    The sign of ``w`` is observable here (near points move faster), unlike orthographically.
    """
    k = depth_scale

    def model(params: np.ndarray, rows: np.ndarray | slice) -> tuple[np.ndarray, np.ndarray]:
        a, b, w = params[:, 0:1], params[:, 1:2], params[:, 2:3]
        tr = t[rows]
        c, s_ = np.cos(w * tr), np.sin(w * tr)
        lateral = a * c + b * s_
        depth = -a * s_ + b * c
        numerator = axis_n + lateral
        denominator = 1.0 - k * depth
        denominator = np.where(np.abs(denominator) > 1e-6, denominator, 1e-6)
        square = denominator**2
        jacobian = np.stack([
            (c * denominator - numerator * k * s_) / square,
            (s_ * denominator + numerator * k * c) / square,
            tr * (depth * denominator - numerator * k * lateral) / square,
        ], axis=2) * weight[rows][:, :, None]
        return numerator / denominator * weight[rows], jacobian

    return model


def _gauss_newton(params: np.ndarray, model: Model, y: np.ndarray, iterations: int) -> np.ndarray:
    """Batched Gauss-Newton on rows of ``params``; returns the refined parameters. A row stops
    once its rate's step is below 1e-9 relative (most converge in a handful of steps, a few
    slowly: only those keep being computed)."""
    params = params.copy()
    eye = np.eye(params.shape[1])
    active = np.arange(len(params))
    for _ in range(iterations):
        if len(active) == 0:
            break
        predicted, jacobian = model(params[active], active)
        residual = y[active] - predicted
        jacobian_t = jacobian.transpose(0, 2, 1)
        jtj = jacobian_t @ jacobian
        jtr = (jacobian_t @ residual[:, :, None])[:, :, 0]
        jtj += 1e-12 * eye * np.trace(jtj, axis1=1, axis2=2)[:, None, None] + 1e-300 * eye
        step = np.linalg.solve(jtj, jtr[:, :, None])[:, :, 0]
        step[~np.isfinite(step).all(axis=1)] = 0.0
        params[active] += step
        converged = np.abs(step[:, 2]) <= 1e-9 * np.maximum(1.0, np.abs(params[active, 2]))
        active = active[~converged]
    return params


def _fit_batch(
    time_s: np.ndarray, offset: np.ndarray, mask: np.ndarray, camera: Camera | None = None, sense: int = 0,
    iterations: int = 20,
) -> list[TrackFit]:
    """Least-squares fits of many padded tracks at once (rows are tracks, ``mask`` marks real samples).

    Orthographic: ``offset = A cos(wt) + B sin(wt)``, started from the exact recurrence and a few
    trial rates around it, refined by Gauss-Newton. With a pinhole ``camera`` that fit starts
    the perspective model in the given ``sense`` (+1 anticlockwise, -1 clockwise), or with
    ``sense=0`` in both, keeping the better one per track.
    """
    return _fit_batch_senses(time_s, offset, mask, camera, (sense,), iterations)[0]


def _fit_batch_senses(
    time_s: np.ndarray, offset: np.ndarray, mask: np.ndarray, camera: Camera | None, senses: tuple[int, ...],
    iterations: int = 20,
) -> list[list[TrackFit]]:
    """:func:`_fit_batch` in each of ``senses`` (one list of fits per sense), the orthographic fit
    that starts them all made once (it was half of the fits in both senses)."""
    weight = mask.astype(float)
    n = weight.sum(axis=1)
    t_mean = (time_s * weight).sum(axis=1) / n
    t = (time_s - t_mean[:, None]) * weight
    y = offset * weight
    # first guess: the exact recurrence y[k-1] + y[k+1] = 2 cos(w dt) y[k], least squares
    triple = weight[:, :-2] * weight[:, 1:-1] * weight[:, 2:]
    middle = y[:, 1:-1] * triple
    cosine = (middle * (y[:, :-2] + y[:, 2:])).sum(axis=1) / np.maximum(2 * (middle * middle).sum(axis=1), 1e-300)
    steps = np.where(weight[:, 1:] * weight[:, :-1] > 0, np.diff(time_s, axis=1), np.nan)
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN rows: single-sample tracks
        dt = np.nanmedian(steps, axis=1)
        omega = np.where(cosine <= -1.0, np.pi / dt, np.arccos(np.clip(cosine, -1.0, 1.0)) / dt)
    valid = (n >= 4) & np.isfinite(omega) & (omega > 0) & (cosine < 1.0)
    omega = np.where(valid, omega, 1.0)

    # the orthographic fit runs on each track's offsets divided by their rms, so that it does
    # not depend on the positions' units (a degenerate track's iterations otherwise can)
    unit = np.sqrt((y * y).sum(axis=1) / np.maximum(n, 1))
    unit = np.where(unit > 0, unit, 1.0)
    y_unit = y / unit[:, None]
    # likewise its times, by their rms about the track's middle: the rate is fitted per unit of it
    period = np.sqrt((t * t).sum(axis=1) / np.maximum(n, 1))
    period = np.where(period > 0, period, 1.0)
    t_unit = t / period[:, None]

    def amplitudes(w: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        c, s_ = np.cos(w[:, None] * t_unit) * weight, np.sin(w[:, None] * t_unit) * weight
        cc, ss, cs = (c * c).sum(1), (s_ * s_).sum(1), (c * s_).sum(1)
        cy, sy = (c * y_unit).sum(1), (s_ * y_unit).sum(1)
        det = cc * ss - cs * cs
        det = np.where(np.abs(det) > 1e-300, det, 1e-300)
        a, b = (ss * cy - cs * sy) / det, (cc * sy - cs * cy) / det
        rss = ((y_unit - a[:, None] * c - b[:, None] * s_) ** 2).sum(1)
        return a, b, rss

    # a few trial rates around the first guess guard against a noisy start
    omega_unit = omega * period
    best_rss = np.full(len(omega), np.inf)
    best = omega_unit.copy()
    for factor in (0.7, 0.85, 1.0, 1.15, 1.3):
        _, _, rss = amplitudes(omega_unit * factor)
        better = rss < best_rss
        best = np.where(better, omega_unit * factor, best)
        best_rss = np.where(better, rss, best_rss)
    a, b, _ = amplitudes(best)
    params = _gauss_newton(np.column_stack([a, b, best]), _orthographic(t_unit, weight), y_unit, iterations)
    params[:, :2] *= unit[:, None]  # back to the offsets' units
    params[:, 2] /= period  # and to rad/s
    if camera is None:
        return [_finish(params, _orthographic(t, weight), y, 1.0, None, valid, n, mask, time_s)]
    # normalised image coordinates relative to the principal point; the orthographic fit
    # (A, B, w) is the same motion as (A, -B, -w): start the pinhole model from both senses
    scale = camera.focal_px
    target = (offset / scale + camera.axis_n) * weight
    model = _pinhole(t, weight, camera.axis_n, camera.depth_scale)
    fits = []
    for sense in senses:
        if sense == 0:
            starts = [params / [scale, scale, 1.0], params * [1.0 / scale, -1.0 / scale, -1.0]]
            fitted = [_gauss_newton(start, model, target, iterations) for start in starts]
            costs = [((target - model(fit, _ALL)[0]) ** 2).sum(1) for fit in fitted]
            sensed = np.where((costs[0] <= costs[1])[:, None], fitted[0], fitted[1])
        else:  # a sense decided for the whole body (see fit_tracks)
            flip = 1.0 if sense > 0 else -1.0
            start = params * [1.0 / scale, 1.0 / scale, 1.0]
            start[:, 1:] *= np.where(start[:, 2:3] * flip < 0, -1.0, 1.0)
            sensed = _gauss_newton(start, model, target, iterations)
        fits.append(_finish(sensed, model, target, scale, camera, valid, n, mask, time_s))
    return fits


def _finish(params: np.ndarray, model: Model, target: np.ndarray, scale: float, camera: Camera | None,
            valid: np.ndarray, n: np.ndarray, mask: np.ndarray, time_s: np.ndarray) -> list[TrackFit]:
    """The fits of a batch from its fitted ``params``: each rate's standard error, misfit and
    amplitude (in pixels: ``scale``), and the arc it turned through."""
    predicted, jacobian = model(params, _ALL)
    residual = target - predicted
    jtj = jacobian.transpose(0, 2, 1) @ jacobian
    rss = (residual**2).sum(1)
    with np.errstate(all="ignore"):
        # a (near-)singular J^T J means omega is not determined by the track: infinite error.
        # Its conditioning is judged with the columns scaled to unit length, so that it does not
        # depend on the units of the positions (the rate's column grows with the amplitude).
        diagonal = np.sqrt(np.maximum(np.einsum("kii->ki", jtj), 1e-300))
        scaled = jtj / diagonal[:, :, None] / diagonal[:, None, :]
        condition = np.linalg.cond(scaled) if len(jtj) else np.empty(0)
        safe = np.where((condition < 1e12)[:, None, None], jtj, np.eye(3))
        inverse_22 = np.where(condition < 1e12, np.linalg.inv(safe)[:, 2, 2], np.inf)
        se = np.sqrt(np.maximum(inverse_22 * rss / np.maximum(n - 3, 1), 0.0))
    duration = np.where(mask, time_s, -np.inf).max(1) - np.where(mask, time_s, np.inf).min(1)
    fits = []
    for k in range(len(params)):
        w_k = abs(float(params[k, 2]))
        if not valid[k] or not math.isfinite(w_k) or w_k == 0:
            fits.append(_FAILED)
            continue
        amplitude = float(math.hypot(params[k, 0], params[k, 1])) * scale
        sense = float(np.sign(params[k, 2])) if camera is not None else math.nan
        fits.append(TrackFit(w_k, float(se[k]), math.sqrt(float(rss[k]) / n[k]) * scale, amplitude,
                             w_k * float(duration[k]), sense))
    return fits


#: How much better (in summed evidence, see :func:`_sense_evidence`) one sense of rotation
#: must explain all tracks than the other before the sense is reported ...
SENSE_EVIDENCE = 25.0
#: ... and, with many tracks, this much times the square root of their number. Where the two
#: senses fit alike, each track's evidence is noise of spread about 3 (simulated pinhole tracks,
#: 5 to 80 of them), so the sum's spread grows as the root of the count: a fixed bar let 80
#: tracks that could not tell the sense decide it wrongly in 15% of trials, and 8 (about 2.5
#: spreads) holds that under 3% at every count tried.
SENSE_EVIDENCE_PER_ROOT_TRACK = 8.0
#: The most one track may add to that evidence: a rigid body's sense is a vote of its tracks,
#: and a track the pinhole model cannot follow (a slipping point, a fit that ran away) must not
#: outvote hundreds of good ones.
TRACK_EVIDENCE_CAP = 9.0


def _sense_evidence(plus: dict[int, TrackFit], minus: dict[int, TrackFit], count: pd.Series) -> tuple[float, int]:
    """Positive when the anticlockwise fits explain the tracks better: per track, the drop in
    squared misfit in units of that track's noise variance, capped at +-TRACK_EVIDENCE_CAP, summed;
    with the number of tracks that added to it."""
    total, voters = 0.0, 0
    for k, fit in plus.items():
        other = minus[k]
        if not (math.isfinite(fit.rms_residual) and math.isfinite(other.rms_residual)):
            continue
        n = int(count[k])
        rss_plus, rss_minus = fit.rms_residual**2 * n, other.rms_residual**2 * n
        variance = max(min(rss_plus, rss_minus) / max(n - 3, 1), 1e-6)
        total += float(np.clip((rss_minus - rss_plus) / variance, -TRACK_EVIDENCE_CAP, TRACK_EVIDENCE_CAP))
        voters += 1
    return total, voters


def fit_tracks(samples: pd.DataFrame, min_samples: int = 4, camera: Camera | None = None) -> dict[int, TrackFit]:
    """Fit every track of ``samples`` (sorted by track then time; columns ``track, time_s,
    offset_px``); keyed by track. Tracks with fewer than ``min_samples`` samples (at least 4)
    get a failed fit without trying.

    With a pinhole ``camera`` all tracks are fitted in both senses of rotation and the sense
    that explains the body as a whole is kept (a rigid body has one); each fit's ``sense`` says
    it, or is NaN when the two senses explain the tracks about equally well. Where the camera
    says the sense (``Camera.sense``), the tracks are fitted in that sense only.
    """
    if camera is None:
        return _fit_all(samples, min_samples, None, (0,))[0]
    if camera.sense:  # the view told it: seen from above, by the way the paths go round
        told = _fit_all(samples, min_samples, camera, (camera.sense,))[0]
        return {k: replace(fit, sense=float(camera.sense) if math.isfinite(fit.omega_rad_s) else math.nan)
                for k, fit in told.items()}
    fits = dict(zip((1, -1), _fit_all(samples, min_samples, camera, (1, -1)), strict=True))
    evidence, voters = _sense_evidence(fits[1], fits[-1], samples.groupby("track", sort=False).size())
    chosen = 1 if evidence >= 0 else -1
    decided = abs(evidence) >= max(SENSE_EVIDENCE, SENSE_EVIDENCE_PER_ROOT_TRACK * math.sqrt(voters))
    return {k: replace(fit, sense=float(chosen) if decided and math.isfinite(fit.omega_rad_s) else math.nan)
            for k, fit in fits[chosen].items()}


def _pad(times: np.ndarray, offsets: np.ndarray, parts: list[slice]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    longest = max((part.stop - part.start for part in parts), default=0)
    time_s = np.zeros((len(parts), longest))
    offset = np.zeros((len(parts), longest))
    mask = np.zeros((len(parts), longest), dtype=bool)
    for row, part in enumerate(parts):
        size = part.stop - part.start
        time_s[row, :size] = times[part]
        offset[row, :size] = offsets[part]
        mask[row, :size] = True
    return time_s, offset, mask


def _fit_all(samples: pd.DataFrame, min_samples: int, camera: Camera | None,
             senses: tuple[int, ...]) -> list[dict[int, TrackFit]]:
    """Every track's fit in each of ``senses`` (see :func:`_fit_batch_senses`), keyed by track."""
    tracks = samples["track"].to_numpy()
    times = samples["time_s"].to_numpy(dtype=float)
    offsets = samples["offset_px"].to_numpy(dtype=float)
    fits: list[dict[int, TrackFit]] = [{} for _ in senses]
    parts = []
    for part in _track_slices(tracks):
        if part.stop - part.start < max(min_samples, 4):
            for sensed in fits:
                sensed[int(tracks[part.start])] = _FAILED
        else:
            parts.append(part)
    parts.sort(key=lambda p: p.stop - p.start)
    batches: list[list[slice]] = []
    index = 0
    while index < len(parts):
        batch = [parts[index]]
        index += 1
        while index < len(parts):
            longest_next = parts[index].stop - parts[index].start
            if (len(batch) + 1) * longest_next > _BATCH_ELEMENTS:
                break
            batch.append(parts[index])
            index += 1
        batches.append(batch)

    def fit(batch: list[slice]) -> list[list[TrackFit]]:
        return _fit_batch_senses(*_pad(times, offsets, batch), camera, senses)

    # numpy lets go of the interpreter inside its array loops: two batches at once use both cores
    with ThreadPoolExecutor(max_workers=_FIT_THREADS) as pool:
        for batch, batch_fits in zip(batches, pool.map(fit, batches), strict=True):
            for sensed, sense_fits in zip(fits, batch_fits, strict=True):
                for part, track_fit in zip(batch, sense_fits, strict=True):
                    sensed[int(tracks[part.start])] = track_fit
    return fits
