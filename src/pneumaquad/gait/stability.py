"""Support polygon and static stability margin of a walking machine.

The static stability margin (McGhee & Frank 1968, "On the stability properties of
quadruped creeping gaits") is the shortest distance from the ground projection of the
centre of mass to the boundary of the support polygon, the convex hull of the feet in
stance. It is positive when the projection lies inside. Thesis 3.3: the shared-control
gait of the CRR never loses static stability, i.e. keeps this margin positive.

Conventions: SI units [m]; points in the ground plane as ``(..., 2)`` arrays; polygons
counter-clockwise.

The hull and the margin are compiled (:func:`pneumaquad.core.jit.compiled`): a gait plan
or a recording asks for them at tens of thousands of instants, each with a handful of
feet. :func:`support_margins` takes all the instants in one call.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from pneumaquad.core.jit import compiled

__all__ = [
    "STANCE_FORCE",
    "centre_of_mass",
    "loaded_support",
    "stability_margin",
    "support_and_margin",
    "support_margins",
    "support_polygon",
]

#: A foot carrying more normal force than this [N] counts as in stance.
STANCE_FORCE = 1.0

Array = NDArray[np.float64]
_COLLINEAR_TOLERANCE = 1e-12  # [m²] cross products below this: collinear points


# --- compiled geometry -----------------------------------------------------------------


@compiled
def _coordinate_before(first: float, second: float) -> bool:
    """``first`` sorts before ``second``: ascending, NaN last (NumPy's sort order)."""
    return first < second or (second != second and first == first)


@compiled
def _point_before(first_x: float, first_y: float, second_x: float, second_y: float) -> bool:
    """Lexicographic order of points, x then y, NaN last (that of ``np.unique(axis=0)``)."""
    if _coordinate_before(first_x, second_x):
        return True
    if _coordinate_before(second_x, first_x):
        return False
    return _coordinate_before(first_y, second_y)


@compiled
def _turn(origin_x: float, origin_y: float, first_x: float, first_y: float,
          second_x: float, second_y: float) -> float:
    """Cross product [m²] of origin→first and origin→second: > 0 for a left turn."""
    return ((first_x - origin_x) * (second_y - origin_y)
            - (first_y - origin_y) * (second_x - origin_x))


@compiled
def _sorted_unique(points, count: int) -> int:
    """Sort the first ``count`` rows of ``points`` (k, 2) in place (x, then y, NaN last),
    drop exact repeats, and return how many distinct rows lead the array."""
    for index in range(1, count):
        x, y = points[index, 0], points[index, 1]
        slot = index
        while slot > 0 and _point_before(x, y, points[slot - 1, 0], points[slot - 1, 1]):
            points[slot, 0] = points[slot - 1, 0]
            points[slot, 1] = points[slot - 1, 1]
            slot -= 1
        points[slot, 0] = x
        points[slot, 1] = y
    distinct = 0
    for index in range(count):
        if (distinct > 0 and points[index, 0] == points[distinct - 1, 0]
                and points[index, 1] == points[distinct - 1, 1]):
            continue
        points[distinct, 0] = points[index, 0]
        points[distinct, 1] = points[index, 1]
        distinct += 1
    return distinct


@compiled
def _hull_into(points, count: int, hull) -> int:
    """Convex hull of the first ``count`` rows of ``points`` (k, 2) [m] into ``hull``
    (≥ 2k, 2), counter-clockwise from the lowest-x (then lowest-y) point; returns the
    number of vertices m. Andrew's monotone chain; sorts ``points`` in place.

    Turns of at most the collinear tolerance are dropped, so m < 3 only for degenerate
    supports: no point, one point, or the two extreme points of a segment.
    """
    distinct = _sorted_unique(points, count)
    if distinct <= 2:
        for index in range(distinct):
            hull[index, 0] = points[index, 0]
            hull[index, 1] = points[index, 1]
        return distinct
    size = 0
    for index in range(distinct):  # lower chain, left to right
        x, y = points[index, 0], points[index, 1]
        while size >= 2 and _turn(hull[size - 2, 0], hull[size - 2, 1], hull[size - 1, 0],
                                  hull[size - 1, 1], x, y) <= _COLLINEAR_TOLERANCE:
            size -= 1
        hull[size, 0] = x
        hull[size, 1] = y
        size += 1
    lower = size + 1  # the upper chain starts at the lower chain's last point
    for index in range(distinct - 2, -1, -1):  # upper chain, right to left
        x, y = points[index, 0], points[index, 1]
        while size >= lower and _turn(hull[size - 2, 0], hull[size - 2, 1],
                                      hull[size - 1, 0], hull[size - 1, 1],
                                      x, y) <= _COLLINEAR_TOLERANCE:
            size -= 1
        hull[size, 0] = x
        hull[size, 1] = y
        size += 1
    vertices = size - 1  # the last point is the first again
    if vertices < 3:  # all collinear: the two extreme points
        hull[0, 0], hull[0, 1] = points[0, 0], points[0, 1]
        hull[1, 0], hull[1, 1] = points[distinct - 1, 0], points[distinct - 1, 1]
        return 2
    return vertices


@compiled
def _segment_distance(point_x: float, point_y: float, start_x: float, start_y: float,
                      end_x: float, end_y: float) -> float:
    """Distance [m] from a point to the segment start→end (a point when start = end)."""
    edge_x, edge_y = end_x - start_x, end_y - start_y
    length = edge_x * edge_x + edge_y * edge_y
    relative_x, relative_y = point_x - start_x, point_y - start_y
    along = (relative_x * edge_x + relative_y * edge_y) / (length if length > 0.0 else 1.0)
    if along < 0.0:  # clipped into [0, 1]; NaN stays NaN
        along = 0.0
    elif along > 1.0:
        along = 1.0
    if not length > 0.0:
        along = 0.0
    offset_x = point_x - (start_x + along * edge_x)
    offset_y = point_y - (start_y + along * edge_y)
    return math.sqrt(offset_x * offset_x + offset_y * offset_y)


@compiled
def _margin_in_hull(point_x: float, point_y: float, hull, vertices: int) -> float:
    """Signed distance [m] from a point to the first ``vertices`` rows of ``hull``
    (counter-clockwise): positive inside, minus the distance outside or to a degenerate
    support (m ≤ 2); NaN for m = 0 or when any distance is NaN."""
    if vertices == 0:
        return math.nan
    if vertices == 1:
        offset_x, offset_y = point_x - hull[0, 0], point_y - hull[0, 1]
        return -math.sqrt(offset_x * offset_x + offset_y * offset_y)
    if vertices == 2:
        return -_segment_distance(point_x, point_y, hull[0, 0], hull[0, 1],
                                  hull[1, 0], hull[1, 1])
    nearest = math.inf
    inside = True
    for index in range(vertices):
        following = index + 1 if index + 1 < vertices else 0
        start_x, start_y = hull[index, 0], hull[index, 1]
        end_x, end_y = hull[following, 0], hull[following, 1]
        distance = _segment_distance(point_x, point_y, start_x, start_y, end_x, end_y)
        if distance != distance:
            return math.nan
        nearest = min(nearest, distance)
        side = _turn(start_x, start_y, end_x, end_y, point_x, point_y)  # > 0: left
        inside = inside and side >= 0.0
    return nearest if inside else -nearest


@compiled
def _hull(points):
    """Convex hull (m, 2) [m] of ``points`` (k, 2), a new array."""
    count = points.shape[0]
    work = points.copy()
    hull = np.empty((2 * count, 2))
    return hull[: _hull_into(work, count, hull)].copy()


@compiled
def _margins_in_polygon(points, polygon):
    """Signed margins (k,) [m] of ``points`` (k, 2) in ``polygon`` (m, 2)."""
    margins = np.empty(points.shape[0])
    for index in range(points.shape[0]):
        margins[index] = _margin_in_hull(points[index, 0], points[index, 1], polygon,
                                         polygon.shape[0])
    return margins


@compiled
def _support_and_margin(feet, stance, com_xy):
    """Hull (m, 2) of the ``stance`` rows of ``feet`` (n, ≥ 2) and the margin of ``com_xy``
    (2,) in it (NaN without support or with a non-finite centre of mass)."""
    count = feet.shape[0]
    points = np.empty((count, 2))
    hull = np.empty((2 * count, 2))
    standing = 0
    for index in range(count):
        if stance[index]:
            points[standing, 0] = feet[index, 0]
            points[standing, 1] = feet[index, 1]
            standing += 1
    if standing == 0:
        return hull[:0].copy(), math.nan
    vertices = _hull_into(points, standing, hull)
    margin = math.nan
    if math.isfinite(com_xy[0]) and math.isfinite(com_xy[1]):
        margin = _margin_in_hull(com_xy[0], com_xy[1], hull, vertices)
    return hull[:vertices].copy(), margin


@compiled
def _support_margins(feet, stance, com_xy):
    """Margins (T,) [m] of ``com_xy`` (T, 2) in the hulls of the ``stance`` (T, n) rows of
    ``feet`` (T, n, ≥ 2), sample by sample; NaN without support or with a non-finite
    centre of mass."""
    samples, count = feet.shape[0], feet.shape[1]
    points = np.empty((count, 2))
    hull = np.empty((2 * count, 2))
    margins = np.empty(samples)
    for sample in range(samples):
        margins[sample] = math.nan
        com_x, com_y = com_xy[sample, 0], com_xy[sample, 1]
        if not (math.isfinite(com_x) and math.isfinite(com_y)):
            continue
        standing = 0
        for index in range(count):
            if stance[sample, index]:
                points[standing, 0] = feet[sample, index, 0]
                points[standing, 1] = feet[sample, index, 1]
                standing += 1
        if standing > 0:
            vertices = _hull_into(points, standing, hull)
            margins[sample] = _margin_in_hull(com_x, com_y, hull, vertices)
    return margins


# --- public functions ------------------------------------------------------------------


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
    points = np.ascontiguousarray(np.asarray(feet_xy, dtype=float).reshape(-1, 2))
    return _hull(points)


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
    vertices = np.ascontiguousarray(np.asarray(polygon, dtype=float).reshape(-1, 2))
    if len(vertices) == 0:
        raise ValueError("no support: the polygon has no vertices")
    flat = np.ascontiguousarray(points.reshape(-1, 2))
    return _margins_in_polygon(flat, vertices).reshape(points.shape[:-1])


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
    feet = np.ascontiguousarray(feet, dtype=float)
    stance = np.ascontiguousarray(stance, dtype=np.bool_)
    com = np.ascontiguousarray(com_xy, dtype=float)
    if feet.ndim != 2 or feet.shape[1] < 2 or stance.shape != feet.shape[:1]:
        raise ValueError(f"feet (n, 2 or 3) and stance (n,) expected, got {feet.shape} "
                         f"and {stance.shape}")
    if com.shape != (2,):
        raise ValueError(f"com_xy must have shape (2,), got {com.shape}")
    return _support_and_margin(feet, stance, com)


def loaded_support(
    feet: ArrayLike, normal_forces: ArrayLike, com_xy: ArrayLike
) -> tuple[Array, float]:
    """:func:`support_and_margin` of the loaded feet: those whose normal contact force
    ``normal_forces`` (n,) [N] is above :data:`STANCE_FORCE`."""
    return support_and_margin(feet, np.asarray(normal_forces) > STANCE_FORCE, com_xy)


def support_margins(feet: ArrayLike, stance: ArrayLike, com_xy: ArrayLike) -> Array:
    """Static margin [m] at many instants: :func:`support_and_margin`'s margin row by row.

    Parameters
    ----------
    feet : (T, n, 2 or 3) array [m]
        Foot positions at each instant (the first two coordinates are the ground plane).
    stance : (T, n) bool array
        The feet that support the robot at each instant.
    com_xy : (T, 2) or (2,) array [m]
        Ground projection of the centre of mass at each instant (or one for all).

    Returns
    -------
    (T,) array [m]
        Signed distance of the centre of mass to the stance feet's support polygon
        (positive inside); NaN at instants without support or with a non-finite centre
        of mass.
    """
    feet = np.ascontiguousarray(feet, dtype=float)
    if feet.ndim != 3 or feet.shape[2] < 2:
        raise ValueError(f"feet must have shape (T, n, 2 or 3), got {feet.shape}")
    samples = feet.shape[0]
    stance = np.ascontiguousarray(np.broadcast_to(np.asarray(stance, dtype=np.bool_),
                                                  feet.shape[:2]))
    com = np.ascontiguousarray(np.broadcast_to(np.asarray(com_xy, dtype=float),
                                               (samples, 2)))
    return _support_margins(feet, stance, com)
