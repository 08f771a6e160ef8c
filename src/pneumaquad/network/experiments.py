"""Reference experiments for the networked actuator side (closed-loop joint references).

Each experiment starts from the posture the dynamics reports in its first ``STATE`` and
gives the joint-angle references [rad] of every control step, all joints closed loop:

``hold``
    Hold the initial posture.
``gamma-step``
    Hold for ``settle`` s, then step the front-right gamma joint by ``step`` rad (the
    coupling test of ``tests/robot/test_robot_coupling.py``, thesis 5.5.2 style).
``gamma-sine``
    Hold for ``settle`` s, then a sine of amplitude ``step / 2`` rad at 1 Hz on the
    front-right gamma joint.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["EXPERIMENTS", "Experiment", "make_experiment"]

EXPERIMENTS = ("hold", "gamma-step", "gamma-sine")


@dataclass(frozen=True)
class Experiment:
    """Joint-angle references of an experiment.

    Attributes
    ----------
    name
        One of :data:`EXPERIMENTS`.
    initial_angles
        Posture at the start [rad], one per joint.
    joint
        Index of the moved joint (-1 for none).
    settle
        Hold time before the motion [s].
    step
        Step size (sine: peak-to-peak) [rad].
    control_step
        Control period [s].
    """

    name: str
    initial_angles: np.ndarray
    joint: int
    settle: float
    step: float
    control_step: float

    def references(self, step_index: int) -> np.ndarray:
        """References [rad] of control step ``step_index`` (time ``step_index * dt``)."""
        angles = self.initial_angles.copy()
        time = step_index * self.control_step
        if self.joint < 0 or time < self.settle - 0.5 * self.control_step:
            return angles
        if self.name == "gamma-step":
            angles[self.joint] += self.step
        elif self.name == "gamma-sine":
            angles[self.joint] += 0.5 * self.step * math.sin(2.0 * math.pi * (time - self.settle))
        return angles


def make_experiment(name: str, joint_names: tuple[str, ...], initial_angles: np.ndarray,
                    control_step: float, settle: float = 0.1,
                    step: float = math.radians(20.0)) -> Experiment:
    """Build an experiment for a robot.

    Parameters
    ----------
    name
        ``"hold"``, ``"gamma-step"`` or ``"gamma-sine"``.
    joint_names
        Robot joint names; the moved joint is ``front_right_gamma``.
    initial_angles
        Starting posture [rad].
    control_step
        Control period [s].
    settle
        Hold before the motion [s].
    step
        Step size [rad].

    Raises
    ------
    ValueError
        Unknown name, or a moving experiment on a robot without ``front_right_gamma``.
    """
    if name not in EXPERIMENTS:
        raise ValueError(f"experiment {name!r} should be one of {', '.join(EXPERIMENTS)}")
    joint = -1
    if name != "hold":
        if "front_right_gamma" not in joint_names:
            raise ValueError(f"experiment {name!r} needs a front_right_gamma joint")
        joint = joint_names.index("front_right_gamma")
    return Experiment(name, np.array(initial_angles, dtype=float), joint, settle, step,
                      control_step)
