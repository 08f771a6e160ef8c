"""Stance control and walking judgement: statics of load sharing, forces through the leg,
force tracking on the simulated robot, slides."""

from __future__ import annotations

import numpy as np
import pytest

from pneumaquad.locomotion.stance_control import (
    cylinder_forces_for_foot_force,
    desired_normal_forces,
    load_shares,
)
from pneumaquad.locomotion.walking import contact_slide, gait_support_margins

FEET = np.array([[0.3, 0.25], [0.3, -0.25], [-0.3, 0.25], [-0.3, -0.25]])


def test_load_shares_are_zero_in_swing_and_ramp_around_stance():
    phases = np.array([0.0, 0.1, 0.2, 0.205, 0.5, 0.98, 0.999])
    shares = load_shares(phases, duty_factor=0.8, rise=0.01, fall=0.04)
    assert shares[0] == shares[1] == 0.0  # swinging
    assert shares[2] == pytest.approx(0.0)  # touchdown
    assert shares[3] == pytest.approx(0.5)  # half way up the rise
    assert shares[4] == 1.0
    assert shares[5] == pytest.approx(0.5) and shares[6] < 0.03  # unloading before lift


@pytest.mark.parametrize("com", [(0.0, 0.0), (0.05, -0.03), (-0.1, 0.08)])
def test_desired_forces_balance_the_load_about_the_centre_of_mass(com):
    load = 60.0
    forces = desired_normal_forces(FEET, com, load, np.ones(4))
    assert forces.sum() == pytest.approx(load)
    assert forces @ FEET == pytest.approx(load * np.array(com))  # moment balance
    assert np.all(forces >= 0.0)


def test_four_feet_share_equally_about_the_centre_and_three_feet_are_determinate():
    assert desired_normal_forces(FEET, (0, 0), 40.0, np.ones(4)) == pytest.approx(10.0)
    forces = desired_normal_forces(FEET, (0.1, -0.05), 30.0, [0.0, 1.0, 1.0, 1.0])
    assert forces[0] == 0.0
    # three feet: the statics alone fix the forces, whatever their weights
    again = desired_normal_forces(FEET, (0.1, -0.05), 30.0, [0.0, 0.2, 1.0, 5.0])
    assert again == pytest.approx(forces)


def test_centre_of_mass_outside_the_support_never_asks_a_foot_to_pull():
    forces = desired_normal_forces(FEET, (0.5, 0.0), 30.0, np.ones(4))
    assert np.all(forces >= 0.0) and forces.sum() == pytest.approx(30.0)


def test_cylinder_forces_of_a_planar_two_link_leg_match_hand_statics():
    # Hip at the origin, thigh 0.2 m straight out along x, shank 0.3 m straight down:
    # joints about y, angles q1 (hip), q2 (knee). Foot at (0.2, 0, -0.3).
    # d(foot)/dq1 = y × r = (-0.3, 0, -0.2); d(foot)/dq2 = y × (0, 0, -0.3) = (-0.3, 0, 0).
    jacobian = np.array([[-0.3, -0.3], [0.0, 0.0], [-0.2, 0.0]])
    ground = np.array([0.0, 0.0, 20.0])  # 20 N up on the foot
    bias = np.array([1.0, 0.5])  # gravity of the links [N m]
    arms = np.array([0.04, -0.025])
    forces = cylinder_forces_for_foot_force(jacobian, bias, arms, ground)
    # Moments about each joint axis (y) of the ground force: hip r × F = -x F_z = -4 N m,
    # knee 0 (the force passes through it); the cylinders must supply bias - moment.
    expected_torques = bias - np.array([-0.2 * 20.0, 0.0])
    assert arms * forces == pytest.approx(expected_torques)


def test_contact_slide_counts_net_motion_per_loaded_stretch_not_jitter():
    steps = 100
    jitter = np.column_stack([1e-3 * (-1.0) ** np.arange(steps), np.zeros(steps)])
    loaded = np.ones(steps, dtype=bool)
    assert contact_slide(jitter, loaded) <= 2e-3 + 1e-12  # end to end, not 0.2 m of path
    sliding = np.column_stack([np.linspace(0.0, 0.02, steps), np.zeros(steps)])
    assert contact_slide(sliding, loaded) == pytest.approx(0.02)
    lifted = loaded.copy()
    lifted[40:60] = False  # the motion while unloaded is not a slide
    assert contact_slide(sliding, lifted) == pytest.approx(0.02 * 78 / 99, rel=1e-6)


def test_tip_over_margin_uses_the_feet_held_down_loaded_or_not():
    recording = {}
    for leg, (x, y) in zip(("a", "b", "c", "d"), FEET, strict=True):
        recording[f"{leg} foot x [m]"] = np.array([x])
        recording[f"{leg} foot y [m]"] = np.array([y])
    recording["centre of mass x [m]"] = np.array([0.0])
    recording["centre of mass y [m]"] = np.array([0.0])
    margins = gait_support_margins(recording, ("a", "b", "c", "d"), np.ones((1, 4), bool))
    assert margins[0] == pytest.approx(0.25)
    diagonal = np.array([[True, False, False, True]])  # a line through the centre: 0
    assert gait_support_margins(recording, ("a", "b", "c", "d"), diagonal)[0] == \
        pytest.approx(0.0, abs=1e-12)
