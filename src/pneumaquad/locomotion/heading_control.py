"""Heading hold for walking: the robot does not turn away from its course.

The crawl gait has no notion of yaw: the feet are placed relative to the body, so every
slide of a stance foot turns the body a little and the next footholds follow it (the flat
1 m walk turned by 13° in its first 14 s and 24° by its end). :class:`HeadingHold`
integrates the measured yaw error into a rotation ``c`` of all commanded feet about the
body's vertical axis: with the stance feet held by the ground, commanding them rotated by
``+c`` turns the body by ``−c``, and the swing feet land on the rotated pattern, so the
course is kept. The correction goes into the joint references through each leg's
Jacobian (``c`` is limited to a few degrees, well inside the linear range).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import mujoco
import numpy as np

from pneumaquad.locomotion.walk import thorax_rotation
from pneumaquad.robot.kinematics import chain_workspace, stack_leg_tables
from pneumaquad.robot.legs import leg_dh_table
from pneumaquad.robot.simulation import RobotSimulation

from .feedback_kernels import HEADING, HEADING_SET, LAST_TIME, ROTATION, heading_step

__all__ = ["HeadingHold"]


class HeadingHold:
    """Joint references that hold the heading the walk started with, one call per chunk.

    Parameters
    ----------
    simulation : RobotSimulation
        Its thorax yaw is read at every call; the first call fixes the heading to hold.
    references : callable
        ``f(times) -> (len(times), joints)`` joint references [rad] to correct.
    gain : float [1/s]
        Rate at which the yaw error [rad] is integrated into the foot rotation.
    limit : float [rad]
        Largest foot rotation.
    yaw_rate : float [rad/s]
        Rate at which the heading to hold turns (a planned turn or arc): the heading is
        the first call's yaw plus yaw_rate times the time since.

    The arithmetic of a call is compiled (:func:`.feedback_kernels.heading_step`) on
    arrays allocated here; :attr:`heading`, :attr:`rotation` and :attr:`last_time` are
    views of its state.
    """

    def __init__(self, simulation: RobotSimulation,
                 references: Callable[[np.ndarray], np.ndarray], gain: float = 0.5,
                 limit: float = math.radians(8.0), yaw_rate: float = 0.0) -> None:
        self.simulation = simulation
        self.yaw_rate = yaw_rate
        self._start: tuple[float, float] | None = None  # (heading [rad], time [s])
        self.references = references
        self.gain = gain
        self.limit = limit
        robot = simulation.robot
        self.tables = [leg_dh_table(robot, leg) for leg in robot.legs]
        self.to_body = np.ascontiguousarray(thorax_rotation(robot))  # thorax → body frame
        self._stacked = stack_leg_tables(self.tables)
        self._workspace = chain_workspace()
        self._matrices = np.zeros((3, 3, 3))
        self._thorax_matrix = simulation.data.xmat[robot.thorax_id]  # a view, thorax → world
        nominal = np.zeros(9)
        mujoco.mju_quat2Mat(nominal, simulation.model.body_quat[robot.thorax_id])
        self._nominal = nominal.reshape(3, 3)
        # heading [rad], heading set (0/1), foot rotation [rad], last call's time [s]
        self._state = np.zeros(4)
        self._state[LAST_TIME] = simulation.time

    @property
    def heading(self) -> float | None:
        """Yaw [rad] to hold; None until the first call fixes it."""
        return float(self._state[HEADING]) if self._state[HEADING_SET] else None

    @heading.setter
    def heading(self, value: float | None) -> None:
        self._state[HEADING_SET] = 0.0 if value is None else 1.0
        self._state[HEADING] = 0.0 if value is None else value

    @property
    def rotation(self) -> float:
        """Rotation [rad] of the commanded feet about the body's z axis."""
        return float(self._state[ROTATION])

    @rotation.setter
    def rotation(self, value: float) -> None:
        self._state[ROTATION] = value

    @property
    def last_time(self) -> float:
        """Simulation time [s] of the last call (of the construction before it)."""
        return float(self._state[LAST_TIME])

    @last_time.setter
    def last_time(self, value: float) -> None:
        self._state[LAST_TIME] = value

    def __call__(self, times: np.ndarray) -> np.ndarray:
        """Joint references (len(times), joints) [rad] for the next chunk."""
        rows = np.array(self.references(times), dtype=float)
        if self.yaw_rate != 0.0 and self._start is not None:
            heading, start = self._start
            self._state[HEADING] = heading + self.yaw_rate * (self.simulation.time - start)
        singular = heading_step(rows, self._thorax_matrix, self._nominal, self.to_body,
                                self._stacked, self._workspace, self._matrices, self._state,
                                self.simulation.time, self.gain, self.limit)
        if singular >= 0:
            raise np.linalg.LinAlgError(f"Singular matrix: the Jacobian of leg {singular}")
        if self._start is None:
            self._start = (float(self._state[HEADING]), self.last_time)
        return rows
