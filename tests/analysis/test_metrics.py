"""Error and step-response figures against closed-form responses."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from pneumaquad.analysis.metrics import (
    lag,
    max_abs_error,
    overshoot_percent,
    rise_time,
    rmse,
    rmse_percent_of_range,
    settling_time,
    steady_state_error,
    step_metrics,
)

DAMPING, NATURAL_FREQUENCY = 0.4, 15.0  # [-], [rad/s]
DT = 1e-4
TIME = np.arange(0.0, 2.0, DT)


def underdamped_step(t, damping=DAMPING, natural_frequency=NATURAL_FREQUENCY):
    """Unit step response of wn^2/(s^2 + 2 zeta wn s + wn^2), 0 < zeta < 1 (textbook form)."""
    root = math.sqrt(1.0 - damping**2)
    damped = natural_frequency * root
    return 1.0 - np.exp(-damping * natural_frequency * t) / root * np.sin(
        damped * t + math.acos(damping)
    )


def test_rmse_max_error_and_percentages():
    reference = np.linspace(0.0, 0.04, 101)  # m
    estimate = reference + 0.001
    estimate[50] += 0.002
    expected_rmse = math.sqrt((100 * 0.001**2 + 0.003**2) / 101)
    assert rmse(estimate, reference) == pytest.approx(expected_rmse)
    assert max_abs_error(estimate, reference) == pytest.approx(0.003)
    assert rmse_percent_of_range(estimate, reference) == pytest.approx(100 * expected_rmse / 0.04)
    stroke = 1.75 * 0.0254
    assert rmse_percent_of_range(estimate, reference, span=stroke) == pytest.approx(
        100 * expected_rmse / stroke
    )
    assert math.isnan(rmse_percent_of_range(estimate, np.ones(101)))
    with pytest.raises(ValueError, match="shape"):
        rmse(estimate, reference[:-1])


def test_second_order_overshoot_peak_rise_and_settling():
    response = underdamped_step(TIME)
    figures = step_metrics(TIME, response, initial_level=0.0, final_level=1.0, unit="m")
    root = math.sqrt(1 - DAMPING**2)
    assert figures["overshoot [%]"] == pytest.approx(
        100 * math.exp(-math.pi * DAMPING / root), abs=1e-4
    )
    assert figures["peak time [s]"] == pytest.approx(math.pi / (NATURAL_FREQUENCY * root), abs=DT)
    # Rise time: the 10 % and 90 % crossings of the closed form, found by root finding.
    first_peak = math.pi / (NATURAL_FREQUENCY * root)
    t10 = brentq(lambda t: underdamped_step(t) - 0.1, 0.0, first_peak)
    t90 = brentq(lambda t: underdamped_step(t) - 0.9, 0.0, first_peak)
    assert figures["rise time [s]"] == pytest.approx(t90 - t10, abs=1e-6)
    # Settling: at the reported instant the error is on the 2 % band, and stays inside.
    settle = figures["settling time [s]"]
    assert abs(underdamped_step(settle) - 1.0) == pytest.approx(0.02, abs=1e-6)
    times = TIME
    later = times[times > settle + DT]
    assert np.all(np.abs(underdamped_step(later) - 1.0) <= 0.02)
    # ... and lies below the envelope bound exp(-zeta wn t)/sqrt(1-zeta^2) = 2 %.
    envelope = -math.log(0.02 * root) / (DAMPING * NATURAL_FREQUENCY)
    assert envelope - 2 * math.pi / (NATURAL_FREQUENCY * root) < settle <= envelope
    assert figures["steady-state error [m]"] == pytest.approx(0.0, abs=1e-4)  # decaying tail
    assert set(figures) == {
        "step time [s]",
        "initial level [m]",
        "final level [m]",
        "rise time [s]",
        "peak time [s]",
        "overshoot [%]",
        "settling time [s]",
        "steady-state error [m]",
    }


def test_settling_band_is_a_parameter():
    response = underdamped_step(TIME)
    wide = settling_time(TIME, response, 1.0, 1.0, band=0.05)
    narrow = settling_time(TIME, response, 1.0, 1.0, band=0.02)
    assert wide < narrow
    assert abs(underdamped_step(wide) - 1.0) == pytest.approx(0.05, abs=1e-6)


def test_first_order_figures_and_falling_step():
    tau = 0.08  # s
    rising = 2.0 - 1.5 * np.exp(-TIME / tau)  # from 0.5 to 2.0
    assert rise_time(TIME, rising, 0.5, 2.0) == pytest.approx(tau * math.log(9), abs=1e-7)
    assert rise_time(TIME, rising, 0.5, 2.0, 0.05, 0.95) == pytest.approx(
        tau * math.log(19), abs=1e-7
    )
    assert overshoot_percent(rising, 0.5, 2.0) == 0.0
    assert settling_time(TIME, rising, 2.0, 1.5) == pytest.approx(tau * math.log(50), abs=1e-7)
    falling = 2.5 - rising  # from 2.0 to 0.5, same shape mirrored
    assert rise_time(TIME, falling, 2.0, 0.5) == pytest.approx(tau * math.log(9), abs=1e-7)
    mirrored = 1.0 - underdamped_step(TIME)
    assert overshoot_percent(mirrored, 1.0, 0.0) == pytest.approx(
        overshoot_percent(underdamped_step(TIME), 0.0, 1.0)
    )


def test_unreached_and_unsettled_give_nan():
    slow = 1.0 - np.exp(-TIME / 5.0)
    assert math.isnan(rise_time(TIME, slow, 0.0, 1.0))
    assert math.isnan(settling_time(TIME, slow, 1.0, 1.0))
    with pytest.raises(ValueError, match="no step"):
        rise_time(TIME, slow, 1.0, 1.0)
    with pytest.raises(ValueError, match="fraction"):
        rise_time(TIME, slow, 0.0, 1.0, 0.9, 0.1)


def test_steady_state_error_uses_the_tail():
    time = np.linspace(0.0, 10.0, 1001)
    response = np.where(time < 9.0, 0.5, 0.98)
    assert steady_state_error(time, response, 1.0) == pytest.approx(0.02)
    assert steady_state_error(time, response, 1.0, window=2.0) == pytest.approx(
        1.0 - np.mean(response[time >= 8.0])
    )


def test_step_metrics_takes_levels_and_step_time_from_the_reference():
    time = np.arange(0.0, 3.0, 1e-3)
    step_at = 1.0
    reference = np.where(time >= step_at, 0.03, 0.01)
    elapsed = np.clip(time - step_at, 0.0, None)
    response = 0.01 + 0.019 * underdamped_step(elapsed)  # settles 1 mm short of 0.03 m
    figures = step_metrics(time, response, reference=reference, unit="m")
    assert figures["step time [s]"] == pytest.approx(step_at)
    assert figures["initial level [m]"] == 0.01
    assert figures["final level [m]"] == 0.03
    assert figures["steady-state error [m]"] == pytest.approx(0.001, abs=1e-6)
    assert math.isnan(figures["settling time [s]"])  # never within 2 % of 0.03 m
    own = step_metrics(time, response, step_time=step_at, unit="m")
    assert "steady-state error [m]" not in own
    assert own["final level [m]"] == pytest.approx(0.029, abs=1e-6)
    assert own["overshoot [%]"] == pytest.approx(
        100 * math.exp(-math.pi * DAMPING / math.sqrt(1 - DAMPING**2)), abs=0.1
    )


MULTISINE_TIME = np.arange(0.0, 6.0, 1e-3)


def multisine(t):
    return np.sin(2 * np.pi * 1.3 * t) + 0.4 * np.sin(2 * np.pi * 0.45 * t + 1.0)


@pytest.mark.parametrize("delay", [0.0, 0.017, 0.0234, 0.25])
def test_lag_of_a_shifted_signal(delay):
    reference = multisine(MULTISINE_TIME)
    delayed = multisine(MULTISINE_TIME - delay)
    assert lag(MULTISINE_TIME, delayed, reference) == pytest.approx(delay, abs=2e-4)
    assert lag(MULTISINE_TIME, reference, delayed) == pytest.approx(-delay, abs=2e-4)


def test_lag_without_refinement_is_whole_samples_and_constant_gives_nan():
    reference = multisine(MULTISINE_TIME)
    delayed = multisine(MULTISINE_TIME - 0.0234)
    assert lag(MULTISINE_TIME, delayed, reference, refine=False) == pytest.approx(0.023)
    flat = np.ones(MULTISINE_TIME.size)
    assert math.isnan(lag(MULTISINE_TIME, flat, reference))


def test_lag_of_a_delayed_step():
    time = np.arange(0.0, 2.0, 1e-3)
    step = np.where(time >= 0.5, 1.0, 0.0)
    late = np.where(time >= 0.5 + 0.04, 1.0, 0.0)
    assert lag(time, late, step) == pytest.approx(0.04, abs=1e-3)
