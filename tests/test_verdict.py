"""The verdict stage (rotrate_cli.stages.verdict): a return of the picture is a turn only when
something says so, and a count left open is weak with an interval that holds every count."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from rotrate_cli.fitting.outliers import Combined
from rotrate_cli.scene.disc import DiscView
from rotrate_cli.scene.picture_angle import PictureAngle
from rotrate_cli.scene.turning import PictureTurning
from rotrate_cli.stages.period import Period
from rotrate_cli.stages.verdict import MOST_REPEATS, judge, tell_repeats


def _return(period_s: float = 0.5, repeats: int = 8, frames: int = 240) -> Period:
    """A picture that comes back every ``period_s`` (exactly), seen ``repeats`` times."""
    return Period(period_s, period_s - 0.001, period_s + 0.001, repeats, frames, 0.05, 0.9, 0.0, 0.0,
                  period_s * 30.0)


def _tracks(omega: float, half: float = 0.01, used: int = 50) -> Combined:
    return Combined(omega, omega * (1 - half), omega * (1 + half), used)


def test_a_return_alone_is_weak_and_its_interval_holds_every_count() -> None:
    period = _return()
    turn = 2 * math.pi / period.period_s
    verdict = judge(None, period)
    assert verdict.quality == "weak" and verdict.rate_from == "repetition"
    assert verdict.omega_low_rad_s <= turn / MOST_REPEATS and verdict.omega_high_rad_s >= turn
    assert "k = 5: " in verdict.weak_because[0]  # the candidates are listed with their rates


def test_a_return_alone_that_also_came_back_sooner_may_span_several_turns() -> None:
    """The record close-up, its camera wobbling 1.5 degrees: its picture came back best after five
    turns (8.85 s) and less alike after two and three. Nothing else measured: the interval holds
    five turns too (it read 0.71 rad/s within [0.044, 0.71] for 3.55)."""
    period = replace(_return(period_s=8.849, repeats=3, frames=600), sooner_s=3.494)
    five_turns = 5 * 2 * math.pi / period.period_s
    verdict = judge(None, period)
    assert verdict.quality == "weak" and verdict.omega_high_rad_s >= five_turns
    assert any("came back sooner too (3.494 s)" in why for why in verdict.weak_because)
    # without a sooner return, or where the tracks tell the count, the interval is as it was
    alone = judge(None, _return(period_s=8.849, repeats=3, frames=600))
    assert alone.omega_high_rad_s < 1.01 * 2 * math.pi / 8.849
    told = judge(_tracks(2 * math.pi / period.period_s), period, 50)
    assert told.quality == "good" and told.omega_high_rad_s < 1.01 * 2 * math.pi / 8.849


def test_a_return_that_came_back_sooner_is_not_taken_for_one_turn_on_the_turning_test_alone() -> None:
    """The bicycle wheel under a light swelling and fading 8% every 3.3 s: its picture came back
    best after 11.08 s (four turns), less alike after 2.77 s; the turning test, whose trials are a
    turn a return at most, told one turn: -75%, good. The test alone no longer tells it: weak, the
    interval up to several turns; the picture's own angle, where it reads four turns' rate, tells."""
    period = replace(_return(period_s=11.08, repeats=1, frames=417), sooner_s=2.772, lag_frames=332.4)
    one_turn = 2 * math.pi / period.period_s
    turning = PictureTurning(one_turn / 0.9, one_turn, one_turn / 0.9, 1, 27, 10)  # its fastest trials
    alone = judge(None, period, turning=turning)
    assert alone.quality == "weak" and alone.omega_high_rad_s >= 4 * one_turn
    assert any("came back sooner too (2.772 s)" in why for why in alone.weak_because)

    def angle(omega: float, score: float = 0.64) -> PictureAngle:
        return PictureAngle(omega, omega * 0.998, omega * 1.002, 1, np.zeros(8), np.zeros(8), 1767.0, score,
                            DiscView((200.0, 160.0), 0.0, 0.0, math.inf))

    told = judge(None, period, turning=turning, angle=lambda: angle(4 * one_turn * 0.9996))
    assert told.quality == "good" and told.rate_from == "repetition"
    assert told.omega_rad_s == pytest.approx(4 * one_turn)
    assert told.omega_low_rad_s < 4 * one_turn < told.omega_high_rad_s
    assert any("spans 4 turns" in note for note in told.notes) and told.turns_spanned == 4
    # an angle that lines up poorly, or reads a rate no count of turns gives, tells nothing
    assert judge(None, period, turning=turning, angle=lambda: angle(4 * one_turn, 0.3)).quality == "weak"
    assert judge(None, period, turning=turning, angle=lambda: angle(3.5 * one_turn)).quality == "weak"


def test_an_angle_that_no_count_of_the_return_gives_is_held_and_over_a_turn_reported() -> None:
    """The bicycle wheel under a light swelling 5% once a second: its picture came back best after
    2.99 s (three of the light's swells, about a turn), nothing told the count, and it read -7.6%,
    weak, its interval missing. Its angle over 4.9 turns read 2.2662 within +-0.2%, which no count
    of a 2.99-s return gives: the interval holds it, and, followed over a turn or more, it is the
    rate reported (still weak: the two disagree)."""
    period = _return(period_s=2.99, repeats=4, frames=417)

    def angle(turned_deg: float) -> PictureAngle:
        return PictureAngle(2.2662, 2.2617, 2.2708, 1, np.zeros(8), np.zeros(8), turned_deg, 0.6,
                            DiscView((200.0, 160.0), 0.0, 0.0, math.inf))

    long = judge(None, period, angle=lambda: angle(1767.0))
    assert long.quality == "weak" and long.rate_from == "turning" and long.omega_rad_s == 2.2662
    assert long.omega_low_rad_s <= 2.2617 and long.omega_high_rad_s >= 2.2708
    assert any("no count of the picture's returns gives" in why for why in long.weak_because)
    short = judge(None, period, angle=lambda: angle(200.0))  # under a turn: held, not reported
    assert short.quality == "weak" and short.rate_from == "repetition" and short.omega_high_rad_s >= 2.2708
    # an angle that fits a count tells it, as before
    fits = judge(None, period, angle=lambda: replace(angle(1767.0), omega_rad_s=2 * math.pi / 2.99,
                                                     omega_low_rad_s=2 * math.pi / 2.995,
                                                     omega_high_rad_s=2 * math.pi / 2.985))
    assert fits.quality == "good" and fits.rate_from == "repetition"


def test_an_angle_that_followed_all_the_time_a_return_spans_is_reported_over_the_tracks() -> None:
    """The shared wheel, its picture growing and shrinking 3% with nothing still in it, 0.9 of a
    turn: its picture came back once, after 2.40 s, not exactly (+15% as a turn); its tracks read
    0.20 rad/s (-91%), too loosely to tell a count; its angle 2.277 rad/s within +-0.5%, which no
    count of the return gives, over 325 degrees: more than the 313 it turns in the return's 2.40 s. The angle has
    watched all the return was timed on, and is reported, weak, the interval holding the tracks'
    rate too; the tracks' was reported before. Followed over less than the return spans, it is
    held, not reported."""
    period = Period(2.403, 2.39, 2.42, 1, 75, 0.3, 0.8, 0.0, 0.2, 72.0)

    def angle(turned_deg: float) -> PictureAngle:
        return PictureAngle(2.277, 2.267, 2.288, -1, np.zeros(8), np.zeros(8), turned_deg, 0.7,
                            DiscView((250.0, 165.0), 0.0, 0.0, math.inf))

    tracks = _tracks(0.2032, 0.2, 20)
    verdict = judge(tracks, period, 20, angle=lambda: angle(325.0))
    assert (verdict.quality, verdict.rate_from, verdict.omega_rad_s) == ("weak", "turning", 2.277)
    assert verdict.omega_low_rad_s <= 0.2032 * 0.8 and verdict.omega_high_rad_s >= 2.288
    assert any("all the time the return spans" in why for why in verdict.weak_because)
    # the count nearest the tracks' is not said to be the rate shown: the angle's is
    assert not any("the rate shown is" in why for why in verdict.weak_because)
    held = judge(tracks, period, 20, angle=lambda: angle(250.0))
    assert held.rate_from == "tracks" and held.omega_high_rad_s >= 2.288
    assert not any("the rate shown is" in why for why in held.weak_because)  # the tracks' is shown
    # (the count told first names the one nearest the tracks' rate as the rate shown)
    assert any("the rate shown is k = 13's" in why for why in tell_repeats(period, tracks, 20, None, None).weak)


@pytest.mark.parametrize("count", [1, 2, 3, 5, 8, 16])
def test_tracks_that_fit_one_count_decide_it(count: int) -> None:
    period = _return()
    body = 2 * math.pi / period.period_s / count
    verdict = judge(_tracks(body), period, 50)
    assert (verdict.quality, verdict.repeats_per_turn) == ("good", count)
    assert verdict.omega_rad_s == pytest.approx(body, rel=1e-6)
    assert (count > 1) == any(f"repeats {count} times a turn" in note for note in verdict.notes)


def test_loose_tracks_say_nothing_and_sliding_tracks_never_decide_a_count() -> None:
    """Tracks that slide on grooves read several times too slow, with wide intervals (the record:
    0.44 rad/s within [0, 0.88] under a 3.55 rad/s return): they are not evidence of a count."""
    period = _return()
    told = tell_repeats(period, Combined(0.44, 0.0, 0.88, 300), 300, None)
    assert not told.decided and told.candidates == tuple(range(1, MOST_REPEATS + 1))


def test_the_picture_s_turning_tells_a_whole_turn_where_the_tracks_do_not() -> None:
    """The record: its tracks slide, its picture's turning says the return is a turn."""
    period = _return()
    turn = 2 * math.pi / period.period_s
    whole = PictureTurning(turn, turn / 1.5, turn, -1, 10, 10)
    verdict = judge(Combined(0.1, 0.0, 5.0, 30), period, 30, turning=whole)
    assert (verdict.quality, verdict.repeats_per_turn, verdict.repeats_told_by) == ("good", 1,
                                                                                      "the picture's turning")
    # a turning that prefers a part of a turn is not taken at its word (a misplaced axis favours one)
    part = PictureTurning(turn / 5, turn / 5.5, turn / 4.5, 1, 10, 10)
    assert judge(Combined(0.1, 0.0, 5.0, 30), period, 30, turning=part).quality == "weak"
    # asked only where needed: tracks that tell the count leave the turning unasked
    asked = []
    judge(_tracks(turn / 3), period, 50, turning=lambda: asked.append(1))
    assert not asked


def test_a_turning_that_leaves_several_counts_open_rules_none_out() -> None:
    period = _return()
    turn = 2 * math.pi / period.period_s
    open_turning = PictureTurning(turn / 6, turn / 8, turn / 3.5, 1, 10, 10)  # 4..8 open
    verdict = judge(None, period, turning=open_turning)
    assert verdict.quality == "weak" and verdict.omega_high_rad_s >= turn  # the truth may be a whole turn


def test_tracks_between_whole_counts_make_it_weak_and_the_interval_holds_both() -> None:
    period = _return()
    turn = 2 * math.pi / period.period_s
    verdict = judge(_tracks(turn / 2.5), period, 50)
    assert verdict.quality == "weak" and "not a whole number" in verdict.weak_because[0]
    assert verdict.omega_low_rad_s <= turn / 2.5 * 0.99 and verdict.omega_high_rad_s >= turn


def test_a_look_alike_half_turn_is_not_a_symmetric_body() -> None:
    """A car's other side half a turn on: the return is not the same picture again (excess)."""
    inexact = Period(10.0, 9.9, 10.1, 1, 60, 0.3, 0.8, 0.0, 0.2, 30.0)
    turn = 2 * math.pi / 10.0
    verdict = judge(_tracks(turn / 2 * 1.04, 0.05, 40), inexact, 40)
    assert verdict.quality == "weak"
    assert not any("repeats 2 times" in note for note in verdict.notes)
    assert verdict.omega_low_rad_s <= turn / 2 * 1.04 * 0.95 <= verdict.omega_high_rad_s


def test_tracks_that_rule_out_a_turn_give_the_rate_of_an_exact_look_alike_return() -> None:
    """EPFL car 02's 45th to 94th photographs: its picture came back after 50 s as exactly as after a
    turn (+99% as a turn), and its tracks turned 47% of a turn in that time (-5.6%), their
    interval's top well under the return's rate. The tracks' rate is reported, weak, and the
    interval holds both."""
    exact = Period(50.0, 49.9, 50.1, 1, 45, 0.05, 0.8, 0.0, 0.05, 30.0)
    turn = 2 * math.pi / 50.0
    tracks = _tracks(0.47 * turn, 0.3, 40)  # too loose to tell a count of repeats
    verdict = judge(tracks, exact, 40)
    assert (verdict.quality, verdict.rate_from) == ("weak", "tracks")
    assert verdict.omega_rad_s == pytest.approx(0.47 * turn)
    assert verdict.omega_low_rad_s <= 0.47 * turn * 0.7 and verdict.omega_high_rad_s >= turn
    assert any("well under a turn" in note for note in verdict.notes)
    # tracks whose interval reaches near the return's rate leave the return's rate reported
    near = judge(_tracks(0.8 * turn, 0.3, 40), exact, 40)
    assert near.rate_from == "repetition"


def test_loose_tracks_pick_the_count_shown_but_decide_none() -> None:
    """EPFL car 02's first 50 photographs: its picture came back once, after 52 s (a look-alike
    view half a turn on), and nothing told the count; its tracks, too loose to tell it (0.0645
    rad/s within [0.061, 0.110] in the sense its near side travels), are still the only measure of
    how fast it turns: the count shown is the one nearest them (k = 2, not the fastest, k = 1: +90%).
    The result stays weak, its interval holding every count; tracks that slide, within [0, x],
    pick nothing."""
    period = Period(51.95, 50.74, 53.17, 1, 48, 0.22, 0.92, 0.0, 0.1, 47.0)
    turn = 2 * math.pi / period.period_s
    tracks = Combined(0.0645, 0.020, 0.145, 94, (0.0827, 0.0645), -1, (0.061, 0.110))
    verdict = judge(tracks, period, 94)
    assert (verdict.quality, verdict.repeats_per_turn) == ("weak", 2)
    assert verdict.omega_rad_s == pytest.approx(turn / 2)
    assert verdict.omega_low_rad_s <= turn / MOST_REPEATS and verdict.omega_high_rad_s >= turn
    assert "nearest to the tracks'" in verdict.weak_because[0]
    sliding = judge(Combined(0.0645, 0.0, 0.13, 94), period, 94)
    assert sliding.repeats_per_turn == 1 and "nearest" not in sliding.weak_because[0]


def _fan_angle(omega: float, first_deg: float, alike_deg: float) -> PictureAngle:
    return PictureAngle(omega, omega * 0.9999, omega * 1.0001, 1, np.zeros(8), np.zeros(8), 540.0, 0.9,
                        DiscView((0.0, 0.0), 0.0, 0.0, 100.0), alike_deg=alike_deg, first_step_deg=first_deg)


def test_a_symmetric_body_s_other_steps_that_fit_no_count_leave_the_angle_s_count() -> None:
    """A fan of three flat blades, 9.15 degrees between changes, its picture back every 0.8725 s:
    its first step fits 129 degrees as well (one blade on), a reading 14 times as fast, which no
    count of the return fits; the angle's count stands (it read 7.20 rad/s for 2.40, weak, as a
    turn). An other step that fits a count, or frames far apart on the turn, leave it open."""
    period = _return(period_s=0.8725, repeats=4, frames=120)
    turn = 2 * math.pi / period.period_s
    verdict = judge(None, period, angle=_fan_angle(turn / 3, -9.15, -129.15))
    assert (verdict.quality, verdict.repeats_per_turn) == ("good", 3)
    assert verdict.omega_rad_s == pytest.approx(turn / 3)
    # its other step three times the first: a whole turn a return, as the return could be
    assert judge(None, period, angle=_fan_angle(turn / 3, 10.0, 30.0)).quality == "weak"
    far = replace(period, far_apart=True)
    assert judge(None, far, angle=_fan_angle(turn / 3, -9.15, -129.15)).quality == "weak"


def test_an_angle_whose_changes_line_up_poorly_tells_no_count() -> None:
    """A flat six-spoked wheel face on, its picture back every 0.698 s: its view found tilted 57
    degrees, its changes lined up at 0.32 and read 2.22 rad/s within +-5%, the rate of four repeats
    a turn (+50%, good). Lining up that poorly, the angle tells no count: the result is weak and its
    interval holds six repeats' rate. Lining up well, the same reading tells its count."""
    period = _return(period_s=0.6983, repeats=7, frames=150)
    turn = 2 * math.pi / period.period_s

    def angle(score: float) -> PictureAngle:
        return PictureAngle(2.2241, 2.1054, 2.3428, 1, np.zeros(8), np.zeros(8), 606.0, score,
                            DiscView((0.0, 0.0), 0.0, 0.0, 100.0))

    poor = judge(None, period, angle=angle(0.32))
    assert poor.quality == "weak" and poor.omega_low_rad_s <= turn / 6 <= poor.omega_high_rad_s
    told = judge(None, period, angle=angle(0.9))
    assert (told.quality, told.repeats_per_turn) == ("good", 4)


def test_an_inexact_return_seen_once_is_set_against_the_picture_s_angle() -> None:
    """Two discs side by side turning 1.0 and 1.6 rad/s, 8 s: the picture came back once, after the
    faster one's turn, but not exactly (its pairs 0.40 apart beyond their timing: the slower disc
    had not come back), and read 1.591 within [1.583, 1.599], good, for 1.6. Narrow as it is, an
    inexact return is set against the picture's own turning angle: where the angle is closer and
    agrees, it gives the rate; where the two disagree, the result is weak and holds both."""
    inexact = Period(3.9494, 3.9285, 3.9702, 1, 226, 0.49, 0.36, 0.0, 0.40, 118.0)
    turning = PictureTurning(1.6, 1.3, 1.7, 1, 10, 10)  # tells that the return is a whole turn

    def angle(omega: float) -> PictureAngle:
        return PictureAngle(omega, omega * 0.9997, omega * 1.0003, 1, np.zeros(8), np.zeros(8), 720.0, 0.84,
                            DiscView((0.0, 0.0), 0.0, 0.0, 100.0))

    closer = judge(_tracks(0.68, 0.33, 55), inexact, 55, turning=turning, angle=angle(1.59935))
    assert (closer.quality, closer.rate_from) == ("good", "turning")
    assert closer.omega_rad_s == pytest.approx(1.59935)
    apart = judge(_tracks(0.68, 0.33, 55), inexact, 55, turning=turning, angle=angle(1.62))
    assert apart.quality == "weak" and apart.omega_high_rad_s >= 1.62 * 1.0003
    # an exact return of the same width is not set against the angle (seconds to measure)
    exact = replace(inexact, excess=0.05)
    assert judge(_tracks(0.68, 0.33, 55), exact, 55, turning=turning, angle=angle(1.62)).quality == "good"
