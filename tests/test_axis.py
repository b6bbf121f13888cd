"""Beyond the paper's geometry: the axis found from the motion, any axis angle, omega(t)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from rotrate_cli import AnalysisConfig, analyze
from rotrate_cli.analysis import rates_from_offsets
from rotrate_cli.cli import app
from rotrate_cli.fitting.camera import Camera
from rotrate_cli.fitting.outliers import RejectionConfig
from rotrate_cli.fitting.series import rate_series
from rotrate_cli.scene import axis as axes
from tests.conftest import DINOSAUR, SAMPLES, direction_seen_as, need, truth_of


def _distance_to_axis(point: tuple[float, float], truth: dict, angle_deg: float) -> float:
    """Pixels from the true axis point to the found axis line."""
    ux, uy = axes.unit_offset(angle_deg)
    fx, fy = truth["fixation_px"]
    return abs((point[0] - fx) * ux + (point[1] - fy) * uy)


def _tracks(rng: np.random.Generator, angle_deg: float, axis_px: tuple[float, float], omega: float,
            alpha: float = 0.0, count: int = 120) -> pd.DataFrame:
    """Orthographic image tracks of points on a body spinning about an axis at ``angle_deg``."""
    ux, uy = axes.unit_offset(angle_deg)
    rows = []
    for track in range(count):
        frames = np.arange(int(rng.integers(0, 150)), int(rng.integers(160, 300)))
        time_s = frames / 30.0
        radius = rng.uniform(20, 120)
        along = rng.uniform(-80, 80)
        offset = radius * np.sin(omega * time_s + 0.5 * alpha * time_s**2 + rng.uniform(0, 2 * np.pi))
        offset = offset + rng.normal(0, 0.1, len(frames))
        rows.append(pd.DataFrame({"track": track, "frame": frames, "time_s": time_s,
                                  "x_px": axis_px[0] + offset * ux - along * uy,
                                  "y_px": axis_px[1] + offset * uy + along * ux}))
    return pd.concat(rows, ignore_index=True)


@pytest.mark.parametrize("angle", [0.0, 10.0, -35.0, 90.0])
def test_axis_angle_and_position_from_analytic_tracks(rng: np.random.Generator, angle: float) -> None:
    tracks = _tracks(rng, angle, (300.0, 200.0), 0.7)
    found = axes.motion_angle_deg(tracks)
    assert math.cos(math.radians(found - angle)) == pytest.approx(1.0, abs=1e-4)  # within ~0.8 degree, any sign
    offset = axes.axis_offset_from_recurrence(tracks, axes.offsets_along(tracks, (0.0, 0.0), found))
    point = axes.point_on_axis(offset, found, tracks)
    assert _distance_to_axis(point, {"fixation_px": (300.0, 200.0)}, found) < 0.5


def test_recurrence_ignores_lags_only_a_few_long_tracks_reach(rng: np.random.Generator) -> None:
    # many short tracks about an axis at x = 320, and a long one well to its right that drifts
    # slowly (a mis-track that lasted): only it reaches a lag of 32 frames. Seen on a
    # 720p cylinder: 121 such triples moved the axis 100 px, and the refined one stayed 10 px off.
    rows = []
    for track in range(300):
        start = int(rng.integers(0, 200))
        frames = np.arange(start, start + 40)
        time_s = frames / 30.0
        offset = rng.uniform(20, 120) * np.sin(1.5 * time_s + rng.uniform(0, 2 * np.pi))
        rows.append(pd.DataFrame({"track": track, "frame": frames, "time_s": time_s, "x_px": 320 + offset,
                                  "y_px": 200.0}))
    for track in range(300, 301):
        frames = np.arange(0, 120)
        rows.append(pd.DataFrame({"track": track, "frame": frames, "time_s": frames / 30.0,
                                  "x_px": 760 + 40 * np.sin(0.4 * frames / 30.0 + track), "y_px": 200.0}))
    tracks = pd.concat(rows, ignore_index=True)
    position = tracks["x_px"].to_numpy()
    assert axes.axis_offset_from_recurrence(tracks, position) == pytest.approx(320.0, abs=0.5)
    # (before: 760, the long track's own centre.) The first rate is a starting guess: within 5%
    assert axes.rate_from_recurrence(tracks, position) == pytest.approx(1.5, rel=0.05)


@pytest.mark.parametrize("seed", range(4))
def test_recurrence_passes_over_long_lags_of_still_reflections(seed: int) -> None:
    """Like a car's glossy paint photographed every 3.7 degrees: 150 tracks on the body, of 12-20
    frames about an axis at x = 190, and four reflections of the hall that stay where they are but
    for a jitter and last all 70 frames, so that they alone reach the lags of 16 and 32 frames.
    Those lags read a slope of almost 2 with a large standard error; the longest one, used
    before, put the axis 24-102 px off and the rate at a tenth to a half of the truth."""
    rng = np.random.default_rng(seed)
    rows = []
    for track in range(150):
        count = int(rng.integers(12, 21))
        frames = np.arange(start := int(rng.integers(0, 70 - count)), start + count)
        x = 190 + rng.uniform(40, 150) * np.sin(0.065 * frames + rng.uniform(0, 2 * np.pi)) + rng.normal(0, 0.7, count)
        rows.append(pd.DataFrame({"track": track, "frame": frames, "time_s": frames * 1.0, "x_px": x, "y_px": 100.0}))
    for track in range(150, 154):
        frames = np.arange(70)
        x = rng.uniform(250, 370) + np.cumsum(rng.normal(0, 0.6, 70))
        rows.append(pd.DataFrame({"track": track, "frame": frames, "time_s": frames * 1.0, "x_px": x, "y_px": 100.0}))
    tracks = pd.concat(rows, ignore_index=True)
    position = tracks["x_px"].to_numpy()
    # a first guess, for the joint fit to refine: the reflections still weigh on the short lags
    assert axes.axis_offset_from_recurrence(tracks, position) == pytest.approx(190.0, abs=25.0)
    assert axes.rate_from_recurrence(tracks, position) == pytest.approx(0.065, rel=0.25)


@pytest.mark.parametrize("omega", [0.7, -0.7])
def test_refining_the_axis_with_a_pinhole_camera(rng: np.random.Generator, omega: float) -> None:
    # normalised image x = (axis_n + r sin th) / (1 - k r cos th); offsets measured from a point
    # 3 px right of the axis: the refinement moves it back by 3 px, in either sense
    focal_px, axis_px, depth_scale = 900.0, 40.0, math.cos(math.radians(20.0))
    rows = []
    for track in range(60):
        time_s = np.arange(int(rng.integers(0, 60)), int(rng.integers(80, 150))) / 30.0
        radius, phase = rng.uniform(0.03, 0.12), rng.uniform(0, 2 * np.pi)
        angle = omega * time_s + phase
        x_n = (axis_px / focal_px + radius * np.sin(angle)) / (1 - depth_scale * radius * np.cos(angle))
        rows.append(pd.DataFrame({"track": track, "time_s": time_s,
                                  "offset_px": x_n * focal_px - (axis_px + 3.0) + rng.normal(0, 0.05, len(time_s))}))
    samples = pd.concat(rows, ignore_index=True)
    camera = Camera(focal_px, (axis_px + 3.0) / focal_px, depth_scale)
    pinhole = axes.refine_axis_offset(samples, omega, camera)
    assert pinhole == pytest.approx(-3.0, abs=0.03)
    # the orthographic model misplaces it (by 0.1 px here: near points move faster)
    assert abs(axes.refine_axis_offset(samples, abs(omega)) + 3.0) > 2 * abs(pinhole + 3.0)


def test_refining_the_axis_moves_it_onto_the_truth(rng: np.random.Generator) -> None:
    tracks = _tracks(rng, 0.0, (300.0, 200.0), 0.7)
    offsets = pd.DataFrame({"track": tracks["track"], "time_s": tracks["time_s"], "offset_px": tracks["x_px"] - 303.0})
    assert axes.refine_axis_offset(offsets, 0.7) == pytest.approx(-3.0, abs=0.05)


def test_a_found_axis_is_moved_to_where_its_moves_end(monkeypatch: pytest.MonkeyPatch) -> None:
    """On a short arc the axis's place and the rate are each found from the other, and each move
    of the axis goes only part of the way: here 15% of what is left (a coupling of 0.85, as on
    the 15th to 64th photographs of EPFL car 10). Two plain moves left 72% of the first point's
    error; the moves now end where the point and the rate agree."""
    from rotrate_cli.stages import geometry

    settled_px, coupling = 7.0, 0.85
    ux, uy = axes.unit_offset(10.0)
    at = {"along": 0.0}
    measured = []

    def shift(offsets: object, omega: float, camera: object) -> float:
        return (1.0 - coupling) * (settled_px - at["along"])

    def measure(point: tuple[float, float]) -> tuple[None, None]:
        at["along"] = (point[0] - 300.0) * ux + (point[1] - 100.0) * uy
        measured.append(point)
        return None, None

    monkeypatch.setattr(geometry, "inliers_and_rate", lambda result, camera: (None, 1.0, None))
    monkeypatch.setattr(geometry.axes, "refine_axis_offset", shift)
    fixation, _, _ = geometry._refine_fixation(None, None, (300.0, 100.0), 10.0, measure)
    assert (fixation[0] - 300.0) * ux + (fixation[1] - 100.0) * uy == pytest.approx(settled_px, abs=0.02)
    assert (fixation[0] - 300.0) * uy - (fixation[1] - 100.0) * ux == pytest.approx(0.0, abs=1e-9)  # across only
    assert len(measured) <= geometry.REFINE_STEPS


@pytest.mark.parametrize(("coupling", "gain"), [(0.0, 1.0), (-0.4, 1.0), (math.nan, 1.0), (0.5, 2.0),
                                                (0.85, 1 / 0.15), (0.97, 10.0), (1.6, 10.0)])
def test_the_axis_and_rate_coupling_multiplies_the_rate_s_uncertainty(coupling: float, gain: float) -> None:
    """An error in the rate moves the axis, which moves the rate: 1 / (1 - coupling) times the
    error the tracks' scatter and the axis's placement give (at most 10: at 1 or more the tracks
    do not tell the two apart)."""
    from rotrate_cli.fitting.outliers import Combined
    from rotrate_cli.stages.checks import with_axis_doubt
    from rotrate_cli.stages.fits import RateResult
    from rotrate_cli.stages.geometry import AxisSpread

    offsets = pd.DataFrame({"track": [1] * 3, "time_s": [0.0, 1.0, 2.0], "offset_px": [0.0] * 3})
    result = RateResult(offsets, pd.DataFrame(), Combined(0.1, 0.099, 0.102, 20), "ccw")
    spread = AxisSpread(se_px=0.3, rate_per_px=0.0, coupling=coupling)  # the placement alone adds nothing
    widened = with_axis_doubt(result, spread)[0].combined
    assert widened.omega_rad_s == 0.1
    assert widened.omega_low_rad_s == pytest.approx(0.1 - gain * 0.001, rel=1e-9)
    assert widened.omega_high_rad_s == pytest.approx(0.1 + gain * 0.002, rel=1e-9)


def test_the_axis_offsets_standard_error_holds_how_tracks_disagree(rng: np.random.Generator) -> None:
    """Each track turns about its own axis, 1 px rms about the true one (a window sliding on a
    real surface, a model left short), on arcs under a turn. Over repeated draws the shared
    offset's error, divided by its standard error, has a spread near 1: the standard error
    comes from how the tracks disagree, not from the samples' noise alone (0.05 px here)."""
    z = []
    for _ in range(150):
        rows = []
        for track in range(30):
            time_s = np.arange(int(rng.integers(0, 40)), int(rng.integers(60, 110))) / 30.0
            amplitude, phase = rng.uniform(40, 120), rng.uniform(0, 2 * np.pi)
            own = rng.normal(0, 1.0)
            rows.append(pd.DataFrame({"track": track, "time_s": time_s,
                                      "offset_px": own + amplitude * np.cos(0.7 * time_s + phase)
                                      + rng.normal(0, 0.05, len(time_s))}))
        samples = pd.concat(rows, ignore_index=True)
        z.append(axes.refine_axis_offset(samples, 0.7) / axes.axis_offset_se(samples, 0.7))
    assert 0.8 <= float(np.std(z)) <= 1.25
    assert abs(float(np.mean(z))) < 0.3


