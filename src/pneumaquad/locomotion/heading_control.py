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

import numpy as np

from pneumaquad.locomotion.walk import thorax_rotation
from pneumaquad.robot.kinematics import forward_kinematics_dh
from pneumaquad.robot.legs import leg_dh_table, shift_feet
from pneumaquad.robot.recording import thorax_attitude
from pneumaquad.robot.simulation import RobotSimulation

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
    """

    def __init__(self, simulation: RobotSimulation,
                 references: Callable[[np.ndarray], np.ndarray], gain: float = 0.5,
                 limit: float = math.radians(8.0)) -> None:
        self.simulation = simulation
        self.references = references
        self.gain = gain
        self.limit = limit
        robot = simulation.robot
        self.tables = [leg_dh_table(robot, leg) for leg in robot.legs]
        self.to_body = thorax_rotation(robot)  # thorax → body frame
        self.heading: float | None = None
        self.rotation = 0.0  # [rad] of the commanded feet about the body's z axis
        self.last_time = simulation.time

    def __call__(self, times: np.ndarray) -> np.ndarray:
        """Joint references (len(times), joints) [rad] for the next chunk."""
        simulation = self.simulation
        rows = np.array(self.references(times), dtype=float)
        yaw = float(thorax_attitude(simulation)[2])
        if self.heading is None:
            self.heading = yaw
        error = math.remainder(yaw - self.heading, 2.0 * math.pi)
        interval = simulation.time - self.last_time
        self.last_time = simulation.time
        self.rotation = float(np.clip(self.rotation + self.gain * error * interval,
                                      -self.limit, self.limit))
        if self.rotation == 0.0:
            return rows
        cos, sin = math.cos(self.rotation), math.sin(self.rotation)
        turn = np.array([[cos, -sin, 0.0], [sin, cos, 0.0], [0.0, 0.0, 1.0]])
        turn_thorax = self.to_body.T @ turn @ self.to_body
        reference = rows[len(rows) // 2]
        feet = np.array([forward_kinematics_dh(table, reference[3 * leg : 3 * leg + 3])
                         for leg, table in enumerate(self.tables)])  # thorax frame
        return shift_feet(rows, self.tables, feet @ turn_thorax.T - feet)
