"""Leg kinematics of a built robot: geometry, DH table, IK in the thorax frame.

The kinematic description of each leg is read off the compiled MuJoCo model at zero joint
angles (joint anchors and axes, foot site), expressed in the thorax body frame, so the DH
table (thesis Table 1, eq 3.1.1) comes from the same parameters as the dynamics.
"""

from __future__ import annotations

import mujoco
import numpy as np

from .builder import RobotModel
from .kinematics import (
    DHTable,
    LegGeometry,
    dh_from_geometry,
    foot_jacobian,
    forward_kinematics_dh,
)
from .leg_ik import IKResult, inverse_kinematics

__all__ = ["leg_dh_table", "leg_geometry", "shift_feet", "solve_leg", "thorax_frame_points"]


def leg_geometry(robot: RobotModel, leg: str) -> LegGeometry:
    """Zero-angle joint points/axes and foot of ``leg`` in the thorax frame [m]."""
    model = robot.model
    data = mujoco.MjData(model)
    data.qpos[:] = model.qpos0
    data.qpos[robot.qpos_address] = 0.0
    mujoco.mj_forward(model, data)
    rotation = data.xmat[robot.thorax_id].reshape(3, 3)
    origin = data.xpos[robot.thorax_id]
    points, axes = [], []
    for joint in ("alpha", "beta", "gamma"):
        joint_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, f"{leg}_{joint}")
        points.append(rotation.T @ (data.xanchor[joint_id] - origin))
        axis = rotation.T @ data.xaxis[joint_id]
        axes.append(axis / np.linalg.norm(axis))
    site = robot.foot_site_id[robot.legs.index(leg)]
    foot = rotation.T @ (data.site_xpos[site] - origin)
    first = robot.joint_names.index(f"{leg}_alpha")
    return LegGeometry(
        joint_points=np.array(points),
        joint_axes=np.array(axes),
        foot_point=foot,
        lower_limits=robot.lower_limits()[first : first + 3],
        upper_limits=robot.upper_limits()[first : first + 3],
    )


def leg_dh_table(robot: RobotModel, leg: str) -> DHTable:
    """DH table of ``leg`` (base transform from the thorax frame), see :func:`leg_geometry`."""
    return dh_from_geometry(leg_geometry(robot, leg))


def solve_leg(
    table: DHTable, foot_in_thorax: np.ndarray, current: np.ndarray | None = None,
    clamp: bool = True,
) -> IKResult:
    """Joint angles [rad] putting the foot at ``foot_in_thorax`` [m] (thorax frame)."""
    return inverse_kinematics(table, foot_in_thorax, clamp=clamp, current_angles=current)


def thorax_frame_points(table: DHTable, angles: np.ndarray) -> np.ndarray:
    """Foot position(s) [m] in the thorax frame for joint angles (..., 3) [rad]."""
    return forward_kinematics_dh(table, angles)


def shift_feet(rows: np.ndarray, tables: list[DHTable], shifts: np.ndarray) -> np.ndarray:
    """Joint references ``rows`` (n, 3·legs) [rad] with each leg's foot moved by
    ``shifts[leg]`` (3,) [m, thorax frame], through the leg Jacobian at the chunk's middle
    row (small shifts: the linear step of the IK). Returns a new array."""
    corrected = np.array(rows, dtype=float)
    middle = corrected[len(corrected) // 2].copy()
    for leg, table in enumerate(tables):
        if not np.any(shifts[leg]):
            continue
        angles = middle[3 * leg : 3 * leg + 3]
        corrected[:, 3 * leg : 3 * leg + 3] += np.linalg.solve(foot_jacobian(table, angles),
                                                               shifts[leg])
    return corrected

