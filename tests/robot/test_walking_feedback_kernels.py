"""The compiled walking feedback against its NumPy formulas.

Heading hold, swing height and force-controlled stance compute once per control chunk in
compiled functions (locomotion.feedback_kernels, locomotion.stance_kernels,
robot.legs.shift_feet_into, robot.kinematics.solve_3x3). Each is checked here against the
NumPy formula it replaces (np.linalg.solve, the gait's own timing functions, MuJoCo's
mj_jacSite, the least-squares load sharing) on the simulated quadruped in a tilted,
turned pose, to round-off.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from pneumaquad.gait.crawl import (
    CrawlGait,
    foot_positions_ground,
    leg_phases,
    stance_flags,
)
from pneumaquad.gait.stability import centre_of_mass
from pneumaquad.locomotion.feedback_kernels import (
    gait_timing,
    leg_phase,
    planned_lift,
    remainder,
)
from pneumaquad.locomotion.heading_control import HeadingHold
from pneumaquad.locomotion.stance_control import (
    StanceController,
    cylinder_forces_for_foot_force,
    desired_normal_forces,
    load_shares,
)
from pneumaquad.locomotion.stance_kernels import (
    load_shares_into,
    normal_forces_into,
    stance_workspace,
)
from pneumaquad.locomotion.swing_control import SwingHeightCorrection
from pneumaquad.locomotion.walk import thorax_rotation
from pneumaquad.locomotion.walking import WalkSettings, walking_phases
from pneumaquad.params import load_robot
from pneumaquad.robot.builder import build_robot
from pneumaquad.robot.feedback import foot_jacobian_world, leg_dof_addresses
from pneumaquad.robot.kinematics import foot_jacobian, forward_kinematics_dh, solve_3x3
from pneumaquad.robot.legs import leg_dh_table, shift_feet
from pneumaquad.robot.linkage import moment_arm
from pneumaquad.robot.recording import thorax_attitude
from pneumaquad.robot.simulation import RobotSimulation

FEET = np.array([[0.3, 0.25, 0.0], [0.3, -0.25, 0.0], [-0.3, 0.25, 0.0], [-0.3, -0.25, 0.0]])


@pytest.fixture(scope="module")
def walking():
    """A quadruped in its walking pose, thorax turned and tilted, and the walk's
    controllers (heading hold around swing height around stance control)."""
    simulation = RobotSimulation(build_robot(load_robot("crr-quadruped"), "quadruped"))
    phases, plan = walking_phases(simulation, WalkSettings(period=4.0, distance=0.05))
    hold = next(phase for phase in phases if phase.name == "walk").references
    turn = np.array([math.cos(0.2), 0.01, 0.02, math.sin(0.2)])  # yaw 0.4 rad, a tilt
    simulation.set_pose(plan.references[0], thorax_position=np.array([0.0, 0.0, 0.25]),
                        thorax_quaternion=turn / np.linalg.norm(turn))
    simulation.command_angles(plan.references[0])
    simulation.step(60)
    return simulation, plan, hold


def _wrapped(hold, kind):
    """The reference function of type ``kind`` in the chain below ``hold``."""
    references = hold
    while not isinstance(references, kind):
        references = references.references
    return references


def _tables(simulation: RobotSimulation):
    return [leg_dh_table(simulation.robot, leg) for leg in simulation.robot.legs]


def _shift_feet_numpy(rows, tables, shifts):
    """The joint step J⁻¹·shift at the middle row, by np.linalg.solve."""
    corrected = np.array(rows, dtype=float)
    middle = corrected[len(corrected) // 2].copy()
    for leg, table in enumerate(tables):
        if np.any(shifts[leg]):
            angles = middle[3 * leg : 3 * leg + 3]
            corrected[:, 3 * leg : 3 * leg + 3] += np.linalg.solve(
                foot_jacobian(table, angles), shifts[leg])
    return corrected


def test_compiled_3x3_solve_matches_numpy_and_refuses_singular_matrices():
    rng = np.random.default_rng(3)
    scratch, solution = np.zeros((3, 4)), np.zeros(3)
    for _ in range(200):
        matrix, right = rng.normal(size=(3, 3)), rng.normal(size=3)
        assert solve_3x3(matrix, right, scratch, solution)
        expected = np.linalg.solve(matrix, right)
        assert solution == pytest.approx(expected, rel=1e-10, abs=1e-12 * np.abs(expected).max())
    needs_pivoting = np.array([[0.0, 1.0, 2.0], [1.0, 0.0, 3.0], [4.0, -3.0, 8.0]])
    assert solve_3x3(needs_pivoting, np.ones(3), scratch, solution)
    assert solution == pytest.approx(np.linalg.solve(needs_pivoting, np.ones(3)), abs=1e-14)
    singular = np.array([[1.0, 2.0, 3.0], [2.0, 4.0, 6.0], [0.0, 1.0, 1.0]])
    assert not solve_3x3(singular, np.ones(3), scratch, solution)


def test_compiled_foot_shift_matches_the_numpy_step_and_moves_the_foot(walking):
    simulation, plan, _ = walking
    tables = _tables(simulation)
    rng = np.random.default_rng(5)
    rows = plan.references[200:209] + rng.normal(0.0, 0.02, (9, 12))
    shifts = rng.normal(0.0, 0.002, (4, 3))
    shifts[2] = 0.0  # a leg without a shift keeps its references exactly
    corrected = shift_feet(rows, tables, shifts)
    assert corrected == pytest.approx(_shift_feet_numpy(rows, tables, shifts), abs=1e-14)
    assert np.array_equal(corrected[:, 6:9], rows[:, 6:9])
    # the linear IK step, checked by forward kinematics: a 0.1 mm shift moves the foot by
    # the shift to first order
    small = 1e-4 * shifts / np.linalg.norm(shifts, axis=1, keepdims=True).clip(1e-300)
    stepped = shift_feet(rows, tables, small)
    middle = len(rows) // 2
    for leg, table in enumerate(tables):
        legs = slice(3 * leg, 3 * leg + 3)
        moved = forward_kinematics_dh(table, stepped[middle, legs]) - forward_kinematics_dh(
            table, rows[middle, legs])
        assert moved == pytest.approx(small[leg], abs=3e-7)  # measured below 0.031 µm


def test_remainder_is_ieee_remainder():
    values = np.concatenate([np.random.default_rng(7).uniform(-4 * np.pi, 4 * np.pi, 2000),
                             [np.pi, -np.pi, 3 * np.pi, -3 * np.pi, 0.0, 2 * np.pi, 1e-300]])
    for value in values:
        assert remainder(value, 2.0 * math.pi) == math.remainder(value, 2.0 * math.pi)


@pytest.mark.parametrize(("lift_fraction", "heading"), [(0.0, 0.0), (0.2, 0.0), (0.1, 3.0)])
def test_gait_timing_of_one_leg_matches_the_gait(lift_fraction, heading):
    gait = CrawlGait(FEET, duty_factor=0.8, period=4.0, stride=0.1, step_height=0.04,
                     heading=heading, lift_fraction=lift_fraction, transfer_gap=0.05)
    timing = gait_timing(gait)
    times = np.linspace(-1.0, 9.0, 1001)
    phases = leg_phases(gait, times)
    lifts = foot_positions_ground(gait, times)[..., 2]
    stance = stance_flags(gait, times)
    shares = load_shares(phases, gait.duty_factor, 0.01, 0.04)
    for n, time in enumerate(times):
        for leg in range(4):
            phase = leg_phase(timing, time, leg)
            assert phase == phases[n, leg]
            assert (phase >= 1.0 - timing.duty_factor - timing.phase_tolerance) == \
                stance[n, leg]
            assert planned_lift(timing, phase) == pytest.approx(lifts[n, leg], abs=1e-16)
    computed = np.zeros(4)
    for n in range(0, len(times), 10):
        load_shares_into(timing, times[n], 0.01, 0.04, computed)
        assert np.array_equal(computed, shares[n])


@pytest.mark.parametrize("weights", [np.ones(4), [0.0, 1.0, 0.5, 1.0], [0.3, 1.0, 1.0, 0.02],
                                     [1.0, 1.0, 1.0, 1e-6]])
def test_compiled_load_sharing_matches_least_squares(weights):
    rng = np.random.default_rng(11)
    workspace, forces = stance_workspace(), np.zeros(4)
    for _ in range(50):
        feet = FEET + rng.normal(0.0, 0.03, (4, 3))
        centre = rng.normal(0.0, 0.06, 2)
        assert normal_forces_into(feet, np.arange(4), centre, 50.0, np.asarray(weights),
                                  workspace, forces)
        expected = desired_normal_forces(feet, centre, 50.0, weights)
        assert forces == pytest.approx(expected, rel=1e-9, abs=1e-9)


def test_compiled_load_sharing_leaves_two_feet_to_least_squares():
    workspace, forces = stance_workspace(), np.zeros(4)
    assert not normal_forces_into(FEET, np.arange(4), np.zeros(2), 50.0,
                                  np.array([1.0, 0.0, 0.0, 1.0]), workspace, forces)
    assert normal_forces_into(FEET, np.arange(4), np.zeros(2), 50.0, np.zeros(4), workspace,
                              forces)  # nothing loaded: nothing to solve
    assert np.all(forces == 0.0)


def test_stance_controller_sets_the_statics_forces(walking):
    simulation, _, hold = walking
    stance = _wrapped(hold, StanceController)
    time = 2.3  # gait time with one leg swinging and one rising
    robot, model, data = simulation.robot, simulation.model, simulation.data
    phases = leg_phases(stance.gait, np.array([time]))[0]
    settings = stance.settings
    shares = load_shares(phases, stance.gait.duty_factor, settings.rise, settings.fall)
    weight = float(model.body_mass.sum() * np.linalg.norm(model.opt.gravity))
    normal = desired_normal_forces(simulation.foot_positions(), centre_of_mass(model, data),
                                   weight, shares)
    start, stance.start = stance.start, simulation.time - time
    try:
        computed = stance.update()
    finally:
        stance.start = start
    assert computed == pytest.approx(normal, rel=1e-12, abs=1e-12)
    assert stance.log[-1] == pytest.approx([simulation.time, *shares, *normal], rel=1e-12)
    angles = simulation.joint_angles()
    gains = simulation.force_tracking_gains()
    assert 0 < np.count_nonzero(shares) < 4
    for leg, name in enumerate(robot.legs):
        joints = robot.joint_names.index(f"{name}_alpha") + np.arange(3)
        if shares[leg] <= 0.0:
            assert np.all(gains[joints] == 0.0)
            continue
        dofs = leg_dof_addresses(robot, name)
        jacobian = foot_jacobian_world(model, data, int(robot.foot_site_id[leg]), dofs)
        arms = np.array([moment_arm(robot.linkages[robot.joint_types[j]], angles[j])
                         for j in joints])
        expected = cylinder_forces_for_foot_force(jacobian, data.qfrc_bias[dofs], arms,
                                                  np.array([0.0, 0.0, normal[leg]]))
        # to round-off of the torques, whose terms partly cancel
        scale = (np.abs(data.qfrc_bias[dofs]) + np.abs(jacobian[2] * normal[leg])) / np.abs(arms)
        assert np.all(np.abs(simulation.force_reference[joints] - expected) <= 1e-12 * scale)
        assert np.all(gains[joints] == settings.force_gain)


def test_swing_correction_matches_its_numpy_formula(walking):
    simulation, plan, _ = walking
    tables = _tables(simulation)
    gait = _wrapped(walking[2], SwingHeightCorrection).gait
    rows = plan.references[100:110]
    swing = SwingHeightCorrection(simulation, gait, 0.0, lambda times: rows)
    swing.correction[:] = [0.0, 0.01, 0.0, 0.0]  # a stance leg's correction fades
    swing.last_time = simulation.time - 0.01
    lift_off = swing.lift_off_height.copy()
    middle_time = 1.0 * gait.period * (0.5 + gait.transfer_gap)  # the second side lifts
    times = middle_time - 0.005 + 0.001 * np.arange(10)
    stance = stance_flags(gait, times[5:6])[0]
    assert not np.all(stance)
    corrected = swing(times)
    # the NumPy formula
    data, robot = simulation.data, simulation.robot
    rotation = data.xmat[robot.thorax_id].reshape(3, 3)
    lift = foot_positions_ground(gait, times[5:6])[0, :, 2]
    correction = np.array([0.0, 0.01 * np.exp(-0.01 / swing.fade), 0.0, 0.0])
    feet = simulation.foot_positions()
    for leg, table in enumerate(tables):
        if not stance[leg]:
            foot = forward_kinematics_dh(table, rows[5, 3 * leg : 3 * leg + 3])
            height = data.xpos[robot.thorax_id][2] + rotation[2] @ foot
            target = feet[leg, 2] + lift[leg]
            correction[leg] = lift[leg] / gait.step_height * np.clip(target - height,
                                                                    -swing.limit, swing.limit)
    up = np.zeros((4, 3))
    up[:, 2] = correction
    assert swing.correction == pytest.approx(correction, rel=1e-12, abs=1e-15)
    assert corrected == pytest.approx(_shift_feet_numpy(rows, tables, up @ rotation),
                                      abs=1e-14)
    assert np.array_equal(swing.lift_off_height[stance], lift_off[stance])
    assert np.array_equal(swing.was_stance, stance)


def test_heading_correction_matches_its_numpy_formula(walking):
    simulation, plan, _ = walking
    tables = _tables(simulation)
    rows = plan.references[300:310]
    hold = HeadingHold(simulation, lambda times: rows, gain=3.0)
    yaw = float(thorax_attitude(simulation)[2])
    assert abs(yaw) > 0.3  # the turned fixture
    hold.heading = heading = yaw - 0.05
    hold.last_time = last = simulation.time - 0.02
    corrected = hold(np.zeros(10))
    error = math.remainder(yaw - heading, 2.0 * math.pi)
    rotation = float(np.clip(3.0 * error * (simulation.time - last), -hold.limit, hold.limit))
    assert hold.rotation == pytest.approx(rotation, rel=1e-12)
    cos, sin = math.cos(rotation), math.sin(rotation)
    turn = np.array([[cos, -sin, 0.0], [sin, cos, 0.0], [0.0, 0.0, 1.0]])
    to_body = thorax_rotation(simulation.robot)
    turn_thorax = to_body.T @ turn @ to_body
    feet = np.array([forward_kinematics_dh(table, rows[5, 3 * leg : 3 * leg + 3])
                     for leg, table in enumerate(tables)])
    expected = _shift_feet_numpy(rows, tables, feet @ turn_thorax.T - feet)
    assert corrected == pytest.approx(expected, abs=1e-14)
    assert hold.heading == yaw - 0.05 and hold.last_time == simulation.time
    unturned = HeadingHold(simulation, lambda times: rows)
    assert np.array_equal(unturned(np.zeros(10)), rows)  # the first call: no error yet
    assert unturned.heading == pytest.approx(yaw, abs=1e-15) and unturned.rotation == 0.0


def test_compiled_vertical_jacobian_row_is_mujocos(walking):
    # The stance set-points use the vertical row of each foot's world Jacobian computed as
    # mj_jacSite does, from cdof and subtree_com: the same numbers, not only close ones.
    simulation, _, _ = walking
    model, data, robot = simulation.model, simulation.data, simulation.robot
    for leg, name in enumerate(robot.legs):
        site = int(robot.foot_site_id[leg])
        dofs = leg_dof_addresses(robot, name)
        jacobian = np.zeros((3, model.nv))
        mujoco.mj_jacSite(model, data, jacobian, None, site)
        root = model.body_rootid[model.site_bodyid[site]]
        offset = data.site_xpos[site] - data.subtree_com[root]
        motion = data.cdof[dofs]
        vertical = motion[:, 5] + (motion[:, 0] * offset[1] - motion[:, 1] * offset[0])
        assert np.array_equal(vertical, jacobian[2, dofs])


def test_compiled_slope_placement_matches_its_numpy_formula(walking):
    """placement_step: the least-squares plane through the stance feet (ground_plane), the
    uphill offset of the centre of mass's height over it (uphill_offset), blended, and
    every foot shifted by minus it in the thorax frame (shift_feet)."""
    from pneumaquad.locomotion.body_placement import ground_plane, uphill_offset
    from pneumaquad.locomotion.course_kernels import placement_step
    from pneumaquad.robot.kinematics import chain_workspace, stack_leg_tables

    simulation, plan, hold = walking
    gait = _wrapped(hold, SwingHeightCorrection).gait
    tables = _tables(simulation)
    data, robot = simulation.data, simulation.robot
    rows = plan.references[100:110]
    timing = gait_timing(gait)
    for gait_time, uphill, limit in ((-1.0, np.zeros(3), 1.0),
                                     (2.3, np.array([0.01, -0.02, 0.003]), 1.0),
                                     (2.3, np.zeros(3), 0.03)):
        corrected = rows.copy()
        state = uphill.copy()
        assert placement_step(corrected, gait_time, timing, data.site_xpos,
                              np.asarray(robot.foot_site_id, dtype=np.int64),
                              data.subtree_com[robot.thorax_id], data.xmat[robot.thorax_id],
                              state, 0.25, limit, 0.0, np.zeros((3, 9)), np.zeros((4, 3)),
                              stack_leg_tables(tables), chain_workspace()) == -1
        stance = (np.ones(4, dtype=bool) if gait_time < 0.0
                  else stance_flags(gait, np.array([gait_time]))[0])
        feet = simulation.foot_positions()[stance]
        normal = ground_plane(feet)
        height = float((data.subtree_com[robot.thorax_id] - feet.mean(axis=0)) @ normal)
        target = uphill_offset(normal, height)
        length = np.linalg.norm(target)  # 0.077 m in this tilted pose
        target *= min(1.0, limit / length)
        expected = uphill + 0.25 * (target - uphill)
        assert state == pytest.approx(expected, rel=1e-12, abs=1e-15)
        shifts = np.tile(-(data.xmat[robot.thorax_id].reshape(3, 3).T @ expected), (4, 1))
        assert corrected == pytest.approx(_shift_feet_numpy(rows, tables, shifts), abs=1e-13)


def test_compiled_turn_leak_and_cross_track_match_their_formulas(walking):
    """leak_into_turn: each foot turned by its accumulated −leak·c·Δtravel about the
    body's z axis (the rotation of heading_step, leg by leg); cross_track_error: the
    thorax's offset from its line, the planned sway turned by the start yaw taken out."""
    from pneumaquad.locomotion.course_kernels import cross_track_error, leak_into_turn
    from pneumaquad.robot.kinematics import chain_workspace, stack_leg_tables

    simulation, plan, _ = walking
    tables = _tables(simulation)
    to_body = thorax_rotation(simulation.robot)
    rows = plan.references[300:310]
    travel, last = np.array([0.3, -0.2, 0.1, 0.45]), np.array([0.31, -0.19, 0.08, 0.44])
    turns = np.array([0.0, 0.01, -0.02, 0.0])
    corrected = rows.copy()
    assert leak_into_turn(corrected, travel, last, True, -0.05, 0.5, turns, to_body,
                          stack_leg_tables(tables), chain_workspace(),
                          np.zeros((3, 3, 3))) == -1
    expected_turns = np.array([0.0, 0.01, -0.02, 0.0]) + 0.025 * (travel - last)
    assert turns == pytest.approx(expected_turns, abs=1e-16)
    middle = rows[len(rows) // 2]
    shifts = np.zeros((4, 3))
    for leg, table in enumerate(tables):
        foot = forward_kinematics_dh(table, middle[3 * leg: 3 * leg + 3])
        cosine, sine = math.cos(turns[leg]), math.sin(turns[leg])
        turn = np.array([[cosine, -sine, 0.0], [sine, cosine, 0.0], [0.0, 0.0, 1.0]])
        shifts[leg] = to_body.T @ turn @ to_body @ foot - foot
    assert corrected == pytest.approx(_shift_feet_numpy(rows, tables, shifts), abs=1e-13)

    state = np.zeros(6)
    yaw, direction = 0.4, np.array([math.cos(0.3), math.sin(0.3)])
    first = cross_track_error(np.array([1.0, 2.0]), np.array([0.0, 0.05]), yaw, direction,
                              state)
    assert first == 0.0
    along = np.array([math.cos(0.7), math.sin(0.7)])  # the travel in the world
    left = np.array([-along[1], along[0]])
    sway = np.array([[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]])
    origin = np.array([1.0, 2.0]) - sway @ [0.0, 0.05]
    position, planned = np.array([1.3, 2.1]), np.array([0.2, -0.04])
    error = cross_track_error(position, planned, yaw, direction, state)
    assert error == pytest.approx((position - sway @ planned - origin) @ left, abs=1e-15)
