"""Is the robot standing as asked? The verdict of a stance, against stated limits.

A stand-up can end anywhere: a cylinder at its force capacity stalls its joint short of
the commanded angle and the thorax stays low, the body rests tilted on a leg that did
not extend, or it never left the ground. :func:`stance_verdict` measures the present
state of a simulation against the stance it was asked for:

- **height**: the thorax height above flat ground against the height that puts the
  commanded pose's feet on the ground;
- **joints**: the largest angle error of any joint against its command;
- **attitude**: the thorax roll and pitch against its nominal placement.

:class:`StanceCheck` is the check as a phase gate (:attr:`.experiment.Phase.gate`): a walk
begins only from a verified stance, and a stand reports the verdict of its hold.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .frames import euler_zyx_matrix
from .legs import leg_dh_table, thorax_frame_points
from .recording import thorax_attitude
from .simulation import RobotSimulation

__all__ = ["StanceCheck", "StanceLimits", "stance_verdict", "standing_height"]


@dataclass(frozen=True)
class StanceLimits:
    """What a verified stance may differ from the one asked for.

    Attributes
    ----------
    height : float [m]
        Largest thorax height error (either way). 0.03 m: about 8 % of the 0.38 m
        standing height, a 6° error of one knee (gamma) of the standing pose.
    joint_error : float [rad]
        Largest angle error of any joint (5°).
    attitude : float [rad]
        Largest thorax roll or pitch (5°).
    """

    height: float = 0.03
    joint_error: float = math.radians(5.0)
    attitude: float = math.radians(5.0)


def stance_verdict(simulation: RobotSimulation, angles: np.ndarray,
                   limits: StanceLimits = StanceLimits()) -> dict[str, Any]:
    """The verdict of the present stance against the commanded joint ``angles`` [rad].

    The free robot on flat ground only (the start of every stand and walk): the target
    height is the thorax height that puts the feet of ``angles`` on the ground.

    Parameters
    ----------
    simulation : RobotSimulation
        The free quadruped, standing (or not) now.
    angles : ndarray
        Commanded angles [rad]: one (alpha, beta, gamma) for every leg, or one per joint.
    limits : StanceLimits

    Returns
    -------
    dict
        ``"verified"`` (bool), ``"reasons"`` (what is out of its limit; empty when
        verified), the measured and target thorax height [m], the largest joint error
        [deg] and its joint, thorax roll and pitch [deg], and the limits.
    """
    robot = simulation.robot
    angles = np.asarray(angles, dtype=float)
    per_joint = angles if angles.size == robot.joint_count else np.tile(angles,
                                                                          len(robot.legs))
    target = standing_height(simulation, per_joint)
    height = float(simulation.data.qpos[2])
    errors = np.abs(simulation.joint_angles() - per_joint)
    worst = int(np.argmax(errors))
    roll, pitch, _ = thorax_attitude(simulation)
    reasons = []
    if abs(height - target) > limits.height:
        reasons.append(f"thorax at {height:.3f} m instead of {target:.3f} m "
                       f"(limit ±{limits.height:g} m)")
    if errors[worst] > limits.joint_error:
        reasons.append(f"{robot.joint_names[worst]} {math.degrees(errors[worst]):.1f}° from "
                       f"its command (limit {math.degrees(limits.joint_error):g}°)")
    for name, angle in (("roll", roll), ("pitch", pitch)):
        if abs(angle) > limits.attitude:
            reasons.append(f"thorax {name} {math.degrees(angle):+.1f}° (limit "
                           f"±{math.degrees(limits.attitude):g}°)")
    return {
        "verified": not reasons,
        "reasons": reasons,
        "thorax height [m]": height,
        "target thorax height [m]": target,
        "largest joint error [deg]": float(math.degrees(errors[worst])),
        "joint with the largest error": robot.joint_names[worst],
        "thorax roll [deg]": float(math.degrees(roll)),
        "thorax pitch [deg]": float(math.degrees(pitch)),
        "limits": {"height [m]": limits.height,
                   "joint error [deg]": math.degrees(limits.joint_error),
                   "roll and pitch [deg]": math.degrees(limits.attitude)},
    }


def standing_height(simulation: RobotSimulation, angles: np.ndarray) -> float:
    """Thorax height [m], level at its nominal placement, that puts the feet of a pose on
    flat ground (on average over the legs): ``angles`` [rad] one (alpha, beta, gamma) for
    every leg, or one angle per joint."""
    robot = simulation.robot
    legs = robot.legs
    angles = np.asarray(angles, dtype=float)
    per_leg = angles.reshape(len(legs), 3) if angles.size == robot.joint_count else [
        angles] * len(legs)
    rotation = euler_zyx_matrix(robot.parameters.placement.rotation_zyx)
    depths = [(rotation @ thorax_frame_points(leg_dh_table(robot, leg), pose))[2]
              for leg, pose in zip(legs, per_leg, strict=True)]
    return -float(np.mean(depths))


class StanceCheck:
    """:func:`stance_verdict` as a phase gate (:attr:`.experiment.Phase.gate`): called
    with the simulation before the phase it guards, it returns (None or the reasons as
    one line, the verdict); the verdict is also kept in :attr:`verdict`.

    Parameters
    ----------
    angles : ndarray
        The commanded stance [rad] (as :func:`stance_verdict`).
    limits : StanceLimits
    """

    def __init__(self, angles: np.ndarray, limits: StanceLimits = StanceLimits()) -> None:
        self.angles = np.asarray(angles, dtype=float)
        self.limits = limits
        self.verdict: dict[str, Any] | None = None

    def __call__(self, simulation: RobotSimulation) -> tuple[str | None, dict[str, Any]]:
        verdict = self.verdict = stance_verdict(simulation, self.angles, self.limits)
        if verdict["verified"]:
            return None, verdict
        return "no verified stance: " + "; ".join(verdict["reasons"]), verdict
