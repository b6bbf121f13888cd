"""Estimators against analytic trajectories y = A cos(omega t + phi) (+ noise)."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from rotrate_cli.fitting import estimators
from rotrate_cli.fitting.camera import Camera
from rotrate_cli.fitting.outliers import RejectionConfig
from rotrate_cli.scene.axis import refine_axis_offset
from rotrate_cli.stages.checks import told_sense_doubt, undecided_sense
from rotrate_cli.stages.fits import rates_from_offsets
from rotrate_cli.stages.geometry import inliers_and_rate


@pytest.mark.parametrize("omega", [0.1, 0.327, 1.0, 3.14])
@pytest.mark.parametrize("step_s", [1 / 60, 1 / 30, 16 / 30])
def test_fit_is_exact_on_clean_sinusoids(omega: float, step_s: float) -> None:
    n = max(8, int(round(2.0 / (omega * step_s))))  # about two radians of arc
    time_s = np.arange(n) * step_s
    offset = 80.0 * np.cos(omega * time_s + 0.4)
    fit = estimators.fit_track(time_s, offset)
    assert fit.omega_rad_s == pytest.approx(omega, rel=1e-7)
    assert fit.amplitude == pytest.approx(80.0, rel=1e-6)
    assert fit.rms_residual < 1e-6


def test_fit_handles_uneven_times_and_coarse_steps() -> None:
    # 10 degrees per sample, as the dinosaur turntable; jittered timestamps
    rng = np.random.default_rng(1)
    time_s = np.cumsum(rng.uniform(0.8, 1.2, 15))
    offset = 150.0 * np.sin(0.17453 * time_s - 1.0)
    assert estimators.fit_track(time_s, offset).omega_rad_s == pytest.approx(0.17453, rel=1e-7)


def test_fit_with_noise_is_unbiased_and_its_error_is_honest(rng: np.random.Generator) -> None:
    omega, sigma = 0.6, 0.3
    time_s = np.arange(90) / 30.0
    estimates, errors = [], []
    for _ in range(200):
        offset = 100.0 * np.cos(omega * time_s - 0.7) + rng.normal(0, sigma, time_s.size)
        fit = estimators.fit_track(time_s, offset)
        estimates.append(fit.omega_rad_s)
        errors.append(fit.omega_se_rad_s)
    estimates = np.array(estimates)
    assert abs(estimates.mean() - omega) < 3 * estimates.std() / math.sqrt(len(estimates))
    # the standard error the fit reports matches the scatter within 20%
    assert np.median(errors) == pytest.approx(estimates.std(), rel=0.2)


def test_recurrence_is_exact_and_flags_curving_away() -> None:
    time_s = np.arange(12) * 0.1
    assert estimators.recurrence_omega(time_s, 5 * np.cos(2.0 * time_s)) == pytest.approx(2.0, rel=1e-9)
    assert math.isnan(estimators.recurrence_omega(time_s, 5 * np.cosh(2.0 * time_s)))
    assert math.isnan(estimators.fit_track(time_s, 5 * np.cosh(2.0 * time_s)).omega_rad_s)


def test_paper_samples_are_backward_differences() -> None:
    time_s = np.arange(5) * 0.5
    offset = np.array([3.0, 2.8, 2.2, 1.4, 0.3])
    samples = pd.DataFrame({"track": 1, "frame": range(5), "time_s": time_s, "offset_px": offset})
    table = estimators.paper_samples(samples)
    dy = np.diff(offset) / 0.5
    assert np.allclose(table["dy_dt"].to_numpy()[1:], dy)
    assert np.allclose(table["d2y_dt2"].to_numpy()[2:], np.diff(dy) / 0.5)
    assert np.allclose(table["omega2"].to_numpy()[2:], -(np.diff(dy) / 0.5) / offset[2:])
    assert table["omega_rad_s"].isna().sum() == 2


def test_local_samples_give_the_rate_at_every_interior_sample() -> None:
    time_s = np.arange(40) / 30.0
    offset = 60.0 * np.cos(0.9 * time_s + 0.2)
    samples = pd.DataFrame({"track": 3, "frame": range(40), "time_s": time_s, "offset_px": offset})
    table = estimators.fit_samples(samples, {3: estimators.fit_tracks(samples)[3].omega_rad_s})
    valid = table["omega_rad_s"].dropna()
    assert len(valid) >= 20
    assert np.allclose(valid, 0.9, rtol=1e-6)
    interior = table.dropna(subset=["d2y_dt2"])
    assert np.allclose(interior["d2y_dt2"], -(0.9**2) * interior["offset_px"], rtol=1e-5, atol=1e-9)


@pytest.mark.parametrize("omega", [0.5, -0.5])
def test_pinhole_fit_recovers_rate_and_sense(omega: float) -> None:
    # camera 1 unit from the axis (normalised), point at radius 0.25, axis 40 px right of centre
    focal_px, axis_px = 1200.0, 40.0
    camera = Camera(focal_px, axis_px / focal_px)
    time_s = np.arange(60) / 30.0
    angle = omega * time_s + 0.3
    x_n = (camera.axis_n + 0.25 * np.sin(angle)) / (1 - 0.25 * np.cos(angle))
    offset = x_n * focal_px - axis_px
    fit = estimators._fit_batch(time_s[None], offset[None], np.ones((1, 60), bool), camera)[0]
    assert fit.omega_rad_s == pytest.approx(abs(omega), rel=1e-7)
    assert fit.sense == np.sign(omega)
    ortho = estimators.fit_track(time_s, offset)
    assert abs(ortho.omega_rad_s / abs(omega) - 1) > 0.01  # what ignoring perspective costs here


def test_pinhole_fit_of_a_camera_looking_down() -> None:
    # seen from 35 degrees above, depth changes by the radial position times cos(35)
    focal_px, depth_scale = 1200.0, math.cos(math.radians(35.0))
    time_s = np.arange(60) / 30.0
    angle = 0.5 * time_s + 0.3
    x_n = 0.25 * np.sin(angle) / (1 - depth_scale * 0.25 * np.cos(angle))
    offset = x_n * focal_px
    looking_down = estimators._fit_batch(time_s[None], offset[None], np.ones((1, 60), bool),
                                    Camera(focal_px, 0.0, depth_scale))[0]
    camera = Camera(focal_px, 0.0)
    level = estimators._fit_batch(time_s[None], offset[None], np.ones((1, 60), bool), camera)[0]
    assert looking_down.omega_rad_s == pytest.approx(0.5, rel=1e-7)
    assert abs(level.omega_rad_s / 0.5 - 1) > 0.005  # what taking the camera as level costs here
    samples = pd.DataFrame({"track": 0, "time_s": time_s, "offset_px": offset})
    # the joint fit's linear form agrees: its misfit vanishes at the true rate only with the elevation
    from rotrate_cli.fitting.joint import track_misfits
    assert track_misfits(samples, 0.5, Camera(focal_px, 0.0, depth_scale))[0] == pytest.approx(0.0, abs=1e-9)
    assert track_misfits(samples, 0.5, Camera(focal_px, 0.0))[0] > 1e-3


def _weak_clockwise_tracks(rng: np.random.Generator, focal_px: float) -> pd.DataFrame:
    """12 short tracks of points near the axis turning clockwise at 0.7 rad/s through a pinhole:
    each says little of the sense."""
    rows = []
    for track in range(12):
        time_s = np.arange(45) / 30.0 + rng.uniform(0, 2)
        angle = -0.7 * time_s + rng.uniform(-1, 1)  # clockwise
        radius = rng.uniform(0.04, 0.09)
        x_n = radius * np.sin(angle) / (1 - radius * np.cos(angle))
        rows.append(pd.DataFrame({"track": track, "time_s": time_s,
                                  "offset_px": x_n * focal_px + rng.normal(0, 0.05, 45)}))
    return pd.concat(rows, ignore_index=True)


def test_body_wide_sense_from_many_weak_tracks(rng: np.random.Generator) -> None:
    focal_px = 1500.0
    camera = Camera(focal_px, 0.0)
    fits = estimators.fit_tracks(_weak_clockwise_tracks(rng, focal_px), camera=camera)
    assert all(fit.sense == -1 for fit in fits.values())
    assert np.median([fit.omega_rad_s for fit in fits.values()]) == pytest.approx(0.7, rel=0.01)


def test_a_sense_the_view_told_is_the_one_fitted(rng: np.random.Generator) -> None:
    """Seen steeply from above, a short noisy turn's tracks can favour the wrong sense through
    the pinhole (a render turned 0.4 rad, 5 grey levels of noise, read cw, +11%, for ccw); the
    lens's fit tells the sense from the way the paths go round, and the tracks are fitted in it."""
    focal_px = 1500.0
    samples = _weak_clockwise_tracks(rng, focal_px)
    told = estimators.fit_tracks(samples, camera=Camera(focal_px, 0.0, sense=-1))
    assert all(fit.sense == -1 for fit in told.values())
    assert np.median([fit.omega_rad_s for fit in told.values()]) == pytest.approx(0.7, rel=0.01)
    # told the other sense, the tracks are fitted in it (and fit worse): the view's word is kept
    wrong = estimators.fit_tracks(samples, camera=Camera(focal_px, 0.0, sense=1))
    assert all(fit.sense == 1 for fit in wrong.values())
    assert (np.median([fit.rms_residual for fit in wrong.values()])
            > np.median([fit.rms_residual for fit in told.values()]))


