"""Turning: the crawl's stance feet turn about the body origin (a turn in place, or an arc
with a stride), and the walk settings that plan a turn of a given angle."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from pneumaquad.gait.crawl import CrawlGait, foot_targets, stance_flags, stance_travel
from pneumaquad.locomotion.walking import TURN_RATE, WalkSettings

FEET = np.array([[0.375, 0.28, -0.38], [0.375, -0.28, -0.38],
                 [-0.375, 0.28, -0.38], [-0.375, -0.28, -0.38]])
PERIOD = 4.0
TIMES = np.arange(0, 3 * 4000) * 1e-3


def test_stance_travel_runs_from_half_to_minus_half_through_each_stance():
    gait = CrawlGait(FEET, duty_factor=0.8, period=PERIOD, stride=0.1, sway=0.0)
    travel = stance_travel(gait, TIMES)
    stance = stance_flags(gait, TIMES)
    # in stance: +1/2 at touchdown to -1/2 at lift-off (the swing's cycloid overshoots)
    assert travel[stance].max() == pytest.approx(0.5, abs=1e-9)
    assert travel[stance].min() == pytest.approx(-0.5, abs=1e-3)
    # in stance the foot moves back relative to the body at the body's speed
    slope = np.diff(travel, axis=0) / 1e-3
    both = stance[1:] & stance[:-1]
    assert slope[both] == pytest.approx(-1.0 / (0.8 * PERIOD), rel=1e-9)
    # the straight gait's feet are neutral + fraction x stride along the heading
    feet = foot_targets(gait, TIMES)
    assert np.allclose(feet[..., 0] - FEET[:, 0], 0.1 * travel, atol=1e-12)


def test_a_turning_gait_turns_each_stance_foot_about_the_body_origin():
    turn = math.radians(12.0)
    gait = CrawlGait(FEET, duty_factor=0.8, period=PERIOD, stride=0.0, sway=0.0, turn=turn)
    feet = foot_targets(gait, TIMES)
    stance = stance_flags(gait, TIMES)
    radius = np.hypot(feet[..., 0], feet[..., 1])
    assert np.allclose(radius, np.hypot(FEET[:, 0], FEET[:, 1]), atol=1e-12)
    angle = np.arctan2(feet[..., 1], feet[..., 0]) - np.arctan2(FEET[:, 1], FEET[:, 0])
    angle = np.remainder(angle + math.pi, 2 * math.pi) - math.pi
    assert angle[stance].max() == pytest.approx(turn / 2, abs=1e-9)  # at touchdown
    assert angle[stance].min() == pytest.approx(-turn / 2, abs=1e-4)  # before lift-off
    assert gait.yaw_rate == pytest.approx(turn / (0.8 * PERIOD))


def test_without_a_turn_the_feet_are_the_straight_gaits():
    gait = CrawlGait(FEET, duty_factor=0.8, period=PERIOD, stride=0.1, heading=0.3)
    assert np.array_equal(foot_targets(gait, TIMES),
                          foot_targets(dataclasses.replace(gait, turn=0.0), TIMES))


@pytest.mark.parametrize(("degrees", "rate", "cycles"), [
    (90.0, 0.0, 6), (-90.0, 0.0, 6), (45.0, 1.0, 6), (10.0, 0.0, 1)])
def test_a_turn_in_place_is_whole_cycles_that_turn_exactly_by_the_angle(degrees, rate,
                                                                       cycles):
    settings = WalkSettings(turn=math.radians(degrees), yaw_rate=math.radians(rate))
    assert settings.turning_in_place and settings.body_speed() == 0.0
    assert settings.duration() == pytest.approx(cycles * settings.period)
    assert settings.body_yaw_rate() * settings.duration() == pytest.approx(
        math.radians(degrees))
    if rate == 0.0 and cycles > 1:  # the default rate, adjusted to whole cycles
        assert abs(settings.body_yaw_rate()) == pytest.approx(TURN_RATE, rel=0.3)


def test_an_arc_keeps_its_speed_and_yaw_rate():
    settings = WalkSettings(distance=1.0, yaw_rate=math.radians(1.0))
    assert not settings.turning_in_place
    assert settings.body_speed() == settings.speed
    assert settings.body_yaw_rate() == math.radians(1.0)
