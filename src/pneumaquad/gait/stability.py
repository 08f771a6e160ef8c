"""Support polygon and static stability margin of a walking machine.

The static stability margin (McGhee & Frank 1968, "On the stability properties of
quadruped creeping gaits") is the shortest distance from the ground projection of the
centre of mass to the boundary of the support polygon, the convex hull of the feet in
stance. It is positive when the projection lies inside. Thesis 3.3: the shared-control
gait of the CRR never loses static stability, i.e. keeps this margin positive.

Conventions: SI units [m]; points in the ground plane as ``(..., 2)`` arrays; polygons
counter-clockwise.
"""

from __future__ import annotations

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "STANCE_FORCE",
    "centre_of_mass",
    "loaded_support",
    "stability_margin",
    "support_and_margin",
    "support_polygon",
]

#: A foot carrying more normal force than this [N] counts as in stance.
STANCE_FORCE = 1.0

Array = NDArray[np.float64]
_COLLINEAR_TOLERANCE = 1e-12  # [m²] cross products below this: collinear points


def _cross(origin: Array, first: Array, second: Array) -> float:
    return float((first[0] - origin[0]) * (second[1] - origin[1])
                 - (first[1] - origin[1]) * (second[0] - origin[0]))


def support_polygon(feet_xy: ArrayLike) -> Array:
    """Convex hull of the stance feet in the ground plane, counter-clockwise.

    Parameters
    ----------
    feet_xy : (n, 2) array [m]
        Ground-plane positions of the feet in stance.

    Returns
    -------
    (m, 2) array [m]
        Hull vertices, counter-clockwise, without repeats (Andrew's monotone chain).
        Degenerate supports give m < 3: one point, or the two ends of the segment when
        there are two feet or all feet are collinear; m = 0 for no feet.
    """
    points = np.asarray(feet_xy, dtype=float).reshape(-1, 2)
    points = np.unique(points, axis=0)  # sorted by x, then y
    if len(points) <= 2:
        return points
    lower: list[Array] = []
    for point in points:
        while len(lower) >= 2 and _cross(lower[-2], lower[-1], point) <= _COLLINEAR_TOLERANCE:
            lower.pop()
        lower.append(point)
    upper: list[Array] = []
    for point in points[::-1]:
        while len(upper) >= 2 and _cross(upper[-2], upper[-1], point) <= _COLLINEAR_TOLERANCE:
            upper.pop()
        upper.append(point)
    hull = np.array(lower[:-1] + upper[:-1])
    if len(hull) < 3:  # all collinear: the two extreme points
        return np.array([points[0], points[-1]])
    return hull


def _segment_distances(points: Array, starts: Array, ends: Array) -> Array:
    """Distances (..., k) from points (..., 2) to the k segments start→end [m]."""
    edges = ends - starts  # (k, 2)
    lengths = np.einsum("kj,kj->k", edges, edges)
    relative = points[..., None, :] - starts  # (..., k, 2)
    safe = np.where(lengths > 0.0, lengths, 1.0)
    along = np.clip(np.einsum("...kj,kj->...k", relative, edges) / safe, 0.0, 1.0)
    along = np.where(lengths > 0.0, along, 0.0)
    nearest = starts + along[..., None] * edges
    return np.linalg.norm(points[..., None, :] - nearest, axis=-1)


def stability_margin(com_xy: ArrayLike, polygon: ArrayLike) -> Array:
    """Signed distance [m] from the centre-of-mass projection to the support boundary.

    Parameters
    ----------
    com_xy : (..., 2) array [m]
        Ground projection(s) of the centre of mass, e.g. one per time sample.
    polygon : (m, 2) array [m]
        From :func:`support_polygon` (convex, counter-clockwise).

    Returns
    -------
    (...) array [m]
        Positive inside (the static stability margin), zero on the boundary, negative
        outside (minus the distance to the polygon). A degenerate support (a segment or
        a point, m ≤ 2) has no inside: the margin is minus the distance to it.

    Raises
    ------
    ValueError
        For an empty polygon.
    """
    points = np.asarray(com_xy, dtype=float)
    vertices = np.asarray(polygon, dtype=float).reshape(-1, 2)
    if len(vertices) == 0:
        raise ValueError("no support: the polygon has no vertices")
    if len(vertices) == 1:
        return -np.linalg.norm(points - vertices[0], axis=-1)
    if len(vertices) == 2:
        return -_segment_distances(points, vertices[:1], vertices[1:])[..., 0]
    starts, ends = vertices, np.roll(vertices, -1, axis=0)
    distances = _segment_distances(points, starts, ends).min(axis=-1)
    edges = ends - starts
    relative = points[..., None, :] - starts
    sides = edges[:, 0] * relative[..., 1] - edges[:, 1] * relative[..., 0]  # > 0: left
    inside = np.all(sides >= 0.0, axis=-1)
    return np.where(inside, distances, -distances)


def centre_of_mass(model: mujoco.MjModel, data: mujoco.MjData) -> Array:
    """Ground projection (x, y) [m] of the whole robot's centre of mass, world frame.

    The body masses weighted by their centres of mass ``data.xipos`` (equal to MuJoCo's
    ``data.subtree_com[0]``), so the kinematics must be current (``mujoco.mj_kinematics``
    or ``mj_forward``).
    """
    masses = np.asarray(model.body_mass, dtype=float)
    centre = masses @ np.asarray(data.xipos, dtype=float) / masses.sum()
    return centre[:2]


def support_and_margin(
    feet: ArrayLike, stance: ArrayLike, com_xy: ArrayLike
) -> tuple[Array, float]:
    """Support polygon of the feet in ``stance`` and the static margin of the centre of mass.

    Parameters
    ----------
    feet : (n, 2 or 3) array [m]
        Foot positions (world; the first two coordinates are the ground plane).
    stance : (n,) bool array
        The feet that support the robot.
    com_xy : (2,) array [m]
        Ground projection of the centre of mass.

    Returns
    -------
    (polygon (m, 2) [m], margin [m])
        :func:`support_polygon` of the stance feet (m = 0 without any) and
        :func:`stability_margin` of the centre of mass; NaN without support or with a
        non-finite centre of mass.
    """
    stance = np.asarray(stance, dtype=bool)
    if not np.any(stance):
        return np.zeros((0, 2)), float("nan")
    polygon = support_polygon(np.asarray(feet, dtype=float)[stance, :2])
    com = np.asarray(com_xy, dtype=float)
    if not np.all(np.isfinite(com)):
        return polygon, float("nan")
    return polygon, float(stability_margin(com, polygon))


def loaded_support(
    feet: ArrayLike, normal_forces: ArrayLike, com_xy: ArrayLike
) -> tuple[Array, float]:
    """:func:`support_and_margin` of the loaded feet: those whose normal contact force
    ``normal_forces`` (n,) [N] is above :data:`STANCE_FORCE`."""
    return support_and_margin(feet, np.asarray(normal_forces) > STANCE_FORCE, com_xy)
