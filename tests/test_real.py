"""Real footage with known truth (../shared/data), default settings, as ``make bench-real`` runs
it: the EPFL cars (the paper's scene) in rad/frame and in rad/s from their EXIF times, the
bicycle wheel seen face on, and the record seen obliquely. Skipped where the data is absent."""

from __future__ import annotations

import json
import math
import subprocess
from collections import deque
from pathlib import Path

import cv2
import numpy as np
import pytest

from rotrate_cli.analysis import AnalysisConfig, analyze
from tests.conftest import SHARED, need

CARS = SHARED / "data" / "epfl_cars"
VIDEOS = SHARED / "data" / "real_videos"


# seq02 in EXIF's seconds takes 12 s, seq10 by frames 7 s and by EXIF 8 s: make test-slow (the frames'
# clock stays in seq02; EXIF's in the parts of seq02 below)
@pytest.mark.parametrize(("clock", "sequence"), [("fps", "seq02"), pytest.param("fps", "seq10", marks=pytest.mark.slow),
                                                 pytest.param("exif", "seq10", marks=pytest.mark.slow),
                                                 pytest.param("exif", "seq02", marks=pytest.mark.slow)])
def test_epfl_car_on_a_turntable(sequence: str, clock: str) -> None:
    folder = CARS / sequence
    need(folder, f"the EPFL car sequence {sequence}")
    truth = json.loads((folder / "truth.json").read_text())
    analysis = analyze(folder, AnalysisConfig(fixation_px=None, fps=1.0 if clock == "fps" else None))
    expected = truth["omega"] if clock == "fps" else truth["omega_rad_s"]
    assert analysis.omega_rad_s == pytest.approx(expected, rel=0.03)
    assert analysis.omega_low_rad_s <= expected <= analysis.omega_high_rad_s
    assert analysis.direction == truth["direction"]
    # good, or weak only because its picture comes back once (a full turn of photographs) while
    # its tracks turn well under a turn in that time: seq02's glossy tracks read 0.028 rad/frame
    # for 0.065, as a car's look-alike view half a turn on would (see the next test); its interval
    # then spans the tracks' rate too
    assert analysis.quality == "good" or all("comes back only once" in why or "nothing tells whether that is a whole "
                                             "turn" in why or "came back sooner too" in why
                                             for why in analysis.verdict.weak_because)
    # (the matched features, the default on photographs, leave seq02's sense through the lens
    # untold, and so the count of returns a turn by EXIF clock: weak, its rate the same +0.16%;
    # its picture also came back, less alike, half a turn on, so its interval holds several
    # turns to a return too)
    assert analysis.clock == clock
    assert analysis.camera_from == "exif"  # the lens from the photographs


# seq04's (about 10 s) and seq10's in make test-slow: the axis's settling stays tested on seq02
@pytest.mark.parametrize(("sequence", "first", "count", "within"), [
    # +5.6% within [+4.4%, +7.0%], good, its axis 7 px aside (6 s: make test-slow)
    pytest.param("seq10", 15, 50, 0.02, marks=pytest.mark.slow),
    ("seq02", 30, 30, 0.02),  # -5.4% within [-6.3%, -4.4%], good
    # settled, -3.6% within [-4.4%, -2.8%] before the coupling's gain
    pytest.param("seq04", 60, 30, 0.05, marks=pytest.mark.slow),
])
def test_a_part_of_a_car_s_turn_settles_its_axis_and_says_how_well(sequence: str, first: int, count: int,
                                                                    within: float) -> None:
    """Photographs ``first`` to ``first + count - 1`` of a car (a third to half a turn through a
    67-degree lens), timed by their EXIF clocks, the tracks alone: the axis is placed at the rate
    measured about it and the rate about the axis, which on a short arc trade off. Two plain
    moves of the axis stopped short of where they agree, with an interval that held neither."""
    from rotrate_cli.video.clock import exif_times

    folder = CARS / sequence
    need(folder, f"the EPFL car sequence {sequence}")
    truth = json.loads((folder / "truth.json").read_text())["omega_rad_s"]
    times_s = exif_times(sorted(folder.glob("*.jpg"))).times_s
    # Lucas-Kanade's tracks, whose axis this is about (the matched features read seq02's -2.3%)
    analysis = analyze(folder, AnalysisConfig(fixation_px=None, start_s=times_s[first] - 0.05,
                                              end_s=times_s[first + count - 1] + 0.05, tracker_kind="klt"))
    assert analysis.rate_from == "tracks"
    assert analysis.omega_rad_s == pytest.approx(truth, rel=within)
    assert analysis.omega_low_rad_s <= truth <= analysis.omega_high_rad_s


@pytest.mark.slow  # about 11 s: in make test-slow (bench-real's EPFL parts hold these photographs too)
def test_an_axis_found_from_two_tracks_leaves_the_rate_open() -> None:
    """seq02's photographs 45-74 (its parts' sweep): two tracks on the front wheel placed the axis
    on the rear one and read 0.014 rad/s within [0, 0.030], weak, the truth 0.063 outside."""
    from rotrate_cli.video.clock import exif_times

    folder = CARS / "seq02"
    need(folder, "the EPFL car sequence seq02")
    truth = json.loads((folder / "truth.json").read_text())["omega_rad_s"]
    times_s = exif_times(sorted(folder.glob("*.jpg"))).times_s
    # Lucas-Kanade's two tracks (the matched features, the default on photographs, keep 89 there)
    analysis = analyze(folder, AnalysisConfig(fixation_px=None, start_s=times_s[45] - 0.05, end_s=times_s[74] + 0.05,
                                              tracker_kind="klt"))
    assert analysis.quality == "weak" and analysis.tracks_used == 2
    assert analysis.omega_low_rad_s <= truth <= analysis.omega_high_rad_s
    assert [w for w in analysis.warnings if "the axis was found from 2 tracks" in w]


# seq02 takes 10 s by either clock: make test-slow (both clocks stay in seq09)
@pytest.mark.parametrize(("clock", "sequence"), [pytest.param("fps", "seq02", marks=pytest.mark.slow),
                                                 ("fps", "seq09"), ("exif", "seq09"),
                                                 pytest.param("exif", "seq02", marks=pytest.mark.slow)])
