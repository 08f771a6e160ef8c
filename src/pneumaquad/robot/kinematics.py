"""Kinematics of one three-joint leg (alpha, beta, gamma): DH extraction, FK, Jacobian.

Three revolute joints in series (thesis section 3.1, Table 1); beta and gamma are parallel.
The zero pose is geometry (a point and unit axis per joint, the foot point, in one fixed
"shoulder" frame) taken from the model's link frames; the DH table is derived from it. The
forward kinematics and the Jacobian have one implementation, the compiled DH chain
(:func:`leg_frames_into`, :func:`leg_chain_into`), for one set of angles or a batch; the
tests check it against MuJoCo's own body and site positions. The inverse kinematics is in
:mod:`.leg_ik`. For compiled loops over legs (the walking feedback, once per control
chunk) the tables stack into :class:`LegTables`, scratch comes in a
:class:`ChainWorkspace`, and :func:`solve_3x3` takes the linear step through a Jacobian.

Conventions: SI and radians; a positive angle turns right-handed about the joint axis;
standard DH ``A_i = Rz(θ_i) Tz(d_i) Tx(a_i) Rx(α_i)`` with ``θ_i = q_i + theta_offset_i``.
FK and Jacobian accept batches of angles, shape ``(..., 3)``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import NamedTuple

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


@compiled
def leg_frames_into(theta_offset: Array, d: Array, alpha: Array, a: Array, base: Array,
                    angles: Array, frames: Array, link: Array) -> None:
    """Poses of DH frames 0..3 of one leg, ``base · A1 · A2 · A3``, written into ``frames``
    (4, 4, 4) for one set of ``angles`` (3,) [rad]; ``link`` (4, 4) is scratch (compiled:
    the package's one DH chain, with no allocation)."""
    frames[0, :, :] = base
    link[2, 0] = 0.0
    link[3, 0], link[3, 1], link[3, 2] = 0.0, 0.0, 0.0
    for i in range(3):
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
                    total += frames[i, r, k] * link[k, c]
                frames[i + 1, r, c] = total


@compiled
def leg_chain_into(theta_offset: Array, d: Array, alpha: Array, a: Array, base: Array,
                   tool: Array, angles: Array, frames: Array, link: Array, foot: Array,
                   jacobian: Array) -> None:
    """Foot position (3,) [m] and Jacobian (3, 3) [m/rad] of one leg for one set of
    ``angles`` (3,) [rad], written into ``foot`` and ``jacobian``; ``frames`` (4, 4, 4) and
    ``link`` (4, 4) are scratch (compiled, no allocation). Column i of the Jacobian is
    ``z_(i-1) × (foot - o_(i-1))`` from the DH frames."""
    leg_frames_into(theta_offset, d, alpha, a, base, angles, frames, link)
    for r in range(3):
        foot[r] = (frames[3, r, 0] * tool[0, 3] + frames[3, r, 1] * tool[1, 3]
                   + frames[3, r, 2] * tool[2, 3] + frames[3, r, 3] * tool[3, 3])
    for i in range(3):
        rx = foot[0] - frames[i, 0, 3]
        ry = foot[1] - frames[i, 1, 3]
        rz = foot[2] - frames[i, 2, 3]
        jacobian[0, i] = frames[i, 1, 2] * rz - frames[i, 2, 2] * ry
        jacobian[1, i] = frames[i, 2, 2] * rx - frames[i, 0, 2] * rz
        jacobian[2, i] = frames[i, 0, 2] * ry - frames[i, 1, 2] * rx


@compiled
def _leg_chain(theta_offset, d, alpha, a, base, tool, angles, foot, jacobian):
    """:func:`leg_chain_into` with its own scratch (compiled)."""
    leg_chain_into(theta_offset, d, alpha, a, base, tool, angles, np.empty((4, 4, 4)),
                   np.empty((4, 4)), foot, jacobian)


@compiled
def _leg_chain_batch(theta_offset, d, alpha, a, base, tool, angles, feet, jacobians):
    """:func:`leg_chain_into` for each row of ``angles`` (n, 3) [rad] (compiled loop)."""
    frames, link = np.empty((4, 4, 4)), np.empty((4, 4))
    for n in range(angles.shape[0]):
        leg_chain_into(theta_offset, d, alpha, a, base, tool, angles[n], frames, link,
                       feet[n], jacobians[n])


@compiled
def _leg_frames_batch(theta_offset, d, alpha, a, base, angles, frames):
    """:func:`leg_frames_into` for each row of ``angles`` (n, 3) [rad] (compiled loop)."""
    link = np.empty((4, 4))
    for n in range(angles.shape[0]):
        leg_frames_into(theta_offset, d, alpha, a, base, angles[n], frames[n], link)


class LegTables(NamedTuple):
    """The DH tables of several legs stacked for compiled loops (row ``leg`` of each
    array is that leg's :class:`DHTable` field)."""

    theta_offset: Array  # (legs, 3) [rad]
    d: Array  # (legs, 3) [m]
    alpha: Array  # (legs, 3) [rad]
    a: Array  # (legs, 3) [m]
    base: Array  # (legs, 4, 4)
    tool: Array  # (legs, 4, 4)


def stack_leg_tables(tables: Sequence[DHTable]) -> LegTables:
    """The legs' DH tables as one :class:`LegTables` (contiguous copies)."""
    return LegTables(*(np.ascontiguousarray([getattr(table, name) for table in tables],
                                            dtype=float)
                       for name in LegTables._fields))


class ChainWorkspace(NamedTuple):
    """Scratch of the compiled leg-chain loops, allocated once by its owner."""

    angles: Array  # (3,) [rad] one leg's joint angles
    frames: Array  # (4, 4, 4) DH frame poses
    link: Array  # (4, 4) one DH link transform
    foot: Array  # (3,) [m] foot position
    jacobian: Array  # (3, 3) [m/rad] foot Jacobian
    elimination: Array  # (3, 4) augmented matrix of a 3×3 solve
    step: Array  # (3,) [rad] solution of a 3×3 solve
    shift: Array  # (3,) [m] a foot shift


def chain_workspace() -> ChainWorkspace:
    """A fresh :class:`ChainWorkspace`."""
    return ChainWorkspace(np.zeros(3), np.zeros((4, 4, 4)), np.zeros((4, 4)), np.zeros(3),
                          np.zeros((3, 3)), np.zeros((3, 4)), np.zeros(3), np.zeros(3))


@compiled
def solve_3x3(matrix: Array, right_side: Array, elimination: Array, solution: Array) -> bool:
    """Solve ``matrix · solution = right_side`` for one 3×3 system (compiled, in place).

    Gaussian elimination with partial pivoting (LAPACK ``gesv``'s method, written out for
    three unknowns) on the augmented scratch ``elimination`` (3, 4); units are the
    caller's. Returns False, leaving ``solution`` undefined, when a pivot is exactly zero
    (a singular matrix, where :func:`numpy.linalg.solve` raises).
    """
    for row in range(3):
        for column in range(3):
            elimination[row, column] = matrix[row, column]
        elimination[row, 3] = right_side[row]
    for column in range(3):
        pivot = column
        for row in range(column + 1, 3):
            if abs(elimination[row, column]) > abs(elimination[pivot, column]):
                pivot = row
        if elimination[pivot, column] == 0.0:
            return False
        if pivot != column:
            for k in range(column, 4):
                swap = elimination[column, k]
                elimination[column, k] = elimination[pivot, k]
                elimination[pivot, k] = swap
        for row in range(column + 1, 3):
            factor = elimination[row, column] / elimination[column, column]
            for k in range(column + 1, 4):
                elimination[row, k] -= factor * elimination[column, k]
    for row in range(2, -1, -1):
        total = elimination[row, 3]
        for k in range(row + 1, 3):
            total -= elimination[row, k] * solution[k]
        solution[row] = total / elimination[row, row]
    return True


def _rows(angles: ArrayLike) -> tuple[Array, tuple[int, ...]]:
    """Angles as contiguous rows (n, 3) [rad] and the batch shape to restore."""
    array = np.asarray(angles, dtype=float)
    if array.shape[-1:] != (3,):
        raise ValueError(f"angles must have shape (..., 3), got {array.shape}")
    return np.ascontiguousarray(array.reshape(-1, 3)), array.shape[:-1]


def _chain(table: DHTable, angles: ArrayLike) -> tuple[Array, Array]:
    """Foot positions (..., 3) [m] and Jacobians (..., 3, 3) [m/rad] for ``angles``."""
    rows, shape = _rows(angles)
    feet = np.empty((len(rows), 3))
    jacobians = np.empty((len(rows), 3, 3))
    if len(rows) == 1:  # one leg at a time is the common case: no batch loop
        _leg_chain(table.theta_offset, table.d, table.alpha, table.a, table.base, table.tool,
                   rows[0], feet[0], jacobians[0])
    else:
        _leg_chain_batch(table.theta_offset, table.d, table.alpha, table.a, table.base,
                         table.tool, rows, feet, jacobians)
    return feet.reshape(*shape, 3), jacobians.reshape(*shape, 3, 3)


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
    rows, shape = _rows(angles)
    frames = np.empty((len(rows), 4, 4, 4))
    _leg_frames_batch(table.theta_offset, table.d, table.alpha, table.a, table.base, rows,
                      frames)
    return frames.reshape(*shape, 4, 4, 4)


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
    return _chain(table, angles)[0]


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
    return _chain(table, angles)[1]
