"""Tests of the App. B.2 equivalent-area procedure and the tanh input-pressure model."""

from __future__ import annotations

from decimal import Decimal

import numpy as np
import pytest

from pneumaquad.core import valve_fit as vf

# App. B.1.2 Port_2 l.44 (x > 0) and l.48 (x <= 0), "reg. polyfit", as printed.
PORT2_POSITIVE_PRINTED = ["1.32e-8", "-1.302e-7", "3.608e-7", "-4.33e-8", "1.42e-8"]
PORT2_NEGATIVE_PRINTED = ["9.4e-9", "9.35e-8", "2.326e-7", "-2.225e-7", "1.87e-8"]

# Port 1 is not printed in the thesis; these are the procedure's results to 4 digits.
PORT1_POSITIVE = ["8.619e-9", "-9.566e-8", "2.899e-7", "7.747e-8", "4.378e-9"]
PORT1_NEGATIVE = ["6.531e-9", "6.397e-8", "1.490e-7", "-1.928e-7", "1.419e-8"]


def _half_last_digit(printed: str) -> float:
    """Half a unit of the last printed digit of a decimal literal."""
    exponent = Decimal(printed).as_tuple().exponent
    assert isinstance(exponent, int)
    return 0.5 * 10.0**exponent


def test_printed_data_shapes() -> None:
    assert vf.THESIS_VOLTAGES.shape == (19,)
    assert vf.THESIS_VOLTAGES[9] == 0.0
    assert np.all(np.diff(vf.THESIS_VOLTAGES) > 0)
    assert vf.PORT1_DISCHARGE_COEFFICIENTS.shape == (19,)
    assert vf.PORT2_DISCHARGE_COEFFICIENTS.shape == (19,)


def test_equivalent_areas_leak_only_at_offset() -> None:
    areas = vf.equivalent_areas(vf.PORT2_DISCHARGE_COEFFICIENTS, vf.THESIS_VOLTAGES)
    assert areas[9] == pytest.approx(0.09 * 2e-7)
    # x = 4.75 V: cd 0.075 times 1e-5 * 4.75 / 5
    assert areas[-1] == pytest.approx(0.075 * 1e-5 * 4.75 / 5.0)
    assert areas[0] == pytest.approx(0.115 * 1e-5 * 4.75 / 5.0)


@pytest.mark.parametrize(
    ("port", "side", "printed"),
    [
        (2, 0, PORT2_NEGATIVE_PRINTED),
        (2, 1, PORT2_POSITIVE_PRINTED),
        (1, 0, PORT1_NEGATIVE),
        (1, 1, PORT1_POSITIVE),
    ],
)
def test_procedure_reproduces_coefficients(port: int, side: int, printed: list[str]) -> None:
    fitted = vf.thesis_port_polynomials(port)[side]
    for value, text in zip(fitted, printed, strict=True):
        assert abs(value - float(text)) <= _half_last_digit(text), (value, text)


def test_invalid_port() -> None:
    with pytest.raises(ValueError):
        vf.thesis_port_polynomials(3)


def test_evaluate_equivalent_area_piecewise_and_clipped() -> None:
    negative, positive = vf.thesis_port_polynomials(2)
    x = np.array([-4.0, -0.5, 0.0, 0.5, 4.0])
    area = vf.evaluate_equivalent_area(negative, positive, x)
    expected = np.where(x > 0, np.polyval(positive, x), np.polyval(negative, x))
    np.testing.assert_allclose(area, expected)
    assert area.shape == x.shape
    # A polynomial dipping below zero is clipped.
    clipped = vf.evaluate_equivalent_area([1.0, -1.0], [1.0, -1.0], np.array([-2.0, 0.5]))
    np.testing.assert_array_equal(clipped, [0.0, 0.0])
    assert vf.evaluate_equivalent_area(negative, positive, 0.0).shape == ()


def test_fit_round_trip_exact_polynomials() -> None:
    x = np.linspace(-5, 5, 21)
    neg_true = np.array([1e-9, 2e-8, 3e-7, -1e-7, 2e-8])
    pos_true = np.array([-1e-9, 1e-8, 2e-7, 1e-7, 2e-8])
    a = np.where(x > 0, np.polyval(pos_true, x), np.polyval(neg_true, x))
    neg, pos = vf.fit_equivalent_area_polynomials(x, a)
    np.testing.assert_allclose(neg, neg_true, rtol=1e-6, atol=1e-15)
    np.testing.assert_allclose(pos, pos_true, rtol=1e-6, atol=1e-15)


PS = 50.0 * 6894.757 + 101325.0
PE = 101325.0


def test_input_pressure_limits() -> None:
    high, low = vf.PORT2_HIGH_CUTOFF, vf.PORT2_LOW_CUTOFF
    assert vf.input_pressure(20.0, PS, PE, high, low) == pytest.approx(PS)
    assert vf.input_pressure(-20.0, PS, PE, high, low) == pytest.approx(PE)
    assert vf.input_pressure((high + low) / 2, PS, PE, high, low) == pytest.approx((PS + PE) / 2)
    # Reversed cutoffs flip the curve.
    assert vf.input_pressure(20.0, PS, PE, low, high) == pytest.approx(PE)
    assert vf.input_pressure(-20.0, PS, PE, low, high) == pytest.approx(PS)


def test_input_pressure_vectorised_and_monotone() -> None:
    u = np.linspace(-5, 5, 101)
    p = vf.input_pressure(u, PS, PE, 1.25, -0.75)
    assert p.shape == u.shape
    assert np.all(np.diff(p) > 0)
    assert np.all((p >= PE) & (p <= PS))


def test_input_pressure_rejects_equal_cutoffs() -> None:
    with pytest.raises(ValueError):
        vf.input_pressure(0.0, PS, PE, 1.0, 1.0)


@pytest.mark.parametrize(("high", "low"), [(1.25, -0.75), (-0.5, 1.0)])
def test_fit_input_pressure_curve_recovers_cutoffs(high: float, low: float) -> None:
    from pneumaquad.identification import fit_input_pressure_curve

    rng = np.random.default_rng(2011)
    u = np.linspace(-5, 5, 81)
    truth = vf.input_pressure(u, PS, PE, high, low)
    noisy = truth + rng.normal(0.0, 0.01 * (PS - PE), u.shape)
    fit = fit_input_pressure_curve(u, noisy, PS, PE)
    assert fit.value("high_pressure_cutoff") == pytest.approx(high, abs=0.05)
    assert fit.value("low_pressure_cutoff") == pytest.approx(low, abs=0.05)


def test_array_input_pressure_is_the_compiled_one() -> None:
    from pneumaquad.core.physics.valve import input_pressure

    u = np.linspace(-3, 3, 61)
    expected = [input_pressure(x, PS, PE, 1.25, -0.75) for x in u]
    np.testing.assert_array_equal(vf.input_pressure(u, PS, PE, 1.25, -0.75), expected)
