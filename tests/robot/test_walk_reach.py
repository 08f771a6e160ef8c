"""Walk plans the legs can follow: the posture follows the heading, an unreachable plan is
refused before anything runs, and the walk's length is the whole number of cycles nearest
to the distance asked."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pneumaquad.locomotion.reach import (
    REACH_TOLERANCE,
    UnreachablePlanError,
    check_reach,
    choose_posture,
    largest_miss,
)
from pneumaquad.locomotion.walk import plan_walk, solve_cycle
from pneumaquad.locomotion.walk_run import WalkSettingsError, plan_walking
from pneumaquad.locomotion.walking import WALKING_ANGLES, WalkSettings, walking_gait
from pneumaquad.params import load_robot
from pneumaquad.robot.builder import build_robot
from pneumaquad.robot.kinematics import forward_kinematics_dh
from pneumaquad.robot.legs import leg_dh_table
from pneumaquad.robot.simulation import RobotSimulation


@pytest.fixture(scope="module")
def robot():
    return build_robot(load_robot("crr-quadruped"), "quadruped", "flat")


def _gait_for(robot, heading_degrees: float, **changes):
    settings = WalkSettings(heading=math.radians(heading_degrees), **changes)
    return lambda angles: walking_gait(robot, settings, angles)


def test_the_miss_is_the_distance_from_the_planned_to_the_reached_foot(robot):
    gait = _gait_for(robot, 90.0)(WALKING_ANGLES)
    cycle = solve_cycle(robot, gait, 50)
    miss = largest_miss(cycle)
    table = leg_dh_table(robot, robot.legs[miss.leg])
    reached = forward_kinematics_dh(table, cycle.angles[miss.sample, 3 * miss.leg:
                                                        3 * miss.leg + 3])
    assert miss.distance == pytest.approx(
        float(np.linalg.norm(reached - cycle.targets[miss.sample, miss.leg])), abs=1e-9)
    assert miss.distance > REACH_TOLERANCE  # sideways about the default posture: > 2 cm


def test_forward_keeps_the_default_posture_and_sideways_gets_one_it_reaches(robot):
    forward = _gait_for(robot, 0.0)
    assert np.array_equal(choose_posture(robot, forward, WALKING_ANGLES), WALKING_ANGLES)
    sideways = _gait_for(robot, 90.0)
    angles = choose_posture(robot, sideways, WALKING_ANGLES)
    assert not np.array_equal(angles, WALKING_ANGLES)
    gait = sideways(angles)
    plan = plan_walk(robot, gait, gait.period)
    check_reach(robot, gait, plan.cycle, plan.start_up)  # does not raise


def test_an_unreachable_plan_names_the_leg_its_phase_and_the_limit(robot):
    gait = _gait_for(robot, 90.0)(WALKING_ANGLES)
    cycle = solve_cycle(robot, gait, 50)
    with pytest.raises(UnreachablePlanError) as refused:
        check_reach(robot, gait, cycle)
    message = str(refused.value)
    assert any(message.startswith(leg) for leg in robot.legs)
    assert "swing" in message or "stance" in message
    assert "limit" in message and "misses by" in message


def test_plan_walking_refuses_before_anything_runs(robot):
    simulation = RobotSimulation(robot)
    settings = WalkSettings(step_height=0.3, distance=0.2)  # a 30 cm lift: out of reach
    with pytest.raises(WalkSettingsError) as refused:
        plan_walking(simulation, settings)
    assert "cannot reach" in str(refused.value)
    assert "step_height" in refused.value.fields
    assert simulation.time == 0.0  # nothing simulated


@pytest.mark.parametrize(("distance", "cycles"), [(0.05, 1), (0.2, 1), (0.25, 2), (1.0, 6)])
def test_the_walk_is_the_whole_number_of_cycles_nearest_to_the_distance(distance, cycles):
    settings = WalkSettings(distance=distance)  # 0.02 m/s, 8 s: 0.16 m of body per cycle
    assert settings.duration() == pytest.approx(cycles * settings.period)
    travel = settings.duration() * settings.speed
    stride = settings.speed * settings.duty_factor * settings.period
    assert abs(travel - distance) <= max(0.5 * settings.speed * settings.period,
                                         0.16 - distance) + 1e-12
    assert abs(travel - distance) < stride


def test_a_heading_out_of_reach_walks_a_shorter_cycle_at_the_same_speed(robot):
    from pneumaquad.locomotion.walking import reachable_plan

    straight = WalkSettings(distance=0.5)
    walked, posture = reachable_plan(robot, straight)
    assert walked == straight  # reachable as asked, about the default posture
    np.testing.assert_array_equal(posture, WALKING_ANGLES)
    asked = WalkSettings(distance=0.5, heading=math.radians(240.0))  # 14 mm out at 8 s
    walked, posture = reachable_plan(robot, asked)
    assert walked.period == pytest.approx(0.875 * asked.period)
    assert walked.speed == asked.speed and walked.heading == asked.heading
    assert posture is not None
    unreachable = WalkSettings(step_height=0.3)  # no cycle makes a 30 cm lift reachable
    assert reachable_plan(robot, unreachable) == (unreachable, None)
