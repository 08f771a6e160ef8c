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

import math
from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from pneumaquad.gait.stability import loaded_support
from pneumaquad.rig.simulate import NORMAL_PRESSURE, NORMAL_TEMPERATURE

from .simulation import RobotSimulation

__all__ = [
    "BODY_COLUMNS",
    "FOOT_COLUMNS",
    "JOINT_COLUMNS",
    "JOINT_QUANTITIES",
    "Column",
    "RowSources",
    "fill_recording_row",
    "recording_columns",
    "recording_row",
    "thorax_attitude",
]


class RowSources(NamedTuple):
    """What a row's columns are read from: the simulation, the joint-angle references
    of the row [rad], and readouts that several columns share, taken once per row."""

    simulation: RobotSimulation
    reference_angles: np.ndarray
    foot_positions: np.ndarray  # (legs, 3) [m]
    foot_forces: np.ndarray  # (legs,) [N]
    attitude: np.ndarray  # thorax roll, pitch, yaw [rad]
    thorax: np.ndarray  # (3,) thorax position [m]
    air: float  # air drawn by all cylinders [kg]


class Column(NamedTuple):
    """One recorded quantity: its name, its SI unit and where its value comes from.

    ``source`` returns one value for a body column, one per joint for a joint column
    and one per leg for a foot column. The header ``quantity [unit]`` and the row are
    both produced from these tables, so adding a column is one line here.
    """

    quantity: str
    unit: str
    source: Callable[[RowSources], np.ndarray | float]

    @property
    def header(self) -> str:
        return f"{self.quantity} [{self.unit}]"


def _force_set_point(row: RowSources) -> np.ndarray:
    s = row.simulation
    return np.where(s.joint_control["force_tracking_gain"] > 0.0, s.force_reference, np.nan)


def _normal_litres(row: RowSources) -> float:
    """Air drawn [NL]: its mass at normal conditions (ISO 8778), in litres."""
    gas_constant = row.simulation.params[0]["gas_constant"]
    return row.air * gas_constant * NORMAL_TEMPERATURE / NORMAL_PRESSURE * 1000.0


def _margin(row: RowSources) -> float:
    centre = row.simulation.data.subtree_com[0, :2]
    return loaded_support(row.foot_positions, row.foot_forces, centre)[1]


#: Per joint, in column order; headers start with the joint name.
JOINT_COLUMNS: tuple[Column, ...] = (
    Column("reference", "rad", lambda row: row.reference_angles),
    Column("angle", "rad",
           lambda row: row.simulation.data.qpos[row.simulation.robot.qpos_address]),
    Column("angular velocity", "rad/s",
           lambda row: row.simulation.data.qvel[row.simulation.robot.dof_address]),
    Column("piston reference", "m", lambda row: row.simulation.reference_positions),
    Column("piston position", "m", lambda row: row.simulation.positions),
    Column("piston velocity", "m/s", lambda row: row.simulation.velocities),
    Column("command", "V", lambda row: row.simulation.commands),
    Column("cap pressure", "Pa", lambda row: row.simulation.state["cap_pressure"]),
    Column("rod pressure", "Pa", lambda row: row.simulation.state["rod_pressure"]),
    Column("force", "N", lambda row: row.simulation.outputs["pneumatic_force"]),
    Column("air consumed", "kg", lambda row: row.simulation.state["air_consumed"]),
    Column("control mode", "-", lambda row: row.simulation.joint_control["mode"]),
    Column("force set-point", "N", _force_set_point),
)

#: Per leg, in column order; headers start with the leg name.
FOOT_COLUMNS: tuple[Column, ...] = (
    Column("foot x", "m", lambda row: row.foot_positions[:, 0]),
    Column("foot y", "m", lambda row: row.foot_positions[:, 1]),
    Column("foot z", "m", lambda row: row.foot_positions[:, 2]),
    Column("foot normal force", "N", lambda row: row.foot_forces),
)


def _thorax(axis: int) -> Callable[[RowSources], float]:
    return lambda row: row.thorax[axis]


def _attitude(axis: int) -> Callable[[RowSources], float]:
    return lambda row: row.attitude[axis]