def test_a_car_half_a_turn_on_is_not_taken_for_a_turn(sequence: str, clock: str) -> None:
    """The first 50 photographs (about half a turn): the car's far side looks like its near side,
    and the picture's single return read twice the rate, as good. Now weak. seq09's picture comes
    back once, inexactly, half a turn on: the tracks' rate is reported, and the interval holds it,
    the truth and the return's half turn. seq02's does not come back
    within these 50: its tracks alone read 5-14% low (35-40% before the recurrence's lag was chosen
    by its standard error and an undecided sense by the near side's travel), and say they are
    weak."""
    folder = CARS / sequence
    need(folder, f"the EPFL car sequence {sequence}")
    truth = json.loads((folder / "truth.json").read_text())
    fps = 1.0 if clock == "fps" else None
    analysis = analyze(folder, AnalysisConfig(fixation_px=None, fps=fps, end_s=50.0 if fps else 52.5))
    expected = truth["omega"] if clock == "fps" else truth["omega_rad_s"]
    assert analysis.quality == "weak"  # neither measurement is sure here, and the report says so
    if sequence == "seq09":
        assert analysis.period is not None and analysis.rate_from == "tracks"
        assert analysis.omega_low_rad_s <= expected <= analysis.omega_high_rad_s
        assert not any("repeats 2 times a turn" in w for w in analysis.warnings)  # a look-alike view, said as one
    else:
        assert analysis.period is None and analysis.omega_rad_s < 1.5 * expected  # not a turn in 50 photographs


def test_bicycle_wheel_seen_face_on() -> None:
    clip = VIDEOS / "bicycle_wheel_frontal.mp4"
    need(clip, "the bicycle wheel video")
    truth = json.loads(clip.with_suffix(".truth.json").read_text())
    analysis = analyze(clip, AnalysisConfig(fixation_px=None))
    assert analysis.omega_rad_s == pytest.approx(truth["omega"], rel=0.02)
    assert analysis.omega_low_rad_s <= truth["omega"] <= analysis.omega_high_rad_s
    assert analysis.rate_from == "repetition"
    # its tracks are points sliding along the rim: they tell no view, and none is claimed
    assert analysis.view is None


@pytest.mark.slow  # 7 s: in make test-slow (make bench-real reads the wheel's first 5 s too)
def test_the_wheel_after_its_calibration_still() -> None:
    """The clip opens on a still calibration frame (a ruler held across the wheel) and cuts to
    the turning: the first 5 s read 0.038 rad/s, weak, with an interval that missed 2.27. Held to
    its sticker's rate over those seconds (it slows 2% over the clip, and turns faster at first)."""
    clip = VIDEOS / "bicycle_wheel_frontal.mp4"
    need(clip, "the bicycle wheel video")
    truth = _wheel_truth(0.0, 5.0)
    analysis = analyze(clip, AnalysisConfig(fixation_px=None, end_s=5.0))
    assert analysis.omega_rad_s == pytest.approx(truth, rel=0.02)
    # the interval holds the sticker's rate to within how well the sticker tells it over 5 s
    assert (analysis.omega_low_rad_s * (1 - STICKER_ACCURACY) <= truth
            <= analysis.omega_high_rad_s * (1 + STICKER_ACCURACY))
    assert analysis.frames == 150
    assert any("cuts once" in warning for warning in analysis.warnings)


#: How well the wheel's hand-tracked sticker (every 5th frame) tells its rate over a few seconds:
#: its line's 95% interval is +-0.13% over 0-5 s, about +-0.3% over 2.6 s (from its residuals).
STICKER_ACCURACY = 0.0025


def _wheel_truth(start_s: float, end_s: float) -> float:
    """The wheel's rate over a part of its clip, from its hand-tracked sticker: it slows 2% over
    the clip, and its first 2.5 s turn 1.06% faster than the whole clip's mean."""
    from benchmarks.scoring import sticker_omega
    return sticker_omega(VIDEOS / "bicycle_wheel_frontal.track.csv", 30.0, start_s, end_s)


@pytest.mark.slow  # about 11 s: in make test-slow (the wheel's third of a turn stays in make test)
def test_the_wheel_under_a_turn_is_read_from_the_pictures_turning() -> None:
    """Its first 2.5 s, under a turn (its first frame still), the axis found: one track of 24 was
    kept, on the hands that hold the axle, and the result was weak. The picture's own turning
    (issue 49) reads it within 1% of its sticker's rate over those seconds, its interval holding
    that: the end of the 0.9 turn matched against its start (+0.77% of the clip's mean)."""
    clip = VIDEOS / "bicycle_wheel_frontal.mp4"
    need(clip, "the bicycle wheel video")
    truth = _wheel_truth(0.0, 2.5)
    analysis = analyze(clip, AnalysisConfig(fixation_px=None, end_s=2.5))
    assert analysis.rate_from == "turning"
    assert analysis.omega_rad_s == pytest.approx(truth, rel=0.01)
    assert analysis.omega_low_rad_s <= truth <= analysis.omega_high_rad_s


def test_a_third_of_the_wheels_turn_through_an_uncertain_view_is_not_called_good_when_off() -> None:
    """Its 1.2-2.03 s (0.3 of a turn): the view found sits 2.5 px (reduced) left of the hub, and
    its changes line up no worse 1.3 px right, where the rate is 2% lower. It read +5.5% within
    +-2.5%, good. The view is now varied as far as its changes do not line up clearly worse
    (issue 49): the interval holds the sticker's rate, and a result that far off is weak."""
    clip = VIDEOS / "bicycle_wheel_frontal.mp4"
    need(clip, "the bicycle wheel video")
    truth = _wheel_truth(1.2, 2.03)
    analysis = analyze(clip, AnalysisConfig(fixation_px=None, start_s=1.2, end_s=2.03))
    assert analysis.rate_from == "turning"
    assert analysis.omega_low_rad_s <= truth <= analysis.omega_high_rad_s
    assert analysis.quality == "weak" or analysis.omega_rad_s == pytest.approx(truth, rel=0.03)


@pytest.mark.slow  # about 13 s: in make test-slow (the wheel's parts stay in make test)
def test_a_view_whose_changes_line_up_clearly_worse_leaves_the_interval() -> None:
    """The record's 0.9 turn from 5 s, the axis found: a view 28 px off the spindle scored 0.76
    against the best's 0.87, nearly as well, and its +6.3% widened the interval past +-5%: weak,
    though the best read +1.4%. Change by change its changes fell short in 32 of 36 (by 0.11 +-
    0.03): it is no longer held (issue 49), and the result is good and within 2%."""
    clip = VIDEOS / "record_oblique_closeup.mp4"
    need(clip, "the record video")
    truth = json.loads(clip.with_suffix(".truth.json").read_text())["omega"]
    end = 5.0 + 0.9 * 2 * math.pi / truth
    analysis = analyze(clip, AnalysisConfig(fixation_px=None, start_s=5.0, end_s=end))
    assert analysis.rate_from == "turning"
    assert analysis.quality == "good"
    assert analysis.omega_rad_s == pytest.approx(truth, rel=0.02)
    assert analysis.omega_low_rad_s <= truth <= analysis.omega_high_rad_s


