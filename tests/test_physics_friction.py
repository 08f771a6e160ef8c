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
    stribeck_flat_velocity,
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


def test_below_the_flat_velocity_the_curve_is_fs_bit_for_bit() -> None:
    """Below stribeck_flat_velocity the Stribeck curve is exactly Fc + (Fs - Fc), for any
    exponent, down to the smallest velocities: the kernels' shortcut there
    (pneumatics.friction_and_slope_of) changes no value."""
    fs, fc, _, vs, _, _ = LAW
    tiny = np.concatenate([np.geomspace(1e-300, 1e-3, 6001), [5e-324, 1e-320, 1e-310]])
    for exponent in (0.3, 0.5, 1.0, 2.0, 2.5, 5.0, 10.0):
        flat = stribeck_flat_velocity(vs, exponent)
        for v in np.concatenate([tiny, flat * np.linspace(0.25, 1.0, 1501)]):
            if abs(v) >= flat:
                continue
            assert stribeck_curve(v, fs, fc, vs, exponent) == fc + (fs - fc), (exponent, v)
            assert stribeck_curve(-v, fs, fc, vs, exponent) == fc + (fs - fc), (exponent, v)


def test_the_kernels_friction_is_the_law_bit_for_bit_around_the_flat_velocity() -> None:
    """The kernels' Stribeck-tanh force and slope (which skip the curve's power and
    exponential below the packed flat velocity) equal the law's on both sides of it."""
    from pneumaquad.core.actuator import pack_parameters
    from pneumaquad.core.pneumatics import friction_and_slope_of
    from pneumaquad.params import load_actuator

    for exponent in (1.0, 5.0, 10.0):
        p = pack_parameters(load_actuator("thesis-rig", [f"friction.stribeck_exponent={exponent}"]))
        law = (p["static_force"], p["coulomb_force"], p["viscous_coefficient"],
               p["stribeck_velocity"], p["stribeck_exponent"], p["tanh_coefficient"])
        flat = p["stribeck_flat_velocity"]
        for v in np.concatenate([[0.0, 5e-324], flat * np.geomspace(1e-6, 1e3, 2001)]):
            for signed in (v, -v):
                assert friction_and_slope_of(p, signed, 0.0) == \
                    stribeck_tanh_force_and_slope(signed, *law), (exponent, signed)


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
