"""Step fits: thesis eq (4.3.1) first order, damped second order, and their sum."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from pneumaquad.analysis.fits import (
    FIRST_ORDER,
    FIRST_PLUS_SECOND_ORDER,
    SECOND_ORDER,
    START_TIME,
    FitError,
    FitResult,
    evaluate_step_fit,
    fit_first_order,
    fit_first_plus_second_order,
    fit_second_order,
    fit_step,
)

STEP_AT = 5.0  # s, the thesis' open-loop steps switch at 5 s (section 4.2.3)
TIME = np.arange(STEP_AT, STEP_AT + 1.5, 1e-3)
ELAPSED = TIME - STEP_AT


def underdamped(t, damping, natural_frequency):
    """1 - unit step response of the standard second-order system, 0 < damping < 1."""
    root = math.sqrt(1 - damping**2)
    return (
        np.exp(-damping * natural_frequency * t)
        / root
        * np.sin(natural_frequency * root * t + math.acos(damping))
    )


def test_first_order_fit_recovers_parameters_from_noisy_pressure_step():
    final, amplitude, tau = 4.0e5, 2.5e5, 0.085  # Pa, Pa, s (tau as in thesis 4.3)
    noise = 2.0e3  # Pa, 0.8 % of the step
    rng = np.random.default_rng(11)
    measured = final - amplitude * np.exp(-ELAPSED / tau) + rng.normal(0, noise, TIME.size)
    fit = fit_first_order(TIME, measured)
    assert fit.name == FIRST_ORDER
    assert fit.details[START_TIME] == STEP_AT
    assert fit.parameters["final value"] == pytest.approx(final, rel=0.002)
    assert fit.parameters["amplitude"] == pytest.approx(amplitude, rel=0.01)
    assert fit.value("time constant") == pytest.approx(tau, rel=0.02)
    assert fit.r_squared > 0.99
    assert fit.residual_rms == pytest.approx(noise, rel=0.1)
    truth = {"final value": final, "amplitude": amplitude, "time constant [s]": tau}
    for name, value in truth.items():
        error = fit.standard_errors[name]
        assert 0 < error < 0.01 * abs(value)
        assert abs(fit.parameters[name] - value) < 4 * error
    curve = evaluate_step_fit(fit, TIME)
    assert np.sqrt(np.mean((curve - measured) ** 2)) == pytest.approx(fit.residual_rms)


def test_first_order_fit_of_a_falling_step_after_a_start_time():
    time = np.arange(0.0, 2.0, 1e-3)
    tau = 0.2
    response = np.where(time < 0.5, 4.0e5, 1.0e5 + 3.0e5 * np.exp(-(time - 0.5) / tau))
    fit = fit_first_order(time, response, start_time=0.5)
    assert fit.parameters["final value"] == pytest.approx(1.0e5, rel=1e-6)
    assert fit.parameters["amplitude"] == pytest.approx(-3.0e5, rel=1e-6)
    assert fit.value("time constant") == pytest.approx(tau, rel=1e-6)
    assert fit.r_squared == pytest.approx(1.0, abs=1e-9)
    assert fit.n_points == 1500


def test_second_order_fit_recovers_damping_and_natural_frequency():
    rng = np.random.default_rng(3)
    final, amplitude, damping, frequency = 0.03, 0.02, 0.3, 25.0  # m, m, -, rad/s
    response = final - amplitude * underdamped(ELAPSED, damping, frequency)
    fit = fit_second_order(TIME, response + rng.normal(0, 5e-5, TIME.size))
    assert fit.name == SECOND_ORDER
    assert fit.parameters["damping ratio [-]"] == pytest.approx(damping, rel=0.02)
    assert fit.parameters["natural frequency [rad/s]"] == pytest.approx(frequency, rel=0.01)
    assert fit.parameters["final value"] == pytest.approx(final, rel=0.002)
    assert fit.r_squared > 0.99
    assert "time constant [s]" not in fit.parameters
    assert not fit.failed and fit.problems == ()


def test_second_order_fit_of_an_overdamped_step():
    # Poles at -4 and -25 rad/s: wn = 10 rad/s, zeta = 29 / 20.
    response = 1.0 - (25 * np.exp(-4 * ELAPSED) - 4 * np.exp(-25 * ELAPSED)) / 21
    fit = fit_second_order(TIME, response)
    assert fit.parameters["natural frequency [rad/s]"] == pytest.approx(10.0, rel=1e-4)
    assert fit.parameters["damping ratio [-]"] == pytest.approx(1.45, rel=1e-4)


def test_first_plus_second_order_fit_of_a_closed_loop_step():
    rng = np.random.default_rng(5)
    tau, damping, frequency = 0.082, 0.2, 40.0  # tau: thesis' simulated mean, 4.3
    response = (
        0.03
        - 0.012 * np.exp(-ELAPSED / tau)
        - 0.004 * underdamped(ELAPSED, damping, frequency)
        + rng.normal(0, 3e-5, TIME.size)
    )
    combined = fit_first_plus_second_order(TIME, response)
    assert combined.name == FIRST_PLUS_SECOND_ORDER
    assert combined.value("time constant") == pytest.approx(tau, rel=0.02)
    assert combined.parameters["natural frequency [rad/s]"] == pytest.approx(frequency, rel=0.02)
    assert combined.parameters["damping ratio [-]"] == pytest.approx(damping, rel=0.05)
    assert combined.parameters["second-order amplitude"] == pytest.approx(0.004, rel=0.05)
    first_only = fit_step(TIME, response, FIRST_ORDER)
    assert combined.r_squared > first_only.r_squared
    assert combined.residual_rms == pytest.approx(3e-5, rel=0.1)


def test_fit_errors_are_clear():
    assert issubclass(FitError, ValueError)
    with pytest.raises(FitError, match="constant"):
        fit_first_order(TIME, np.full(TIME.size, 2.0))
    with pytest.raises(FitError, match="non-finite"):
        fit_first_order(TIME, np.where(ELAPSED > 0.1, np.nan, 1.0))
    with pytest.raises(FitError, match="need more than 3 samples"):
        fit_first_order(TIME[:3], np.array([0.0, 1.0, 1.5]))
    with pytest.raises(FitError, match="need more than 3 samples"):
        fit_first_order(TIME, np.sin(TIME), start_time=TIME[-2])
    with pytest.raises(FitError, match="samples"):
        fit_first_order(TIME, np.sin(TIME)[:-1])
    with pytest.raises(ValueError, match="unknown step model"):
        fit_step(TIME, np.sin(TIME), "third order")


def test_fit_result_is_immutable():
    fit = fit_first_order(TIME, 1.0 - np.exp(-ELAPSED / 0.1))
    with pytest.raises(dataclasses.FrozenInstanceError):
        fit.r_squared = 0.5
    with pytest.raises(TypeError):
        fit.parameters["time constant [s]"] = 1.0


def test_every_fit_of_the_package_returns_the_one_result_type():
    from pneumaquad.identification import (
        fit_area_polynomials,
        fit_coulomb_viscous,
        fit_input_pressure_curve,
    )
    from pneumaquad.identification.friction import StictionEstimate, summarize_stiction

    step = fit_first_order(TIME, 1.0 - np.exp(-ELAPSED / 0.1))
    velocity = np.linspace(-0.2, 0.2, 41)
    friction = fit_coulomb_viscous(velocity, 10.0 * np.sign(velocity) + 50.0 * velocity)
    voltages = np.linspace(-2.0, 2.0, 21)
    polynomials = fit_area_polynomials(voltages, {1: 1e-7 * (1.0 + voltages**2)})[1]
    curve = fit_input_pressure_curve(
        voltages, 1e5 + 5e5 * (1.0 + np.tanh(2.0 * voltages)) / 2.0, 6e5, 1e5, port=1
    )
    stiction = summarize_stiction(
        [StictionEstimate(20.0, 1, 5.0, 5.01, 1e3, True, 6.0, 1e-3)]
    )
    for fit in (step, friction, polynomials.fit, curve, stiction):
        assert type(fit) is FitResult
        assert fit.rows() and fit.n_points > 0 and math.isfinite(fit.residual_rms)
    # the polynomial fit's parameters are its coefficients, with finite standard errors
    assert polynomials.fit.value("area_positive_c2") == pytest.approx(1e-7, rel=1e-6)
    assert polynomials.fit.value("area_negative_c0") == pytest.approx(1e-7, rel=1e-6)
    assert all(math.isfinite(error) for error in polynomials.fit.standard_errors.values())
    assert polynomials.residual_rms == polynomials.fit.residual_rms
    assert polynomials.fit.residual_unit == "m^2"
