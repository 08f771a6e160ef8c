"""The crawl gait turned into joint-angle references for the quadruped.

The feet of :mod:`.crawl` (body frame: x forward, y left, z up) are mapped into the
thorax frame (x up, y right, z forward: the placement rotation EulerZYX(180°, −90°, 0°)
sends thorax x to world up, y to world −y, z to world forward) and solved per leg by the
analytic inverse kinematics (:func:`pneumaquad.robot.legs.solve_leg`, clamped into the
joint limits). The body-frame foot paths repeat every cycle, so the IK is solved once on
a grid over one cycle and the joint angles are interpolated at the control rate, as
:func:`pneumaquad.robot.scenarios.foot_cycle_phases` does.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import NDArray

from pneumaquad.gait.crawl import (
    LEGS,
    CrawlGait,
    foot_targets,
    plan_margins,
    stance_flags,
    sway_for_margin,
)
from pneumaquad.gait.stability import centre_of_mass, support_margins
from pneumaquad.robot.builder import RobotModel
from pneumaquad.robot.frames import euler_zyx_matrix, rotation_to_quaternion
from pneumaquad.robot.legs import leg_dh_table, solve_leg, thorax_frame_points
from pneumaquad.robot.scenarios import STANDING_ANGLES

__all__ = ["CycleSolution", "WalkPlan", "cycle_targets", "plan_walk", "robot_gait", "solve_cycle",
           "standing_feet", "thorax_rotation"]

Array = NDArray[np.float64]
_LIMIT_TOLERANCE = 1e-6  # [rad] a clamped joint this close to a limit sits on it


def thorax_rotation(robot: RobotModel) -> Array:
    """Rotation (3, 3) taking thorax-frame vectors to the body frame (x fwd, y left, z up)."""
    return euler_zyx_matrix(robot.parameters.placement.rotation_zyx)


def standing_feet(robot: RobotModel, angles: Array = STANDING_ANGLES) -> Array:
    """Feet (4, 3) [m] in the body frame, every leg at ``angles`` (alpha, beta, gamma) [rad]."""
    rotation = thorax_rotation(robot)
    return np.array([rotation @ thorax_frame_points(leg_dh_table(robot, leg), angles)
                     for leg in LEGS])


def _pose_data(robot: RobotModel, angles: Array,
               data: mujoco.MjData | None = None) -> mujoco.MjData:
    """MuJoCo data with the thorax upright at the origin and the 12 joints at ``angles``
    (``data`` filled in, or a new one)."""
    model = robot.model
    data = mujoco.MjData(model) if data is None else data
    data.qpos[:] = model.qpos0
    if robot.free:
        address = model.jnt_qposadr[0]
        data.qpos[address : address + 3] = 0.0
        data.qpos[address + 3 : address + 7] = rotation_to_quaternion(thorax_rotation(robot))
    data.qpos[robot.qpos_address] = angles
    mujoco.mj_kinematics(model, data)
    return data


def _body_com(robot: RobotModel, angles: Array,
              data: mujoco.MjData | None = None) -> Array:
    """Centre-of-mass projection (2,) [m] in the body frame for joint ``angles`` (12,)
    (``data``: MuJoCo data to pose, or a new one)."""
    data = _pose_data(robot, angles, data)
    origin = data.xpos[robot.thorax_id][:2]
    return centre_of_mass(robot.model, data) - origin


def robot_gait(robot: RobotModel, speed: float, heading: float = 0.0,
               duty_factor: float = 0.8, period: float = 4.0, step_height: float = 0.04,
               sway: float = 1.0, angles: Array = STANDING_ANGLES,
               minimum_margin: float | None = None, lift_fraction: float = 0.0,
               transfer_gap: float = 0.0, start_up: bool = False,
               yaw_rate: float = 0.0) -> CrawlGait:
    """A crawl gait for ``robot`` about its feet at ``angles`` (speed [m/s], heading [rad],
    yaw rate [rad/s]: an arc, or with speed 0 a turn in place).

    The stride is speed·β·T, the turn per stance yaw rate·β·T; the centre of mass is the
    robot's in the pose ``angles``.
    With ``minimum_margin`` [m], the sway is the least giving that planned margin
    (:func:`.crawl.sway_for_margin`) instead of ``sway``.
    """
    com = _body_com(robot, np.tile(angles, len(robot.legs)))
    gait = CrawlGait(standing_feet(robot, angles), duty_factor=duty_factor, period=period,
                     stride=speed * duty_factor * period, step_height=step_height,
                     heading=heading, sway=sway, com_offset=com,
                     lift_fraction=lift_fraction, transfer_gap=transfer_gap,
                     start_up=start_up, turn=yaw_rate * duty_factor * period)
    return gait if minimum_margin is None else sway_for_margin(gait, minimum_margin)


@dataclass(frozen=True)
class CycleSolution:
    """Inverse kinematics of one gait cycle on a grid.

    Attributes
    ----------
    phases : (samples,)  cycle fractions in [0, 1).
    targets : (samples, 4, 3) [m]  planned feet in the thorax frame.
    angles : (samples, 12) [rad]  joint angles, ``robot.joint_names`` order.
    feet : (samples, 4, 3) [m]  feet reached (FK of ``angles``), thorax frame.
    reachable : (samples, 4) bool  the IK met the target exactly.
    limit_hits : dict  leg → Counter of "<joint> lower/upper" over unreachable samples.
    robot_margins : (samples,) [m]  static margin with the whole robot's centre of mass
        (legs included) in the IK pose and the reached stance feet.
    """

    phases: Array
    targets: Array
    angles: Array
    feet: Array
    reachable: NDArray[np.bool_]
    limit_hits: dict[str, Counter]
    robot_margins: Array

    @property
    def unreachable_counts(self) -> dict[str, int]:
        """Unreachable grid samples per leg."""
        return {leg: int((~self.reachable[:, k]).sum()) for k, leg in enumerate(LEGS)}


def cycle_targets(robot: RobotModel, gait: CrawlGait, samples: int,
                  first: bool = False) -> tuple[Array, Array, Array]:
    """The IK grid of one cycle: cycle fractions (samples,), times (samples,) [s] and the
    planned feet (samples, 4, 3) [m] in the thorax frame, of a steady cycle or, with
    ``first``, of the gait's first cycle."""
    phases = np.arange(samples) / samples
    times = (phases + (0.0 if first else 1.0)) * gait.period
    return phases, times, foot_targets(gait, times) @ thorax_rotation(robot)


