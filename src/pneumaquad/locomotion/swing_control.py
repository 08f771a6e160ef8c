"""Swing-foot height measured from the ground, not from the body.

The crawl plans a swing foot's lift relative to the body. When a leg lifts, the three
stance legs take its share of the load and the compliant pneumatic legs let the body sag
on that corner, by about as much as the planned lift: the foot then only just clears the
ground (5–20 mm of a planned 40 mm in our flat walks) and catches on a plate edge or a
raised cell. :class:`SwingHeightCorrection` closes that loop once per control chunk: the
swing foot's height target is taken in the world — its height at lift-off plus the
planned lift — and the joint references of the swinging leg are corrected, through the
leg Jacobian, by the difference between that target and where the planned foot would be
with the body as measured (thorax position and attitude), weighted by the planned lift
(0 at lift-off and touchdown, 1 at mid-swing): the foot lands where the plan puts it and
the stance leg's reference does not jump. What remains of a correction at touchdown fades
out with a time constant.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from pneumaquad.gait.crawl import CrawlGait, foot_positions_ground, stance_flags
from pneumaquad.robot.kinematics import forward_kinematics_dh
from pneumaquad.robot.legs import leg_dh_table, shift_feet
from pneumaquad.robot.simulation import RobotSimulation

__all__ = ["SwingHeightCorrection"]

Array = NDArray[np.float64]


class SwingHeightCorrection:
    """Joint references with swing feet lifted above the ground, one call per chunk.

    Parameters
    ----------
    simulation : RobotSimulation
        Read (thorax pose, feet) at every call.
    gait : CrawlGait
        The gait the references follow (swing timing and planned lift).
    start : float [s]
        Simulation time of the gait's time 0.
    references : callable
        ``f(times) -> (len(times), joints)`` planned joint references [rad] (the plan,
        or a :class:`.stance_control.StanceController`).
    limit : float [m]
        Largest correction.
    fade : float [s]
        Time constant of the correction's fade after touchdown.
    """

    def __init__(self, simulation: RobotSimulation, gait: CrawlGait, start: float,
                 references: Callable[[np.ndarray], np.ndarray], limit: float = 0.06,
                 fade: float = 0.15) -> None:
        self.simulation = simulation
        self.gait = gait
        self.start = start
        self.references = references
        self.limit = limit
        self.fade = fade
        robot = simulation.robot
        self.tables = [leg_dh_table(robot, leg) for leg in robot.legs]
        self.lift_off_height = simulation.foot_positions()[:, 2].copy()  # [m] world z
        self.was_stance = np.ones(len(robot.legs), dtype=bool)
        self.correction = np.zeros(len(robot.legs))  # [m] world z, per leg
        self.last_time = simulation.time

    def _planned_lift(self, time: float) -> Array:
        return foot_positions_ground(self.gait, np.array([time]))[0, :, 2]

    def __call__(self, times: np.ndarray) -> np.ndarray:
        """Joint references (len(times), joints) [rad] for the next chunk."""
        simulation = self.simulation
        rows = np.array(self.references(times), dtype=float)
        middle = float(np.asarray(times)[len(times) // 2]) - self.start
        stance = stance_flags(self.gait, np.array([middle]))[0]
        feet = simulation.foot_positions()
        lifting = self.was_stance & ~stance
        self.lift_off_height[lifting] = feet[lifting, 2]
        self.was_stance = stance
        interval = simulation.time - self.last_time
        self.last_time = simulation.time
        data, robot = simulation.data, simulation.robot
        thorax_rotation = data.xmat[robot.thorax_id].reshape(3, 3)  # thorax → world
        thorax_height = float(data.xpos[robot.thorax_id][2])
        lift = self._planned_lift(middle)
        reference = rows[len(rows) // 2]
        for leg, table in enumerate(self.tables):
            if stance[leg]:
                self.correction[leg] *= np.exp(-interval / self.fade)
                continue
            foot = forward_kinematics_dh(table, reference[3 * leg : 3 * leg + 3])
            height = thorax_height + float(thorax_rotation[2] @ foot)  # world z [m]
            target = self.lift_off_height[leg] + lift[leg]
            # weighted by the planned lift, so the correction vanishes at lift-off and
            # touchdown: the foot lands where planned, with no step in the reference
            weight = lift[leg] / self.gait.step_height if self.gait.step_height else 0.0
            self.correction[leg] = weight * float(
                np.clip(target - height, -self.limit, self.limit))
        up = np.zeros((len(self.tables), 3))
        up[:, 2] = self.correction
        return shift_feet(rows, self.tables, up @ thorax_rotation)  # world → thorax
