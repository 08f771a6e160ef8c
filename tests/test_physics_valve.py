"""Proportional valve: saturation, area models and the underlapped input pressure (4.2.3)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from conftest import PSI, actuator_setup
from pneumaquad.core.actuator import pack_parameters
from pneumaquad.core.physics.valve import (
    centered_voltage,
    input_pressure,
    polynomial_area,
    simple_valve_area,
)
from pneumaquad.core.pneumatics import valve_connections

# App. B.1.1 l.24-27, 78-79
PS = (50.3 + 14.7) * PSI
PE = 15.7 * PSI
# App. B.1.2 Port_2 l.21-22
HPC, LPC = 1.25, -0.75
# App. B.1.2 Port_2 l.44 (Vc > 0) and l.48 (otherwise), highest power first
PORT2_POSITIVE = np.array([1.32e-8, -1.302e-7, 3.608e-7, -4.33e-8, 1.42e-8])
PORT2_NEGATIVE = np.array([9.4e-9, 9.35e-8, 2.326e-7, -2.225e-7, 1.87e-8])


def thesis_port2_pressure(vc: float, ps: float, pe: float) -> float:
    """App. B.1.2 Port_2 lines 26-36, transcribed (English units, then back to Pa)."""
    psi2pa = 6894.76
    ps_eng, pe_eng = ps / psi2pa, pe / psi2pa
    x_offset = (HPC + LPC) / 2
    y_offset = (ps_eng + pe_eng) / 2
    scaling = math.copysign(1.0, HPC - LPC) * (ps_eng - pe_eng) / 2
    m = 2 * math.pi / abs(LPC - HPC)
    return (y_offset + scaling * math.tanh(m * (vc - x_offset))) * psi2pa


def thesis_port2_area(vc: float) -> float:
    """App. B.1.2 Port_2 lines 42-50, transcribed."""
    f = PORT2_POSITIVE if vc > 0 else PORT2_NEGATIVE
    return f[0] * vc**4 + f[1] * vc**3 + f[2] * vc**2 + f[3] * vc + f[4]


# --- command saturation ---------------------------------------------------------------


@pytest.mark.parametrize(
    ("command", "expected"),
    [(-3.0, -5.25), (0.0, -5.25), (5.25, 0.0), (6.0, 0.75), (10.0, 4.75), (12.0, 4.75)],
)
def test_centered_voltage_saturates_at_0_and_10_volts(command: float, expected: float) -> None:
    assert centered_voltage(command, 5.25, 0.0, 10.0) == pytest.approx(expected, abs=1e-15)


# --- underlapped input pressure (eq 4.2.7-4.2.11) --------------------------------------


def test_input_pressure_matches_the_thesis_port2_code() -> None:
    for vc in (-5.25, -2.0, -0.75, -0.4, 0.0, 0.25, 0.3, 0.6, 1.25, 4.75):
        assert input_pressure(vc, PS, PE, HPC, LPC) == pytest.approx(
            thesis_port2_pressure(vc, PS, PE), rel=1e-12
        )


def test_input_pressure_limits_port2() -> None:
    span = PS - PE
    tail = 1 - math.tanh(math.pi)  # K·(C_HP - x_offset) = pi at the cutoff (eq 4.2.11)
    # supply at and above the high-pressure cutoff, exhaust at and below the low one
    for vc in (HPC, 2.0, 4.75):
        assert PS - tail * span / 2 - 1e-6 <= input_pressure(vc, PS, PE, HPC, LPC) <= PS
    for vc in (LPC, -2.0, -5.25):
        assert PE <= input_pressure(vc, PS, PE, HPC, LPC) <= PE + tail * span / 2 + 1e-6
    assert input_pressure(4.75, PS, PE, HPC, LPC) == pytest.approx(PS, rel=1e-12)
    assert input_pressure(-5.25, PS, PE, HPC, LPC) == pytest.approx(PE, rel=1e-12)
    # mean pressure at the centre (C_HP + C_LP)/2 = 0.25 V, the valve's offset (4.2.1)
    assert input_pressure(0.25, PS, PE, HPC, LPC) == pytest.approx((PS + PE) / 2, rel=1e-14)
    values = [input_pressure(v, PS, PE, HPC, LPC) for v in np.linspace(-2.0, 2.5, 451)]
    assert np.all(np.diff(values) > 0.0)  # monotone between the limits


def test_input_pressure_reversed_cutoffs_mirror_the_curve() -> None:
    """Port 1 of the shipped sets: C_HP < C_LP, supply for low voltages (eq 4.2.10 sign)."""
    hpc, lpc = -1.25, 0.75
    assert input_pressure(-5.25, PS, PE, hpc, lpc) == pytest.approx(PS, rel=1e-12)
    assert input_pressure(4.75, PS, PE, hpc, lpc) == pytest.approx(PE, rel=1e-12)
    assert input_pressure(-0.25, PS, PE, hpc, lpc) == pytest.approx((PS + PE) / 2, rel=1e-14)
    for vc in np.linspace(-3.0, 3.0, 13):
        mirrored = input_pressure(-vc, PS, PE, HPC, LPC)
        assert input_pressure(vc, PS, PE, hpc, lpc) == pytest.approx(mirrored, rel=1e-12)


# --- area models -----------------------------------------------------------------------


@pytest.mark.parametrize("vc", [-4.75, -2.0, -1.0, -0.5, 0.0, 0.3, 0.5, 1.0, 2.0, 4.75])
def test_polynomial_area_reproduces_thesis_port2(vc: float) -> None:
    area = polynomial_area(vc, PORT2_NEGATIVE, PORT2_POSITIVE)
    assert area == pytest.approx(thesis_port2_area(vc), rel=1e-12)


def test_polynomial_area_known_values() -> None:
    """Sums of the printed coefficients: A(±1 V) and the offset area A(0) = 1.87e-8 m^2."""
    assert polynomial_area(1.0, PORT2_NEGATIVE, PORT2_POSITIVE) == pytest.approx(2.147e-7)
    assert polynomial_area(-1.0, PORT2_NEGATIVE, PORT2_POSITIVE) == pytest.approx(3.897e-7)
    assert polynomial_area(0.0, PORT2_NEGATIVE, PORT2_POSITIVE) == pytest.approx(1.87e-8)


def test_polynomial_area_clipped_at_zero() -> None:
    falling = np.array([0.0, 0.0, 0.0, -1e-7, 1e-8])  # 1e-8 - 1e-7·u, negative for u > 0.1
    rising = np.array([0.0, 0.0, 0.0, 1e-7, 1e-8])
    assert polynomial_area(1.0, rising, falling) == 0.0
    assert polynomial_area(-1.0, rising, falling) == 0.0
    assert polynomial_area(0.05, rising, falling) == pytest.approx(5e-9)


@pytest.mark.parametrize("setup", ["gamma", "thesis"])
def test_shipped_port2_is_the_thesis_port2(setup: str, request: pytest.FixtureRequest) -> None:
    loaded = request.getfixturevalue(setup)
    valve = loaded.valve if setup == "gamma" else loaded.actuator.valve
    np.testing.assert_allclose(valve.port2.area_positive, PORT2_POSITIVE, rtol=1e-12)
    np.testing.assert_allclose(valve.port2.area_negative, PORT2_NEGATIVE, rtol=1e-12)
    assert (valve.port2.high_pressure_cutoff, valve.port2.low_pressure_cutoff) == (HPC, LPC)
    assert valve.offset_voltage == 5.25


def test_simple_area_is_linear_with_leak() -> None:
    max_area, leak = 1e-5, 2e-7  # App. B.2 l.12-13
    assert simple_valve_area(0.0, max_area, leak, 5.0) == leak
    assert simple_valve_area(5.0, max_area, leak, 5.0) == pytest.approx(max_area + leak)
    assert simple_valve_area(-2.5, max_area, leak, 5.0) == pytest.approx(max_area / 2 + leak)


# --- valve connections as the kernel uses them -----------------------------------------


@pytest.mark.parametrize("cap_port", [1, 2])
def test_underlapped_connections_follow_cap_port(cap_port: int) -> None:
    actuator = actuator_setup("crr-gamma", f"valve.cap_port={cap_port}")
    row = pack_parameters(actuator)
    ps, pe = actuator.supply.supply_pressure, actuator.supply.exhaust_pressure
    ports = {1: actuator.valve.port1, 2: actuator.valve.port2}
    cap, rod = ports[cap_port], ports[3 - cap_port]
    for vc in (-1.0, -0.4, 0.0, 0.3, 1.5):
        cap_p, cap_a, rod_p, rod_a = valve_connections(row, vc, ps)
        assert cap_p == pytest.approx(
            input_pressure(vc, ps, pe, cap.high_pressure_cutoff, cap.low_pressure_cutoff)
        )
        assert rod_p == pytest.approx(
            input_pressure(vc, ps, pe, rod.high_pressure_cutoff, rod.low_pressure_cutoff)
        )
        assert cap_a == pytest.approx(
            polynomial_area(vc, np.array(cap.area_negative), np.array(cap.area_positive))
        )
        assert rod_a == pytest.approx(
            polynomial_area(vc, np.array(rod.area_negative), np.array(rod.area_positive))
        )


def test_simple_connections_switch_supply_and_exhaust() -> None:
    actuator = actuator_setup("crr-gamma", 'valve.model="simple"')
    row = pack_parameters(actuator)
    ps, pe = row["supply_pressure"], row["exhaust_pressure"]
    cap_p, cap_a, rod_p, rod_a = valve_connections(row, 2.0, ps)
    area = 1e-5 * 2.0 / 5.0 + 2e-7
    assert (cap_p, rod_p) == (ps, pe)  # positive: extend (cap to supply), Fig. 18
    assert cap_a == pytest.approx(0.09 * area) and rod_a == pytest.approx(0.12 * area)
    cap_p, _, rod_p, _ = valve_connections(row, -2.0, ps)
    assert (cap_p, rod_p) == (pe, ps)