def test_no_motion_gives_no_angle() -> None:
    still = pd.DataFrame({"track": [1, 1, 1], "frame": [0, 1, 2], "x_px": [5.0] * 3, "y_px": [7.0] * 3})
    assert math.isnan(axes.motion_angle_deg(still))


def test_series_follows_an_analytic_spin_up(rng: np.random.Generator) -> None:
    tracks = _tracks(rng, 0.0, (0.0, 0.0), 0.3, alpha=0.15, count=200)
    offsets = pd.DataFrame({"track": tracks["track"], "frame": tracks["frame"], "time_s": tracks["time_s"],
                            "offset_px": tracks["x_px"]}).sort_values(["track", "time_s"])
    series = rate_series(offsets, 2.0, lambda part: rates_from_offsets(part, "fit", RejectionConfig()).combined)
    # tracks here start anywhere in the first 5 s: the first windows hold few, and short
    whole = series[np.isclose(series["time_s"] % 1.0, 0.0) & (series["time_s"] >= 3.0)]
    assert len(whole) >= 6
    truth = 0.3 + 0.15 * whole["time_s"]
    assert (np.abs(whole["omega_rad_s"] / truth - 1) < 0.03).all()


@pytest.mark.parametrize("name", ["box_ortho", "cylinder_ortho", "box_roll10", "cylinder_horizontal"])
def test_fixation_auto_on_sample_clips(name: str) -> None:
    clip = SAMPLES / f"{name}.mp4"
    truth = truth_of(clip)
    given = analyze(clip, AnalysisConfig(fixation_px=tuple(truth["fixation_px"])))
    found = analyze(clip, AnalysisConfig(fixation_px=None))
    assert found.axis_found and found.axis_angle_found
    error_deg = found.axis_angle_deg - truth.get("axis_angle_deg", 0.0)
    assert abs(math.sin(math.radians(error_deg))) < math.sin(math.radians(1.0))  # the line within 1 degree
    assert _distance_to_axis(found.fixation_px, truth, found.axis_angle_deg) < 2.0
    assert found.omega_rad_s == pytest.approx(given.omega_rad_s, rel=0.01)
    assert found.omega_rad_s == pytest.approx(truth["omega_rad_s"], rel=0.01)
    assert found.direction == direction_seen_as(truth, found.axis_angle_deg)


