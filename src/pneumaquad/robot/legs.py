"""Leg kinematics of a built robot: geometry, DH table, IK in the thorax frame.

The kinematic description of each leg is read off the compiled MuJoCo model at zero joint
angles (joint anchors and axes, foot site), expressed in the thorax body frame, so the DH
table (thesis Table 1, eq 3.1.1) comes from the same parameters as the dynamics.

Small corrections of joint references (the walking feedback, once per control chunk) move
a foot by the linear step of the IK through its Jacobian: :func:`shift_feet`, compiled in
place as :func:`shift_feet_into` on stacked tables (:class:`.kinematics.LegTables`).
"""

from __future__ import annotations

from collections.abc import Sequence

import mujoco
import numpy as np

from pneumaquad.core.jit import compiled

from .builder import RobotModel
from .kinematics import (
    ChainWorkspace,
    DHTable,
    LegGeometry,
    LegTables,
    chain_workspace,
    dh_from_geometry,
    forward_kinematics_dh,
    leg_chain_into,
    solve_3x3,
    stack_leg_tables,
)
from .leg_ik import IKResult, inverse_kinematics

__all__ = ["add_leg_step", "leg_dh_table", "leg_geometry", "middle_leg_chain", "shift_feet",
           "shift_feet_into", "solve_leg", "thorax_frame_points"]


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


@compiled
def middle_leg_chain(rows: np.ndarray, tables: LegTables, leg: int,
                     workspace: ChainWorkspace) -> None:
    """Foot position [m] and Jacobian [m/rad] of ``leg`` (thorax frame) at the middle row
    of ``rows`` (n, 3·legs) [rad], written into ``workspace.foot`` and
    ``workspace.jacobian`` (compiled; ``tables`` a :class:`.kinematics.LegTables`,
    ``workspace`` a :class:`.kinematics.ChainWorkspace`)."""
    middle = rows.shape[0] // 2
    for k in range(3):
        workspace.angles[k] = rows[middle, 3 * leg + k]
    leg_chain_into(tables.theta_offset[leg], tables.d[leg], tables.alpha[leg], tables.a[leg],
                   tables.base[leg], tables.tool[leg], workspace.angles, workspace.frames,
                   workspace.link, workspace.foot, workspace.jacobian)


@compiled
def add_leg_step(rows: np.ndarray, leg: int, shift: np.ndarray,
                 workspace: ChainWorkspace) -> bool:
    """Add to every row of ``rows`` (n, 3·legs) [rad], in place, the joint step of ``leg``
    that moves its foot by ``shift`` (3,) [m] through ``workspace.jacobian`` [m/rad]
    (the linear step of the IK; compiled). Returns False, with ``rows`` unchanged, where
    the Jacobian is singular."""
    if not solve_3x3(workspace.jacobian, shift, workspace.elimination, workspace.step):
        return False
    for n in range(rows.shape[0]):
        for k in range(3):
            rows[n, 3 * leg + k] += workspace.step[k]
    return True


@compiled
def shift_feet_into(rows: np.ndarray, tables: LegTables, shifts: np.ndarray,
                    workspace: ChainWorkspace) -> int:
    """:func:`shift_feet` in place (compiled): every leg whose shift (row of ``shifts``
    (legs, 3) [m, thorax frame]) is not zero takes its :func:`add_leg_step` through its
    Jacobian at the middle row (:func:`middle_leg_chain`). Returns -1, or the first leg
    whose Jacobian is singular (the legs before it shifted)."""
    for leg in range(shifts.shape[0]):
        if shifts[leg, 0] != 0.0 or shifts[leg, 1] != 0.0 or shifts[leg, 2] != 0.0:
            middle_leg_chain(rows, tables, leg, workspace)
            if not add_leg_step(rows, leg, shifts[leg], workspace):
                return leg
    return -1


def shift_feet(rows: np.ndarray, tables: Sequence[DHTable] | LegTables,
               shifts: np.ndarray) -> np.ndarray:
    """Joint references ``rows`` (n, 3·legs) [rad] with each leg's foot moved by
    ``shifts[leg]`` (3,) [m, thorax frame], through the leg Jacobian at the chunk's middle
    row (small shifts: the linear step of the IK). Returns a new array.

    Raises
    ------
    numpy.linalg.LinAlgError
        Where a shifted leg's Jacobian is singular.
    """
    corrected = np.array(rows, dtype=float)
    stacked = tables if isinstance(tables, LegTables) else stack_leg_tables(tables)
    singular = shift_feet_into(corrected, stacked,
                               np.ascontiguousarray(shifts, dtype=float), chain_workspace())
    if singular >= 0:
        raise np.linalg.LinAlgError(f"Singular matrix: the Jacobian of leg {singular}")
    return corrected