def test_a_few_tracks_that_disagree_give_way_to_the_pictures_turning() -> None:
    """Its 3-7 s about the truth's fixation: three tracks at 0.76, 1.08 and 2.80 rad/s, whose
    joint fit read 0.94, weak. Under two turns of a wheel seen face on, the picture tells the rate
    (issue 49: its own turning; since the slow change is taken out of the thumbnails, its single
    return): within 2%, its interval holding the sticker's rate, good; the tracks that disagree
    with it are not shown as used."""
    clip = VIDEOS / "bicycle_wheel_frontal.mp4"
    need(clip, "the bicycle wheel video")
    fixation = tuple(json.loads(clip.with_suffix(".truth.json").read_text())["fixation"])
    truth = _wheel_truth(3.0, 7.0)
    analysis = analyze(clip, AnalysisConfig(fixation_px=fixation, start_s=3.0, end_s=7.0))
    assert analysis.rate_from in ("turning", "repetition")
    assert analysis.quality == "good"
    assert analysis.omega_rad_s == pytest.approx(truth, rel=0.02)
    assert analysis.omega_low_rad_s <= truth <= analysis.omega_high_rad_s
    used = analysis.features[analysis.features["inlier"]]
    assert ((used["omega_rad_s"].abs() / analysis.omega_rad_s - 1).abs() <= 0.05).all()


@pytest.mark.parametrize("fixation", [None, "truth"])
def test_record_seen_obliquely(fixation: str | None) -> None:
    """The first 12 s (7 turns) of the record: grooves, glints and a label 8.5 degrees a frame."""
    clip = VIDEOS / "record_oblique_closeup.mp4"
    need(clip, "the record video")
    truth = json.loads(clip.with_suffix(".truth.json").read_text())
    point = None if fixation is None else tuple(truth["fixation"])
    analysis = analyze(clip, AnalysisConfig(fixation_px=point, end_s=12.0))
    assert analysis.omega_rad_s == pytest.approx(truth["omega"], rel=0.01)
    assert analysis.omega_low_rad_s <= truth["omega"] <= analysis.omega_high_rad_s
    assert analysis.quality == "good"
    # the view from the label's paths: seen from above at a slant, and the found axis is the
    # spindle (read by eye, +-5 px; through the close lens the paths' centre sits ~20 px off)
    assert analysis.view is not None and analysis.view.name == "oblique"
    assert 10 <= analysis.view.elevation_deg <= 40
    if fixation is None:
        assert math.dist(analysis.fixation_px, truth["fixation"]) < 40


def test_under_a_turn_of_the_record_the_pictures_turning_gives_the_rate() -> None:
    """The record's first 1.5 s (0.85 of a turn) with the truth's fixation: its few long tracks sit
    on the still reflections (the axis followed from the given point ran 1,043,327 px away, and
    the result was weak from the tracks). The picture's own turning angle gives the rate (issue
    49): within 2%, the interval holding the truth; no warning names where the tracks turn. (It
    was good, -0.3% within +-1.8%; its view sought again through changes nearer together finds a
    second, 4 px aside, that lines its changes up nearly as well and reads +1.3% within +-4.4%: the
    interval holds both, and is wider than +-5%.)"""
    clip = VIDEOS / "record_oblique_closeup.mp4"
    need(clip, "the record video")
    truth = json.loads(clip.with_suffix(".truth.json").read_text())
    analysis = analyze(clip, AnalysisConfig(fixation_px=tuple(truth["fixation"]), end_s=1.5))
    assert analysis.rate_from == "turning"
    assert analysis.omega_rad_s == pytest.approx(truth["omega"], rel=0.02)
    assert analysis.omega_low_rad_s <= truth["omega"] <= analysis.omega_high_rad_s
    assert not [w for w in analysis.warnings if "the tracks turn about an axis through" in w]


@pytest.mark.slow  # writes the record's copy and analyses it (about 12 s): make test-slow keeps make test under
# 4 minutes; make bench-variants-parts measures the same copy's parts
def test_the_record_played_backwards_at_half_size_finds_its_spindle_under_a_turn(tmp_path: Path) -> None:
    """The record at half size played backwards (as ``make bench-variants`` writes it), 0.6 of a
    turn from 2 s, the axis found: the coarse search's two best centres refined to views that told
    no rate, and the result was the sliding tracks', -74%, weak, the interval missing. A third
    start refined reaches the spindle (issue 49): within 2%, the interval holding the truth."""
    clip = VIDEOS / "record_oblique_closeup.mp4"
    need(clip, "the record video")
    truth = json.loads(clip.with_suffix(".truth.json").read_text())
    reader = cv2.VideoCapture(str(clip))
    fps = reader.get(cv2.CAP_PROP_FPS)
    end_s = 2.0 + 0.6 * 2 * math.pi / truth["omega"]
    # the reversed clip's first 3.5 s alone: the encoder writes them as it would the whole clip's
    frames: deque[np.ndarray] = deque(maxlen=round(3.5 * fps))
    while True:
        ok, frame = reader.read()
        if not ok:
            break
        frames.append(cv2.resize(frame, None, fx=0.5, fy=0.5, interpolation=cv2.INTER_AREA))
    reader.release()
    out = tmp_path / "backwards.mp4"
    writer = cv2.VideoWriter(str(out), cv2.VideoWriter_fourcc(*"mp4v"), fps, (frames[0].shape[1], frames[0].shape[0]))
    for frame in reversed(frames):
        writer.write(frame)
    writer.release()
    analysis = analyze(out, AnalysisConfig(fixation_px=None, start_s=2.0, end_s=end_s))
    assert analysis.rate_from == "turning"
    assert analysis.omega_rad_s == pytest.approx(truth["omega"], rel=0.02)
    assert analysis.omega_low_rad_s <= truth["omega"] <= analysis.omega_high_rad_s