def test_given_axis_angle_is_used() -> None:
    clip = SAMPLES / "box_roll10.mp4"
    truth = truth_of(clip)
    result = analyze(clip, AnalysisConfig(fixation_px=tuple(truth["fixation_px"]), axis_angle_deg=10.0))
    assert result.axis_angle_deg == 10.0 and not result.axis_angle_found
    assert result.omega_rad_s == pytest.approx(0.5, rel=0.01)
    assert result.direction == "ccw"


def test_spin_up_series_within_three_percent_at_whole_seconds(tmp_path: Path) -> None:
    clip = SAMPLES / "box_spinup.mp4"
    truth = truth_of(clip)
    series_path = tmp_path / "series.csv"
    result = CliRunner().invoke(app, ["analyze", str(clip), "--fixation", "{},{}".format(*truth["fixation_px"]),
                                      "--window", "2", "--series-csv", str(series_path), "--format", "json"])
    assert result.exit_code == 0, result.output
    series = pd.read_csv(series_path)
    assert list(series.columns) == ["time_s", "omega", "omega_low", "omega_high", "tracks_used", "rate_from",
                                    "quality"]
    assert set(series["rate_from"]) == {"tracks"}  # a spin-up does not repeat: its tracks rate it
    whole = series[np.isclose(series["time_s"] % 1.0, 0.0) & (series["time_s"] >= 2.0)]
    assert len(whole) >= 5
    rate = truth["scene"]["omega_rad_s"] + truth["alpha_rad_s2"] * whole["time_s"]
    assert (np.abs(whole["omega"] / rate - 1) < 0.03).all(), whole
    assert '"series"' in result.stdout


