"""Standing up from lying on the ground: the legs' path, all together or a pair at a time.

The stand-up draws the feet in under the body and then extends the legs
(:func:`stand_up_path`). Rising with all four legs, each foot carries a quarter of the
weight while the legs are still spread wide: near the lying pose the knee (gamma) and hip
(beta) cylinders need most of their stall force (about 43 psig supply for the 5.2 kg
robot by statics, :mod:`pneumaquad.locomotion.capacity`), and the feet, sliding inward
under load, ask for more.

The **staged** rise (:func:`staged_rise_phases`) swings the legs away from the body's
middle first (front legs forward, rear legs back, :data:`STAGED_ALPHA`) and lifts the
front of the body with the front pair while the rear still rests on the ground: with the
feet far from the resting end, each carries less than a quarter of the weight. The front
feet then slide back under the body (the rear still resting), the rear pair lifts the rear
of the body with its feet far back, and each rear leg in turn steps forward to where it
stands, its foot lifted, while the other three carry the body (the centre of mass stays
inside their triangle because the other rear foot is still far back). No foot slides
under the whole body's load. It stands up at 45 psig and with a 3 or 4 kg thorax at 50.3
psig, where the four-legged rise stalls (docs/robot.md).
"""

from __future__ import annotations

import math

import numpy as np

from .experiment import Phase
from .simulation import RobotSimulation

__all__ = [
    "STAGED_ALPHA",
    "STAGED_RISE_TIME",
    "alpha_swing_signs",
    "smooth_ramp",
    "staged_rise_phases",
    "stand_up_path",
]

#: How far each leg's alpha joint swings away from the body's middle [rad] for a staged
#: rise: 45° (30° and 40° with a 4 s rise left a rear beta 7–12° off at 45 psig).
STAGED_ALPHA = math.radians(45.0)
#: Duration of each pair's rise in a staged stand-up [s] (4 s failed with a 3 kg thorax).
STAGED_RISE_TIME = 5.0
#: Duration of the alpha swings out and back [s].
SWING_TIME = 2.0
#: A rear leg's step from its swung pose to where it stands [s].
STEP_TIME = 1.5
#: How far a stepping leg's beta joint rises at mid-step [rad] (lifts the foot about 5 cm).
STEP_LIFT = math.radians(15.0)


def stand_up_path(fractions: np.ndarray, standing: np.ndarray, lying: np.ndarray,
                  tucked: np.ndarray) -> np.ndarray:
    """Joint angles [rad] of the stand-up at ``fractions`` (0 lying, 1 standing) of it.

    The first half draws the feet in (``lying`` to ``tucked``), the second half extends
    the legs into ``standing``, each as a smooth step (zero speed at both ends). The poses
    are one (alpha, beta, gamma) or one angle per joint; the result is (len(fractions),
    pose size).
    """
    fraction = np.asarray(fractions, dtype=float)
    first = np.clip(2.0 * fraction, 0.0, 1.0)
    second = np.clip(2.0 * fraction - 1.0, 0.0, 1.0)
    first = (first * first * (3.0 - 2.0 * first))[:, None]
    second = (second * second * (3.0 - 2.0 * second))[:, None]
    return lying + first * (tucked - lying) + second * (standing - tucked)


def alpha_swing_signs(simulation: RobotSimulation, pose: np.ndarray) -> np.ndarray:
    """Per leg, the sign of the alpha swing that moves its foot away from the body's
    middle along the body (front feet forward, rear feet back), from the kinematics of
    ``pose`` (joints,) [rad]. The simulation's pose is changed."""
    legs = len(simulation.robot.legs)
    reach = []
    for sign in (1.0, -1.0):
        swung = np.array(pose, dtype=float)
        swung[0::3] += sign * STAGED_ALPHA
        simulation.set_pose(swung, thorax_position=np.array([0.0, 0.0, 1.0]))
        reach.append(np.abs(simulation.foot_positions()[:, 0]))
    return np.where(reach[0] >= reach[1], 1.0, -1.0)[:legs]


