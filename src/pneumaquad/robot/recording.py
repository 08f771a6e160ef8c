"""Recording rows of a robot run: per-joint, thorax, feet and supply columns (SI).

Columns are named ``quantity [unit]``; per-joint columns start with the joint name
(``"front_right_gamma angle [rad]"``), per-leg columns with the leg name. A joint's
``control mode [-]`` is 0 with its valve held at the offset, 1 under closed-loop control
and 2 with an open-loop valve voltage; its ``force set-point [N]`` is the cylinder force it
tracks in a force-controlled stance (NaN under plain position control).
``stability margin [m]`` is the signed distance of the centre-of-mass projection to the
support polygon of the feet carrying load (positive inside; NaN with no foot on the
ground), the static stability margin of a crawl gait.
"""

from __future__ import annotations

import mujoco
import numpy as np

from pneumaquad.gait.stability import loaded_support
from pneumaquad.rig.simulate import NORMAL_PRESSURE, NORMAL_TEMPERATURE

from .simulation import RobotSimulation

__all__ = ["JOINT_QUANTITIES", "recording_columns", "recording_row", "thorax_attitude"]

#: Per-joint quantities, in column order.
JOINT_QUANTITIES = (
    "reference [rad]",
    "angle [rad]",
    "angular velocity [rad/s]",
    "piston reference [m]",
    "piston position [m]",
    "piston velocity [m/s]",
    "command [V]",
    "cap pressure [Pa]",
    "rod pressure [Pa]",
    "force [N]",
    "air consumed [kg]",
    "control mode [-]",
    "force set-point [N]",
)
_THORAX = ("thorax x [m]", "thorax y [m]", "thorax z [m]", "thorax roll [rad]",
           "thorax pitch [rad]", "thorax yaw [rad]")
_SUPPLY = ("supply pressure [Pa]", "air consumed [kg]", "air consumed [NL]")
_BALANCE = ("centre of mass x [m]", "centre of mass y [m]", "stability margin [m]")


def recording_columns(simulation: RobotSimulation) -> tuple[str, ...]:
    """Column names of a robot run's recording."""
    robot = simulation.robot
    columns = ["time [s]"]
    for joint in robot.joint_names:
        columns += [f"{joint} {quantity}" for quantity in JOINT_QUANTITIES]
    columns += list(_THORAX)
    for leg in robot.legs:
        columns += [f"{leg} foot x [m]", f"{leg} foot y [m]", f"{leg} foot z [m]",
                    f"{leg} foot normal force [N]"]
    columns += list(_SUPPLY)
    columns += list(_BALANCE)
    return tuple(columns)


def thorax_attitude(simulation: RobotSimulation) -> np.ndarray:
    """Roll, pitch, yaw [rad] of the thorax relative to its nominal placement.

    The nominal placement (thesis main.cpp: thorax axis forward, along world x) has all
    three zero; the angles are Z-Y-X Euler angles of the rotation from it, in the world.
    """
    robot = simulation.robot
    rotation = simulation.data.xmat[robot.thorax_id].reshape(3, 3)
    nominal = simulation.model.body_quat[robot.thorax_id]
    nominal_matrix = np.zeros(9)
    mujoco.mju_quat2Mat(nominal_matrix, nominal)
    relative = rotation @ nominal_matrix.reshape(3, 3).T
    yaw = np.arctan2(relative[1, 0], relative[0, 0])
    pitch = -np.arcsin(np.clip(relative[2, 0], -1.0, 1.0))
    roll = np.arctan2(relative[2, 1], relative[2, 2])
    return np.array([roll, pitch, yaw])


def recording_row(simulation: RobotSimulation, reference_angles: np.ndarray) -> np.ndarray:
    """One recording row (layout of :func:`recording_columns`) of the current state."""
    s = simulation
    robot = s.robot
    per_joint = np.column_stack(
        [
            reference_angles,
            s.data.qpos[robot.qpos_address],
            s.data.qvel[robot.dof_address],
            s.reference_positions,
            s.positions,
            s.velocities,
            s.commands,
            s.state["cap_pressure"],
            s.state["rod_pressure"],
            s.outputs["pneumatic_force"],
            s.state["air_consumed"],
            s.joint_control["mode"],
            np.where(s.joint_control["force_tracking_gain"] > 0.0, s.force_reference, np.nan),
        ]
    ).ravel()
    thorax = np.concatenate([s.data.xpos[robot.thorax_id], thorax_attitude(s)])
    foot_positions = s.foot_positions()
    foot_forces = s.foot_normal_forces()
    feet = np.column_stack([foot_positions, foot_forces]).ravel()
    air = s.air_consumed()
    gas_constant = s.params[0]["gas_constant"]
    normal_litres = air * gas_constant * NORMAL_TEMPERATURE / NORMAL_PRESSURE * 1000.0
    supply = np.array([s.supply_pressure(), air, normal_litres])
    com = s.data.subtree_com[0, :2]
    _, margin = loaded_support(foot_positions, foot_forces, com)
    balance = np.array([com[0], com[1], margin])
    return np.concatenate([[s.time], per_joint, thorax, feet, supply, balance])