def test_series_csv_needs_a_window(tmp_path: Path) -> None:
    result = CliRunner().invoke(app, ["analyze", str(SAMPLES / "box_ortho.mp4"), "--fixation", "auto",
                                      "--series-csv", str(tmp_path / "s.csv")])
    assert result.exit_code == 2
    assert "--window" in result.output


def test_dinosaur_with_fixation_auto_within_two_percent() -> None:
    need(DINOSAUR / "frames", "the dinosaur photographs")
    result = analyze(DINOSAUR / "frames", AnalysisConfig(fixation_px=None, fps=1.0))
    assert result.omega_rad_s == pytest.approx(0.17453, rel=0.02)
    # the matched features (the default on photographs) include the turntable's top and the far
    # side, travelling the other way: 68% of the travel one way leaves the sense untold (70%
    # needed); Lucas-Kanade's fewer tracks told it
    assert result.direction in ("cw", "unknown")
    klt = analyze(DINOSAUR / "frames", AnalysisConfig(fixation_px=None, fps=1.0, tracker_kind="klt"))
    assert klt.direction == "cw"


@pytest.mark.slow  # renders a clip (about 10 s): make test-slow keeps make test under 4 minutes
def test_camera_elevation_seen_from_above(tmp_path: Path) -> None:
    # a camera looking down 25 degrees: the top shows and points move on ellipses; the horizontal
    # offset is still a sinusoid, so rate, axis and direction hold (the renderer's elevation)
    clip = tmp_path / "above.mp4"
    result = CliRunner().invoke(app, ["synth", str(clip), "--shape", "box", "--omega", "-0.6", "--elevation", "25",
                                      "--size", "320x180", "--duration", "4", "--seed", "43"])
    assert result.exit_code == 0, result.output
    truth = truth_of(clip)
    given = analyze(clip, AnalysisConfig(fixation_px=tuple(truth["fixation_px"])))
    found = analyze(clip, AnalysisConfig(fixation_px=None))
    for analysis in (given, found):
        assert analysis.omega_rad_s == pytest.approx(0.6, rel=0.01)
        assert analysis.direction == "cw"
    assert found.fixation_px[0] == pytest.approx(truth["fixation_px"][0], abs=2.0)


