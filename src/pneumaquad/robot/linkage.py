"""Cylinder linkage of a joint: piston position ↔ joint angle, force ↔ torque.

A cylinder acts between a barrel pivot on the parent link at distance ``l3`` from the
joint axis and a rod-end pin on the child link at distance ``l1``. With γ the included
angle between the two pivots at the axis, the pin-to-pin length follows from the law of
cosines and the piston extension is that length minus the retracted length ``l2``
(thesis eq 5.2.1, 5.2.3, 5.2.5)::

    x = -l2 + sqrt(l1² + l3² - 2·l1·l3·cos γ),     γ = γ0 + s·θ

where ``s`` = +1 for alpha and beta and -1 for gamma (eq 5.2.2, 5.2.4, 5.2.6). The torque
of a cylinder force F about the joint is F times the moment arm
``l1·l3·sin γ / (l2 + x)`` (eq 5.2.7-5.2.9), and τ·θ̇ = F·ẋ. In the MuJoCo model the same
relation comes from a two-site tendon between the pivots; these functions are the
closed form used for references, design and tests.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

__all__ = [
    "Linkage",
    "design_linkage",
    "joint_angle",
    "moment_arm",
    "pin_length",
    "piston_position",
    "piston_velocity",
]


@dataclass(frozen=True)
class Linkage:
    """Geometry of one cylinder linkage (SI units, angles in rad).

    Attributes
    ----------
    parent_pivot_radius : float
        l3, joint axis to barrel pivot [m].
    child_pivot_radius : float
        l1, joint axis to rod-end pin [m].
    included_angle_at_zero : float
        γ0, included angle at joint angle 0 [rad].
    retracted_length : float
        l2, pin-to-pin length at zero extension [m].
    direction : int
        +1 if γ grows with the joint angle, -1 if it shrinks.
    """

    parent_pivot_radius: float
    child_pivot_radius: float
    included_angle_at_zero: float
    retracted_length: float
    direction: int

    def included_angle(self, joint_angle: np.ndarray | float) -> np.ndarray | float:
        """γ = γ0 + s·θ [rad] (eq 5.2.2, 5.2.4, 5.2.6)."""
        return self.included_angle_at_zero + self.direction * joint_angle


def pin_length(linkage: Linkage, joint_angle: np.ndarray | float) -> np.ndarray | float:
    """Pin-to-pin length l2 + x [m] at joint angle θ [rad] (law of cosines)."""
    l1, l3 = linkage.child_pivot_radius, linkage.parent_pivot_radius
    gamma = linkage.included_angle(joint_angle)
    return np.sqrt(l1 * l1 + l3 * l3 - 2.0 * l1 * l3 * np.cos(gamma))


def piston_position(linkage: Linkage, joint_angle: np.ndarray | float) -> np.ndarray | float:
    """Piston extension x [m] at joint angle θ [rad] (eq 5.2.1, 5.2.3, 5.2.5)."""
    return pin_length(linkage, joint_angle) - linkage.retracted_length


def moment_arm(linkage: Linkage, joint_angle: np.ndarray | float) -> np.ndarray | float:
    """dx/dθ [m/rad]: torque per unit cylinder force (eq 5.2.7-5.2.9 with the sign of s).

    τ = F·dx/dθ; positive when extending the cylinder turns the joint positive.
    """
    l1, l3 = linkage.child_pivot_radius, linkage.parent_pivot_radius
    gamma = linkage.included_angle(joint_angle)
    return linkage.direction * l1 * l3 * np.sin(gamma) / pin_length(linkage, joint_angle)


def piston_velocity(
    linkage: Linkage, joint_angle: np.ndarray | float, joint_velocity: np.ndarray | float
) -> np.ndarray | float:
    """ẋ [m/s] from θ [rad] and θ̇ [rad/s] (eq 5.2.1, 5.2.3, 5.2.5, second lines)."""
    return moment_arm(linkage, joint_angle) * joint_velocity


def joint_angle(linkage: Linkage, position: np.ndarray | float) -> np.ndarray | float:
    """Inverse of :func:`piston_position`: θ [rad] from x [m] (γ taken in (0, π))."""
    l1, l3 = linkage.child_pivot_radius, linkage.parent_pivot_radius
    length = np.asarray(position) + linkage.retracted_length
    cosine = np.clip((l1 * l1 + l3 * l3 - length * length) / (2.0 * l1 * l3), -1.0, 1.0)
    angle = (np.arccos(cosine) - linkage.included_angle_at_zero) * linkage.direction
    return angle if np.ndim(angle) else float(angle)


def design_linkage(
    parent_pivot_radius: float,
    stroke: float,
    lower_limit: float,
    upper_limit: float,
    direction: int,
) -> Linkage:
    """Design a linkage whose stroke spans the joint range exactly.

    The included angle γ sweeps a window of the joint's span centred on 90° (largest
    smallest moment arm for a given span); the child pivot radius l1 is solved so that the
    pin length changes by ``stroke`` over the window; l2 is the pin length at the
    retracted end. The joint limits then coincide with the cylinder's end stops.

    Parameters
    ----------
    parent_pivot_radius : float
        l3 [m], chosen (where the barrel pivot sits on the parent link).
    stroke : float
        Cylinder stroke [m].
    lower_limit, upper_limit : float
        Joint range [rad]; the span must be below π.
    direction : int
        +1 or -1, see :class:`Linkage`.

    Returns
    -------
    Linkage

    Raises
    ------
    ValueError
        If no pivot radius below ``parent_pivot_radius`` gives that stroke over that span.
    """
    span = upper_limit - lower_limit
    if not 0.0 < span < math.pi:
        raise ValueError(f"joint span {math.degrees(span):.1f}° should be in (0°, 180°)")
    gamma_low = 0.5 * (math.pi - span)
    gamma_high = gamma_low + span
    l3 = parent_pivot_radius

    def stroke_error(l1: float) -> float:
        low = math.sqrt(l1 * l1 + l3 * l3 - 2.0 * l1 * l3 * math.cos(gamma_low))
        high = math.sqrt(l1 * l1 + l3 * l3 - 2.0 * l1 * l3 * math.cos(gamma_high))
        return high - low - stroke

    smallest, largest = 1e-6 * l3, l3
    if stroke_error(largest) < 0.0:
        raise ValueError(
            f"parent pivot radius {l3 * 1000:.1f} mm is too short for a "
            f"{stroke * 1000:.1f} mm stroke over {math.degrees(span):.1f}°; make it longer"
        )
    l1 = brentq(stroke_error, smallest, largest, xtol=1e-13)
    gamma_zero = gamma_low - lower_limit if direction > 0 else gamma_low + upper_limit
    retracted = math.sqrt(l1 * l1 + l3 * l3 - 2.0 * l1 * l3 * math.cos(gamma_low))
    return Linkage(l3, l1, gamma_zero, retracted, direction)