@pytest.mark.slow  # 10-14 s: in make test-slow (the same 1.5 s about the truth's point stays, above)
def test_the_record_s_tracks_in_two_groups_are_told_and_held() -> None:
    """The record's first 1.5 s, less than a turn (the repetition cannot give the rate), the axis
    found: the grooves' highlights read about 0.6 rad/s, the label's few tracks about 4, nothing
    between. They do not give the rate: the picture's own turning does, its interval holding the
    truth, 3.55 (-0.2% within [-1.8%, +7.5%], weak: two views hold; a view through which the
    changes lined up at 0.44 against 0.72, reading +35%, is no longer one of them). The groups are
    a doubt of the tracks' rate, not the one reported: a line says the tracks' checks are left out
    (the groups' warning said the interval held both, and it did not)."""
    clip = VIDEOS / "record_oblique_closeup.mp4"
    need(clip, "the record video")
    truth = json.loads(clip.with_suffix(".truth.json").read_text())
    analysis = analyze(clip, AnalysisConfig(fixation_px=None, end_s=1.5))
    assert analysis.rate_from == "turning"
    assert analysis.omega_low_rad_s <= truth["omega"] <= analysis.omega_high_rad_s
    assert analysis.quality == "weak" or analysis.omega_rad_s == pytest.approx(truth["omega"], rel=0.05)
    assert not [w for w in analysis.warnings if "fall into two groups" in w]
    assert [w for w in analysis.warnings if "the tracks' own rate" in w and "left out" in w]


def test_real_cases_are_never_confidently_wrong() -> None:
    """Whatever the source of the rate, a result off by more than 5% must say it is weak: run on
    the dinosaur photographs at a frame rate of 1."""
    folder = SHARED / "data" / "dinosaur" / "frames"
    need(folder, "the dinosaur photographs")
    analysis = analyze(Path(folder), AnalysisConfig(fixation_px=None, fps=1.0))
    error = abs(analysis.omega_rad_s / 0.17453292519943295 - 1)
    assert error <= 0.01
    assert analysis.rate_from == "repetition"


def test_record_whose_spindle_is_outside_the_picture(tmp_path: Path) -> None:
    """The record clip's first 8 s cropped 1000 px wide: its spindle (x 1093) lies outside the
    frame. The rate still comes from the repetition, and --fixation auto puts the axis where the
    label's paths turn, outside the frame (it used to be put 28,000 px away)."""
    clip = VIDEOS / "record_oblique_closeup.mp4"
    need(clip, "the record video")
    truth = json.loads(clip.with_suffix(".truth.json").read_text())
    cropped = tmp_path / "record_cropped.avi"
    capture = cv2.VideoCapture(str(clip))
    writer = cv2.VideoWriter(str(cropped), cv2.VideoWriter_fourcc(*"MJPG"), capture.get(cv2.CAP_PROP_FPS), (1000, 720))
    for _ in range(192):  # 8 s: 4.5 turns
        ok, frame = capture.read()
        if not ok:
            break
        writer.write(np.ascontiguousarray(frame[:, :1000]))
    writer.release()
    capture.release()
    analysis = analyze(cropped, AnalysisConfig(fixation_px=None))
    assert analysis.omega_rad_s == pytest.approx(truth["omega"], rel=0.01)
    assert analysis.fixation_px[0] > 1000  # outside the picture
    assert math.dist(analysis.fixation_px, truth["fixation"]) < 60
    assert any("lies outside the 1000x720 frame" in warning for warning in analysis.warnings)


def _wheel_turned(clip: Path, out: Path, turn: int | None, flip: bool, size: float = 1.0) -> Path:
    """The wheel's clip with every frame rotated by ``turn`` (an OpenCV rotate code) and/or
    mirrored left to right, and scaled by ``size``."""
    reader = cv2.VideoCapture(str(clip))
    writer = None
    while True:
        ok, frame = reader.read()
        if not ok:
            break
        frame = cv2.rotate(frame, turn) if turn is not None else frame
        frame = cv2.flip(frame, 1) if flip else frame
        frame = frame if size == 1.0 else cv2.resize(frame, None, fx=size, fy=size, interpolation=cv2.INTER_AREA)
        if writer is None:
            writer = cv2.VideoWriter(str(out), cv2.VideoWriter_fourcc(*"mp4v"), reader.get(cv2.CAP_PROP_FPS),
                                     (frame.shape[1], frame.shape[0]))
        writer.write(frame)
    assert writer is not None
    writer.release()
    return out


@pytest.mark.slow  # about 10 s: in make test-slow (the wheel's and the record's sense as they are stay)
def test_the_face_on_wheel_turns_the_way_its_sticker_does_however_the_picture_is_held(tmp_path: Path) -> None:
    """Face on, the sense is the one the wheel goes round in the picture. Its hand-tracked rim
    sticker goes round the axle anticlockwise on the screen (its angle, y down, falls). The side
    view's rule (which way the near side travels) read the clip turned upside down the other way:
    it told only how the picture was held. Mirrored, the sense must change."""
    clip = VIDEOS / "bicycle_wheel_frontal.mp4"
    need(clip, "the bicycle wheel video")
    truth = json.loads(clip.with_suffix(".truth.json").read_text())
    sticker = np.loadtxt(clip.with_suffix(".track.csv"), delimiter=",", skiprows=1)
    assert sticker[-1, 3] < sticker[0, 3]  # anticlockwise on the screen
    for turn, flip, expected in ((None, False, "ccw"), (cv2.ROTATE_180, False, "ccw"), (None, True, "cw")):
        source = clip if turn is None and not flip else _wheel_turned(clip, tmp_path / f"wheel_{turn}_{flip}.mp4",
                                                                      turn, flip)
        analysis = analyze(source, AnalysisConfig(fixation_px=None))
        assert analysis.direction == expected, (turn, flip)
        assert analysis.direction_in_picture
        assert analysis.omega_rad_s == pytest.approx(truth["omega"], rel=0.02)


def test_the_record_turns_clockwise_seen_from_above() -> None:
    """A record player turns clockwise seen from above, as this camera sees it. Before the sense
    was read from the picture, the side view's rule could not tell (unknown)."""
    clip = VIDEOS / "record_oblique_closeup.mp4"
    need(clip, "the record video")
    analysis = analyze(clip, AnalysisConfig(fixation_px=None))
    assert analysis.direction == "cw" and analysis.direction_in_picture


# 10-14 s each: make test-slow (the wheel's parts and its rolled copy stay in make test)
@pytest.mark.slow
@pytest.mark.parametrize("size", [0.5, 0.25])
def test_the_wheel_filmed_small_is_measured(tmp_path: Path, size: float) -> None:
    """At 256x192 "no point could be tracked": the tracker's window (21 px long) seeds only where
    it lies wholly on moving pixels, and the wheel's thin spokes left 24 corners in the whole
    clip. Frames under 320 px on their longer side are now enlarged for tracking (measured: -0.56% at half
    size, -0.69% at a quarter, 128x96)."""
    clip = VIDEOS / "bicycle_wheel_frontal.mp4"
    need(clip, "the bicycle wheel video")
    truth = json.loads(clip.with_suffix(".truth.json").read_text())
    small = _wheel_turned(clip, tmp_path / "wheel_small.mp4", None, False, size)
    analysis = analyze(small, AnalysisConfig(fixation_px=None))
    assert analysis.omega_rad_s == pytest.approx(truth["omega"], rel=0.02)
    assert analysis.omega_low_rad_s <= truth["omega"] <= analysis.omega_high_rad_s
    assert analysis.direction in ("ccw", "unknown")


