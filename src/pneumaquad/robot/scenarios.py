"""The robot experiments of thesis ch. 5.5 and beyond, as lists of phases.

* :func:`leg_validation_phases` — thesis 5.5.2: fixed thorax, the front-right leg; the
  joints not under test are first driven to full extension open loop, then the tested
  joint follows steps, trapezoids, a slow or a fast sine.
* :func:`foot_cycle_phases` — thesis 5.5.2.4: the foot of the front-right leg goes
  rear-bottom → arc up → front-bottom → drag back, through inverse kinematics, at slow,
  medium and fast rates.
* :func:`stand_up_phases` — the quadruped lying on the ground stands up on its 12
  pneumatic joints, holds, then follows body height, roll and pitch commands.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from .experiment import Phase
from .frames import euler_zyx_matrix
from .legs import leg_dh_table, solve_leg, thorax_frame_points
from .simulation import RobotSimulation
from .stance_check import StanceCheck, standing_height
from .stand_up import STAGED_RISE_TIME, staged_rise_phases, stand_up_path

__all__ = [
    "DIRECT_RISE_TIME",
    "FOOT_CYCLE_PERIODS",
    "LEG_SIGNALS",
    "LYING_ANGLES",
    "STANCE_CHECK",
    "STANDING_ANGLES",
    "TUCKED_ANGLES",
    "foot_cycle_phases",
    "leg_validation_phases",
    "resting_height",
    "stand_up_phases",
    "standing_height",
]

#: Duration of the four-legged rise from lying to standing [s].
DIRECT_RISE_TIME = 3.0
#: The name of the phase, after a stand-up's hold, whose gate checks the stance.
STANCE_CHECK = "stance check"
LEG_SIGNALS = ("steps", "trapezoid", "slow-sine", "fast-sine")
#: Foot-cycle periods [s] of the slow, medium and fast walking motions (not in thesis).
FOOT_CYCLE_PERIODS = {"slow": 4.0, "medium": 2.0, "fast": 1.0}
#: Alpha, beta, gamma [rad] of a leg lying flat (feet level with the mounts) and standing.
LYING_ANGLES = np.radians([0.0, -65.0, 55.0])
#: Feet drawn in under the body while it still lies on the ground (first half of standing up).
TUCKED_ANGLES = np.radians([0.0, -65.0, 95.0])
STANDING_ANGLES = np.radians([0.0, -15.0, 90.0])
#: Open-loop command that extends a cylinder fully [V] (offset 5.25 V + 2 V).
EXTEND_VOLTAGE = 7.25


def _leg_slice(simulation: RobotSimulation, leg: str) -> slice:
    first = simulation.robot.joint_names.index(f"{leg}_alpha")
    return slice(first, first + 3)


def _extended_angle(simulation: RobotSimulation, index: int) -> float:
    joint_type = simulation.robot.joint_types[index]
    lower = simulation.robot.lower_limits()[index]
    upper = simulation.robot.upper_limits()[index]
    return upper if simulation.robot.linkages[joint_type].direction > 0 else lower


def _joint_signal(kind: str, lower: float, upper: float, start: float):
    span = upper - lower
    middle = 0.5 * (lower + upper)
    if kind == "steps":
        levels = lower + span * np.array([0.5, 0.2, 0.8, 0.35, 0.65, 0.1, 0.9, 0.5])
        hold = 2.0

        def signal(times):
            index = np.clip(((times - start) // hold).astype(int), 0, levels.size - 1)
            return levels[index]

        return signal, hold * levels.size
    if kind == "trapezoid":
        low, high, ramp, hold = lower + 0.2 * span, lower + 0.8 * span, 1.0, 2.0
        period = 2 * (ramp + hold)

        def signal(times):
            t = np.mod(times - start, period)
            up = np.clip(t / ramp, 0.0, 1.0)
            down = np.clip((t - ramp - hold) / ramp, 0.0, 1.0)
            return low + (high - low) * (up - down)

        return signal, 3 * period
    if kind in ("slow-sine", "fast-sine"):
        frequency, cycles = (0.1, 2) if kind == "slow-sine" else (0.5, 5)

        def signal(times):
            return middle + 0.3 * span * np.sin(2 * math.pi * frequency * (times - start))

        return signal, cycles / frequency
    raise ValueError(f"signal {kind!r} should be one of {LEG_SIGNALS}")


def leg_validation_phases(
    simulation: RobotSimulation, joint: str, signal: str, settle: float = 2.0
) -> list[Phase]:
    """Thesis 5.5.2 on the front-right leg (fixed thorax): settle, then the test signal."""
    robot = simulation.robot
    count = robot.joint_count
    tested = robot.joint_names.index(f"front_right_{joint}")
    leg = _leg_slice(simulation, "front_right")
    lower, upper = robot.lower_limits()[tested], robot.upper_limits()[tested]
    reference, duration = _joint_signal(signal, lower, upper, settle)
    pose = np.zeros(count)
    voltages = np.full(count, np.nan)
    for index in range(leg.start, leg.stop):
        pose[index] = _extended_angle(simulation, index)
        if index != tested:
            voltages[index] = EXTEND_VOLTAGE
    pose[tested] = float(reference(np.array([settle]))[0])
    others = [i for i in range(count) if i < leg.start or i >= leg.stop]
    for index in others:
        pose[index] = 0.5 * (robot.lower_limits()[index] + robot.upper_limits()[index])
    simulation.set_pose(pose)
    closed = np.zeros(count, dtype=bool)
    closed[tested] = True

    def references(times):
        table = np.tile(pose, (times.size, 1))
        table[:, tested] = reference(np.maximum(times, settle))
        return table

    return [
        Phase("extend others", settle, references, closed, voltages),
        Phase(signal, duration, references, closed, voltages),
    ]


def _foot_path(phase: np.ndarray, rear: np.ndarray, front: np.ndarray, up: np.ndarray,
               lift: float) -> np.ndarray:
    """Foot positions along the cycle: swing (arc up, rear→front) then drag back."""
    phase = np.mod(phase, 1.0)[:, None]
    swing = np.clip(2.0 * phase, 0.0, 1.0)
    stance = np.clip(2.0 * phase - 1.0, 0.0, 1.0)
    in_swing = phase < 0.5
    along_swing = rear + swing * (front - rear) + up * lift * np.sin(math.pi * swing)
    along_stance = front + stance * (rear - front)
    return np.where(in_swing, along_swing, along_stance)


def foot_cycle_phases(
    simulation: RobotSimulation,
    rates: tuple[str, ...] = ("slow", "medium", "fast"),
    cycles: int = 3,
    stride: float = 0.12,
    lift: float = 0.06,
    neutral: tuple[float, float, float] = (0.0, -0.5236, 1.0472),
) -> list[Phase]:
    """Thesis 5.5.2.4: the walking-like foot cycle of the front-right leg through IK.

    The stride [m] runs along the body axis (thorax z), the lift [m] upwards (thorax x),
    centred on the foot position of the ``neutral`` joint angles [rad] (0°, −30°, 60°).
    """
    robot = simulation.robot
    count = robot.joint_count
    leg = _leg_slice(simulation, "front_right")
    neutral = np.asarray(neutral, dtype=float)
    table = leg_dh_table(robot, "front_right")
    centre = thorax_frame_points(table, neutral)
    forward, up = np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0])
    rear, front = centre - 0.5 * stride * forward, centre + 0.5 * stride * forward
    grid = np.linspace(0.0, 1.0, 401)
    targets = _foot_path(grid, rear, front, up, lift)
    angles = np.empty((grid.size, 3))
    current = neutral
    for k, target in enumerate(targets):
        current = solve_leg(table, target, current).angles
        angles[k] = current
    pose = np.zeros(count)
    for index in range(count):
        pose[index] = 0.5 * (robot.lower_limits()[index] + robot.upper_limits()[index])
    pose[leg] = angles[0]
    simulation.set_pose(pose)
    closed = np.zeros(count, dtype=bool)
    closed[leg] = True
    phases = [Phase("settle", 1.0, pose, closed)]
    start = 1.0
    for rate in rates:
        period = FOOT_CYCLE_PERIODS[rate]

        def references(times, start=start, period=period):
            fraction = np.mod((times - start) / period, 1.0)
            table_rows = np.tile(pose, (times.size, 1))
            for j in range(3):
                table_rows[:, leg.start + j] = np.interp(fraction, grid, angles[:, j])
            return table_rows

        phases.append(Phase(rate, cycles * period, references, closed))
        start += cycles * period
    return phases


def resting_height(simulation: RobotSimulation, angles: np.ndarray) -> float:
    """Thorax height [m] at which the lowest robot geom just touches flat ground.

    With the robot upright at its nominal attitude and the joints at ``angles`` [rad]:
    the lowest point of every capsule/sphere/cylinder is found from its world pose.
    """
    model, data = simulation.model, simulation.data
    probe = 1.0
    simulation.set_pose(angles, thorax_position=np.array([0.0, 0.0, probe]))
    lowest = probe
    for geom in range(model.ngeom):
        if model.geom_bodyid[geom] == 0:
            continue
        radius, half = model.geom_size[geom][0], model.geom_size[geom][1]
        axis_z = abs(data.geom_xmat[geom].reshape(3, 3)[2, 2])
        centre = data.geom_xpos[geom][2]
        if model.geom_type[geom] == mujoco.mjtGeom.mjGEOM_CAPSULE:
            low = centre - axis_z * half - radius
        elif model.geom_type[geom] == mujoco.mjtGeom.mjGEOM_CYLINDER:
            low = centre - axis_z * half - radius * np.sqrt(max(0.0, 1.0 - axis_z**2))
        else:
            low = centre - radius
        lowest = min(lowest, low)
    return probe - lowest


def stand_up_phases(simulation: RobotSimulation, rise_time: float | None = None,
                    hold: float = 3.0,
                    posture: bool = True,
                    standing_angles: np.ndarray = STANDING_ANGLES,
                    check: bool = True, staged: bool = False) -> list[Phase]:
    """The quadruped stands up from lying on the ground, holds, then follows body commands.

    ``standing_angles`` [rad] is the pose it stands up into: (alpha, beta, gamma) for every
    leg, or one angle per joint (e.g. the first pose of a walk; no body commands then).

    ``staged``: the legs rise a pair at a time, swung away from the body's middle
    (:func:`.stand_up.staged_rise_phases`), ``rise_time`` [s] per pair (default 5 s; the
    four-legged rise's default is 3 s),
    so that each foot carries less of the weight while the legs are spread; the robot
    stands up so at a lower supply pressure or with a heavier body.

    With ``check``, the hold ends in a "stance check" (a phase of no duration whose gate
    is :class:`.stance_check.StanceCheck`): the verdict goes to the summary's
    ``"checks"``, and a stance that is not verified ends the run there (no body commands).

    Body commands (thorax height ±3 cm, roll ±5°, pitch ±5°, 2 s each) keep the feet where
    they stand and move the body: each leg's foot target in the thorax frame comes from
    the commanded body pose, through inverse kinematics.
    """
    robot = simulation.robot
    count = robot.joint_count
    legs = robot.legs
    lying = np.tile(LYING_ANGLES, len(legs))
    standing_angles = np.asarray(standing_angles, dtype=float)
    per_joint = standing_angles.size == count
    standing = standing_angles if per_joint else np.tile(standing_angles, len(legs))
    placement = robot.parameters.placement
    rotation = euler_zyx_matrix(placement.rotation_zyx)
    height = resting_height(simulation, lying)
    simulation.set_pose(lying, thorax_position=np.array([0.0, 0.0, height + 0.001]))
    closed = np.ones(count, dtype=bool)

    tucked = np.tile(TUCKED_ANGLES, len(legs))

    rise_time = rise_time or (STAGED_RISE_TIME if staged else DIRECT_RISE_TIME)

    def rise(times):
        return stand_up_path(np.clip((times - 0.5) / rise_time, 0.0, 1.0), standing,
                             lying, tucked)

    phases = [Phase("rest", 0.5, lying, closed)]
    if staged:
        phases += staged_rise_phases(simulation, lying, tucked, standing, 0.5, rise_time)
    else:
        phases.append(Phase("stand up", rise_time, rise, closed))
    phases.append(Phase("hold", hold, standing, closed))
    if check:
        phases.append(Phase(STANCE_CHECK, 0.0, standing, closed,
                            gate=StanceCheck(standing)))
    if not posture:
        return phases
    if per_joint:
        raise ValueError("body commands (posture=True) need one (alpha, beta, gamma) "
                         "standing pose for all legs")
    height = standing_height(simulation, standing_angles)
    tables = [leg_dh_table(robot, leg) for leg in legs]
    feet_world = [
        np.array([0.0, 0.0, height]) + rotation @ thorax_frame_points(t, standing_angles)
        for t in tables
    ]
    commands = [  # (height change [m], roll [rad], pitch [rad])
        ("height up", (0.03, 0.0, 0.0)),
        ("height down", (-0.03, 0.0, 0.0)),
        ("roll", (0.0, math.radians(5.0), 0.0)),
        ("pitch", (0.0, 0.0, math.radians(5.0))),
    ]
    previous = standing
    for name, (dz, roll, pitch) in commands:
        body_rotation = euler_zyx_matrix((0.0, pitch, roll)) @ rotation
        body_position = np.array([0.0, 0.0, height + dz])
        target = np.empty(count)
        for k, (table, foot) in enumerate(zip(tables, feet_world, strict=True)):
            in_thorax = body_rotation.T @ (foot - body_position)
            target[3 * k : 3 * k + 3] = solve_leg(
                table, in_thorax, previous[3 * k : 3 * k + 3]
            ).angles
        phases.append(Phase(name, 2.0, _ramp(previous, target, 1.0), closed))
        previous = target
    phases.append(Phase("back to standing", 2.0, _ramp(previous, standing, 1.0), closed))
    return phases


def _ramp(start_angles: np.ndarray, end_angles: np.ndarray, duration: float):
    state: dict[str, float] = {}

    def references(times):
        first = state.setdefault("start", float(times[0]) - (times[1] - times[0] if
                                                              times.size > 1 else 0.0))
        fraction = np.clip((times - first) / duration, 0.0, 1.0)[:, None]
        return start_angles + fraction * (end_angles - start_angles)

    return references
