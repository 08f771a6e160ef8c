"""Crawl gait on the real robot: standing feet, planned margins, IK reference tables."""

from __future__ import annotations

import functools

import numpy as np
import pytest

from pneumaquad.gait.crawl import LEGS, foot_targets, plan_margins
from pneumaquad.locomotion.walk import (
    plan_walk,
    robot_gait,
    solve_cycle,
    standing_feet,
    thorax_rotation,
)
from pneumaquad.params import load_robot
from pneumaquad.robot.builder import build_robot
from pneumaquad.robot.legs import leg_dh_table, thorax_frame_points

WALKING_ANGLES = np.radians([0.0, -20.0, 80.0])  # gamma 15° inside its 95° limit


@functools.cache
def _robot():
    return build_robot(load_robot("crr-quadruped"), "quadruped")


def test_thorax_axes_in_the_body_frame():
    rotation = thorax_rotation(_robot())
    assert np.allclose(rotation @ [1, 0, 0], [0, 0, 1], atol=1e-12)  # thorax x: up
    assert np.allclose(rotation @ [0, 1, 0], [0, -1, 0], atol=1e-12)  # thorax y: right
    assert np.allclose(rotation @ [0, 0, 1], [1, 0, 0], atol=1e-12)  # thorax z: forward


def test_standing_feet_are_symmetric():
    feet = standing_feet(_robot())
    signs = np.array([[1, 1], [1, -1], [-1, 1], [-1, -1]])  # LEGS: front/rear, left/right
    assert np.allclose(np.abs(feet[:, :2]), np.abs(feet[0, :2]), atol=1e-9)
    assert np.all(np.sign(feet[:, :2]) == signs)
    assert feet[0, :2] == pytest.approx([0.375, 0.2789], abs=1e-3)
    assert np.allclose(feet[:, 2], -0.3823, atol=1e-3)


def test_planned_margin_with_and_without_sway():
    still = robot_gait(_robot(), 0.03, sway=0.0)
    assert 0.0 < plan_margins(still)[1].min() < 0.01
    swaying = robot_gait(_robot(), 0.03, minimum_margin=0.04)
    assert plan_margins(swaying, samples=800)[1].min() >= 0.04 - 1e-4


def test_reference_table_reproduces_the_planned_feet():
    robot = _robot()
    gait = robot_gait(robot, 0.03, angles=WALKING_ANGLES, minimum_margin=0.03)
    plan = plan_walk(robot, gait, duration=gait.period, samples=200)
    steps = plan.times.size
    assert plan.references.shape == (steps, 12)
    assert plan.stance.shape == (steps, 4)
    assert sum(plan.cycle.unreachable_counts.values()) == 0
    assert plan.margins.min() >= 0.03 - 1e-3
    assert plan.cycle.robot_margins.min() > 0.02  # legs' mass included
    every = slice(0, steps, 7)
    planned = foot_targets(gait, plan.times[every]) @ thorax_rotation(robot)  # → thorax
    for k, leg in enumerate(LEGS):
        first = robot.joint_names.index(f"{leg}_alpha")
        angles = plan.references[every, first : first + 3]
        reached = thorax_frame_points(leg_dh_table(robot, leg), angles)
        assert np.abs(reached - planned[:, k]).max() < 1e-3


def test_unreachable_samples_are_counted_with_their_limit():
    robot = _robot()
    gait = robot_gait(robot, 0.01, sway=1.0)  # standing gamma 90°, 5° from its limit
    cycle = solve_cycle(robot, gait, samples=100)
    counts = cycle.unreachable_counts
    assert all(counts[leg] > 0 for leg in LEGS)
    for k, leg in enumerate(LEGS):
        assert sum(cycle.limit_hits[leg].values()) >= counts[leg]
        assert "gamma upper" in cycle.limit_hits[leg]
        errors = np.linalg.norm(cycle.feet[:, k] - cycle.targets[:, k], axis=-1)
        assert np.all(errors[cycle.reachable[:, k]] < 1e-6)
        assert np.all(errors[~cycle.reachable[:, k]] > 1e-6)
