"""Inverse kinematics of one three-joint leg: analytic for the thesis's Table-1 structure
(alpha axis, then two parallel axes beta and gamma), limits, clamping, clear errors.

θ1 follows from the target's projection on the plane normal to the alpha axis (two
shoulder branches), θ2 and θ3 from the planar two-link problem (two elbow branches);
candidates inside the joint limits are kept. Without one, a bounded least-squares search
finds the reachable foot nearest the target (clamping). SI units and radians; frames and
tables of :mod:`.kinematics`.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import product

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import least_squares

from .kinematics import (
    _LENGTH_TOLERANCE,
    _LIMIT_TOLERANCE,
    JOINT_NAMES,
    DHTable,
    LegGeometry,
    _checked,
    dh_from_geometry,
    foot_jacobian,
    forward_kinematics_dh,
)

__all__ = ["IKResult", "UnreachableTargetError", "exact_solutions", "inverse_kinematics"]

Array = NDArray[np.float64]


class UnreachableTargetError(ValueError):
    """No joint angles inside the limits put the foot on the requested target."""


@dataclass(frozen=True, eq=False)
class IKResult:
    """Inverse-kinematics answer.

    Attributes
    ----------
    angles : (3,) [rad]  joint angles, inside the joint limits.
    reachable : bool  whether the target is reached exactly.
    foot : (3,) [m]  foot position for ``angles``.
    error : float [m]  distance from ``foot`` to the target.
    """

    angles: Array
    reachable: bool
    foot: Array
    error: float


def _into_limits(angles: Array, lower: Array, upper: Array) -> Array:
    """The 2π-equivalents of ``angles`` inside [lower, upper], else the ones closest to it."""
    wrapped = lower + np.mod(angles - lower, 2.0 * np.pi)  # in [lower, lower + 2π)
    below = wrapped - 2.0 * np.pi
    return np.where(lower - below < np.maximum(wrapped - upper, 0.0), below, wrapped)


def _analytic_candidates(table: DHTable, target: Array) -> list[Array]:
    """Exact solutions ignoring limits, order: shoulder branch ±, then elbow ±."""
    structure_ok = (
        abs(np.cos(table.alpha[0])) < 1e-9
        and all(abs(np.sin(t)) < 1e-9 and np.cos(t) > 0 for t in table.alpha[1:])
    )
    if not structure_ok:
        raise ValueError(
            "analytic inverse kinematics needs the thesis Table-1 structure "
            f"(alpha = ±90, 0, 0 deg); got {np.degrees(table.alpha).round(6).tolist()} deg"
        )
    sign = np.sign(np.sin(table.alpha[0]))
    local = np.linalg.solve(table.base, np.append(target, 1.0))[:3]
    tool = table.tool[:3, 3]
    forearm_x, forearm_y = table.a[2] + tool[0], tool[1]
    forearm = np.hypot(forearm_x, forearm_y)
    upper_arm = table.a[1]
    if upper_arm < _LENGTH_TOLERANCE or forearm < _LENGTH_TOLERANCE:
        raise ValueError("analytic inverse kinematics needs a2 > 0 and a nonzero forearm")
    height = table.d[1] + table.d[2] + tool[2]  # constant offset along the beta axis
    radial_squared = local[0] ** 2 + local[1] ** 2 - height**2
    if radial_squared < -1e-15:
        return []
    candidates = []
    for shoulder in (1.0, -1.0):
        radial = shoulder * np.sqrt(max(radial_squared, 0.0))
        theta1 = np.arctan2(local[1], local[0]) - np.arctan2(-sign * height, radial)
        planar_x, planar_y = radial - table.a[0], sign * (local[2] - table.d[0])
        cos_elbow = (planar_x**2 + planar_y**2 - upper_arm**2 - forearm**2) / (
            2.0 * upper_arm * forearm
        )
        if abs(cos_elbow) > 1.0 + 1e-12:
            continue
        for elbow in (1.0, -1.0):
            psi = elbow * np.arccos(np.clip(cos_elbow, -1.0, 1.0))
            theta2 = np.arctan2(planar_y, planar_x) - np.arctan2(
                forearm * np.sin(psi), upper_arm + forearm * np.cos(psi)
            )
            theta3 = psi - np.arctan2(forearm_y, forearm_x)
            angles = np.array([theta1, theta2, theta3]) - table.theta_offset
            candidates.append(_into_limits(angles, table.lower_limits, table.upper_limits))
    return candidates


def _within_limits(angles: Array, table: DHTable) -> bool:
    return bool(np.all(angles >= table.lower_limits - _LIMIT_TOLERANCE)
                and np.all(angles <= table.upper_limits + _LIMIT_TOLERANCE))


def _nearest_in_limits(
    table: DHTable, target: Array, starts: list[Array], grid_points: int = 7
) -> Array:
    """Joint angles in the limit box whose foot is closest to ``target`` (multi-start TRF)."""
    lower, upper = table.lower_limits, table.upper_limits
    grid = np.array(list(product(*np.linspace(lower, upper, grid_points).T)))
    distances = np.linalg.norm(forward_kinematics_dh(table, grid) - target, axis=-1)
    starts = [np.clip(start, lower, upper) for start in starts]
    starts += list(grid[np.argsort(distances)[:4]])
    best, best_cost = starts[-1], np.inf
    for start in starts:
        fit = least_squares(
            lambda q: forward_kinematics_dh(table, q) - target, start,
            jac=lambda q: foot_jacobian(table, q), bounds=(lower, upper), method="trf",
            xtol=1e-14, ftol=1e-14, gtol=1e-14, max_nfev=200,
        )
        if fit.cost < best_cost:
            best, best_cost = np.clip(fit.x, lower, upper), fit.cost
    return best


def _millimetres(point: Array) -> str:
    return "(" + ", ".join(f"{1000.0 * value:.1f}" for value in point) + ") mm"


def _blocking_limits(candidates: list[Array], table: DHTable) -> str:
    reasons = []
    for number, angles in enumerate(candidates, start=1):
        blocked = []
        for name, q, low, high in zip(JOINT_NAMES, angles, table.lower_limits,
                                      table.upper_limits, strict=True):
            if q < low - _LIMIT_TOLERANCE:
                blocked.append(f"{name} {np.degrees(q):.1f} deg < lower limit "
                               f"{np.degrees(low):.1f} deg")
            elif q > high + _LIMIT_TOLERANCE:
                blocked.append(f"{name} {np.degrees(q):.1f} deg > upper limit "
                               f"{np.degrees(high):.1f} deg")
        reasons.append(f"solution {number}: " + ", ".join(blocked))
    return "blocked by joint limits (" + "; ".join(reasons) + ")"


def exact_solutions(table: DHTable, foot_target: ArrayLike) -> list[Array]:
    """The analytic IK answers (3,) [rad] inside the joint limits (empty: unreachable);
    no search, so cheap enough for every control chunk."""
    target = _checked(foot_target, (3,), "foot_target")
    return [angles for angles in _analytic_candidates(table, target)
            if _within_limits(angles, table)]


def inverse_kinematics(
    model: LegGeometry | DHTable, foot_target: ArrayLike, *, clamp: bool = False,
    current_angles: ArrayLike | None = None,
) -> IKResult:
    """Joint angles that put the foot on a target (analytic, thesis Table-1 structure).

    θ1 follows from the target's projection on the plane normal to the alpha axis (two
    shoulder branches), θ2 and θ3 from the planar two-link problem (two elbow branches).
    Candidates inside the joint limits are kept; the one nearest ``current_angles`` wins,
    else the first in the order (shoulder +, elbow +), (+, −), (−, +), (−, −).

    Parameters
    ----------
    model : LegGeometry or DHTable
    foot_target : (3,) array [m], in the geometry frame.
    clamp : bool
        If no in-limit exact solution exists: False raises, True returns the in-limit
        angles whose foot is nearest the target (bounded least squares), ``reachable=False``.
    current_angles : (3,) array [rad], optional
        Present joint angles, used to pick the branch and to seed the clamped search.

    Returns
    -------
    IKResult

    Raises
    ------
    UnreachableTargetError
        With the target [mm], the distance to the nearest reachable point [mm] and the
        blocking joint limits (or "outside workspace"), when ``clamp`` is False.
    """
    table = model if isinstance(model, DHTable) else dh_from_geometry(model)
    target = _checked(foot_target, (3,), "foot_target")
    current = None if current_angles is None else _checked(current_angles, (3,),
                                                           "current_angles")
    candidates = _analytic_candidates(table, target)
    valid = [angles for angles in candidates if _within_limits(angles, table)]
    if valid:
        if current is not None:
            valid.sort(key=lambda angles: float(np.linalg.norm(angles - current)))
        angles, reachable = np.clip(valid[0], table.lower_limits, table.upper_limits), True
    else:
        starts = candidates + ([] if current is None else [current])
        angles, reachable = _nearest_in_limits(table, target, starts), False
    foot = forward_kinematics_dh(table, angles)
    error = float(np.linalg.norm(foot - target))
    if not reachable and not clamp:
        reason = _blocking_limits(candidates, table) if candidates else "outside workspace"
        raise UnreachableTargetError(
            f"foot target {_millimetres(target)} is unreachable: {reason}; nearest "
            f"reachable point {_millimetres(foot)} is {1000.0 * error:.1f} mm away"
        )
    angles.flags.writeable = False
    foot.flags.writeable = False
    return IKResult(angles=angles, reachable=reachable, foot=foot, error=error)