def _near_side_paths(angle_deg: float, elevation_deg: float, omega: float, seed: int = 5) -> pd.DataFrame:
    """Points of a body turning about an axis at ``angle_deg`` in the image, seen from
    ``elevation_deg`` above (orthographic): each on an ellipse, seen only over part of the near
    side, and more on one side of the axis than the other (as points appear on one side and
    turn away on the other)."""
    rng = np.random.default_rng(seed)
    ux, uy = axes.unit_offset(angle_deg)
    vx, vy = -uy, ux  # along the axis, downwards for a vertical axis
    rows = []
    for k in range(80):
        radius = rng.uniform(40, 120)
        height = rng.uniform(-60, 60)
        start = rng.uniform(-1.4, 0.2)  # the near side is theta in (-pi/2, pi/2); starts lean left
        length = rng.uniform(0.6, 1.4)
        times = np.arange(0.0, length / omega, 1 / 30)
        theta = start + omega * times
        u = radius * np.sin(theta) + rng.normal(0, 0.05, len(times))
        v = height + radius * np.cos(theta) * math.sin(math.radians(elevation_deg)) + rng.normal(0, 0.05, len(times))
        for i, t in enumerate(times):
            rows.append((k, i, t, 320 + u[i] * ux + v[i] * vx, 180 + u[i] * uy + v[i] * vy))
    return pd.DataFrame(rows, columns=["track", "frame", "time_s", "x_px", "y_px"])


