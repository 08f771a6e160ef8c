"""Foot feedback forces from physics: contact loads, actuator resistance, device mapping."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from pneumaquad.console.app import initial_pose
from pneumaquad.params import load_robot
from pneumaquad.robot.builder import build_robot
from pneumaquad.robot.feedback import (
    MAX_DAMPING,
    device_force,
    foot_feedback,
    foot_force_from_joint_torques,
    foot_jacobian_world,
    leg_dof_addresses,
)
from pneumaquad.robot.simulation import RobotSimulation

GRAVITY = 9.81  # [m/s^2], the model's |g|


def _standing(configuration: str) -> RobotSimulation:
    """The console's reset pose after 1 s of closed-loop holding (the free robot's reset
    pose is settled for 1 s already)."""
    simulation = RobotSimulation(build_robot(load_robot("crr-quadruped"), configuration, "flat"))
    initial_pose(simulation)
    if not simulation.robot.free:
        simulation.step(1000)
    return simulation


@pytest.fixture(scope="module")
def standing() -> RobotSimulation:
    return _standing("quadruped")


@pytest.fixture(scope="module")
def hanging() -> RobotSimulation:
    return _standing("fixed")


def _joint_axis(simulation: RobotSimulation, leg: str, joint: str) -> tuple[np.ndarray, ...]:
    model, data = simulation.model, simulation.data
    joint_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, f"{leg}_{joint}")
    return data.xanchor[joint_id].copy(), data.xaxis[joint_id].copy()


def test_standing_contact_forces_carry_the_weight(standing: RobotSimulation) -> None:
    feedback = foot_feedback(standing)
    weight = mujoco.mj_getTotalmass(standing.model) * GRAVITY
    total = feedback.contact.sum(axis=0)
    assert total[2] == pytest.approx(weight, rel=0.03)
    assert np.hypot(total[0], total[1]) < 0.02 * weight  # at rest: no net friction
    assert np.all(feedback.contact[:, 2] > 0.15 * weight)  # every foot pushed up
    # the normal components are the project's own foot normal forces
    np.testing.assert_allclose(feedback.contact[:, 2], standing.foot_normal_forces(), rtol=1e-3)


def test_foot_in_the_air_has_no_contact_force(hanging: RobotSimulation) -> None:
    assert np.all(hanging.foot_positions()[:, 2] > 0.02)  # fixed thorax, feet above ground
    feedback = foot_feedback(hanging)
    np.testing.assert_array_equal(feedback.contact, 0.0)
    assert np.all(np.linalg.norm(feedback.resistance, axis=1) > 0.1)  # legs held up


def test_resistance_reproduces_the_actuator_torques(hanging: RobotSimulation) -> None:
    robot, data = hanging.robot, hanging.data
    assert np.max(np.abs(hanging.joint_velocities())) < 0.01  # static
    feedback = foot_feedback(hanging)
    for index, leg in enumerate(robot.legs):
        dofs = leg_dof_addresses(robot, leg)
        jacobian = foot_jacobian_world(hanging.model, data, int(robot.foot_site_id[index]),
                                       dofs)
        torques = data.qfrc_actuator[dofs]
        assert np.max(np.abs(torques)) > 0.1
        np.testing.assert_allclose(jacobian.T @ -feedback.resistance[index], torques,
                                   rtol=1e-9, atol=1e-12)


def test_gamma_torque_alone_pushes_along_the_beta_foot_line(hanging: RobotSimulation) -> None:
    """Statics without a Jacobian: zero moment about alpha and beta, τ about gamma."""
    robot, leg, torque = hanging.robot, "front_right", 2.0  # [N m]
    index = robot.legs.index(leg)
    foot = hanging.data.site_xpos[robot.foot_site_id[index]].copy()
    jacobian = foot_jacobian_world(hanging.model, hanging.data, int(robot.foot_site_id[index]),
                                   leg_dof_addresses(robot, leg))
    force = foot_force_from_joint_torques(jacobian, np.array([0.0, 0.0, torque]))
    beta_point, _ = _joint_axis(hanging, leg, "beta")
    gamma_point, gamma_axis = _joint_axis(hanging, leg, "gamma")
    line = (foot - beta_point) / np.linalg.norm(foot - beta_point)
    lever_arm = abs(gamma_axis @ np.cross(foot - gamma_point, line))  # [m]
    assert np.linalg.norm(np.cross(force / np.linalg.norm(force), line)) < 1e-6
    assert np.linalg.norm(force) == pytest.approx(torque / lever_arm, rel=1e-6)
    for joint, expected in (("alpha", 0.0), ("beta", 0.0), ("gamma", torque)):
        point, axis = _joint_axis(hanging, leg, joint)
        assert axis @ np.cross(foot - point, force) == pytest.approx(expected, abs=1e-9)


def test_singular_jacobian_gives_a_bounded_force() -> None:
    stretched = np.array([[0.0, 0.0, 0.0], [0.3, 0.2, 0.1], [0.0, 0.0, 0.1]])  # rank 2
    torques = np.array([1.0, 2.0, 3.0])
    force = foot_force_from_joint_torques(stretched, torques)
    assert np.all(np.isfinite(force))
    assert np.linalg.norm(force) <= np.linalg.norm(torques) / (2 * MAX_DAMPING) + 1e-9
    regular = np.diag([0.2, 0.15, 0.12])
    np.testing.assert_allclose(foot_force_from_joint_torques(regular, torques),
                               np.linalg.solve(regular.T, torques))


def test_device_force_scales_and_saturates() -> None:
    np.testing.assert_allclose(device_force(np.array([0.0, 0.0, 20.0])), [0.0, 0.0, 1.0])
    big = device_force(np.array([300.0, 0.0, 400.0]))  # 25 N at the device before saturation
    assert np.linalg.norm(big) == pytest.approx(3.3)
    np.testing.assert_allclose(big / np.linalg.norm(big), [0.6, 0.0, 0.8])
    np.testing.assert_allclose(device_force(np.array([1.0, 2.0, 2.0]), scale=0.5,
                                            max_force=10.0), [0.5, 1.0, 1.0])
    np.testing.assert_array_equal(device_force(np.array([np.nan, 0.0, 1.0])), 0.0)


def test_standing_feet_render_the_ground_reaction_once(standing: RobotSimulation) -> None:
    # Statics of a light leg: the actuators' push on the ground and the ground's push on
    # the foot are one action-reaction pair, so the resistance ~ the contact force (the
    # difference is the leg's own weight and the seal friction, which MuJoCo carries in
    # the tendon friction constraint, not in qfrc_actuator) and the total is not doubled.
    feedback = foot_feedback(standing)
    weight = float(standing.model.body_mass.sum()) * GRAVITY
    for index in range(len(feedback.legs)):
        contact, total = feedback.contact[index], feedback.total[index]
        assert total == pytest.approx(feedback.resistance[index])
        # the leg's weight and what the seals' stiction holds (5.3 N at most, measured)
        assert np.linalg.norm(total - contact) < 0.15 * weight
        assert 0.5 * contact[2] < total[2] < 1.5 * contact[2]  # doubled would be 2x
