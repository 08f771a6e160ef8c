"""Observation, reward and fall test of the Gymnasium environment (:mod:`.gym_env`).

The observation is one flat ``float64`` vector; :data:`OBSERVATION_LAYOUT` names its
blocks in order, with their sizes and units, and :func:`observation_slices` gives each
block's slice. Joint and leg order is the robot's (``joint_names``: front_left alpha,
beta, gamma, front_right …, rear_left …, rear_right …; legs in the same order).

Reward per environment step of duration T [s] (:class:`RewardWeights`)::

    r = Δx / T  −  c_y · |y − y0|  −  c_air · ΔV / T  −  P_fall · [fell]

Δx [m] is the thorax's forward progress along world x (the robot faces +x at reset)
during the step, |y − y0| [m] its distance from the line it started on at the end of
the step, ΔV [NL] the air drawn from the supply during the step in normal litres
(DIN 1343: 0 °C, 101.325 kPa), and [fell] is 1 on the step that ends the episode by a
fall (:func:`has_fallen`), else 0. The first term is the mean forward speed [m/s];
the episode return of a steady walk is about its speed times the number of steps.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pneumaquad.rig.simulate import NORMAL_PRESSURE, NORMAL_TEMPERATURE
from pneumaquad.robot.recording import thorax_attitude
from pneumaquad.robot.simulation import RobotSimulation

__all__ = [
    "OBSERVATION_LAYOUT",
    "PRESSURE_UNIT",
    "RewardWeights",
    "body_rotation",
    "has_fallen",
    "normal_litres",
    "observation_size",
    "observation_slices",
]

#: Pressures are observed in MPa (absolute): values of order 1, as for the other blocks.
PRESSURE_UNIT = 1e6

#: (name, size, unit) of each observation block, in order.
OBSERVATION_LAYOUT: tuple[tuple[str, int, str], ...] = (
    ("joint angles", 12, "rad"),
    ("joint velocities", 12, "rad/s"),
    ("cap pressures", 12, "MPa"),
    ("rod pressures", 12, "MPa"),
    ("thorax roll pitch yaw", 3, "rad"),
    ("thorax angular velocity", 3, "rad/s"),
    ("thorax velocity", 3, "m/s"),
    ("thorax height", 1, "m"),
    ("foot normal forces", 4, "N"),
)


def observation_slices() -> dict[str, slice]:
    """Slice of each :data:`OBSERVATION_LAYOUT` block in the observation vector."""
    slices, start = {}, 0
    for name, size, _ in OBSERVATION_LAYOUT:
        slices[name] = slice(start, start + size)
        start += size
    return slices


def observation_size() -> int:
    """Length of the observation vector (62)."""
    return sum(size for _, size, _ in OBSERVATION_LAYOUT)


def body_rotation(simulation: RobotSimulation) -> np.ndarray:
    """Rotation (3, 3) from the thorax's own frame to the robot's body axes.

    Body axes: forward, left, up at the nominal placement (the thorax frame itself
    points x up, z forward). A thorax-frame vector ``v`` has body-axis components
    ``body_rotation(sim) @ v``; it is the nominal placement's rotation, a constant.
    """
    return simulation.thorax_placement


def write_observation(simulation: RobotSimulation, to_body: np.ndarray,
                      into: np.ndarray) -> None:
    """Fill ``into`` (:func:`observation_size`,) with the present state (layout above).

    ``to_body`` is :func:`body_rotation` of the simulation: the free joint's angular
    velocity is in the thorax frame, the observation gives it about the body axes
    (roll rate about forward, pitch rate about left, yaw rate about up).
    """
    robot = simulation.robot
    data = simulation.data
    pressures = simulation.chamber_pressures()
    into[0:12] = data.qpos[robot.qpos_address]
    into[12:24] = data.qvel[robot.dof_address]
    into[24:36] = pressures[:, 0] / PRESSURE_UNIT
    into[36:48] = pressures[:, 1] / PRESSURE_UNIT
    into[48:51] = thorax_attitude(simulation)
    into[51:54] = to_body @ data.qvel[3:6]
    into[54:57] = data.qvel[0:3]
    into[57] = data.xpos[robot.thorax_id, 2]
    into[58:62] = simulation.foot_normal_forces()


def normal_litres(simulation: RobotSimulation, mass: float) -> float:
    """Volume [NL] at normal conditions (0 °C, 101.325 kPa) of ``mass`` [kg] of air."""
    robot = simulation.robot
    gas_constant = robot.actuators[robot.joint_types[0]].gas.gas_constant  # [J/(kg K)]
    return mass * gas_constant * NORMAL_TEMPERATURE / NORMAL_PRESSURE * 1e3


@dataclass(frozen=True)
class RewardWeights:
    """Weights of the reward (module docstring).

    Attributes
    ----------
    lateral : float [1/s]
        c_y, per metre off the start line.
    air : float [m/NL]
        c_air, per normal litre of air drawn (0.01: walking at 2 cm/s on ≈ 0.2 NL/s
        pays about a tenth of its forward reward for air).
    fall : float [-]
        P_fall, subtracted once on the step that ends in a fall.
    """

    lateral: float = 0.05
    air: float = 0.01
    fall: float = 10.0

    def __post_init__(self) -> None:
        for name in ("lateral", "air", "fall"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"reward weight {name} must be finite and >= 0, got {value!r}")


def has_fallen(height: float, roll: float, pitch: float, fall_height: float,
               fall_tilt: float) -> bool:
    """A fall: thorax height [m] below ``fall_height`` or |roll| or |pitch| [rad] above
    ``fall_tilt`` (the criteria of :func:`pneumaquad.locomotion.walking.walking_outcome`
    with its defaults 0.15 m and 30°). A NaN state counts as a fall."""
    return not (height >= fall_height and abs(roll) <= fall_tilt and abs(pitch) <= fall_tilt)