def smooth_ramp(start: np.ndarray, end: np.ndarray, begin: float, duration: float):
    """References from ``start`` to ``end`` (joints,) [rad] as a smooth step of
    ``duration`` [s] from ``begin`` [s], then held."""
    def references(times: np.ndarray) -> np.ndarray:
        fraction = np.clip((times - begin) / duration, 0.0, 1.0)
        fraction = (fraction * fraction * (3.0 - 2.0 * fraction))[:, None]
        return start + fraction * (end - start)

    return references


def _rise(begin: float, duration: float, rising: np.ndarray, before: np.ndarray,
          lying: np.ndarray, tucked: np.ndarray, standing: np.ndarray):
    """References of the joints ``rising`` (joints,) bool along :func:`stand_up_path`
    from ``begin`` [s]; the others hold ``before``."""
    def references(times: np.ndarray) -> np.ndarray:
        fraction = np.clip((times - begin) / duration, 0.0, 1.0)
        return np.where(rising, stand_up_path(fraction, standing, lying, tucked), before)

    return references


def _step(begin: float, leg: int, before: np.ndarray, after: np.ndarray):
    """References that move leg ``leg``'s joints from ``before`` to ``after`` (joints,)
    [rad] in :data:`STEP_TIME` from ``begin`` [s], its foot lifted on the way (beta
    raised by up to :data:`STEP_LIFT`); the other legs hold ``before``."""
    joints = slice(3 * leg, 3 * leg + 3)

    def references(times: np.ndarray) -> np.ndarray:
        fraction = np.clip((times - begin) / STEP_TIME, 0.0, 1.0)
        smooth = fraction * fraction * (3.0 - 2.0 * fraction)
        table = np.tile(before, (times.size, 1))
        table[:, joints] = before[joints] + smooth[:, None] * (after[joints] - before[joints])
        table[:, 3 * leg + 1] -= STEP_LIFT * np.sin(np.pi * fraction)
        return table

    return references


def staged_rise_phases(simulation: RobotSimulation, lying: np.ndarray, tucked: np.ndarray,
                       standing: np.ndarray, start: float,
                       rise_time: float = STAGED_RISE_TIME) -> list[Phase]:
    """The phases of a staged rise (module docstring), beginning at ``start`` [s].

    ``lying``, ``tucked`` and ``standing`` are per joint [rad]; the robot lies at
    ``lying`` when they begin (the simulation's pose is left so). Phases: "swing out"
    (all legs, :data:`SWING_TIME`), "front pair up" (``rise_time``), "front pair back"
    (:data:`SWING_TIME`: the front feet slide back while the rear of the body rests on
    the ground), "rear pair up" (``rise_time``), then "step <leg>" for each rear leg
    (:data:`STEP_TIME`: lifted, swung back and set down where it stands, the other three
    feet carrying the body).
    """
    robot = simulation.robot
    count = robot.joint_count
    closed = np.ones(count, dtype=bool)
    saved = simulation.snapshot()
    signs = alpha_swing_signs(simulation, lying)
    simulation.restore(saved)
    swing = np.zeros(count)
    swing[0::3] = signs * STAGED_ALPHA
    front_legs = np.array([leg.startswith("front") for leg in robot.legs])
    front = np.repeat(front_legs, 3)
    swung = (lying + swing, tucked + swing, standing + swing)
    time = start
    pose = lying + swing
    phases = [Phase("swing out", SWING_TIME, smooth_ramp(lying, pose, time, SWING_TIME),
                    closed)]
    time += SWING_TIME
    phases.append(Phase("front pair up", rise_time, _rise(time, rise_time, front, pose,
                                                          *swung), closed))
    time += rise_time
    pose = np.where(front, standing + swing, pose)
    back = np.where(front, standing, pose)
    phases.append(Phase("front pair back", SWING_TIME,
                        smooth_ramp(pose, back, time, SWING_TIME), closed))
    time += SWING_TIME
    pose = back
    phases.append(Phase("rear pair up", rise_time, _rise(time, rise_time, ~front, pose,
                                                         *swung), closed))
    time += rise_time
    pose = np.where(front, pose, standing + swing)
    for leg in np.flatnonzero(~front_legs):
        after = pose.copy()
        after[3 * leg: 3 * leg + 3] = standing[3 * leg: 3 * leg + 3]
        phases.append(Phase(f"step {robot.legs[leg]}", STEP_TIME,
                            _step(time, int(leg), pose, after), closed))
        time += STEP_TIME
        pose = after
    return phases
