"""Kinematics of one three-joint leg (alpha, beta, gamma): DH extraction, FK, Jacobian.

Three revolute joints in series (thesis section 3.1, Table 1); beta and gamma are parallel.
The zero pose is geometry (a point and unit axis per joint, the foot point, in one fixed
"shoulder" frame) taken from the model's link frames; the DH table is derived from it. Two
independent forward kinematics: product of exponentials over the joint screws, and the DH
chain. The inverse kinematics is in :mod:`.leg_ik`.

Conventions: SI and radians; a positive angle turns right-handed about the joint axis;
standard DH ``A_i = Rz(θ_i) Tz(d_i) Tx(a_i) Rx(α_i)`` with ``θ_i = q_i + theta_offset_i``.
FK and Jacobian accept batches of angles, shape ``(..., 3)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pneumaquad.core.jit import compiled

JOINT_NAMES = ("alpha", "beta", "gamma")
_UNIT_TOLERANCE = 1e-9  # allowed | |axis| - 1 |
_PARALLEL_TOLERANCE = 1e-12  # |w_a x w_b| below this: parallel axes
_LENGTH_TOLERANCE = 1e-12  # [m] common normals shorter than this: intersecting axes
_LIMIT_TOLERANCE = 1e-10  # [rad] slack when testing joint limits

Array = NDArray[np.float64]


def _checked(value: ArrayLike, shape: tuple[int, ...], name: str) -> Array:
    array = np.array(value, dtype=float)
    if array.shape != shape:
        raise ValueError(f"{name} must have shape {shape}, got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name} must be finite, got {array.tolist()}")
    array.flags.writeable = False
    return array


def _checked_limits(lower: ArrayLike, upper: ArrayLike) -> tuple[Array, Array]:
    lower_array = _checked(lower, (3,), "lower_limits")
    upper_array = _checked(upper, (3,), "upper_limits")
    for name, low, high in zip(JOINT_NAMES, lower_array, upper_array, strict=True):
        if not low < high:
            raise ValueError(
                f"joint {name}: lower limit {np.degrees(low):.3f} deg must be below "
                f"upper limit {np.degrees(high):.3f} deg"
            )
    return lower_array, upper_array


@dataclass(frozen=True, eq=False)
class LegGeometry:
    """Zero-configuration geometry of a three-joint leg, in one fixed frame.

    Attributes
    ----------
    joint_points : (3, 3) array [m]
        A point on each joint axis (rows: alpha, beta, gamma).
    joint_axes : (3, 3) array [-]
        Unit direction of each joint axis; a positive angle turns right-handed about it.
    foot_point : (3,) array [m]
        The foot (contact point) at zero joint angles.
    lower_limits, upper_limits : (3,) arrays [rad]
        Joint range.
    """

    joint_points: Array
    joint_axes: Array
    foot_point: Array
    lower_limits: Array
    upper_limits: Array

    def __post_init__(self) -> None:
        set_field = object.__setattr__
        set_field(self, "joint_points", _checked(self.joint_points, (3, 3), "joint_points"))
        axes = _checked(self.joint_axes, (3, 3), "joint_axes")
        norms = np.linalg.norm(axes, axis=1)
        if np.any(np.abs(norms - 1.0) > _UNIT_TOLERANCE):
            raise ValueError(f"joint_axes must be unit vectors, got norms {norms.tolist()}")
        set_field(self, "joint_axes", axes)
        set_field(self, "foot_point", _checked(self.foot_point, (3,), "foot_point"))
        lower, upper = _checked_limits(self.lower_limits, self.upper_limits)
        set_field(self, "lower_limits", lower)
        set_field(self, "upper_limits", upper)


def _rotate(vectors: Array, axis: Array, angles: Array) -> Array:
    """Rodrigues rotation of ``vectors (..., 3)`` by ``angles (...)`` about a unit ``axis``."""
    cosine = np.cos(angles)[..., None]
    sine = np.sin(angles)[..., None]
    along = np.sum(vectors * axis, axis=-1, keepdims=True) * axis
    return vectors * cosine + np.cross(axis, vectors) * sine + along * (1.0 - cosine)


def forward_kinematics_screw(geometry: LegGeometry, angles: ArrayLike) -> Array:
    """Foot position by the product of exponentials of the joint screws (Rodrigues).

    Parameters
    ----------
    geometry : LegGeometry
    angles : array_like, shape (..., 3)
        Joint angles alpha, beta, gamma [rad].

    Returns
    -------
    ndarray, shape (..., 3)
        Foot position in the geometry frame [m].
    """
    angles = np.asarray(angles, dtype=float)
    position = np.broadcast_to(geometry.foot_point, angles.shape).copy()
    for joint in (2, 1, 0):  # distal joint first: exp(S1 q1) exp(S2 q2) exp(S3 q3) foot
        point = geometry.joint_points[joint]
        position = point + _rotate(position - point, geometry.joint_axes[joint], angles[..., joint])
    return position


@dataclass(frozen=True, eq=False)
class DHTable:
    """Standard Denavit-Hartenberg description of the leg (thesis Table 1).

    Attributes
    ----------
    theta_offset : (3,) [rad]  DH θ_i at zero joint angle (θ_i = q_i + theta_offset_i).
    d : (3,) [m]  offset along z_(i-1).
    alpha : (3,) [rad]  twist about x_i.
    a : (3,) [m]  length along x_i.
    base : (4, 4)  pose of DH frame 0 in the geometry frame (maps frame-0 coordinates there).
    tool : (4, 4)  pose of the foot frame in DH frame 3 (here a pure translation).
    lower_limits, upper_limits : (3,) [rad]  joint range in joint angles q.
    """

    theta_offset: Array
    d: Array
    alpha: Array
    a: Array
    base: Array = field(default_factory=lambda: np.eye(4))
    tool: Array = field(default_factory=lambda: np.eye(4))
    lower_limits: Array = field(default_factory=lambda: np.full(3, -np.pi))
    upper_limits: Array = field(default_factory=lambda: np.full(3, np.pi))

    def __post_init__(self) -> None:
        set_field = object.__setattr__
        for name in ("theta_offset", "d", "alpha", "a"):
            set_field(self, name, _checked(getattr(self, name), (3,), name))
        for name in ("base", "tool"):
            set_field(self, name, _checked(getattr(self, name), (4, 4), name))
        lower, upper = _checked_limits(self.lower_limits, self.upper_limits)
        set_field(self, "lower_limits", lower)
        set_field(self, "upper_limits", upper)

    def dh_rows_degrees(self) -> tuple[tuple[float, float, float, float], ...]:
        """Rows ``(θ offset [deg], d [m], α [deg], a [m])`` for joints 1..3, as in Table 1."""
        return tuple(
            (float(np.degrees(theta)), float(d), float(np.degrees(alpha)), float(a))
            for theta, d, alpha, a in zip(self.theta_offset, self.d, self.alpha, self.a,
                                          strict=True)
        )


def format_dh_table(table: DHTable) -> str:
    """Text rendering of a :class:`DHTable` in the layout of thesis Table 1."""
    lines = [f"{'joint':<6}{'theta [deg]':>13}{'d [m]':>10}{'alpha [deg]':>13}{'a [m]':>10}"]
    for number, (theta, d, alpha, a) in enumerate(table.dh_rows_degrees(), start=1):
        lines.append(f"{number:<6}{f'q{number}{theta:+.2f}':>13}{d:>10.4f}{alpha:>13.2f}{a:>10.4f}")
    return "\n".join(lines)


def _any_perpendicular(axis: Array) -> Array:
    helper = np.eye(3)[np.argmin(np.abs(axis))]
    perpendicular = helper - np.dot(helper, axis) * axis
    return perpendicular / np.linalg.norm(perpendicular)


def _common_normal(
    origin: Array, axis: Array, point: Array, next_axis: Array, fallback_x: Array | None
) -> tuple[Array, Array, Array]:
    """Common normal from line (origin, axis) to line (point, next_axis).

    Returns the foot on the first line, the foot on the second line and the unit direction x.
    For parallel lines the normal through ``origin`` is chosen (so that d = 0).
    """
    normal = np.cross(axis, next_axis)
    normal_norm = np.linalg.norm(normal)
    offset = point - origin
    if normal_norm < _PARALLEL_TOLERANCE:
        foot_first = origin
        foot_second = point - np.dot(offset, next_axis) * next_axis
    else:
        foot_first = origin + np.dot(np.cross(offset, next_axis), normal) / normal_norm**2 * axis
        foot_second = point + np.dot(np.cross(offset, axis), normal) / normal_norm**2 * next_axis
    difference = foot_second - foot_first
    length = np.linalg.norm(difference)
    if length > _LENGTH_TOLERANCE:
        return foot_first, foot_second, difference / length
    if normal_norm >= _PARALLEL_TOLERANCE:  # intersecting axes
        return foot_first, foot_first, normal / normal_norm
    x = _any_perpendicular(axis) if fallback_x is None else fallback_x  # coincident axes
    return foot_first, foot_first, x


def _signed_angle(start: Array, end: Array, about: Array) -> float:
    return float(np.arctan2(np.dot(np.cross(start, end), about), np.dot(start, end)))


def dh_from_geometry(geometry: LegGeometry) -> DHTable:
    """Derive the standard DH table of a three-joint leg from its zero-pose geometry.

    Frame i-1 has z along joint axis i (same sign, so θ_i = q_i + offset). Its x axis runs
    along the common normal to the next axis; for parallel axes the normal through the
    previous origin is taken (d_i = 0, as in thesis Table 1) and for intersecting axes
    x = z_(i-1) × z_i. Frame 0 sits at ``joint_points[0]`` with x0 = x1 at zero angles, so
    theta_offset_1 = 0. Frame 3 keeps z3 = z2 (α3 = 0, d3 = 0) with x3 pointing at the
    foot; any foot offset along z3 goes into the ``tool`` translation.

    Parameters
    ----------
    geometry : LegGeometry

    Returns
    -------
    DHTable
        Any 3R chain has one; parallel, intersecting and coincident axes are handled.
    """
    axes, points = geometry.joint_axes, geometry.joint_points
    # The foot is treated as a fourth "axis" parallel to the last joint axis.
    line_points = [points[1], points[2], geometry.foot_point]
    line_axes = [axes[1], axes[2], axes[2]]
    origins, z_axes, x_axes, normal_starts = [points[0]], [axes[0]], [], []
    for index in range(3):
        fallback = x_axes[-1] if x_axes else None
        start, end, x = _common_normal(
            origins[-1], z_axes[-1], line_points[index], line_axes[index], fallback
        )
        normal_starts.append(start)
        origins.append(end)
        z_axes.append(line_axes[index])
        x_axes.append(x)
    x_axes.insert(0, x_axes[0])
    theta_offset, d, alpha, a = (np.zeros(3) for _ in range(4))
    for i in range(3):
        z_previous, z_next = z_axes[i], z_axes[i + 1]
        theta_offset[i] = _signed_angle(x_axes[i], x_axes[i + 1], z_previous)
        d[i] = np.dot(normal_starts[i] - origins[i], z_previous)
        a[i] = np.dot(origins[i + 1] - normal_starts[i], x_axes[i + 1])
        alpha[i] = _signed_angle(z_previous, z_next, x_axes[i + 1])
    base, tool = np.eye(4), np.eye(4)
    base[:3, :3] = np.column_stack([x_axes[0], np.cross(z_axes[0], x_axes[0]), z_axes[0]])
    base[:3, 3] = origins[0]
    tool[2, 3] = np.dot(geometry.foot_point - origins[3], z_axes[3])
    return DHTable(theta_offset, d, alpha, a, base, tool,
                   geometry.lower_limits, geometry.upper_limits)


def _dh_link_transforms(table: DHTable, angles: Array) -> Array:
    """``A_i`` for each joint, shape (..., 3, 4, 4)."""
    theta = angles + table.theta_offset
    cos_t, sin_t = np.cos(theta), np.sin(theta)
    cos_a, sin_a = np.broadcast_to(np.cos(table.alpha), theta.shape), np.sin(table.alpha)
    links = np.zeros((*theta.shape, 4, 4))
    links[..., 0, :] = np.stack([cos_t, -sin_t * cos_a, sin_t * sin_a, table.a * cos_t], -1)
    links[..., 1, :] = np.stack([sin_t, cos_t * cos_a, -cos_t * sin_a, table.a * sin_t], -1)
    links[..., 2, 1], links[..., 2, 2], links[..., 2, 3] = sin_a, cos_a, table.d
    links[..., 3, 3] = 1.0
    return links


def dh_frames(table: DHTable, angles: ArrayLike) -> Array:
    """Poses of DH frames 0..3 in the geometry frame (for drawing the leg).

    Parameters
    ----------
    table : DHTable
    angles : array_like, shape (..., 3)
        Joint angles alpha, beta, gamma [rad].

    Returns
    -------
    ndarray, shape (..., 4, 4, 4)
        Homogeneous transforms, frame index on axis -3 [m].
    """
    angles = np.asarray(angles, dtype=float)
    links = _dh_link_transforms(table, angles)
    frames = np.empty((*angles.shape[:-1], 4, 4, 4))
    frames[..., 0, :, :] = table.base
    for i in range(3):
        frames[..., i + 1, :, :] = frames[..., i, :, :] @ links[..., i, :, :]
    return frames


@compiled
def _single_leg_chain(theta_offset, d, alpha, a, base, tool, angles, jacobian):
    """Foot position (3,) [m] of one leg for one set of ``angles`` (3,) [rad] through the
    DH chain, and its Jacobian written into ``jacobian`` (3, 3) [m/rad] (compiled; the
    same formulas as :func:`dh_frames` and :func:`foot_jacobian` without their batching,
    which costs a hundred times more than the arithmetic for a single leg)."""
    frame = base.copy()
    product = np.empty((4, 4))
    link = np.zeros((4, 4))
    axes = np.empty((3, 3))
    points = np.empty((3, 3))
    for i in range(3):
        for r in range(3):
            axes[i, r] = frame[r, 2]
            points[i, r] = frame[r, 3]
        theta = angles[i] + theta_offset[i]
        cos_t, sin_t = math.cos(theta), math.sin(theta)
        cos_a, sin_a = math.cos(alpha[i]), math.sin(alpha[i])
        link[0, 0], link[0, 1], link[0, 2] = cos_t, -sin_t * cos_a, sin_t * sin_a
        link[1, 0], link[1, 1], link[1, 2] = sin_t, cos_t * cos_a, -cos_t * sin_a
        link[2, 1], link[2, 2] = sin_a, cos_a
        link[0, 3], link[1, 3], link[2, 3], link[3, 3] = a[i] * cos_t, a[i] * sin_t, d[i], 1.0
        for r in range(4):
            for c in range(4):
                total = 0.0
                for k in range(4):
                    total += frame[r, k] * link[k, c]
                product[r, c] = total
        frame[:, :] = product
    foot = np.empty(3)
    for r in range(3):
        foot[r] = (frame[r, 0] * tool[0, 3] + frame[r, 1] * tool[1, 3]
                   + frame[r, 2] * tool[2, 3] + frame[r, 3] * tool[3, 3])
    for i in range(3):
        rx = foot[0] - points[i, 0]
        ry = foot[1] - points[i, 1]
        rz = foot[2] - points[i, 2]
        jacobian[0, i] = axes[i, 1] * rz - axes[i, 2] * ry
        jacobian[1, i] = axes[i, 2] * rx - axes[i, 0] * rz
        jacobian[2, i] = axes[i, 0] * ry - axes[i, 1] * rx
    return foot


def _single(table: DHTable, angles: Array) -> tuple[Array, Array]:
    jacobian = np.empty((3, 3))
    foot = _single_leg_chain(table.theta_offset, table.d, table.alpha, table.a, table.base,
                             table.tool, np.ascontiguousarray(angles, dtype=float), jacobian)
    return foot, jacobian


def forward_kinematics_dh(table: DHTable, angles: ArrayLike) -> Array:
    """Foot position through the DH chain ``base · A1 A2 A3 · tool``.

    Parameters
    ----------
    table : DHTable
    angles : array_like, shape (..., 3)
        Joint angles alpha, beta, gamma [rad].

    Returns
    -------
    ndarray, shape (..., 3)
        Foot position in the geometry frame [m].
    """
    angles = np.asarray(angles, dtype=float)
    if angles.shape == (3,):
        return _single(table, angles)[0]
    last = dh_frames(table, angles)[..., 3, :, :]
    return (last @ table.tool[:, 3])[..., :3]


def foot_jacobian(model: DHTable | LegGeometry, angles: ArrayLike) -> Array:
    """Jacobian of the foot position with respect to the joint angles.

    Column i is ``w_i × (foot - p_i)`` for the current screw axis of joint i (direction w_i
    through p_i), taken from the DH frames (derived first when given a geometry).

    Parameters
    ----------
    model : DHTable or LegGeometry
    angles : array_like, shape (..., 3)
        Joint angles alpha, beta, gamma [rad].

    Returns
    -------
    ndarray, shape (..., 3, 3)
        d(foot)/d(angles) [m/rad]; rows foot x, y, z, columns alpha, beta, gamma.
    """
    table = model if isinstance(model, DHTable) else dh_from_geometry(model)
    angles = np.asarray(angles, dtype=float)
    if angles.shape == (3,):
        return _single(table, angles)[1]
    frames = dh_frames(table, angles)  # z axis of frame i-1 is the current axis of joint i
    axes, points = frames[..., :3, :3, 2], frames[..., :3, :3, 3]
    foot = (frames[..., 3, :, :] @ table.tool[:, 3])[..., None, :3]
    return np.swapaxes(np.cross(axes, foot - points), -1, -2)