@pytest.mark.slow  # 7-12 s: in make test-slow
def test_the_wheel_small_under_a_turn_is_read_about_its_hub_not_one_track_s_axis(tmp_path: Path) -> None:
    """The wheel at 0.6 its size, 0.9 of a turn from 8 s: one track in a corner gave the axis, no
    view about it told a rate, and the result was that track's, 0.099 rad/s (-96%), weak. An axis
    from tracks that do not hold together is no evidence: the view is sought about the picture's
    middle too, and the picture's turning reads within 1% of the sticker's rate, good."""
    clip = VIDEOS / "bicycle_wheel_frontal.mp4"
    need(clip, "the bicycle wheel video")
    start_s, end_s = 8.0, 8.0 + 0.9 * 2 * math.pi / 2.273
    small = _wheel_turned(clip, tmp_path / "wheel_small.mp4", None, False, 0.6)
    truth = _wheel_truth(start_s, end_s)
    analysis = analyze(small, AnalysisConfig(fixation_px=None, start_s=start_s, end_s=end_s))
    assert analysis.verdict.rate_from == "turning"
    assert analysis.omega_rad_s == pytest.approx(truth, rel=0.01)
    assert (analysis.omega_low_rad_s * (1 - STICKER_ACCURACY) <= truth
            <= analysis.omega_high_rad_s * (1 + STICKER_ACCURACY))


@pytest.mark.slow  # 14 s: in make test-slow (make bench-real holds the record's 2-s windows too)
def test_the_record_s_windows_and_features_agree_with_its_return() -> None:
    """omega(t) over 2-s windows of the record comes from the picture's return in each window,
    as the headline does (the tracks read about 0.45 rad/s in every window before), and no
    feature that reads another rate is shown as used."""
    clip = VIDEOS / "record_oblique_closeup.mp4"
    need(clip, "the record video")
    truth = json.loads((VIDEOS / "record_oblique_closeup.truth.json").read_text())["omega"]
    analysis = analyze(clip, AnalysisConfig(fixation_px=None, window_s=2.0))
    assert analysis.quality == "good" and analysis.omega_rad_s == pytest.approx(truth, rel=0.005)
    series = analysis.series
    holding = (series["omega_low_rad_s"] <= truth) & (truth <= series["omega_high_rad_s"])
    assert holding.mean() >= 0.9 and (abs(series["omega_rad_s"] / truth - 1) <= 0.02).mean() >= 0.9
    assert set(series["rate_from"]) == {"repetition"}
    used = analysis.features[analysis.features["inlier"]]
    assert (abs(used["omega_rad_s"].abs() / analysis.omega_rad_s - 1) <= 0.05).all()
    assert "slides" in set(analysis.features["reason"])


@pytest.mark.slow  # about 10 s: in make test-slow
def test_the_wheels_windows_shorter_than_a_turn_are_read_from_the_pictures_turning() -> None:
    """omega(t) in 2 s windows of a wheel that comes back every 2.8 s: no window holds a return,
    and its tracks slide (14 of 44 windows held the truth). The picture's own angle in each window
    (issue 48, item 3): nine in ten windows hold the truth over them, and most lie within 2% of
    it. Each window is held to its sticker's rate over it, as `make bench-real` holds them: the
    wheel slows 2% over the clip, and its first seconds turn 1% faster than its mean, which a
    window's interval need not hold once it is read closely (59% of these held the clip's mean
    once the view's allowance was measured rather than fixed)."""
    clip = VIDEOS / "bicycle_wheel_frontal.mp4"
    need(clip, "the bicycle wheel video")
    truth = json.loads(clip.with_suffix(".truth.json").read_text())
    analysis = analyze(clip, AnalysisConfig(fixation_px=tuple(truth["fixation"]), end_s=7.0, window_s=2.0))
    windows = analysis.series
    assert windows is not None and len(windows) >= 15
    assert (windows["rate_from"] == "turning").all()
    local = np.array([_wheel_truth(t - 1.0, t + 1.0) for t in windows["time_s"]])
    held = (windows["omega_low_rad_s"] <= local) & (local <= windows["omega_high_rad_s"])
    assert held.mean() >= 0.9
    assert ((windows["omega_rad_s"] / local - 1).abs() <= 0.02).mean() >= 0.8


@pytest.mark.slow  # about 10 s: in make test-slow
def test_a_third_of_the_wheels_turn_with_no_point_tracked_is_read_from_the_picture() -> None:
    """0.3 of a turn of the wheel (0.3-1.13 s), the axis found: no point could be tracked (the
    spokes blur, the rim is plain) and there was no result. The picture's own turning needs no
    track (issue 49): a result, its interval holding the truth over that part (its sticker's
    rate: the wheel turns 1% faster then than its clip's mean, which the interval, read closely
    since the view's allowance is measured, no longer reaches)."""
    clip = VIDEOS / "bicycle_wheel_frontal.mp4"
    need(clip, "the bicycle wheel video")
    end = 0.3 + 0.3 * 2 * math.pi / 2.27298
    truth = _wheel_truth(0.3, end)
    analysis = analyze(clip, AnalysisConfig(fixation_px=None, start_s=0.3, end_s=end))
    assert analysis.rate_from == "turning" and analysis.tracks_used == 0
    assert analysis.omega_low_rad_s <= truth <= analysis.omega_high_rad_s
    assert analysis.omega_rad_s == pytest.approx(truth, rel=0.05)


def test_the_wheel_seen_by_a_rolling_camera_is_measured_as_from_a_still_one(tmp_path: Path) -> None:
    """The wheel filmed by a camera rolling 3 degrees a second (its picture turned about its
    middle, enlarged so that no corner shows): no return, and the tracks stuck, gave -28%. The
    still background shows the roll, which is taken out of the tracks and the frames alike and
    reported; the rate within 1% of the clip's whole (the wheel slows: its sticker's steady slowing)."""
    from benchmarks.bench_variants import rolled_frames
    clip = VIDEOS / "bicycle_wheel_frontal.mp4"
    need(clip, "the bicycle wheel video")
    reader = cv2.VideoCapture(str(clip))
    out = tmp_path / "rolled.mp4"
    writer = cv2.VideoWriter(str(out), cv2.VideoWriter_fourcc(*"mp4v"), 30.0, (512, 384))
    frames = []
    while True:
        ok, frame = reader.read()
        if not ok:
            break
        frames.append(frame)
    reader.release()
    for frame in rolled_frames(3.0, False, 30.0)(frames):
        writer.write(frame)
    writer.release()
    analysis = analyze(out, AnalysisConfig(fixation_px=None))
    truth = _wheel_truth(0.0, len(frames) / 30.0)
    assert analysis.omega_rad_s == pytest.approx(truth, rel=0.01)
    assert analysis.omega_low_rad_s <= truth <= analysis.omega_high_rad_s
    assert analysis.shake is not None and analysis.shake.smooth
    assert analysis.shake.turn_deg_s == pytest.approx(-3.0, rel=0.05)  # clockwise as the picture shows it
    assert any("turned" in warning and "clockwise" in warning for warning in analysis.warnings)


