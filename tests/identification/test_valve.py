"""Valve identification: input-pressure cutoffs, equivalent areas and their polynomials.

Measured on the seeded data of conftest: cutoffs within 0.001 V of the truth from ten
spacer voltages; equivalent areas within 1 % at two steps (tolerance 10 %).
"""

from __future__ import annotations

import numpy as np
import pytest

from pneumaquad.identification import (
    IdentificationError,
    area_polynomial_updates,
    areas_table,
    equivalent_area_for_step,
    fit_area_polynomials,
    fit_input_pressure_curve,
    input_pressure_curves,
)
from pneumaquad.valve_fit import (
    PORT2_DISCHARGE_COEFFICIENTS,
    THESIS_VOLTAGES,
    equivalent_areas,
    evaluate_equivalent_area,
    input_pressure,
    thesis_port_polynomials,
)

from .conftest import (
    SPACER_VOLTAGES,
    TRUE_AREA_FACTORS,
    TRUE_CUTOFFS,
    rig,
    scaled_polynomial_overrides,
    spacer_recording,
    step_recording,
)

SUPPLY, EXHAUST = 448159.2, 108247.7  # thesis-rig [Pa]


def true_area(setup, port: int, centered: float) -> float:
    valve_port = getattr(setup.actuator.valve, f"port{port}")
    return float(
        evaluate_equivalent_area(valve_port.area_negative, valve_port.area_positive, centered)
    )


def test_fit_input_pressure_curve_on_noisy_points() -> None:
    rng = np.random.default_rng(5)
    voltages = np.linspace(-2.0, 2.0, 15)
    pressures = input_pressure(voltages, SUPPLY, EXHAUST, 1.25, -0.75)
    fit = fit_input_pressure_curve(
        voltages, pressures + rng.normal(0.0, 500.0, voltages.size), SUPPLY, EXHAUST
    )
    assert fit.value("high_pressure_cutoff") == pytest.approx(1.25, abs=0.02)
    assert fit.value("low_pressure_cutoff") == pytest.approx(-0.75, abs=0.02)
    assert fit.r_squared > 0.999 and fit.residual_unit == "Pa"
    # a falling curve (supply at negative voltage, like port 1) keeps its orientation
    falling = fit_input_pressure_curve(
        voltages, input_pressure(voltages, SUPPLY, EXHAUST, -1.25, 0.75), SUPPLY, EXHAUST
    )
    assert falling.value("high_pressure_cutoff") == pytest.approx(-1.25, abs=1e-4)
    assert falling.value("low_pressure_cutoff") == pytest.approx(0.75, abs=1e-4)


def test_input_pressure_curves_from_spacer_staircase(spacer_rig) -> None:
    recording = spacer_recording(spacer_rig, SPACER_VOLTAGES, hold=6.0, seed=21)
    curves = input_pressure_curves([recording], spacer_rig)
    assert curves.points.centered_voltage == pytest.approx(SPACER_VOLTAGES)
    assert np.max(np.abs(curves.points.cap_drift)) < 2e3  # settled to within 2 kPa
    print("\ninput-pressure cutoffs: port, key, recovered, true")
    for port, (high, low) in TRUE_CUTOFFS.items():
        fit = curves.fits[port]
        for key, truth in (("high_pressure_cutoff", high), ("low_pressure_cutoff", low)):
            print(f"  port {port} {key:22s} {fit.value(key):+.4f} {truth:+.4f}")
            assert fit.value(key) == pytest.approx(truth, abs=0.02)
        assert fit.r_squared > 0.999


def test_spacer_points_need_columns(spacer_rig) -> None:
    with pytest.raises(IdentificationError, match="columns"):
        input_pressure_curves([{"time [s]": np.arange(3.0)}], spacer_rig)


@pytest.mark.parametrize("voltage", [6.0, 4.0])
def test_equivalent_area_recovery(area_rig, voltage: float) -> None:
    base = rig()
    recording = step_recording(area_rig, voltage, seed=31, duration=1.2)
    fit = equivalent_area_for_step(base, recording)
    centered = voltage - base.actuator.valve.offset_voltage
    assert fit.centered_voltage == pytest.approx(centered)
    print(f"\nequivalent area at {centered:+.2f} V: port, recovered, true, initial [m^2]")
    for port, factor in TRUE_AREA_FACTORS.items():
        truth = true_area(area_rig, port, centered)
        assert truth == pytest.approx(factor * fit.initial_areas[port])
        print(f"  port {port} {fit.areas[port]:.4e} {truth:.4e} {fit.initial_areas[port]:.4e}")
        assert fit.areas[port] == pytest.approx(truth, rel=0.10)
    assert fit.position_rmse < 2e-4 and fit.pressure_rmse < 5e3
    assert fit.fit.details["evaluations"] <= 60


def test_equivalent_area_common_scale() -> None:
    truth = rig(*scaled_polynomial_overrides(rig(), {1: 1.2, 2: 1.2}))
    recording = step_recording(truth, 6.5, seed=32, duration=1.2)
    fit = equivalent_area_for_step(rig(), recording, mode="scale")
    assert fit.fit.value("area_scale") == pytest.approx(1.2, rel=0.05)
    with pytest.raises(IdentificationError, match="mode"):
        equivalent_area_for_step(rig(), recording, mode="wobble")


def test_fit_area_polynomials_reproduces_the_thesis_procedure() -> None:
    areas = equivalent_areas(PORT2_DISCHARGE_COEFFICIENTS, THESIS_VOLTAGES)
    fitted = fit_area_polynomials(THESIS_VOLTAGES, {2: areas})
    negative, positive = thesis_port_polynomials(2)
    np.testing.assert_allclose(fitted[2].negative, negative)
    np.testing.assert_allclose(fitted[2].positive, positive)
    updates = area_polynomial_updates(fitted)
    assert set(updates) == {"valve.port2.area_negative", "valve.port2.area_positive"}
    assert len(updates["valve.port2.area_positive"]) == 5
    with pytest.raises(IdentificationError, match="port 1"):
        fit_area_polynomials([0.0, 0.5, 1.0], {1: [1e-8, 2e-8, 3e-8]})


def test_area_polynomials_from_simulated_steps(area_rig) -> None:
    """The whole App. B.2 chain: areas at eleven step voltages, then the polynomials."""
    base = rig()
    offset = base.actuator.valve.offset_voltage
    centered = (-3.0, -2.0, -1.25, -0.75, -0.35, 0.0, 0.35, 0.75, 1.25, 2.0, 3.0)
    fits = [
        equivalent_area_for_step(
            base, step_recording(area_rig, offset + value, seed=40 + index, duration=1.2)
        )
        for index, value in enumerate(centered)
    ]
    voltages, areas = areas_table(fits)
    polynomials = fit_area_polynomials(voltages, areas)
    print("\narea chain: port, centered [V], step fit / true, polynomial / true")
    for port in (1, 2):
        truth = np.array([true_area(area_rig, port, value) for value in centered])
        fitted = evaluate_equivalent_area(
            polynomials[port].negative, polynomials[port].positive, voltages
        )
        for value, area, curve, exact in zip(centered, areas[port], fitted, truth, strict=True):
            print(f"  port {port} {value:+5.2f} {area / exact:.4f} {curve / exact:.4f}")
        np.testing.assert_allclose(areas[port], truth, rtol=0.10)
        np.testing.assert_allclose(fitted, truth, rtol=0.15)