@pytest.mark.parametrize(("angle_deg", "elevation_deg"), [(0.0, 30.0), (7.0, 25.0), (-12.0, 40.0), (88.0, 20.0)])
def test_path_shape_finds_the_angle_where_the_motion_leans(angle_deg: float, elevation_deg: float) -> None:
    tracks = _near_side_paths(angle_deg, elevation_deg, omega=0.5)
    motion = axes.motion_angle_deg(tracks)
    omega = axes.rate_from_recurrence(tracks, axes.offsets_along(tracks, (0.0, 0.0), motion))
    shape = axes.path_shape(tracks, omega)
    assert shape is not None
    paths = shape.angle_deg

    def apart(a: float, b: float) -> float:
        return abs((a - b + 90) % 180 - 90)

    assert apart(motion, angle_deg) > 2.0  # the uneven near-side arcs lean the steps' direction
    assert apart(paths, angle_deg) < 0.3
    assert omega == pytest.approx(0.5, rel=0.03)
    # at the exact rate it is exact to within the noise, and the paths' width gives the elevation
    exact = axes.path_shape(tracks, 0.5)
    assert exact is not None
    assert apart(exact.angle_deg, angle_deg) < 0.1
    assert exact.elevation_deg == pytest.approx(elevation_deg, abs=0.3)


def test_path_shape_needs_a_rate_and_enough_turning_tracks() -> None:
    tracks = _near_side_paths(0.0, 30.0, omega=0.5)
    assert axes.path_shape(tracks, math.nan) is None
    assert axes.path_shape(tracks[tracks["track"] < 5], 0.5) is None


@pytest.mark.slow  # renders a clip (about 10 s): make test-slow keeps make test under 4 minutes
def test_angle_from_paths_on_a_cylinder_seen_from_above(tmp_path: Path) -> None:
    # measured on the accuracy suite's cylinder seen from 30 degrees above: the motion's angle
    # 10.3 degrees (omega -1.0%, interval +-7%), the paths' 2.0 (+0.6%, +-0.5%)
    clip = tmp_path / "above.mp4"
    result = CliRunner().invoke(app, ["synth", str(clip), "--shape", "cylinder", "--omega", "-0.5", "--elevation",
                                      "30", "--size", "320x180", "--duration", "4", "--seed", "44"])
    assert result.exit_code == 0, result.output
    truth = truth_of(clip)
    motion = analyze(clip, AnalysisConfig(fixation_px=tuple(truth["fixation_px"]), angle_from="motion"))
    paths = analyze(clip, AnalysisConfig(fixation_px=tuple(truth["fixation_px"]), angle_from="paths"))
    assert abs(paths.axis_angle_deg) < 2.5
    assert abs(paths.axis_angle_deg) < abs(motion.axis_angle_deg)
    assert paths.axis_angle_from == "paths" and paths.axis_angle_found
    assert paths.omega_rad_s == pytest.approx(0.5, rel=0.01)
    assert paths.direction == "cw"
    # the default sees the camera looking down and takes the paths' angle itself
    default = analyze(clip, AnalysisConfig(fixation_px=tuple(truth["fixation_px"])))
    assert default.axis_angle_from == "paths" and default.axis_angle_deg == pytest.approx(paths.axis_angle_deg)


@pytest.mark.parametrize(("elevation_deg", "expected"), [(0.0, "motion"), (8.0, "motion"), (20.0, "paths"),
                                                         (40.0, "paths")])