@pytest.mark.slow  # about 40 s (the copy is written first): in make test-slow
def test_the_record_filmed_by_a_rolling_camera_comes_back_once_the_roll_is_taken_out(tmp_path: Path) -> None:
    """The record close-up turned as by a camera rolling 3 degrees a second (as bench-variants
    writes it): nothing in the picture stands still, so no background tells the roll, and each
    turn the picture came back turned: its tracks read -49%, weak, the interval missing. The roll
    found from the return (issue 49) is reported, and the rate is the return's with it taken
    out."""
    out, truth = _record_filmed_moving(tmp_path, 3.0, wobble=False)
    analysis = analyze(out, AnalysisConfig(fixation_px=None, window_s=4.0))
    assert analysis.rate_from == "repetition"
    assert analysis.omega_rad_s == pytest.approx(truth["omega"], rel=0.005)
    # good: the picture's turning, tested about the axis turned with the camera and the tracks'
    # paths turned back by the roll, tells one return a turn (weak before, every count 1-16 held)
    assert analysis.quality == "good" and analysis.verdict.repeats_per_turn == 1
    assert analysis.omega_high_rad_s - analysis.omega_low_rad_s < 0.02 * truth["omega"]
    # omega(t) from the same source: each window's return, the roll taken out of it too
    assert analysis.series is not None and (analysis.series["rate_from"] == "repetition").all()
    assert np.allclose(analysis.series["omega_rad_s"], truth["omega"], rtol=0.01)
    assert analysis.omega_low_rad_s <= truth["omega"] <= analysis.omega_high_rad_s
    assert analysis.period is not None and analysis.period.roll_deg_s == pytest.approx(-3.0, abs=0.3)
    assert [w for w in analysis.warnings if "rolling 3.00 degrees a second (clockwise" in w]
    # its first 12 s: three tracks on the sliding label, followed in the rolling picture, told 2
    # returns a turn, and the result was half the truth, its interval missing; they tell nothing now
    first = analyze(out, AnalysisConfig(fixation_px=None, end_s=12.0))
    assert first.omega_low_rad_s <= truth["omega"] <= first.omega_high_rad_s
    assert first.omega_rad_s == pytest.approx(truth["omega"], rel=0.01)


@pytest.mark.slow  # about 40 s each (the copy is written first): in make test-slow
@pytest.mark.parametrize("roll_deg_s", [0.0, -3.0])
def test_the_record_filmed_by_a_swaying_camera_comes_back_each_turn(tmp_path: Path, roll_deg_s: float) -> None:
    """The record close-up as a hand-held camera would show it (as bench-variants writes it: a
    sway of 1.5 and 0.4 degrees at 0.9 and 2.3 Hz and a 4-pixel shake, and a steady roll or
    none), nothing in it still. Plainly its picture came back only after five turns, where the
    sway lined up too (-80%, weak); rolled as well, its tracks read -29%. Allowed the sway, or
    with the roll taken out, it comes back each turn (issue 49): within 0.5%, its interval
    holding the truth, and what was allowed is said."""
    out, truth = _record_filmed_moving(tmp_path, roll_deg_s, wobble=True)
    analysis = analyze(out, AnalysisConfig(fixation_px=None, window_s=4.0))
    assert analysis.rate_from == "repetition"
    assert analysis.omega_rad_s == pytest.approx(truth["omega"], rel=0.005)
    assert analysis.omega_low_rad_s <= truth["omega"] <= analysis.omega_high_rad_s
    # the picture's turning tells one return a turn: good (weak before: its pairs 2.67 s apart, one
    # and a half turns, were tested in two interleaved halves, one of which saw the label's blank side)
    assert analysis.quality == "good" and analysis.verdict.repeats_per_turn == 1
    assert analysis.period is not None
    if roll_deg_s:
        assert analysis.period.roll_deg_s == pytest.approx(-roll_deg_s, abs=0.5)
        assert [w for w in analysis.warnings if "rolling" in w and "anticlockwise" in w]
    else:
        assert analysis.period.sway_deg > 0 and analysis.period.roll_deg_s == 0
        assert [w for w in analysis.warnings if "sways in the hand" in w]
    # omega(t): each window's rate from its return or the picture's turning, none from the tracks
    assert analysis.series is not None and (analysis.series["rate_from"] != "tracks").all()
    if not roll_deg_s:
        # its first 12 s (good: the picture's turning tells one return a turn): a window's few returns
        # read through the sway are weak (one read 3.606 within [3.577, 3.635], called good)
        first = analyze(out, AnalysisConfig(fixation_px=None, end_s=12.0, window_s=4.0))
        assert first.omega_rad_s == pytest.approx(truth["omega"], rel=0.005)
        assert first.omega_low_rad_s <= truth["omega"] <= first.omega_high_rad_s
        assert first.series is not None and (first.series["quality"] == "weak").all()


@pytest.mark.slow  # about 30 s (the copy is written first): in make test-slow
def test_the_record_filmed_by_a_camera_coming_nearer_and_going_back_comes_back_each_turn(tmp_path: Path) -> None:
    """The record close-up, its picture 3% larger and smaller once in five seconds (a camera
    coming nearer and going back, as bench-variants writes it), nothing in it still: plainly its
    picture came back best after three turns, and sooner less alike: -66.6%, weak. Allowed a few
    percent larger or smaller, it comes back each turn: within 0.2%, good, the zoom said."""
    out, truth = _record_filmed_moving(tmp_path, 0.0, wobble=False, nearer=0.03)
    analysis = analyze(out, AnalysisConfig(fixation_px=None))
    assert analysis.rate_from == "repetition" and analysis.quality == "good"
    assert analysis.omega_rad_s == pytest.approx(truth["omega"], rel=0.002)
    assert analysis.omega_low_rad_s <= truth["omega"] <= analysis.omega_high_rad_s
    assert analysis.period is not None and analysis.period.zoom_share > 0
    assert [w for w in analysis.warnings if "coming nearer and going back" in w]


