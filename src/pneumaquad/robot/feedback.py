"""Haptic-style force feedback at the feet: contact force plus actuator resistance.

Thesis 3.3 drives the front feet with two haptic styluses; this module computes what such
a stylus can render for each foot, from the state of a :class:`RobotSimulation`:

* the **contact force** on the foot: the sum over the contacts of the leg's lowest link
  (the tibia body, whose geom is the foot; the same identification as
  :meth:`RobotSimulation.foot_normal_forces`) of :func:`mujoco.mj_contactForce`, rotated
  from the contact frame to the world frame, with the sign that makes it the force **on**
  the foot (a standing foot gives +z, about its normal load);
* the **actuator resistance**: the cylinders' joint torques τ on the leg's three joints
  (``data.qfrc_actuator`` at the leg's dofs: cylinder force × moment arm) mapped to the
  foot by the 3×3 foot position Jacobian J (world frame, w.r.t. those dofs). In statics,
  ``F_leg = J^{-T} τ`` is the force the leg pushes with on something that holds the foot;
  the force that something must exert on the foot to hold it, and that an operator holding
  the foot feels as the leg's resistance, is ``resistance = -F_leg``. Both quantities are
  therefore forces exerted **on** the foot from outside, in newtons, world frame.

The inverse is a damped least-squares solve (see :func:`foot_force_from_joint_torques`)
so that a stretched leg (singular J) gives a bounded force. :func:`device_force` scales a
foot force to a desktop haptic device and saturates it.

SI units throughout: N, N·m, m.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from .builder import RobotModel, tibia_body_legs
from .simulation import RobotSimulation

__all__ = [
    "DEFAULT_DEVICE_SCALE",
    "DEFAULT_MAX_DEVICE_FORCE",
    "FootFeedback",
    "actuator_resistance",
    "device_force",
    "foot_contact_forces",
    "foot_feedback",
    "foot_force_from_joint_torques",
    "foot_jacobian_world",
    "leg_dof_addresses",
    "tibia_body_legs",
]

#: Device force per foot force [N/N] (a 25 N foot load becomes 1.25 N at the stylus).
DEFAULT_DEVICE_SCALE = 0.05
#: Maximum device force norm [N], typical continuous force of a desktop haptic stylus.
DEFAULT_MAX_DEVICE_FORCE = 3.3
#: Smallest singular value of J [m] below which the least-squares solve is damped.
SINGULAR_THRESHOLD = 0.03
#: Damping λ [m] reached at an exactly singular J.
MAX_DAMPING = 0.01


def leg_dof_addresses(robot: RobotModel, leg: str) -> np.ndarray:
    """Dof addresses (``qvel`` / ``qfrc_*`` indices) of the leg's alpha, beta, gamma joints."""
    first = robot.joint_names.index(f"{leg}_alpha")
    return np.asarray(robot.dof_address[first:first + 3], dtype=int)


def foot_contact_forces(model: mujoco.MjModel, data: mujoco.MjData,
                        body_legs: dict[int, int], leg_count: int) -> np.ndarray:
    """Total contact force on each foot [N], world frame, shape ``(leg_count, 3)``.

    Parameters
    ----------
    model, data
        The MuJoCo model and its data after a step or ``mj_forward`` (contacts present).
    body_legs
        Foot body id → leg index, :func:`tibia_body_legs`.
    leg_count
        Number of legs.

    Returns
    -------
    ndarray
        Per leg, the sum over its contacts of the force exerted on the foot [N]. MuJoCo's
        contact frame has its normal (first row) from ``geom1`` to ``geom2`` and
        :func:`mujoco.mj_contactForce` gives the force on ``geom2``; a foot that is
        ``geom1`` receives the opposite force. A foot without contact gets 0.
    """
    forces = np.zeros((leg_count, 3))
    wrench = np.zeros(6)
    for index in range(data.ncon):
        contact = data.contact[index]
        for geom, sign in ((contact.geom1, -1.0), (contact.geom2, 1.0)):
            leg = body_legs.get(int(model.geom_bodyid[geom]))
            if leg is None:
                continue
            mujoco.mj_contactForce(model, data, index, wrench)
            frame = contact.frame.reshape(3, 3)  # rows: normal, tangent 1, tangent 2
            forces[leg] += sign * (frame.T @ wrench[:3])
    return forces


def foot_jacobian_world(model: mujoco.MjModel, data: mujoco.MjData, foot_site: int,
                        dofs: np.ndarray) -> np.ndarray:
    """Foot position Jacobian [m/rad], world frame, w.r.t. the leg's three dofs, (3, 3).

    Column i is d(foot site position)/d(q_i) from :func:`mujoco.mj_jacSite`, evaluated at the
    kinematics stored in ``data`` (the same instant as its contacts and actuator forces).
    """
    translational = np.zeros((3, model.nv))
    mujoco.mj_jacSite(model, data, translational, None, int(foot_site))
    return translational[:, np.asarray(dofs, dtype=int)]


