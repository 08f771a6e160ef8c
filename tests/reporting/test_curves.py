"""Model curves are the physics of the configured parameters (thesis Fig. 15-16, 23, 24)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pneumaquad.core.actuator import chamber_ports
from pneumaquad.params import load_actuator, load_rig
from pneumaquad.reporting.curves import (
    area_curves,
    centered_voltage_range,
    friction_curve,
    friction_zoom_limit,
    group_equal,
    input_pressure_curves,
)

VELOCITY = np.concatenate([-np.geomspace(1.0, 1e-6, 200), np.geomspace(1e-6, 1.0, 200)])


@pytest.fixture(scope="module")
def rig():
    return load_rig("thesis-rig")


def _friction(rig, model: str, **changes):
    return rig.actuator.friction.model_copy(update={"model": model, **changes})


@pytest.mark.parametrize(
    "model", ["stribeck_tanh", "viscous", "coulomb", "coulomb_viscous", "lugre"]
)
def test_friction_curve_is_odd_and_opposes_motion(rig, model: str) -> None:
    friction = _friction(rig, model)
    force = friction_curve(friction, VELOCITY)
    np.testing.assert_allclose(force, -friction_curve(friction, -VELOCITY), rtol=1e-12)
    assert np.all(force[VELOCITY > 0] > 0)
    assert friction_curve(friction, [0.0])[0] == 0.0


def test_stribeck_tanh_follows_eq_4_2_6(rig) -> None:
    f = rig.actuator.friction
    v = VELOCITY
    g = f.coulomb_force + (f.static_force - f.coulomb_force) * np.exp(
        -((np.abs(v) / f.stribeck_velocity) ** f.stribeck_exponent)
    )
    expected = g * np.tanh(f.tanh_coefficient * v) + f.viscous_coefficient * v
    np.testing.assert_allclose(friction_curve(f, v), expected, rtol=1e-12, atol=1e-12)
    # the breakaway peak lies between Fc and Fs (4.5 lbf) and is within 10 % of Fs
    peak = friction_curve(f, np.linspace(0, f.stribeck_velocity, 2001)).max()
    assert f.coulomb_force < peak <= f.static_force + f.viscous_coefficient * f.stribeck_velocity
    assert peak == pytest.approx(f.static_force, rel=0.1)


def test_stribeck_tanh_equals_static_force_just_above_zero(rig) -> None:
    # with a sharp tanh, tanh(k v) = 1 while (v/vS)^i is still 0: F(0+) = Fs + Cv v
    f = _friction(rig, "stribeck_tanh", tanh_coefficient=1e8)
    v = 1e-6
    assert friction_curve(f, [v])[0] == pytest.approx(
        f.static_force + f.viscous_coefficient * v, rel=1e-9
    )
    fast = 50 * f.stribeck_velocity
    assert friction_curve(f, [fast])[0] == pytest.approx(
        f.coulomb_force + f.viscous_coefficient * fast, rel=1e-9
    )


def test_lugre_steady_state_is_stribeck_plus_viscous(rig) -> None:
    f = _friction(rig, "lugre")
    v = np.array([1e-3, 0.01, 0.1])
    g = f.coulomb_force + (f.static_force - f.coulomb_force) * np.exp(
        -((v / f.stribeck_velocity) ** f.stribeck_exponent)
    )
    np.testing.assert_allclose(friction_curve(f, v), g + f.viscous_coefficient * v, rtol=1e-9)


def test_zoom_window_shows_the_breakaway(rig) -> None:
    f = rig.actuator.friction
    window = friction_zoom_limit(f, 1.0)
    assert window >= 3 / f.tanh_coefficient
    assert window >= 4 * f.stribeck_velocity


def test_area_curves_are_the_port_polynomials(rig) -> None:
    valve = rig.actuator.valve
    cap, rod = chamber_ports(valve)
    samples = np.array([-5.0, -2.5, -1.0, -0.3, 0.0, 0.2, 0.9, 2.0, 4.5])
    curves = area_curves(valve, samples)
    assert [(c.chamber, c.side) for c in curves] == [
        ("cap", "negative"),
        ("cap", "positive"),
        ("rod", "negative"),
        ("rod", "positive"),
    ]
    assert curves[0].port == valve.cap_port and curves[2].port == 3 - valve.cap_port
    for curve, port, side in zip(
        curves, (cap, cap, rod, rod), ("negative", "positive") * 2, strict=True
    ):
        coefficients = port.area_negative if side == "negative" else port.area_positive
        expected = np.maximum(np.polyval(coefficients, curve.voltage), 0.0)
        np.testing.assert_allclose(curve.area, expected, rtol=1e-13)
        assert np.all(curve.voltage <= 0) if side == "negative" else np.all(curve.voltage > 0)
    # port 2 (cap) at the offset: the printed constant term 1.87e-8 m^2 (App. B.1.2 l.48)
    assert curves[0].area[curves[0].voltage == 0.0][0] == pytest.approx(1.87e-8)


def test_simple_valve_area_is_linear(rig) -> None:
    valve = rig.actuator.valve.model_copy(update={"model": "simple"})
    s = valve.simple
    u = np.array([-4.0, -1.0, 0.0, 1.0, 4.0])
    for curve in area_curves(valve, u):
        cd = s.cap_discharge_coefficient if curve.chamber == "cap" else s.rod_discharge_coefficient
        expected = cd * (s.max_area * np.abs(curve.voltage) / s.full_scale_voltage + s.leak_area)
        np.testing.assert_allclose(curve.area, expected)


def test_voltage_range_spans_the_valve_input(rig) -> None:
    valve = rig.actuator.valve
    u = centered_voltage_range(valve)
    assert u[0] == pytest.approx(valve.min_voltage - valve.offset_voltage)
    assert u[-1] == pytest.approx(valve.max_voltage - valve.offset_voltage)
    assert 0.0 in u and np.all(np.diff(u) > 0)


def test_input_pressure_monotonic_between_exhaust_and_supply(rig) -> None:
    actuator = rig.actuator
    ps, pe = actuator.supply.supply_pressure, actuator.supply.exhaust_pressure
    curves = input_pressure_curves(actuator)
    assert [c.chamber for c in curves] == ["cap", "rod"]
    for curve in curves:
        slope = np.diff(curve.pressure)
        direction = math.copysign(1.0, curve.high_cutoff - curve.low_cutoff)
        assert np.all(direction * slope >= 0.0)  # monotonic in the model's direction
        assert np.all((curve.pressure >= pe - 1e-6) & (curve.pressure <= ps + 1e-6))
        middle = 0.5 * (curve.high_cutoff + curve.low_cutoff)
        index = np.argmin(np.abs(curve.voltage - middle))
        assert curve.pressure[index] == pytest.approx(0.5 * (ps + pe), rel=0.02)
    # the cap fills (supply) for positive commands, the rod for negative ones
    assert curves[0].pressure[-1] == pytest.approx(ps, rel=1e-6)
    assert curves[1].pressure[-1] == pytest.approx(pe, rel=1e-6)


def test_simple_valve_input_pressure_switches_at_the_offset(rig) -> None:
    actuator = rig.actuator.model_copy(
        update={"valve": rig.actuator.valve.model_copy(update={"model": "simple"})}
    )
    ps, pe = actuator.supply.supply_pressure, actuator.supply.exhaust_pressure
    cap, rod = input_pressure_curves(actuator, [-1.0, 0.5])
    np.testing.assert_array_equal(cap.pressure, [pe, ps])
    np.testing.assert_array_equal(rod.pressure, [ps, pe])


def test_group_equal_merges_identical_sub_models() -> None:
    alpha, gamma = load_actuator("crr-alpha"), load_actuator("crr-gamma")
    groups = group_equal({"alpha": alpha.friction, "gamma": gamma.friction, "x": 1})
    assert groups[0][0] == "alpha, gamma" and groups[1] == ("x", 1)