def test_the_default_angle_comes_from_the_paths_when_the_camera_looks_down(elevation_deg: float,
                                                                             expected: str) -> None:
    """``angle_from="auto"``: the steps' spread across their main direction tells a camera
    looking down, and there the paths give the angle (the motion's leans: -3 degrees at 20
    degrees above, for -6); from the side the motion does (and the paths, which cost time,
    are not read)."""
    from rotrate_cli.stages.geometry import axis_angle

    tracks = _near_side_paths(-6.0, elevation_deg, omega=0.5)
    spread = axes.steps_spread(tracks)
    assert spread <= math.sin(math.radians(elevation_deg)) ** 2 + 0.005
    angle, source, elevation, _ = axis_angle(tracks, axes.motion_angle_deg(tracks), AnalysisConfig(fixation_px=None))
    assert source == expected
    if expected == "paths":
        assert angle == pytest.approx(-6.0, abs=1.0) and elevation == pytest.approx(elevation_deg, abs=3.0)
    else:
        assert angle == axes.motion_angle_deg(tracks) and math.isnan(elevation)


@pytest.mark.parametrize(("options", "message"), [
    (["--angle-from", "sideways"], "--angle-from must be one of auto, motion, paths"),
    (["--angle-from", "paths", "--axis-angle", "3"], "either --axis-angle or --angle-from paths"),
    (["--angle-from", "paths", "--segment"], "cannot be combined with --segment"),
])
def test_angle_from_bad_combinations_are_one_line_errors(options: list[str], message: str) -> None:
    fixation = [] if "--segment" in options else ["--fixation", "auto"]
    result = CliRunner().invoke(app, ["analyze", str(SAMPLES / "box_ortho.mp4"), *fixation, *options])
    assert result.exit_code == 2
    assert message in result.stderr and len(result.stderr.strip().splitlines()) == 1


@pytest.mark.slow  # renders a clip (about 10 s): make test-slow keeps make test under 4 minutes
def test_pinhole_camera_seen_from_above(tmp_path: Path) -> None:
    # a 25-degree lens looking down 30 degrees: a point's depth changes by its radial position
    # times cos(30), which the level pinhole model overstates (measured -1.19%); given the
    # elevation, or found from the paths (as the default now does here), the model fits (+0.02%, -0.43%)
    clip = tmp_path / "above.mp4"
    result = CliRunner().invoke(app, ["synth", str(clip), "--shape", "box", "--omega", "0.5", "--projection",
                                      "perspective", "--fov", "25", "--elevation", "30", "--size", "320x180",
                                      "--duration", "4", "--seed", "45"])
    assert result.exit_code == 0, result.output
    fixation = tuple(truth_of(clip)["fixation_px"])
    level = analyze(clip, AnalysisConfig(fixation_px=fixation, fov_deg=25.0, angle_from="motion"))
    given = analyze(clip, AnalysisConfig(fixation_px=fixation, fov_deg=25.0, elevation_deg=30.0))
    found = analyze(clip, AnalysisConfig(fixation_px=fixation, fov_deg=25.0, angle_from="paths"))
    default = analyze(clip, AnalysisConfig(fixation_px=fixation, fov_deg=25.0))  # sees it looks down: paths
    assert abs(level.omega_rad_s - 0.5) > 0.005
    assert default.axis_angle_from == "paths" and default.omega_rad_s == pytest.approx(found.omega_rad_s)
    assert given.omega_rad_s == pytest.approx(0.5, rel=0.003)
    assert found.omega_rad_s == pytest.approx(0.5, rel=0.007)
    assert found.elevation_deg == pytest.approx(30.0, abs=7.0)  # measured 25 (perspective narrows the paths)
    # the level model measured as level; the elevation it reports is the view's, read from the
    # paths after the fit (it used to stay NaN before the view was read, as this test asserted)
    assert level.camera is not None and level.camera.depth_scale == 1.0
    assert level.view is not None and level.elevation_deg == level.view.elevation_deg
    for analysis in (level, given, found, default):
        assert analysis.direction == "ccw"


def test_elevation_needs_the_pinhole_model() -> None:
    result = CliRunner().invoke(app, ["analyze", str(SAMPLES / "box_ortho.mp4"), "--fixation", "auto",
                                      "--fov", "ortho", "--elevation", "20"])
    assert result.exit_code == 2 and "--fov or --focal-px" in result.stderr


