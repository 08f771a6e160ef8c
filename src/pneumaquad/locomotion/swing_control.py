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

from pneumaquad.core.jit import load_compiled
from pneumaquad.gait.crawl import CrawlGait
from pneumaquad.robot.kinematics import chain_workspace, stack_leg_tables
from pneumaquad.robot.legs import leg_dh_table
from pneumaquad.robot.simulation import RobotSimulation

from .feedback_kernels import gait_timing, swing_step

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

    Notes
    -----
    The arithmetic of a call is compiled (:func:`.feedback_kernels.swing_step`) on arrays
    allocated here: :attr:`lift_off_height`, :attr:`was_stance` and :attr:`correction`
    are updated in place.
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
        self._clock = np.array([simulation.time])  # [s] of the last call
        self._timing = gait_timing(gait)
        self._stacked = stack_leg_tables(self.tables)
        self._workspace = chain_workspace()
        data = simulation.data
        self._thorax_matrix = data.xmat[robot.thorax_id]  # views: thorax → world, ...
        self._thorax_position = data.xpos[robot.thorax_id]  # ... thorax origin [m]
        self._site_positions = data.site_xpos  # [m]
        self._foot_sites = np.asarray(robot.foot_site_id, dtype=np.int64)
        load_compiled(swing_step, *self._step_arguments(np.zeros((1, robot.joint_count)), 0.0))

    @property
    def last_time(self) -> float:
        """Simulation time [s] of the last call (of the construction before it)."""
        return float(self._clock[0])

    @last_time.setter
    def last_time(self, value: float) -> None:
        self._clock[0] = value

    def __call__(self, times: np.ndarray) -> np.ndarray:
        """Joint references (len(times), joints) [rad] for the next chunk."""
        rows = np.array(self.references(times), dtype=float)
        middle = float(np.asarray(times)[len(times) // 2]) - self.start
        singular = swing_step(*self._step_arguments(rows, middle))
        if singular >= 0:
            raise np.linalg.LinAlgError(f"Singular matrix: the Jacobian of leg {singular}")
        return rows

    def _step_arguments(self, rows: np.ndarray, middle: float) -> tuple:
        """:func:`.feedback_kernels.swing_step`'s arguments: ``rows`` to correct, the
        chunk's middle [s] in gait time."""
        return (rows, middle, self.simulation.time, self._thorax_matrix,
                self._thorax_position, self._site_positions, self._foot_sites, self._timing,
                self.lift_off_height, self.was_stance, self.correction, self._clock,
                self.limit, self.fade, self._stacked, self._workspace)
