"""Where the body stands over its feet on a slope: uphill, by as much as gravity moves it.

The crawl plans the feet relative to a level body on flat ground. On a slope the legs
hold the body parallel to the ground (the feet are planned at one height in the body
frame), so gravity carries the centre of mass downhill of where the plan put it, by
h·tan θ (h the centre of mass's height over the ground plane, θ the slope: 8 cm at 12°
for our 0.38 m stance), and the static margin on the downhill side shrinks by as much.
:class:`BodyPlacement` fits the ground plane through the stance feet once per control
chunk (least squares, :func:`ground_plane`, through the feet the gait has in stance) and
moves the body uphill by that offset
(:func:`uphill_offset`, low-pass filtered, limited), by translating every commanded foot
the other way: the stance feet are held by the ground, so commanding them shifted by
``d`` moves the body by ``−d``, and the swing feet land on the shifted pattern. On level
ground (a fitted plane tilted less than :data:`LEVEL_SLOPE`) nothing moves.

Units: SI; the offset is computed in the world and applied in the thorax frame through
each leg's Jacobian (:func:`pneumaquad.robot.legs.shift_feet_into`).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from pneumaquad.core.jit import load_compiled
from pneumaquad.gait.crawl import CrawlGait
from pneumaquad.robot.kinematics import chain_workspace, stack_leg_tables
from pneumaquad.robot.legs import leg_dh_table
from pneumaquad.robot.simulation import RobotSimulation

from .course_kernels import placement_step
from .feedback_kernels import gait_timing

__all__ = ["LEVEL_SLOPE", "BodyPlacement", "ground_plane", "uphill_offset"]

#: A fitted ground plane tilted less than this [rad] is level ground: the feet's heights
#: differ there only by how far each presses into the contact (on flat ground the fitted
#: offset stayed below 0.4 mm, and moved a heading-225° walk onto a joint limit).
LEVEL_SLOPE = math.radians(1.0)

Array = NDArray[np.float64]


def ground_plane(feet: Array) -> Array | None:
    """Unit normal (3,) (z > 0) of the least-squares plane z = a + b·x + c·y through
    ``feet`` (n, 3) [m], n ≥ 3; None where the feet are collinear in x-y."""
    design = np.column_stack([np.ones(len(feet)), feet[:, 0], feet[:, 1]])
    if len(feet) < 3 or np.linalg.matrix_rank(design) < 3:
        return None
    (_, slope_x, slope_y), *_ = np.linalg.lstsq(design, feet[:, 2], rcond=None)
    normal = np.array([-slope_x, -slope_y, 1.0])
    return normal / np.linalg.norm(normal)


def uphill_offset(normal: Array, height: float) -> Array:
    """Displacement (3,) [m] of a body whose centre of mass stands ``height`` [m] above a
    plane of unit normal ``normal`` (along the normal) that brings the centre of mass
    back over the point of the plane below it along the normal, as on level ground.

    The vertical through the centre of mass meets the plane at h·(n − ẑ/(ẑ·n)) from the
    foot of the normal, so the body moves by h·(ẑ/(ẑ·n) − n): in the plane, uphill,
    of length h·tan θ.
    """
    up = np.array([0.0, 0.0, 1.0])
    return height * (up / float(normal @ up) - normal)


class BodyPlacement:
    """Joint references with the body placed uphill on a slope, one call per chunk.

    :func:`ground_plane` and :func:`uphill_offset` are the reference in NumPy of the
    compiled call (:func:`.course_kernels.placement_step`), on arrays allocated here.

    Parameters
    ----------
    simulation : RobotSimulation
        Read (thorax position and attitude, feet, centre of mass) at every call.
    gait : CrawlGait
        The gait walked (which feet are in stance, for the ground plane).
    start : float [s]
        Simulation time of the gait's time 0.
    references : callable
        ``f(times) -> (len(times), joints)`` joint references [rad] to correct.
    limit : float [m]
        Largest shift of the feet.
    time_constant : float [s]
        Low-pass time constant of the slope offset.
    level : float [rad]
        Slopes below this are level ground: no offset (:data:`LEVEL_SLOPE`).
    """

    def __init__(self, simulation: RobotSimulation, gait: CrawlGait, start: float,
                 references: Callable[[np.ndarray], np.ndarray], *,
                 limit: float = 0.06, time_constant: float = 2.0,
                 level: float = LEVEL_SLOPE) -> None:
        self.simulation = simulation
        self.references = references
        self.start = start
        self.timing = gait_timing(gait)
        self.limit, self.time_constant, self.level = limit, time_constant, level
        robot = simulation.robot
        self._stacked = stack_leg_tables([leg_dh_table(robot, leg) for leg in robot.legs])
        self._workspace = chain_workspace()
        self._shifts = np.zeros((len(robot.legs), 3))
        data = simulation.data
        self._feet = np.ascontiguousarray(robot.foot_site_id, dtype=np.int64)
        self._site_positions = data.site_xpos  # views of MuJoCo's arrays
        self._centre = data.subtree_com[robot.thorax_id]
        self._thorax_matrix = data.xmat[robot.thorax_id]
        self._scratch = np.zeros((3, 9))
        self.uphill = np.zeros(3)  # [m] world shift of the body uphill (filtered)
        self.last_time = simulation.time
        load_compiled(placement_step,
                      *self._step_arguments(np.zeros((1, robot.joint_count)), 0.0, 0.0))

    def __call__(self, times: np.ndarray) -> np.ndarray:
        """Joint references (len(times), joints) [rad] for the next chunk."""
        rows = self.references(times)  # a fresh array of the chain below (corrected here)
        if not (rows.flags.writeable and rows.dtype == np.float64):
            rows = np.array(rows, dtype=float)
        time = self.simulation.time
        interval, self.last_time = time - self.last_time, time
        singular = placement_step(*self._step_arguments(
            rows, time - self.start, interval / (self.time_constant + interval)))
        if singular >= 0:
            raise np.linalg.LinAlgError(f"Singular matrix: the Jacobian of leg {singular}")
        return rows

    def _step_arguments(self, rows: np.ndarray, gait_time: float, blend: float) -> tuple:
        """:func:`.course_kernels.placement_step`'s arguments: ``rows`` to correct, the
        gait time [s] and the low-pass filter's blend of this call."""
        return (rows, gait_time, self.timing, self._site_positions, self._feet,
                self._centre, self._thorax_matrix, self.uphill, blend, self.limit,
                self.level, self._scratch, self._shifts, self._stacked, self._workspace)
