"""Zero-phase Chebyshev II filtering, velocity from position, amplitude spectrum."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import signal as sp_signal

from pneumaquad.analysis.filters import (
    amplitude_spectrum,
    design_lowpass,
    lowpass_filter,
    sample_rate_of,
    velocity_from_position,
)

SAMPLE_RATE = 1000.0  # Hz, the thesis rig's 1 ms sampling (App. A.2 gradient spacing)
TIME = np.arange(0.0, 4.0, 1.0 / SAMPLE_RATE)
INTERIOR = slice(500, -500)  # away from the edge transients


def _sine_fit(time: np.ndarray, values: np.ndarray, frequency: float) -> tuple[float, float]:
    """Amplitude and phase [rad] of the ``frequency`` component by linear least squares."""
    basis = np.column_stack(
        [np.sin(2 * np.pi * frequency * time), np.cos(2 * np.pi * frequency * time)]
    )
    (sine, cosine), *_ = np.linalg.lstsq(basis, values, rcond=None)
    return math.hypot(sine, cosine), math.atan2(cosine, sine)


def test_slow_sine_keeps_amplitude_and_phase():
    frequency = 2.0  # Hz, far below the 50 Hz cut-off
    raw = 0.7 * np.sin(2 * np.pi * frequency * TIME)
    filtered = lowpass_filter(TIME, raw, cutoff=50.0)
    amplitude, phase = _sine_fit(TIME[INTERIOR], filtered[INTERIOR], frequency)
    assert amplitude == pytest.approx(0.7, rel=0.005)
    assert abs(phase) < 1e-6  # forward-backward: no phase shift
    assert np.max(np.abs(filtered[INTERIOR] - raw[INTERIOR])) < 0.005 * 0.7


@pytest.mark.parametrize("attenuation", [30.0, 60.0])
@pytest.mark.parametrize("ratio", [1.2, 3.0])
def test_content_above_cutoff_is_attenuated_by_at_least_the_design_attenuation(attenuation, ratio):
    cutoff = 40.0
    noise = np.sin(2 * np.pi * ratio * cutoff * TIME)
    filtered = lowpass_filter(TIME, noise, cutoff, stopband_attenuation=attenuation)
    assert np.max(np.abs(filtered[INTERIOR])) <= 10 ** (-attenuation / 20)


def test_single_pass_gain_at_cutoff_equals_design_attenuation():
    sections = design_lowpass(SAMPLE_RATE, 50.0, order=5, stopband_attenuation=45.0)
    assert sections.shape == (3, 6)
    _, response = sp_signal.sosfreqz(sections, worN=[0.0, 50.0, 80.0, 200.0], fs=SAMPLE_RATE)
    gain_db = 20 * np.log10(np.abs(response))
    assert gain_db[0] == pytest.approx(0.0, abs=1e-6)
    assert gain_db[1] == pytest.approx(-45.0, abs=0.01)
    assert np.all(gain_db[2:] <= -45.0 + 1e-6)


def test_noisy_signal_is_cleaned_without_delay():
    rng = np.random.default_rng(4)
    clean = np.sin(2 * np.pi * 1.5 * TIME) + 0.5 * np.sin(2 * np.pi * 4.0 * TIME)
    filtered = lowpass_filter(TIME, clean + rng.normal(0.0, 0.05, TIME.size), cutoff=30.0)
    error = filtered[INTERIOR] - clean[INTERIOR]
    assert np.sqrt(np.mean(error**2)) < 0.05 / 3


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        ((1000.0, 500.0), "Nyquist"),
        ((1000.0, 600.0), "below the Nyquist frequency 500 Hz"),
        ((1000.0, 0.0), "cut-off"),
        ((1000.0, -5.0), "cut-off"),
        ((math.nan, 50.0), "sample rate"),
        ((1000.0, 50.0, 0), "order"),
        ((1000.0, 50.0, 2.5), "order"),
        ((1000.0, 50.0, 4, 0.0), "attenuation"),
    ],
)
def test_design_rejects_bad_parameters(arguments, message):
    with pytest.raises(ValueError, match=message):
        design_lowpass(*arguments)


def test_filter_rejects_short_nan_and_nonuniform_input():
    with pytest.raises(ValueError, match="too short"):
        lowpass_filter(TIME[:10], np.zeros(10), 50.0)
    with pytest.raises(ValueError, match="NaN"):
        lowpass_filter(TIME, np.where(TIME > 1, np.nan, 0.0), 50.0)
    uneven = TIME.copy()
    uneven[100:] += 0.0004
    with pytest.raises(ValueError, match="not uniformly sampled"):
        lowpass_filter(uneven, np.zeros(TIME.size), 50.0)
    with pytest.raises(ValueError, match="samples"):
        lowpass_filter(TIME, np.zeros(TIME.size - 1), 50.0)


def test_sample_rate_and_time_errors():
    assert sample_rate_of(TIME) == pytest.approx(1000.0)
    backwards = TIME.copy()
    backwards[7] = backwards[6]
    with pytest.raises(ValueError, match="index 7"):
        sample_rate_of(backwards)


def test_velocity_of_quadratic_position():
    acceleration, start_velocity = 0.3, -0.02  # m/s^2, m/s
    position = 0.01 + start_velocity * TIME + 0.5 * acceleration * TIME**2
    velocity = velocity_from_position(TIME, position, cutoff=40.0)
    expected = start_velocity + acceleration * TIME
    # The central difference is exact for a quadratic; only the filter's edge transients
    # (ramp start-up, a few time constants of the filter) remain near the ends.
    assert np.max(np.abs(velocity[INTERIOR] - expected[INTERIOR])) < 1e-9


def test_velocity_of_noisy_sine_position():
    rng = np.random.default_rng(7)
    amplitude, frequency = 0.02, 1.0  # m, Hz
    position = amplitude * np.sin(2 * np.pi * frequency * TIME)
    noisy = position + rng.normal(0.0, 2e-5, TIME.size)
    velocity = velocity_from_position(TIME, noisy, cutoff=20.0, position_cutoff=40.0)
    expected = 2 * np.pi * frequency * amplitude * np.cos(2 * np.pi * frequency * TIME)
    peak = 2 * np.pi * frequency * amplitude
    assert np.max(np.abs(velocity[INTERIOR] - expected[INTERIOR])) < 0.02 * peak


def test_amplitude_spectrum_finds_sine_amplitude_and_mean():
    values = 1.5 + 3.0 * np.sin(2 * np.pi * 10.0 * TIME) + 0.2 * np.cos(2 * np.pi * 120.0 * TIME)
    frequencies, amplitudes = amplitude_spectrum(TIME, values)
    assert frequencies[0] == 0.0
    assert frequencies[-1] == pytest.approx(500.0)
    assert amplitudes[0] == pytest.approx(0.0, abs=1e-12)
    assert amplitudes[np.argmin(np.abs(frequencies - 10.0))] == pytest.approx(3.0)
    assert amplitudes[np.argmin(np.abs(frequencies - 120.0))] == pytest.approx(0.2)
    _, with_mean = amplitude_spectrum(TIME, values, remove_mean=False)
    assert with_mean[0] == pytest.approx(1.5)