def _pinhole_tracks(rng: np.random.Generator, count: int, omega: float, focal_px: float = 500.0) -> pd.DataFrame:
    """``count`` tracks of 45 samples (1.5 s) at radii 0.2-0.6 of the camera's distance, turning
    anticlockwise at ``omega`` through a pinhole, with 1.5 px of noise."""
    rows = []
    for track in range(count):
        time_s = np.arange(45) / 30.0 + rng.uniform(0, 2)
        angle = omega * time_s + rng.uniform(0, 2 * np.pi)
        radius = rng.uniform(0.2, 0.6)
        x_n = radius * np.sin(angle) / (1 - radius * np.cos(angle))
        rows.append(pd.DataFrame({"track": track, "time_s": time_s,
                                  "offset_px": x_n * focal_px + rng.normal(0, 1.5, 45)}))
    return pd.concat(rows, ignore_index=True)


def _senses(omega: float, count: int, trials: int) -> list[float]:
    camera = Camera(500.0, 0.0)
    rng = np.random.default_rng(17)
    senses = []
    for _ in range(trials):
        told = {fit.sense for fit in estimators.fit_tracks(_pinhole_tracks(rng, count, omega), camera=camera).values()
                if math.isfinite(fit.omega_rad_s)}
        assert len(told) == 1  # one body, one sense (or NaN for all)
        senses.append(told.pop())
    return senses


