"""The Stribeck-tanh law (thesis eq 4.2.6) in its cheap forms equals its plain form."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pneumaquad.core.physics.friction import (
    FRICTION_STRIBECK_TANH,
    friction_damping,
    saturating_tanh,
    stribeck_curve,
    stribeck_tanh_force,
    stribeck_tanh_force_and_slope,
)

#: thesis-rig's law in SI: Fs 4.5 lbf, Fc 3 lbf, Cv 0.5 lbf s/in, vS 0.1 in/s, i 5, k 40 s/in
LAW = (20.017, 13.345, 87.56, 0.00254, 5.0, 1574.8)
VELOCITIES = np.concatenate([np.linspace(-0.3, 0.3, 20001), np.geomspace(1e-9, 1.0, 2001)])


def plain_force(v: float, fs: float, fc: float, cv: float, vs: float, i: float,
                k: float) -> float:
    g = fc + (fs - fc) * math.exp(-((abs(v) / vs) ** i))
    return g * math.tanh(k * v) + cv * v


def test_saturating_tanh_is_tanh_bit_for_bit() -> None:
    for x in np.linspace(-60.0, 60.0, 240001):
        assert saturating_tanh(x) == math.tanh(x)


def test_stribeck_curve_skips_only_an_exact_zero() -> None:
    fs, fc, _, vs, i, _ = LAW
    for v in VELOCITIES:
        assert stribeck_curve(v, fs, fc, vs, i) == fc + (fs - fc) * math.exp(-((abs(v) / vs) ** i))


def test_stribeck_curve_of_a_piston_nearly_at_rest_is_the_plain_law_bit_for_bit() -> None:
    """Below the velocity where (|v|/vS)^i < 2^-55 the curve skips the power and the
    exponential; its value is still the plain law's, for any exponent, on both sides of
    that velocity and down to the smallest velocities."""
    fs, fc, _, vs, _, _ = LAW
    tiny = np.concatenate([np.geomspace(1e-300, 1e-3, 6001), [5e-324, 1e-320, 1e-310]])
    for exponent in (0.3, 0.5, 1.0, 2.0, 2.5, 5.0, 10.0):
        edge = vs * 2.0 ** (-55.0 / exponent)  # about where the shortcut ends
        for v in np.concatenate([tiny, edge * np.linspace(0.25, 4.0, 1501)]):
            plain = fc + (fs - fc) * math.exp(-((abs(v) / vs) ** exponent))
            assert stribeck_curve(v, fs, fc, vs, exponent) == plain, (exponent, v)
            assert stribeck_curve(-v, fs, fc, vs, exponent) == plain, (exponent, -v)


def test_force_equals_the_plain_law_and_the_combined_form() -> None:
    for v in VELOCITIES:
        plain = plain_force(v, *LAW)
        assert stribeck_tanh_force(v, *LAW) == plain
        force, _ = stribeck_tanh_force_and_slope(v, *LAW)
        assert force == plain


def test_slope_equals_the_sech_form_and_friction_damping_takes_it() -> None:
    """The slope written with (1 - t)(1 + t) equals g·k·sech²(k·v) + Cv (clipped at 0) to
    rounding; friction_damping gives the same number."""
    fs, fc, cv, vs, i, k = LAW
    for v in VELOCITIES:
        _, slope = stribeck_tanh_force_and_slope(v, *LAW)
        g = fc + (fs - fc) * math.exp(-((abs(v) / vs) ** i))
        sech = 1.0 / math.cosh(min(abs(k * v), 300.0))
        assert slope == pytest.approx(max(g * k * sech * sech + cv, 0.0), rel=1e-12, abs=1e-9)
        assert friction_damping(FRICTION_STRIBECK_TANH, v, fs, fc, cv, vs, i, k, 0.0, 0.0,
                                0.0, 0.0) == slope


def test_slope_is_the_derivative_where_the_law_rises() -> None:
    # where the Stribeck curve is flat (|v| >> vS) the slope is the law's derivative
    for v in (0.01, 0.02, -0.015):
        h = 1e-7
        derivative = (plain_force(v + h, *LAW) - plain_force(v - h, *LAW)) / (2 * h)
        assert stribeck_tanh_force_and_slope(v, *LAW)[1] == pytest.approx(derivative, rel=1e-6)
