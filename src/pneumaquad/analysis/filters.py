"""Zero-phase low-pass filtering, velocity from position, and amplitude spectra.

The thesis processed its lab recordings offline with MATLAB's ``filtfilt``, i.e. each
signal is filtered forward and then backward so that the phase shifts cancel (thesis
section 4.2.1, text line 543 of the reference transcript, and the analysis script of
appendix A.2, script lines 24-31). Its filters were Chebyshev type II low-pass filters
built with MATLAB's ``filterbuilder``, one per signal kind (position, velocity, force,
pressure; appendix A.3, Figure 56), with the cut-offs chosen by inspecting each signal's
spectrum. The numerical filter settings appear only in the screenshots of Figure 56 and
are not recoverable from the text, so the defaults here (order 4, 40 dB) are this
project's choice. Velocity was obtained as ``gradient`` of the filtered position with
a 1 ms sample spacing and then filtered again (appendix A.2, script lines 27-28).

Here the filters are designed from plain parameters with `scipy.signal.cheby2` in
second-order sections and applied with `scipy.signal.sosfiltfilt`.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

__all__ = [
    "DEFAULT_FILTER_ORDER",
    "DEFAULT_STOPBAND_ATTENUATION",
    "amplitude_spectrum",
    "apply_zero_phase",
    "design_lowpass",
    "lowpass_filter",
    "sample_rate_of",
    "velocity_from_position",
]

#: Default order of the Chebyshev type II low-pass (project choice, see module docstring).
DEFAULT_FILTER_ORDER = 4
#: Default minimum stop-band attenuation of one filter pass [dB] (project choice).
DEFAULT_STOPBAND_ATTENUATION = 40.0

#: Largest relative deviation of a sample interval from the mean one for "uniform" sampling.
_UNIFORM_TOLERANCE = 1e-3


def design_lowpass(
    sample_rate: float,
    cutoff: float,
    order: int = DEFAULT_FILTER_ORDER,
    stopband_attenuation: float = DEFAULT_STOPBAND_ATTENUATION,
) -> np.ndarray:
    """Design a digital Chebyshev type II low-pass filter in second-order sections.

    Parameters
    ----------
    sample_rate : float
        Sampling frequency of the signals to be filtered [Hz].
    cutoff : float
        Stop-band edge [Hz]: from this frequency upwards one pass of the filter attenuates
        by at least ``stopband_attenuation``. Must lie strictly between 0 and the Nyquist
        frequency ``sample_rate / 2``. The pass band ends well below it: with order 4 and
        40 dB one pass is 3 dB down at about 0.51 x cut-off and within 0.5 % of unit gain
        up to about 0.30 x cut-off, so place the cut-off above the band to keep.
    order : int
        Filter order (number of poles), at least 1.
    stopband_attenuation : float
        Minimum attenuation in the stop band for one pass [dB], positive. Applied
        forward-backward (`apply_zero_phase`) the attenuation doubles.

    Returns
    -------
    numpy.ndarray
        Second-order sections, shape ``(n_sections, 6)``, for `scipy.signal.sosfiltfilt`.

    Raises
    ------
    ValueError
        If a parameter is not finite or out of range, naming the parameter and value.
    """
    _require_positive("sample rate [Hz]", sample_rate)
    _require_positive("cut-off [Hz]", cutoff)
    _require_positive("stop-band attenuation [dB]", stopband_attenuation)
    nyquist = 0.5 * sample_rate
    if cutoff >= nyquist:
        raise ValueError(
            f"cut-off {cutoff:g} Hz must be below the Nyquist frequency {nyquist:g} Hz "
            f"(half the sample rate {sample_rate:g} Hz)"
        )
    if isinstance(order, bool) or not isinstance(order, int | np.integer) or order < 1:
        raise ValueError(f"filter order {order!r} must be an integer of at least 1")
    from scipy import signal as sp_signal  # slow to import: loaded on first use

    return sp_signal.cheby2(
        int(order),
        float(stopband_attenuation),
        float(cutoff),
        btype="lowpass",
        output="sos",
        fs=float(sample_rate),
    )


def apply_zero_phase(values: ArrayLike, sections: np.ndarray, axis: int = 0) -> np.ndarray:
    """Filter forward and backward (no phase shift, squared magnitude response).

    Parameters
    ----------
    values : array_like
        Uniformly sampled signal(s); filtered along ``axis``.
    sections : numpy.ndarray
        Second-order sections from `design_lowpass`.
    axis : int
        Axis along which the samples run.

    Returns
    -------
    numpy.ndarray
        The filtered signal, same shape as ``values``.

    Raises
    ------
    ValueError
        If the signal holds non-finite values or is too short for the edge padding.
    """
    data = np.asarray(values, dtype=float)
    if not np.all(np.isfinite(data)):
        raise ValueError("cannot filter a signal containing NaN or infinite values")
    # sosfiltfilt's default edge padding length for these sections.
    padding = 3 * (
        2 * len(sections)
        + 1
        - min(int(np.sum(sections[:, 2] == 0)), int(np.sum(sections[:, 5] == 0)))
    )
    if data.shape[axis] <= padding:
        raise ValueError(
            f"signal of {data.shape[axis]} samples is too short for zero-phase filtering "
            f"with {len(sections)} second-order sections; it needs more than {padding}"
        )
    from scipy import signal as sp_signal

    return sp_signal.sosfiltfilt(sections, data, axis=axis)


def sample_rate_of(time: ArrayLike) -> float:
    """Sample rate of a uniformly sampled time vector [Hz].

    Parameters
    ----------
    time : array_like
        Sample times [s], strictly increasing with (nearly) constant spacing.

    Returns
    -------
    float
        One over the mean sample interval [Hz].

    Raises
    ------
    ValueError
        If there are fewer than two samples, the times do not increase, or the spacing
        varies by more than 0.1 % of the mean interval (resample first).
    """
    times = np.asarray(time, dtype=float).ravel()
    if times.size < 2:
        raise ValueError("need at least two samples to find the sample rate")
    intervals = np.diff(times)
    if not np.all(intervals > 0):
        index = int(np.argmax(~(intervals > 0))) + 1
        raise ValueError(
            f"time must increase strictly; at index {index} it goes from "
            f"{times[index - 1]:g} s to {times[index]:g} s"
        )
    mean_interval = float(np.mean(intervals))
    deviation = float(np.max(np.abs(intervals - mean_interval)))
    if deviation > _UNIFORM_TOLERANCE * mean_interval:
        raise ValueError(
            f"time is not uniformly sampled: sample intervals vary by {deviation:g} s "
            f"around the mean {mean_interval:g} s; resample onto a uniform grid first"
        )
    return 1.0 / mean_interval


def lowpass_filter(
    time: ArrayLike,
    values: ArrayLike,
    cutoff: float,
    order: int = DEFAULT_FILTER_ORDER,
    stopband_attenuation: float = DEFAULT_STOPBAND_ATTENUATION,
) -> np.ndarray:
    """Zero-phase Chebyshev type II low-pass of a sampled signal (thesis 4.2.1, A.2).

    Parameters
    ----------
    time : array_like
        Uniform sample times [s].
    values : array_like
        Signal samples, same length as ``time`` (any unit; the output has the same unit).
    cutoff : float
        Stop-band edge of one pass [Hz], see `design_lowpass`.
    order : int
        Filter order.
    stopband_attenuation : float
        Stop-band attenuation of one pass [dB].

    Returns
    -------
    numpy.ndarray
        The filtered samples.
    """
    data = np.asarray(values, dtype=float)
    _require_same_length(time, data)
    sections = design_lowpass(sample_rate_of(time), cutoff, order, stopband_attenuation)
    return apply_zero_phase(data, sections)


def velocity_from_position(
    time: ArrayLike,
    position: ArrayLike,
    cutoff: float,
    order: int = DEFAULT_FILTER_ORDER,
    stopband_attenuation: float = DEFAULT_STOPBAND_ATTENUATION,
    position_cutoff: float | None = None,
) -> np.ndarray:
    """Velocity as the zero-phase filtered numerical derivative of position.

    Follows the thesis' appendix A.2 procedure (script lines 25-28): optionally filter
    the position, take the central-difference gradient (second-order one-sided at the
    ends), filter the result.

    Parameters
    ----------
    time : array_like
        Uniform sample times [s].
    position : array_like
        Position samples [m].
    cutoff : float
        Stop-band edge of the velocity filter [Hz].
    order : int
        Filter order of both filters.
    stopband_attenuation : float
        Stop-band attenuation of one pass [dB].
    position_cutoff : float, optional
        If given, the position is first low-passed with this stop-band edge [Hz].

    Returns
    -------
    numpy.ndarray
        Velocity [m/s].
    """
    times = np.asarray(time, dtype=float)
    positions = np.asarray(position, dtype=float)
    _require_same_length(times, positions)
    sample_rate = sample_rate_of(times)
    if position_cutoff is not None:
        positions = apply_zero_phase(
            positions, design_lowpass(sample_rate, position_cutoff, order, stopband_attenuation)
        )
    raw_velocity = np.gradient(positions, times, edge_order=2)
    sections = design_lowpass(sample_rate, cutoff, order, stopband_attenuation)
    return apply_zero_phase(raw_velocity, sections)


def amplitude_spectrum(
    time: ArrayLike, values: ArrayLike, remove_mean: bool = True
) -> tuple[np.ndarray, np.ndarray]:
    """Single-sided amplitude spectrum, to choose filter cut-offs (cf. thesis A.3).

    Parameters
    ----------
    time : array_like
        Uniform sample times [s].
    values : array_like
        Signal samples (any unit).
    remove_mean : bool
        Subtract the mean first, so the zero-frequency bin does not dominate plots.

    Returns
    -------
    frequencies : numpy.ndarray
        Bin frequencies from 0 to the Nyquist frequency [Hz].
    amplitudes : numpy.ndarray
        Amplitude per bin, in the unit of ``values``: a sine of amplitude ``a`` whose
        frequency falls on a bin shows as ``a`` in that bin.
    """
    data = np.asarray(values, dtype=float)
    _require_same_length(time, data)
    if not np.all(np.isfinite(data)):
        raise ValueError("cannot take the spectrum of a signal containing NaN or infinity")
    sample_rate = sample_rate_of(time)
    if remove_mean:
        data = data - np.mean(data)
    count = data.size
    amplitudes = np.abs(np.fft.rfft(data)) / count
    # Fold the negative frequencies onto the positive ones (not DC nor the Nyquist bin).
    last_doubled = amplitudes.size - 1 if count % 2 == 0 else amplitudes.size
    amplitudes[1:last_doubled] *= 2.0
    frequencies = np.fft.rfftfreq(count, d=1.0 / sample_rate)
    return frequencies, amplitudes


def _require_positive(name: str, value: float) -> None:
    if not (
        isinstance(value, int | float | np.floating | np.integer)
        and math.isfinite(value)
        and value > 0
    ):
        raise ValueError(f"{name} must be a finite number greater than 0, got {value!r}")


def _require_same_length(time: ArrayLike, values: np.ndarray) -> None:
    count = np.asarray(time).shape[0]
    if values.shape[0] != count:
        raise ValueError(f"time has {count} samples but the signal has {values.shape[0]}")