def _record_filmed_moving(tmp_path: Path, roll_deg_s: float, wobble: bool,
                          nearer: float = 0.0) -> tuple[Path, dict]:
    """The record close-up as a camera rolling ``roll_deg_s`` (and swaying in the hand, where
    ``wobble``; or coming ``nearer`` and going back) would show it, as bench-variants writes it;
    and its truth."""
    from benchmarks.bench_variants import nearer_and_back_frames, rolled_frames

    clip = VIDEOS / "record_oblique_closeup.mp4"
    need(clip, "the record video")
    truth = json.loads(clip.with_suffix(".truth.json").read_text())
    reader = cv2.VideoCapture(str(clip))
    fps = reader.get(cv2.CAP_PROP_FPS)

    def frames():
        while True:
            ok, frame = reader.read()
            if not ok:
                return
            yield frame

    out = tmp_path / "moving.mp4"
    writer = None
    moved = nearer_and_back_frames(nearer, 0.2, fps) if nearer else rolled_frames(roll_deg_s, wobble, fps)
    for frame in moved(frames()):
        if writer is None:
            writer = cv2.VideoWriter(str(out), cv2.VideoWriter_fourcc(*"mp4v"), fps, (frame.shape[1], frame.shape[0]))
        writer.write(frame)
    reader.release()
    assert writer is not None
    writer.release()
    return out, truth


def _printed_disc(path: Path, photograph: Path, backdrop: Path, omega: float, fps: float, seconds: float,
                  size: tuple[int, int] = (1280, 720), radius: int = 260, h264_crf: int | None = None,
                  tilt_deg: float = 0.0) -> None:
    """A real photograph laid on a disc turning ``omega`` about the frame's centre, face on (or
    tilted ``tilt_deg`` about the horizontal, seen from far away), before another photograph
    standing still (MPEG-4, OpenCV's own writer; or, with ``h264_crf``, H.264 by imageio-ffmpeg's
    FFmpeg, as a phone or a screen recorder writes)."""
    width, height = size
    side = 2 * radius + 1
    face = cv2.resize(cv2.imread(str(photograph)), (side, side), interpolation=cv2.INTER_CUBIC)
    wall = cv2.resize(cv2.imread(str(backdrop)), size, interpolation=cv2.INTER_CUBIC).astype(np.float32)
    yy, xx = np.mgrid[:side, :side]
    disc = (((yy - radius) ** 2 + (xx - radius) ** 2) <= radius ** 2).astype(np.float32)
    squash = math.cos(math.radians(tilt_deg))
    place = np.array([[1.0, 0.0, width / 2 - radius], [0.0, squash, height / 2 - squash * radius]])
    inside = cv2.warpAffine(disc, place, size)[..., None]
    if h264_crf is None:
        writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), fps, size)
        write, close = writer.write, writer.release
    else:
        from rotrate_cli.video.pipe import ffmpeg_program

        program = ffmpeg_program()
        if program is None:
            pytest.skip("FFmpeg (imageio-ffmpeg) is not installed: the H.264 clip cannot be written")
        encoder = subprocess.Popen([program, "-v", "error", "-y", "-f", "rawvideo", "-pix_fmt", "bgr24", "-s",
                                    f"{width}x{height}", "-r", str(fps), "-i", "-", "-c:v", "libx264", "-crf",
                                    str(h264_crf), "-pix_fmt", "yuv420p", str(path)], stdin=subprocess.PIPE)

        def write(picture: np.ndarray) -> None:
            encoder.stdin.write(picture.tobytes())

        def close() -> None:
            encoder.stdin.close()
            encoder.wait()
    for index in range(int(round(seconds * fps))):
        turn = cv2.getRotationMatrix2D((radius, radius), math.degrees(omega * index / fps), 1.0)
        turned = cv2.warpAffine(cv2.warpAffine(face, turn, (side, side)), place, size)
        write(np.clip(wall * (1 - inside) + turned * inside, 0, 255).astype(np.uint8))
    close()


@pytest.mark.slow  # about 15 s
def test_a_printed_disc_turning_slowly_at_sixty_frames_a_second(tmp_path: Path) -> None:
    """An EPFL car's photograph on a disc turning 0.25 rad/s (a quarter of a degree a frame) at 60
    frames/s for 4 s, before a dinosaur photograph: its picture changes by about a grey level from
    frame to frame, and only the rings above that counted, which lined its changes up through a
    wrong view (tilted 33 degrees) better than through the right one. Its tracks' plane then read
    -0.7% to -0.8%, good with its interval missing (H.264), or weak (this writer's MPEG-4)."""
    photograph, backdrop = CARS / "seq04" / "050.jpg", SHARED / "data" / "dinosaur" / "frames" / "viff.030.png"
    need(photograph, "the EPFL car photographs")
    need(backdrop, "the dinosaur photographs")
    path = tmp_path / "slow_disc.mp4"
    _printed_disc(path, photograph, backdrop, 0.25, 60.0, 4.0)
    analysis = analyze(path, AnalysisConfig(fixation_px=None))
    assert analysis.quality == "good" and analysis.verdict.rate_from == "turning"
    assert analysis.omega_rad_s == pytest.approx(0.25, rel=0.005)
    assert analysis.omega_low_rad_s <= 0.25 <= analysis.omega_high_rad_s


@pytest.mark.slow  # about 15 s
def test_a_printed_disc_face_on_is_read_from_its_tracks_placed_again_not_where_they_slid(tmp_path: Path) -> None:
    """An EPFL car's photograph on a disc turning 1.2 rad/s face on, 0.4 of a turn at 30 frames/s
    (H.264, CRF 12). Lucas-Kanade's tracks slide on a turning picture: their plane's pairs read
    -0.30% within [-0.51%, -0.09%], good and missing. Then the picture's changes unrolled through
    that plane gave the rate (+0.01%); now the tracks placed again on the tracker's images give
    it, +0.003% within +-0.08%."""
    photograph, backdrop = CARS / "seq09" / "020.jpg", SHARED / "data" / "dinosaur" / "frames" / "viff.030.png"
    need(photograph, "the EPFL car photographs")
    need(backdrop, "the dinosaur photographs")
    path = tmp_path / "face_on.mp4"
    _printed_disc(path, photograph, backdrop, 1.2, 30.0, 0.4 * 2 * math.pi / 1.2, radius=240, h264_crf=12)
    analysis = analyze(path, AnalysisConfig(fixation_px=None))
    assert analysis.quality == "good" and analysis.verdict.rate_from == "turning"
    assert analysis.verdict.plane and not analysis.verdict.plane_changes
    assert analysis.omega_rad_s == pytest.approx(1.2, rel=0.0015)
    assert analysis.omega_low_rad_s <= 1.2 <= analysis.omega_high_rad_s
    assert any("matched again against its first patch" in note for note in analysis.verdict.notes)


