"""Standing up from lying on the ground: the legs' path, all together or a pair at a time.

The stand-up draws the feet in under the body and then extends the legs
(:func:`stand_up_path`). Rising with all four legs, each foot carries a quarter of the
weight while the legs are still spread wide: near the lying pose the knee (gamma) and hip
(beta) cylinders need most of their stall force (about 43 psig supply for the 5.2 kg
robot by statics, :mod:`pneumaquad.locomotion.capacity`), and the feet, sliding inward
under load, ask for more.

The **staged** rise (:func:`staged_rise_phases`) swings the legs away from the body's
middle first (front legs forward, rear legs back, :data:`STAGED_ALPHA`), then lifts the
front of the body with the front pair while the rear still rests on the ground, then
the rear with the rear pair, and finally swings the legs back under the standing body.
While one pair lifts, the lever between the resting end and the far-placed feet gives
each of them less than a quarter of the weight. It stands up at 45 psig, and with a 3 kg
thorax at 50.3 psig, where the four-legged rise stalls (docs/robot.md).
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
#: Standing still after the swing back, before the hold [s]: the feet slid while the legs
#: swung back, and the last pair's beta joints take about 6 s to work off the error (4.5°
#: after 6 s, 5.2° after 3 s at 45 psig).
SETTLE_TIME = 3.0


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


def _smooth_ramp(start: np.ndarray, end: np.ndarray, begin: float, duration: float):
    def references(times: np.ndarray) -> np.ndarray:
        fraction = np.clip((times - begin) / duration, 0.0, 1.0)
        fraction = (fraction * fraction * (3.0 - 2.0 * fraction))[:, None]
        return start + fraction * (end - start)

    return references


def staged_rise_phases(simulation: RobotSimulation, lying: np.ndarray, tucked: np.ndarray,
                       standing: np.ndarray, start: float,
                       rise_time: float = STAGED_RISE_TIME) -> list[Phase]:
    """The phases of a staged rise (module docstring), beginning at ``start`` [s].

    ``lying``, ``tucked`` and ``standing`` are per joint [rad]; the robot lies at
    ``lying`` when they begin (the simulation's pose is left so). Phases: "swing out"
    (2 s), "front pair up" and "rear pair up" (``rise_time`` each), "swing back" (2 s),
    "settle" (3 s).
    """
    robot = simulation.robot
    count = robot.joint_count
    closed = np.ones(count, dtype=bool)
    saved = simulation.snapshot()
    signs = alpha_swing_signs(simulation, lying)
    simulation.restore(saved)
    swing = np.zeros(count)
    swing[0::3] = signs * STAGED_ALPHA
    front = np.array([leg.startswith("front") for leg in robot.legs])
    pairs = [("front pair up", front), ("rear pair up", ~front)]
    pose = lying + swing
    phases = [Phase("swing out", SWING_TIME, _smooth_ramp(lying, pose, start, SWING_TIME),
                    closed)]
    time = start + SWING_TIME
    for name, rising in pairs:
        joints = np.repeat(rising, 3)
        target = np.where(joints, standing + swing, pose)

        def references(times: np.ndarray, begin: float = time, joints: np.ndarray = joints,
                       before: np.ndarray = pose) -> np.ndarray:
            fraction = np.clip((times - begin) / rise_time, 0.0, 1.0)
            path = stand_up_path(fraction, standing + swing, lying + swing, tucked + swing)
            return np.where(joints, path, before)

        phases.append(Phase(name, rise_time, references, closed))
        pose = target
        time += rise_time
    phases.append(Phase("swing back", SWING_TIME,
                        _smooth_ramp(pose, standing, time, SWING_TIME), closed))
    phases.append(Phase("settle", SETTLE_TIME, standing, closed))
    return phases