def solve_cycle(robot: RobotModel, gait: CrawlGait, samples: int = 200,
                first: bool = False) -> CycleSolution:
    """Solve the leg IK on ``samples`` instants over one cycle (clamped into the limits):
    a steady cycle, or with ``first`` the gait's first cycle (its start-up, if any)."""
    if tuple(robot.legs) != LEGS:
        raise ValueError(f"the crawl gait needs the legs {LEGS}, the robot has {robot.legs}")
    phases, times, targets = cycle_targets(robot, gait, samples, first)
    to_thorax = thorax_rotation(robot).T
    angles = np.empty((samples, 12))
    feet = np.empty((samples, 4, 3))
    reachable = np.empty((samples, 4), dtype=bool)
    limit_hits: dict[str, Counter] = {leg: Counter() for leg in LEGS}
    for k, leg in enumerate(LEGS):
        table = leg_dh_table(robot, leg)
        current = np.asarray(STANDING_ANGLES, dtype=float)
        for sample in range(samples):
            result = solve_leg(table, targets[sample, k], current, clamp=True)
            current = np.array(result.angles)
            angles[sample, 3 * k : 3 * k + 3] = current
            feet[sample, k] = result.foot
            reachable[sample, k] = result.reachable
            if not result.reachable:
                for j, joint in enumerate(("alpha", "beta", "gamma")):
                    if current[j] <= table.lower_limits[j] + _LIMIT_TOLERANCE:
                        limit_hits[leg][f"{joint} lower"] += 1
                    elif current[j] >= table.upper_limits[j] - _LIMIT_TOLERANCE:
                        limit_hits[leg][f"{joint} upper"] += 1
    stance = stance_flags(gait, times)
    body_feet = feet @ to_thorax  # thorax → body frame
    pose = mujoco.MjData(robot.model)  # one for all samples: each sets the whole qpos
    coms = np.array([_body_com(robot, angles[s], pose) for s in range(samples)])
    margins = support_margins(body_feet, stance, coms)
    return CycleSolution(phases, targets, angles, feet, reachable, limit_hits, margins)


@dataclass(frozen=True)
class WalkPlan:
    """Joint references for walking, at the control rate.

    Attributes
    ----------
    times : (steps,) [s]
    references : (steps, 12) [rad]  ``robot.joint_names`` order.
    stance : (steps, 4) bool  planned stance per leg (:data:`.crawl.LEGS` order).
    margins : (steps,) [m]  planned static margin (gait centre of mass).
    cycle : CycleSolution  the IK grid the references interpolate (steady cycles).
    start_up : CycleSolution or None  the IK grid of the first cycle of a gait with a
        start-up (:attr:`.crawl.CrawlGait.start_up`).
    """

    times: Array
    references: Array
    stance: NDArray[np.bool_]
    margins: Array
    cycle: CycleSolution
    start_up: CycleSolution | None = None


def plan_walk(robot: RobotModel, gait: CrawlGait, duration: float,
              control_step: float | None = None, samples: int = 200) -> WalkPlan:
    """Joint-angle references (steps, 12) for ``duration`` [s] of the crawl ``gait``.

    Parameters
    ----------
    robot : RobotModel
    gait : CrawlGait
        E.g. from :func:`robot_gait`; time 0 is the lift-off of the first leg.
    duration : float [s]
    control_step : float [s], optional
        Default: the robot's ``simulation.control_step``.
    samples : int
        IK grid size per cycle.
    """
    step = robot.parameters.simulation.control_step if control_step is None else control_step
    times = np.arange(round(duration / step)) * step
    cycle = solve_cycle(robot, gait, samples)
    fraction = np.mod(times / gait.period, 1.0)
    references = np.column_stack([
        np.interp(fraction, cycle.phases, cycle.angles[:, j], period=1.0)
        for j in range(cycle.angles.shape[1])
    ])
    start_up = None
    if gait.start_up:
        start_up = solve_cycle(robot, gait, samples, first=True)
        first = times < gait.period
        # the first cycle ends where the steady one begins: interpolate towards it
        phases = np.append(start_up.phases, 1.0)
        angles = np.vstack([start_up.angles, cycle.angles[:1]])
        references[first] = np.column_stack([
            np.interp(fraction[first], phases, angles[:, j]) for j in range(angles.shape[1])
        ])
    _, margins = plan_margins(gait, times)
    return WalkPlan(times, references, stance_flags(gait, times), margins, cycle, start_up)
