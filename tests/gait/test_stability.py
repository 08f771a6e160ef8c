"""Support polygon and static stability margin: exact values on a square and a triangle."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pneumaquad.gait.stability import stability_margin, support_polygon

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