@pytest.mark.slow  # about 15 s
def test_a_printed_disc_nearly_edge_on_is_read_from_its_plane_where_its_paths_tell_a_side_view(
        tmp_path: Path) -> None:
    """An EPFL car's photograph on a disc tilted 75 degrees, turning 2 rad/s, 0.3 of a turn: its
    tracks' paths are as flat as a side view's, where the picture does not turn, and their
    one-point fits read -5.9% within +-22%, weak. Its tracks are one plane turning: +0.7% within
    +-0.75% (+0.3% at CRF 18; at 72 and 78 degrees +0.2% and -0.3%)."""
    photograph, backdrop = CARS / "seq09" / "020.jpg", SHARED / "data" / "dinosaur" / "frames" / "viff.030.png"
    need(photograph, "the EPFL car photographs")
    need(backdrop, "the dinosaur photographs")
    path = tmp_path / "edge_on.mp4"
    _printed_disc(path, photograph, backdrop, 2.0, 30.0, 0.3 * 2 * math.pi / 2.0, radius=300, h264_crf=23,
                  tilt_deg=75.0)
    analysis = analyze(path, AnalysisConfig(fixation_px=None))
    assert analysis.quality == "good" and analysis.verdict.rate_from == "turning" and analysis.verdict.plane
    assert analysis.omega_rad_s == pytest.approx(2.0, rel=0.01)
    assert analysis.omega_low_rad_s <= 2.0 <= analysis.omega_high_rad_s


@pytest.mark.slow
def test_the_wheel_played_backwards_a_third_of_a_turn_through_a_wrong_view_is_not_good(tmp_path) -> None:
    """`make bench-variants-parts`: the wheel at half size played backwards, 0.3 of a turn from 2 s,
    is read through a view tilted 37 degrees (it faces the camera) 10.8% slow. Leaving out far
    shifts that show no peak steadied the rates through its views varied, and it turned good, its
    interval missing; its views' spread is measured with those shifts kept, and it stays weak."""
    from benchmarks.bench_variants import _frames, _scaled
    from benchmarks.scoring import part_truth

    wheel = VIDEOS / "bicycle_wheel_frontal.mp4"
    need(wheel, "the shared bicycle wheel clip")
    truth = json.loads(wheel.with_suffix(".truth.json").read_text())
    pictures = list(_scaled(0.5)(_frames(wheel)))[::-1]
    clip = tmp_path / "backwards.mp4"
    writer = cv2.VideoWriter(str(clip), cv2.VideoWriter_fourcc(*"mp4v"), truth["fps"],
                             (pictures[0].shape[1], pictures[0].shape[0]))
    for picture in pictures:
        writer.write(picture)
    writer.release()
    length_s = truth["frames"] / truth["fps"]
    end_s = 2.0 + 0.3 * 2.0 * math.pi / truth["omega"]
    omega = part_truth(wheel, truth["omega"], truth["fps"], length_s - end_s, length_s - 2.0)
    result = analyze(clip, AnalysisConfig(fixation_px=None, start_s=2.0, end_s=end_s))
    covers = result.omega_low_rad_s <= omega <= result.omega_high_rad_s
    assert result.quality == "weak" or (covers and abs(result.omega_rad_s / omega - 1) < 0.05)


def _copy(source: Path, out: Path, transform, until_s: float | None = None) -> Path:
    """``source``'s frames (up to ``until_s``) through ``transform`` (frames -> frames), written as
    MPEG-4 at the source's rate and size."""
    reader = cv2.VideoCapture(str(source))
    fps = reader.get(cv2.CAP_PROP_FPS)
    frames = []
    while until_s is None or len(frames) < until_s * fps:
        ok, frame = reader.read()
        if not ok:
            break
        frames.append(frame)
    reader.release()
    height, width = frames[0].shape[:2]
    writer = cv2.VideoWriter(str(out), cv2.VideoWriter_fourcc(*"mp4v"), fps, (width, height))
    for frame in transform(frames):
        writer.write(frame)
    writer.release()
    return out


def test_a_third_of_the_wheels_turn_under_a_rolling_camera_is_not_narrowed_by_its_circles(tmp_path: Path) -> None:
    """The wheel under a camera rolling 3 degrees a second (enlarged 1.15 about the middle), 2 to
    2.83 s: nothing still in the part shows the roll, so its picture turns with the wheel and the
    camera alike. Through the view its circles tell, that sum read -2.5% within +-2.1%, good, its
    interval missing; the circles do not narrow a reading where nothing still shows the camera."""
    from benchmarks.bench_variants import rolled_frames
    clip = VIDEOS / "bicycle_wheel_frontal.mp4"
    need(clip, "the bicycle wheel video")
    copy = _copy(clip, tmp_path / "rolled.mp4", rolled_frames(3.0, False, 30.0), until_s=3.0)
    analysis = analyze(copy, AnalysisConfig(fixation_px=None, start_s=2.0, end_s=2.83))
    truth = _wheel_truth(2.0, 2.83)
    assert analysis.quality == "weak" or analysis.omega_low_rad_s <= truth <= analysis.omega_high_rad_s


@pytest.mark.slow  # about 15 s (the copy is written first): in make test-slow
def test_the_record_upside_down_is_not_narrowed_by_one_circle() -> None:
    """The shared record turned upside down, 0.9 of a turn from 8 s: its label's edge is its one
    clear circle, which holds the view only along a valley. Through the view it told, the record read
    -7.3% within [-11.4%, -3.3%], good, missing. The record fills the picture: nothing still shows
    the camera's motion, and there the circles are not sought."""
    clip = VIDEOS / "record_oblique_closeup.mp4"
    need(clip, "the record video")
    import tempfile
    with tempfile.TemporaryDirectory() as folder:
        copy = _copy(clip, Path(folder) / "upside.mp4", lambda frames: (cv2.rotate(f, cv2.ROTATE_180) for f in frames),
                     until_s=9.7)
        analysis = analyze(copy, AnalysisConfig(fixation_px=None, start_s=8.0, end_s=9.59))
    truth = json.loads(clip.with_suffix(".truth.json").read_text())["omega"]
    assert analysis.quality == "weak" or analysis.omega_low_rad_s <= truth <= analysis.omega_high_rad_s