#: Thorax, supply and balance, after the joints, and the feet after the thorax.
THORAX_COLUMNS: tuple[Column, ...] = (
    Column("thorax x", "m", _thorax(0)),
    Column("thorax y", "m", _thorax(1)),
    Column("thorax z", "m", _thorax(2)),
    Column("thorax roll", "rad", _attitude(0)),
    Column("thorax pitch", "rad", _attitude(1)),
    Column("thorax yaw", "rad", _attitude(2)),
)
BODY_COLUMNS: tuple[Column, ...] = (
    Column("supply pressure", "Pa", lambda row: row.simulation.supply_pressure()),
    Column("air consumed", "kg", lambda row: row.air),
    Column("air consumed", "NL", _normal_litres),
    Column("centre of mass x", "m", lambda row: row.simulation.data.subtree_com[0, 0]),
    Column("centre of mass y", "m", lambda row: row.simulation.data.subtree_com[0, 1]),
    Column("stability margin", "m", _margin),
)

#: Per-joint headers without the joint name (``"angle [rad]"`` …), in column order.
JOINT_QUANTITIES: tuple[str, ...] = tuple(column.header for column in JOINT_COLUMNS)


def recording_columns(simulation: RobotSimulation) -> tuple[str, ...]:
    """Column names of a robot run's recording: time, per joint, thorax, per leg, body."""
    robot = simulation.robot
    columns = ["time [s]"]
    for joint in robot.joint_names:
        columns += [f"{joint} {column.header}" for column in JOINT_COLUMNS]
    columns += [column.header for column in THORAX_COLUMNS]
    for leg in robot.legs:
        columns += [f"{leg} {column.header}" for column in FOOT_COLUMNS]
    columns += [column.header for column in BODY_COLUMNS]
    return tuple(columns)


def thorax_attitude(simulation: RobotSimulation) -> np.ndarray:
    """Roll, pitch, yaw [rad] of the thorax relative to its nominal placement.

    The nominal placement (thesis main.cpp: thorax axis forward, along world x) has all
    three zero; the angles are Z-Y-X Euler angles of the rotation from it, in the world.
    """
    rotation = simulation.data.xmat[simulation.robot.thorax_id].reshape(3, 3)
    relative = rotation @ simulation.thorax_placement.T
    yaw = math.atan2(relative[1, 0], relative[0, 0])
    pitch = -math.asin(min(max(relative[2, 0], -1.0), 1.0))
    roll = math.atan2(relative[2, 1], relative[2, 2])
    return np.array([roll, pitch, yaw])


def recording_row(simulation: RobotSimulation, reference_angles: np.ndarray) -> np.ndarray:
    """One recording row (layout of :func:`recording_columns`) of the current state.

    ``reference_angles`` [rad] are the joint-angle references recorded with the row
    (the simulation's own, or a planned trajectory's sample).
    """
    joints, legs = simulation.robot.joint_count, len(simulation.robot.legs)
    row = np.empty(1 + joints * len(JOINT_COLUMNS) + len(THORAX_COLUMNS)
                   + legs * len(FOOT_COLUMNS) + len(BODY_COLUMNS))
    fill_recording_row(simulation, reference_angles, row)
    return row


def fill_recording_row(simulation: RobotSimulation, reference_angles: np.ndarray,
                       row: np.ndarray) -> None:
    """Write the current state into ``row`` in place (the layout of
    :func:`recording_columns`, ``row`` as long as it): what :func:`recording_row`
    returns, without a new array, for a row of a preallocated block."""
    sources = RowSources(simulation, reference_angles, simulation.foot_positions(),
                         simulation.foot_normal_forces(), thorax_attitude(simulation),
                         simulation.data.xpos[simulation.robot.thorax_id],
                         simulation.air_consumed())
    joints, legs = simulation.robot.joint_count, len(simulation.robot.legs)
    row[0] = simulation.time
    start = _fill_columns(row, 1, joints, JOINT_COLUMNS, sources)
    start = _fill_columns(row, start, 1, THORAX_COLUMNS, sources)
    start = _fill_columns(row, start, legs, FOOT_COLUMNS, sources)
    _fill_columns(row, start, 1, BODY_COLUMNS, sources)


def _fill_columns(row: np.ndarray, start: int, count: int, columns: tuple[Column, ...],
                  sources: RowSources) -> int:
    """Write a group of columns from ``row[start]`` on: ``count`` entries (joints, legs,
    or 1 for the thorax and body), each with all of ``columns``; the index after it."""
    end = start + count * len(columns)
    if count == 1:  # one value a column: written at once
        row[start:end] = [column.source(sources) for column in columns]
        return end
    block = row[start:end].reshape(count, len(columns))
    for index, column in enumerate(columns):
        block[:, index] = column.source(sources)
    return end