def test_many_tracks_that_cannot_tell_the_sense_leave_it_undecided() -> None:
    """80 tracks turned 0.3 rad each: the two senses fit about alike, and summed over many
    tracks that noise passed the fixed bar alone, deciding the wrong sense in 3 of these 40
    trials (undecided in 24)."""
    senses = _senses(0.2, 80, 40)
    assert sum(sense == -1 for sense in senses) <= 1
    assert sum(math.isnan(sense) for sense in senses) >= 30


def test_many_tracks_that_tell_the_sense_decide_it() -> None:
    senses = _senses(0.5, 80, 10)
    assert sum(sense == 1 for sense in senses) >= 9


def test_an_undecided_sense_reads_alike_both_ways_round() -> None:
    """A clip and its mirror image (the same body turning the other way) whose tracks cannot
    tell the sense read the same rate, midway between the two senses' rates, within the same
    interval, which holds the truth: nothing depends on which sense is the default (the
    anticlockwise one's rate was the point: 0.205 rad/s for the clip, 0.185 for its mirror)."""
    camera = Camera(500.0, 0.0)
    tracks = _pinhole_tracks(np.random.default_rng(5), 80, 0.2)
    tracks["frame"] = np.round(tracks["time_s"] * 30).astype(int)
    mirror = tracks.assign(offset_px=-tracks["offset_px"])
    results = [rates_from_offsets(table, "fit", RejectionConfig(), camera) for table in (tracks, mirror)]
    for result in results:
        assert result.direction == "unknown"  # undecided
        assert result.combined.omega_low_rad_s <= 0.2 <= result.combined.omega_high_rad_s
        slower, faster = sorted(result.combined.senses_rad_s)
        assert slower < result.combined.omega_rad_s < faster
        assert f"{slower:.4g} and {faster:.4g} rad/s" in undecided_sense(result.combined)
    first, second = (result.combined for result in results)
    assert (first.omega_rad_s, first.omega_low_rad_s, first.omega_high_rad_s) == pytest.approx(
        (second.omega_rad_s, second.omega_low_rad_s, second.omega_high_rad_s), rel=1e-3)


def _near_side_tracks(rng: np.random.Generator, count: int, omega: float, focal_px: float = 500.0) -> pd.DataFrame:
    """As :func:`_pinhole_tracks`, but each track seen only on the near side of its circle, within
    1.2 rad of its middle, as on an opaque body: a clockwise turn travels left there."""
    rows = []
    for track in range(count):
        time_s = np.arange(45) / 30.0 + rng.uniform(0, 2)
        angle = omega * (time_s - time_s[22]) + rng.uniform(-1.2, 1.2)
        radius = rng.uniform(0.2, 0.6)
        x_n = radius * np.sin(angle) / (1 - radius * np.cos(angle))
        rows.append(pd.DataFrame({"track": track, "time_s": time_s,
                                  "offset_px": x_n * focal_px + rng.normal(0, 1.5, 45)}))
    tracks = pd.concat(rows, ignore_index=True)
    return tracks.assign(frame=np.round(tracks["time_s"] * 30).astype(int))


