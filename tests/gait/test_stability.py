"""Support polygon and static stability margin: exact values on a square and a triangle,
the compiled hull against SciPy's and the margin against closed forms and brute force."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial import ConvexHull

from pneumaquad.gait.stability import (
    STANCE_FORCE,
    loaded_support,
    stability_margin,
    support_and_margin,
    support_margins,
    support_polygon,
)

SQUARE = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]])
TRIANGLE = np.array([[0.0, 0.0], [4.0, 0.0], [0.0, 3.0]])  # incircle radius 1 at (1, 1)


def _signed_area(polygon: np.ndarray) -> float:
    x, y = polygon[:, 0], polygon[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def test_hull_is_counter_clockwise_and_drops_interior_points():
    points = np.vstack([SQUARE[[2, 0, 3, 1]], [[1.0, 1.0], [1.0, 0.0]]])
    hull = support_polygon(points)
    assert len(hull) == 4
    assert _signed_area(hull) == pytest.approx(4.0)
    assert {tuple(p) for p in hull} == {tuple(p) for p in SQUARE}


@pytest.mark.parametrize(("point", "expected"), [
    ((1.0, 1.0), 1.0), ((0.5, 1.0), 0.5), ((1.0, 1.9), 0.1),  # inside
    ((2.0, 1.0), 0.0), ((0.0, 0.0), 0.0),  # on an edge, on a corner
    ((3.0, 1.0), -1.0), ((3.0, 3.0), -math.sqrt(2.0)), ((1.0, -0.25), -0.25),  # outside
])
def test_square_margins(point, expected):
    assert stability_margin(point, support_polygon(SQUARE)) == pytest.approx(expected, abs=1e-12)


@pytest.mark.parametrize(("point", "expected"), [
    ((1.0, 1.0), 1.0),  # incentre: the inradius
    ((0.5, 0.5), 0.5),
    ((2.0, 1.5), 0.0),  # on the hypotenuse 3x + 4y = 12
    ((4.0, 3.0), -12.0 / 5.0),  # distance to the hypotenuse
    ((5.0, -1.0), -math.sqrt(2.0)),  # nearest the corner (4, 0)
])
def test_triangle_margins(point, expected):
    polygon = support_polygon(TRIANGLE[::-1])
    assert stability_margin(point, polygon) == pytest.approx(expected, abs=1e-12)


def test_margins_are_vectorised_over_time():
    points = np.array([[1.0, 1.0], [3.0, 1.0], [1.0, -0.25]])
    assert np.allclose(stability_margin(points, SQUARE), [1.0, -1.0, -0.25])


def test_degenerate_supports_have_no_inside():
    segment = support_polygon([[0.0, 0.0], [2.0, 0.0]])
    assert len(segment) == 2
    assert stability_margin((1.0, 0.0), segment) == pytest.approx(0.0)
    assert stability_margin((1.0, 0.5), segment) == pytest.approx(-0.5)
    assert stability_margin((3.0, 0.0), segment) == pytest.approx(-1.0)
    collinear = support_polygon([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]])
    assert np.allclose(collinear, [[0.0, 0.0], [2.0, 2.0]])
    point = support_polygon([[1.0, 1.0]])
    assert stability_margin((4.0, 5.0), point) == pytest.approx(-5.0)
    with pytest.raises(ValueError, match="no support"):
        stability_margin((0.0, 0.0), support_polygon(np.empty((0, 2))))


# --- the compiled hull and margin against independent closed forms ----------------------

UNIT_SQUARE = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])


def test_unit_square_margin_from_its_centre_is_half_a_side():
    assert stability_margin((0.5, 0.5), support_polygon(UNIT_SQUARE)) == pytest.approx(0.5)
    feet = np.column_stack([UNIT_SQUARE, np.zeros(4)])[None]  # (1, 4, 3): z ignored
    assert support_margins(feet, np.ones((1, 4), bool), (0.5, 0.5)) == pytest.approx([0.5])


@pytest.mark.parametrize("distance", [1e-6, 0.1, 2.5])
def test_points_outside_the_square_have_minus_their_distance(distance):
    polygon = support_polygon(UNIT_SQUARE)
    beside_edge = (1.0 + distance, 0.3)
    off_corner = (1.0 + distance / math.sqrt(2.0), 1.0 + distance / math.sqrt(2.0))
    assert stability_margin(beside_edge, polygon) == pytest.approx(-distance, abs=1e-12)
    assert stability_margin(off_corner, polygon) == pytest.approx(-distance, abs=1e-12)


def test_triangle_margin_at_its_incentre_is_the_inradius():
    rng = np.random.default_rng(3)
    for _ in range(50):
        corners = rng.uniform(-1.0, 1.0, size=(3, 2))
        sides = np.linalg.norm(np.roll(corners, -1, axis=0) - np.roll(corners, -2, axis=0),
                               axis=1)  # side k opposite corner k
        (ax, ay), (bx, by), (cx, cy) = corners
        area = 0.5 * abs((bx - ax) * (cy - ay) - (by - ay) * (cx - ax))
        if area < 1e-3:
            continue
        incentre = sides @ corners / sides.sum()
        inradius = 2.0 * area / sides.sum()
        margin = stability_margin(incentre, support_polygon(corners))
        assert margin == pytest.approx(inradius, rel=1e-9)


def test_hull_has_scipys_vertices_in_counter_clockwise_order():
    rng = np.random.default_rng(4)
    for count in range(3, 9):
        for _ in range(40):
            points = rng.normal(size=(count, 2))
            hull = support_polygon(points)
            expected = points[ConvexHull(points).vertices]  # counter-clockwise in 2-D
            assert hull.shape == expected.shape
            start = int(np.flatnonzero(np.all(expected == hull[0], axis=1))[0])
            assert np.array_equal(np.roll(expected, -start, axis=0), hull)
            assert _signed_area(hull) > 0.0


def _edge_distance_by_sampling(point: np.ndarray, polygon: np.ndarray) -> float:
    """Least distance from ``point`` to 20001 points along each edge (brute force)."""
    fractions = np.linspace(0.0, 1.0, 20001)[:, None]
    ends = np.roll(polygon, -1, axis=0)
    samples = np.concatenate([start + fractions * (end - start)
                              for start, end in zip(polygon, ends, strict=True)])
    return float(np.min(np.linalg.norm(samples - point, axis=1)))


def test_random_margins_against_scipy_facets_and_sampled_edges():
    rng = np.random.default_rng(5)
    for _ in range(60):
        points = rng.normal(size=(rng.integers(3, 7), 2))
        polygon = support_polygon(points)
        facets = ConvexHull(points).equations  # unit normal · x + offset ≤ 0 inside
        com = rng.normal(size=2) * 1.5
        margin = float(stability_margin(com, polygon))
        signed = facets[:, :2] @ com + facets[:, 2]
        sampled = _edge_distance_by_sampling(com, polygon)
        if np.all(signed <= 0.0):  # inside: the distance to the nearest edge line
            assert margin == pytest.approx(-signed.max(), abs=1e-12)
        else:
            assert margin < 0.0
        assert abs(margin) == pytest.approx(sampled, abs=1e-3 * np.ptp(points))
        assert abs(margin) <= sampled + 1e-12


def test_repeated_and_collinear_feet_give_degenerate_supports():
    repeated = support_polygon([[1.0, 2.0], [1.0, 2.0], [1.0, 2.0]])
    assert np.array_equal(repeated, [[1.0, 2.0]])
    pair = support_polygon([[3.0, 0.0], [1.0, 1.0], [3.0, 0.0]])
    assert np.array_equal(pair, [[1.0, 1.0], [3.0, 0.0]])  # sorted by x
    collinear = support_polygon([[2.0, 1.0], [0.0, 0.0], [4.0, 2.0], [1.0, 0.5]])
    assert np.array_equal(collinear, [[0.0, 0.0], [4.0, 2.0]])
    assert stability_margin((2.0, 2.0), collinear) == pytest.approx(-2.0 / math.sqrt(5.0))
    square_with_repeats = support_polygon(np.vstack([UNIT_SQUARE, UNIT_SQUARE[::-1]]))
    assert len(square_with_repeats) == 4


def test_support_and_margin_without_support_or_centre_of_mass():
    feet = np.column_stack([UNIT_SQUARE, np.zeros(4)])
    polygon, margin = support_and_margin(feet, np.zeros(4, bool), (0.5, 0.5))
    assert polygon.shape == (0, 2) and math.isnan(margin)
    polygon, margin = support_and_margin(feet, np.ones(4, bool), (math.nan, 0.5))
    assert len(polygon) == 4 and math.isnan(margin)
    polygon, margin = loaded_support(feet, [10.0, 10.0, STANCE_FORCE, 10.0], (0.3, 0.3))
    assert len(polygon) == 3  # the third foot carries no more than the stance force
    assert margin == pytest.approx(0.4 / math.sqrt(2.0))  # to the diagonal (1, 0)–(0, 1)


def test_batched_margins_equal_the_single_sample_ones_row_by_row():
    rng = np.random.default_rng(6)
    samples = 500
    feet = rng.normal(size=(samples, 4, 3))
    stance = rng.random((samples, 4)) < 0.75
    stance[:5] = False  # no support
    com = rng.normal(size=(samples, 2)) * 0.5
    com[5:8, 0] = np.nan  # no centre of mass
    margins = support_margins(feet, stance, com)
    expected = [support_and_margin(feet[k], stance[k], com[k])[1] for k in range(samples)]
    assert np.array_equal(margins, expected, equal_nan=True)
    supported = stance.any(axis=1) & np.isfinite(com).all(axis=1)
    assert np.array_equal(np.isfinite(margins), supported)