def test_the_geometry_stage_is_one_typed_result() -> None:
    """The geometry stage on its own: the camera, axis and fixation of the perspective sample, as
    given or as found, in one Geometry; its view is read once the rate is known."""
    from rotrate_cli.scene.view import keep_for_view
    from rotrate_cli.stages.geometry import locate, measure
    from rotrate_cli.stages.tracks import read_footage
    from rotrate_cli.stages.view_at_rate import view_at_rate

    truth = truth_of(SAMPLES / "box_perspective.mp4")
    given = AnalysisConfig(fixation_px=tuple(truth["fixation_px"]), fov_deg=25.0)
    footage = read_footage(SAMPLES / "box_perspective.mp4", given)
    size = (footage.info.width_px, footage.info.height_px)
    geometry, body = locate(footage.tracks, footage.motion_angle_deg, given, footage.info, seek_lens=True)
    assert (geometry.lens.source, geometry.fixation_found, geometry.angle_from) == ("given", False, "motion")
    assert geometry.camera(size) is not None and abs(geometry.axis_angle_deg) < 1.0
    geometry, result = measure(body, geometry, given, size)
    assert geometry.fixation_px == tuple(truth["fixation_px"])  # a given fixation is not moved
    assert result.combined.omega_rad_s == pytest.approx(truth["omega_rad_s"], rel=0.01)
    seen = view_at_rate(geometry, keep_for_view(footage.tracks), result.combined.omega_rad_s, "tracks", size)
    assert seen.view is not None and seen.view.name == "side"

    found = AnalysisConfig(fixation_px=None)  # the lens and the axis from the tracks
    geometry, body = locate(footage.tracks, footage.motion_angle_deg, found, footage.info, seek_lens=True)
    assert geometry.lens.source == "found" and geometry.fixation_found
    geometry, _ = measure(body, geometry, found, size)
    assert geometry.fixation_px[0] == pytest.approx(truth["fixation_px"][0], abs=3.0)


def test_the_lens_question_is_asked_only_where_a_lens_is_sought() -> None:
    """``locate`` takes the question "seek the lens?" as a function (the analysis works the
    answer, the clip's repetition, out beside the axis's search): asked once, after the axis
    is found, and only where the lens is not given; its answer is obeyed."""
    from rotrate_cli.stages.geometry import locate
    from rotrate_cli.stages.tracks import read_footage

    asked: list[bool] = []

    def answer(value: bool):
        def ask() -> bool:
            asked.append(value)
            return value
        return ask

    given = AnalysisConfig(fixation_px=None, fov_deg=25.0)
    footage = read_footage(SAMPLES / "box_perspective.mp4", given)
    geometry, _ = locate(footage.tracks, footage.motion_angle_deg, given, footage.info, seek_lens=answer(True))
    assert asked == [] and geometry.lens.source == "given"
    found = AnalysisConfig(fixation_px=None)
    geometry, _ = locate(footage.tracks, footage.motion_angle_deg, found, footage.info, seek_lens=answer(False))
    assert asked == [False] and geometry.lens.source == "orthographic"
    geometry, _ = locate(footage.tracks, footage.motion_angle_deg, found, footage.info, seek_lens=answer(True))
    assert asked == [False, True] and geometry.lens.source == "found"


def test_direction_takes_ccw_or_cw() -> None:
    result = CliRunner().invoke(app, ["analyze", str(SAMPLES / "box_ortho.mp4"), "--fixation", "auto",
                                      "--direction", "left"])
    assert result.exit_code == 2 and "--direction must be one of ccw, cw" in result.stderr


def test_a_direction_given_is_the_camera_s_sense() -> None:
    from rotrate_cli.stages.camera import camera_at, lens_from
    from rotrate_cli.video.frames import VideoInfo

    info = VideoInfo("clip.mp4", 640, 360, 30.0, 90, False, False)
    for direction, sense in (("ccw", 1), ("cw", -1), (None, 0)):
        lens = lens_from(AnalysisConfig(fixation_px=None, fov_deg=50.0, direction=direction), info)
        assert camera_at(lens, (640, 360), (319.5, 179.5), 0.0).sense == sense