def foot_force_from_joint_torques(jacobian: np.ndarray, joint_torques: np.ndarray,
                                  singular_threshold: float = SINGULAR_THRESHOLD,
                                  max_damping: float = MAX_DAMPING) -> np.ndarray:
    """Foot force F [N] whose joint torques ``J^T F`` equal ``joint_torques`` [N·m].

    Damped least squares with variable damping: with ``J = U Σ V^T``,

        F = U diag(σ_i / (σ_i² + λ²)) V^T τ,
        λ² = 0                                 if σ_min ≥ singular_threshold,
        λ² = max_damping² (1 − (σ_min / singular_threshold)²)   otherwise,

    so F is exactly ``J^{-T} τ`` away from singular poses and bounded by
    ``|τ| / (2 λ)`` at them. The defaults (30 mm, 10 mm) leave the robot's standing legs
    (σ_min ≈ 0.12 m) undamped.

    Parameters
    ----------
    jacobian
        Foot position Jacobian (3, 3) [m/rad].
    joint_torques
        Torques τ (3,) [N·m] of the joints, in the Jacobian's column order.
    singular_threshold
        σ_min [m] below which damping starts.
    max_damping
        λ [m] at σ_min = 0.

    Returns
    -------
    ndarray (3,)
        F [N] in the Jacobian's row frame.
    """
    left, singular, right_transposed = np.linalg.svd(np.asarray(jacobian, dtype=float))
    smallest = float(singular[-1])
    damping_squared = 0.0
    if smallest < singular_threshold:
        damping_squared = max_damping**2 * (1.0 - (smallest / singular_threshold) ** 2)
    gains = singular / (singular**2 + damping_squared)
    return left @ (gains * (right_transposed @ np.asarray(joint_torques, dtype=float)))


def actuator_resistance(jacobian: np.ndarray, joint_torques: np.ndarray) -> np.ndarray:
    """Force [N] that holding the foot against the actuator torques takes: ``-J^{-T} τ``.

    ``J^{-T} τ`` is the force the leg pushes with on whatever holds its foot; the holder
    (the operator) exerts its opposite on the foot. Gravity and inertia of the leg are not
    included (only the actuators' torques).
    """
    return -foot_force_from_joint_torques(jacobian, joint_torques)


@dataclass(frozen=True)
class FootFeedback:
    """Feedback forces of every foot, world frame [N].

    Attributes
    ----------
    legs
        Leg names, in the robot's order.
    contact
        (legs, 3) contact force on each foot [N].
    resistance
        (legs, 3) actuator resistance at each foot [N].
    """

    legs: tuple[str, ...]
    contact: np.ndarray
    resistance: np.ndarray

    @property
    def effort(self) -> np.ndarray:
        """(legs, 3) the part of the resistance not balanced by the ground [N]:
        ``resistance − contact`` (the leg pulling towards its target, or holding its
        own weight; ≈ 0 for a foot standing still)."""
        return self.resistance - self.contact

    @property
    def total(self) -> np.ndarray:
        """(legs, 3) force rendered to the operator [N]: contact + effort.

        That is the resistance itself: a standing foot renders the ground reaction
        (not twice: the actuators' push on the ground and the ground's push back are
        one force pair), a foot in the air the actuators' effort towards the target.
        """
        return self.contact + self.effort

    def of(self, leg: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(contact, resistance, total)`` of ``leg``, each (3,) [N]."""
        index = self.legs.index(leg)
        return self.contact[index], self.resistance[index], self.total[index]


def foot_feedback(simulation: RobotSimulation) -> FootFeedback:
    """Contact force and actuator resistance of every foot, from the simulation's state.

    Reads ``data`` as the last step left it (contacts, ``qfrc_actuator`` and kinematics of
    the same instant); nothing is recomputed, so the simulation is unchanged.
    """
    robot, model, data = simulation.robot, simulation.model, simulation.data
    contact = foot_contact_forces(model, data, tibia_body_legs(robot), len(robot.legs))
    resistance = np.zeros_like(contact)
    for index, leg in enumerate(robot.legs):
        dofs = leg_dof_addresses(robot, leg)
        jacobian = foot_jacobian_world(model, data, int(robot.foot_site_id[index]), dofs)
        resistance[index] = actuator_resistance(jacobian, data.qfrc_actuator[dofs])
    return FootFeedback(tuple(robot.legs), contact, resistance)


def device_force(foot_force: np.ndarray, scale: float = DEFAULT_DEVICE_SCALE,
                 max_force: float = DEFAULT_MAX_DEVICE_FORCE) -> np.ndarray:
    """Force [N] to render on a haptic device for a foot force [N].

    ``scale · foot_force``, shortened to the norm ``max_force`` when longer (direction
    kept); a non-finite input gives zero force (never command a device with NaN).

    Parameters
    ----------
    foot_force
        (3,) force at the foot [N], in the device's axes.
    scale
        Device newtons per foot newton [N/N].
    max_force
        Saturation of the device force norm [N].
    """
    force = scale * np.asarray(foot_force, dtype=float)
    if not np.all(np.isfinite(force)):
        return np.zeros(3)
    norm = float(np.linalg.norm(force))
    if norm > max_force:
        force *= max_force / norm
    return force