@pytest.mark.parametrize(("seed", "omega", "direction"), [(1, 0.2, "ccw"), (3, -0.2, "cw")])
def test_an_undecided_sense_is_the_one_the_near_side_travels(seed: int, omega: float, direction: str) -> None:
    """Where the fits through the lens do not tell the sense but the tracks, all on the near side
    of an opaque body, travel one way (the paper's rule), the rate is that sense's, and the
    interval still holds the other's: midway, these read 0.249 and 0.229 rad/s for 0.2."""
    result = rates_from_offsets(_near_side_tracks(np.random.default_rng(seed), 80, omega), "fit", RejectionConfig(),
                                Camera(500.0, 0.0))
    combined = result.combined
    assert result.direction == direction
    assert combined.senses_rad_s is not None  # the fits did not tell
    assert combined.seen_sense == (1 if direction == "ccw" else -1)
    assert combined.omega_rad_s == pytest.approx(0.2, rel=0.02)
    assert combined.omega_low_rad_s <= min(combined.senses_rad_s) <= max(combined.senses_rad_s) \
        <= combined.omega_high_rad_s
    assert f"the rate is the {direction} one" in undecided_sense(combined)


def test_an_undecided_sense_places_the_axis_without_the_lens() -> None:
    """Where the tracks cannot tell the sense through a lens, the axis is placed
    orthographically: the pinhole model in the wrong sense moved a fixation 10 px right of the
    axis 91 px to its left (the mirror image, the anticlockwise default); now 4 px or less
    from it, the clip and its mirror alike."""
    camera = Camera(500.0, 0.0)
    tracks = _pinhole_tracks(np.random.default_rng(5), 80, 0.2)
    tracks["frame"] = np.round(tracks["time_s"] * 30).astype(int)
    for table in (tracks, tracks.assign(offset_px=-tracks["offset_px"])):
        off_axis = table.assign(offset_px=table["offset_px"] - 10.0)  # measured from 10 px right of the axis
        result = rates_from_offsets(off_axis, "fit", RejectionConfig(), camera)
        assert result.direction == "unknown"
        offsets, omega, placing = inliers_and_rate(result, camera)
        assert placing is None
        assert refine_axis_offset(offsets, omega, placing) == pytest.approx(-10.0, abs=4.0)


def _fitted_through(tracks: pd.DataFrame, camera: Camera):
    tracks = tracks.assign(frame=np.round(tracks["time_s"] * 30).astype(int))
    return rates_from_offsets(tracks, "fit", RejectionConfig(), camera)


def test_a_sense_the_user_gave_is_fitted_and_checked_against_the_tracks() -> None:
    """--direction: the tracks are fitted in the sense given. Where they clearly tell the other
    (80 tracks turned 0.75 rad through a 500 px pinhole) a doubt says so; where they tell the
    same, or cannot tell, nothing is said."""
    tracks = _pinhole_tracks(np.random.default_rng(3), 80, 0.5)
    for told, doubted in ((1, False), (-1, True)):
        camera = Camera(500.0, 0.0, 1.0, told)
        result = _fitted_through(tracks, camera)
        assert result.direction == ("ccw" if told > 0 else "cw")
        doubt = told_sense_doubt(result, camera, told)
        assert (doubt is not None) == doubted
    assert "turns ccw, not cw as `direction` says" in doubt
    right = _fitted_through(tracks, Camera(500.0, 0.0, 1.0, 1)).combined
    assert right.omega_low_rad_s <= 0.5 <= right.omega_high_rad_s
    weak = _pinhole_tracks(np.random.default_rng(5), 80, 0.2)  # undecided (see above)
    camera = Camera(500.0, 0.0, 1.0, -1)
    assert told_sense_doubt(_fitted_through(weak, camera), camera, -1) is None


def test_the_sense_the_tracks_told_is_read_one_way() -> None:
    """The tracks' senses (NaN where a track's fit did not tell one) give the sense by their sum's
    sign; evenly split, 0; none told, None. The joint fit, the axis's placing and the second looks
    read it from the one function."""
    from rotrate_cli.stages.fits import told_sense

    nan = float("nan")
    assert told_sense(np.array([1.0, 1.0, -1.0, nan])) == 1
    assert told_sense(np.array([-1.0, nan, -1.0])) == -1
    assert told_sense(np.array([1.0, -1.0])) == 0
    assert told_sense(np.array([nan, nan])) is None
    assert told_sense(np.array([])) is None
