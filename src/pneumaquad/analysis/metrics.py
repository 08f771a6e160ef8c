"""Error and step-response figures of sampled signals.

The thesis judged its simulation by the RMSE of position over a whole run, also as a
fraction of the 1.75 in stroke (section 4.3, transcript lines 824-826), by rise and settling
time of closed-loop steps (line 820) and by the lag of sine tracking behind the
reference (line 818). These functions compute such figures from numpy arrays; every
dictionary key names its unit.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from .filters import sample_rate_of

__all__ = [
    "lag",
    "max_abs_error",
    "overshoot_percent",
    "peak_time",
    "rise_time",
    "rmse",
    "rmse_percent_of_range",
    "settling_time",
    "steady_state_error",
    "step_metrics",
]


def rmse(estimate: ArrayLike, reference: ArrayLike) -> float:
    """Root-mean-square error between two equally sampled signals (unit of the inputs)."""
    error = _pair(estimate, reference)
    return float(np.sqrt(np.mean(error**2)))


def rmse_percent_of_range(
    estimate: ArrayLike, reference: ArrayLike, span: float | None = None
) -> float:
    """RMSE as a percentage of a span [%].

    Parameters
    ----------
    estimate, reference : array_like
        Equally sampled signals.
    span : float, optional
        Range the error is related to, e.g. the stroke [m] as in thesis 4.3; by default
        the range (max - min) of ``reference``.

    Returns
    -------
    float
        ``100 * rmse / span`` [%]; NaN when the span is zero.
    """
    reference_values = np.asarray(reference, dtype=float)
    if span is None:
        span = float(np.ptp(reference_values)) if reference_values.size else 0.0
    value = rmse(estimate, reference_values)
    return 100.0 * value / span if span > 0 else math.nan


def max_abs_error(estimate: ArrayLike, reference: ArrayLike) -> float:
    """Largest absolute difference between two equally sampled signals."""
    return float(np.max(np.abs(_pair(estimate, reference))))


def rise_time(
    time: ArrayLike,
    response: ArrayLike,
    initial_level: float,
    final_level: float,
    lower_fraction: float = 0.1,
    upper_fraction: float = 0.9,
) -> float:
    """Time the response takes from ``lower_fraction`` to ``upper_fraction`` of the step [s].

    Crossing instants are interpolated linearly between samples; the first crossing of
    each level counts. Works for falling steps (``final_level < initial_level``) too.

    Returns
    -------
    float
        Rise time [s]; NaN when the upper level is never reached.
    """
    if not 0.0 <= lower_fraction < upper_fraction <= 1.0:
        raise ValueError(
            f"need 0 <= lower fraction < upper fraction <= 1, got "
            f"{lower_fraction!r} and {upper_fraction!r}"
        )
    times, progress = _progress(time, response, initial_level, final_level)
    lower = _first_crossing(times, progress, lower_fraction)
    upper = _first_crossing(times, progress, upper_fraction)
    return upper - lower


def overshoot_percent(response: ArrayLike, initial_level: float, final_level: float) -> float:
    """Largest excursion beyond the final level, in % of the step size (0 if none) [%]."""
    _, progress = _progress(np.arange(np.size(response)), response, initial_level, final_level)
    return float(max(0.0, 100.0 * (np.max(progress) - 1.0)))


def peak_time(
    time: ArrayLike, response: ArrayLike, initial_level: float, final_level: float
) -> float:
    """Time of the largest progress towards (or past) the final level [s], sample resolution."""
    times, progress = _progress(time, response, initial_level, final_level)
    return float(times[int(np.argmax(progress))])


def settling_time(
    time: ArrayLike,
    response: ArrayLike,
    final_level: float,
    step_size: float,
    band: float = 0.02,
) -> float:
    """Instant after which the response stays within ``band`` of the final level [s].

    Parameters
    ----------
    time : array_like
        Sample times [s]; the result is on this time axis (subtract the step time to
        get a duration).
    response : array_like
        Response samples.
    final_level : float
        Level the response settles to.
    step_size : float
        Size of the step; the band half-width is ``band * |step_size|``.
    band : float
        Band half-width as a fraction of the step size (0.02 = 2 %).

    Returns
    -------
    float
        The instant [s], interpolated linearly where the response enters the band for the
        last time; ``time[0]`` if it never leaves the band; NaN if it is outside the band
        at the last sample.
    """
    if not band > 0:
        raise ValueError(f"settling band must be greater than 0, got {band!r}")
    times = np.asarray(time, dtype=float)
    deviation = np.abs(np.asarray(response, dtype=float) - final_level)
    half_width = band * abs(step_size)
    outside = np.nonzero(deviation > half_width)[0]
    if outside.size == 0:
        return float(times[0])
    last = int(outside[-1])
    if last == times.size - 1:
        return math.nan
    before, after = deviation[last], deviation[last + 1]
    fraction = (before - half_width) / (before - after)
    return float(times[last] + fraction * (times[last + 1] - times[last]))


def steady_state_error(
    time: ArrayLike, response: ArrayLike, target: float, window: float | None = None
) -> float:
    """Target minus the mean response over the final ``window`` seconds.

    Parameters
    ----------
    time : array_like
        Sample times [s].
    response : array_like
        Response samples.
    target : float
        Level the response should reach (unit of ``response``).
    window : float, optional
        Averaging window at the end [s]; default the last 10 % of the duration.

    Returns
    -------
    float
        ``target - mean(response over window)``: positive when the response stays short
        of a rising target (the control convention ``e = r - y``).
    """
    times = np.asarray(time, dtype=float)
    values = np.asarray(response, dtype=float)
    return float(target - np.mean(values[_tail(times, window)]))


def lag(
    time: ArrayLike,
    values: ArrayLike,
    reference: ArrayLike,
    max_lag: float | None = None,
    refine: bool = True,
) -> float:
    """Delay of ``values`` behind ``reference`` from their cross-correlation [s].

    For each shift within ``±max_lag`` the Pearson correlation of the overlapping parts
    is computed, so the shrinking overlap does not bias the result; the best shift is
    refined to sub-sample resolution by a parabola through the peak and its neighbours.

    Parameters
    ----------
    time : array_like
        Uniform sample times [s] of both signals.
    values, reference : array_like
        The signals, same length as ``time``.
    max_lag : float, optional
        Largest delay searched either way [s]; default a quarter of the duration.
    refine : bool
        Apply the parabolic sub-sample refinement.

    Returns
    -------
    float
        Lag [s], positive when ``values`` follows ``reference`` late, i.e.
        ``values(t) ≈ reference(t - lag)``; NaN when either signal is constant.
    """
    times = np.asarray(time, dtype=float)
    x = np.asarray(reference, dtype=float)
    y = np.asarray(values, dtype=float)
    if x.shape != times.shape or y.shape != times.shape:
        raise ValueError(
            f"time, values and reference need equal lengths, got {times.size}, {y.size} "
            f"and {x.size}"
        )
    interval = 1.0 / sample_rate_of(times)
    count = times.size
    if max_lag is None:
        max_lag = 0.25 * (times[-1] - times[0])
    max_shift = min(count - 2, round(max_lag / interval))
    shifts = np.arange(-max_shift, max_shift + 1)
    scores = _shifted_correlations(x, y, shifts)
    if not np.any(np.isfinite(scores)):
        return math.nan
    best = int(np.nanargmax(scores))
    shift = float(shifts[best])
    if refine and 0 < best < shifts.size - 1:
        left, centre, right = scores[best - 1], scores[best], scores[best + 1]
        curvature = left - 2.0 * centre + right
        if np.isfinite(curvature) and curvature < 0:
            shift += 0.5 * (left - right) / curvature
    return shift * interval


def step_metrics(
    time: ArrayLike,
    response: ArrayLike,
    *,
    reference: ArrayLike | None = None,
    initial_level: float | None = None,
    final_level: float | None = None,
    step_time: float | None = None,
    settling_band: float = 0.02,
    rise_fractions: Sequence[float] = (0.1, 0.9),
    tail_window: float | None = None,
    unit: str = "-",
) -> dict[str, float]:
    """Figures of one step response; keys name their units.

    Levels and step instant come, in order of precedence, from the explicit arguments,
    from ``reference`` (its first and last value, and its first change), or from the
    response itself (its value at the step and its mean over the tail window).

    Parameters
    ----------
    time : array_like
        Sample times [s].
    response : array_like
        Response samples, e.g. position [m] or pressure [Pa].
    reference : array_like, optional
        The commanded reference, sampled like the response (same unit); its step instant
        is its first sample differing from the first one, so pass ``step_time`` for a
        noisy reference (or use `pneumaquad.analysis.segmentation.find_steps`).
    initial_level, final_level : float, optional
        Levels before and after the step (unit of the response).
    step_time : float, optional
        Instant of the step [s]; default from ``reference`` or ``time[0]``.
    settling_band : float
        Settling band half-width as a fraction of the step size.
    rise_fractions : sequence of two floats
        Lower and upper fraction of the step for the rise time.
    tail_window : float, optional
        Averaging window at the end for the final value [s]; default last 10 %.
    unit : str
        Unit of the response, used in the keys, e.g. ``"m"`` gives ``"final level [m]"``.

    Returns
    -------
    dict of str to float
        ``"step time [s]"``, ``"initial level [unit]"``, ``"final level [unit]"``,
        ``"rise time [s]"``, ``"peak time [s]"`` (after the step), ``"overshoot [%]"``,
        ``"settling time [s]"`` (after the step), and, when a target final level is known
        (from ``final_level`` or ``reference``), ``"steady-state error [unit]"``.
        Figures that cannot be determined are NaN.
    """
    times = np.asarray(time, dtype=float)
    values = np.asarray(response, dtype=float)
    if values.shape != times.shape or times.size < 2:
        raise ValueError(
            f"time and response need equal lengths of at least 2, got {times.size} "
            f"and {values.size}"
        )
    has_target = final_level is not None or reference is not None
    if reference is not None:
        references = np.asarray(reference, dtype=float)
        if step_time is None:
            changed = np.nonzero(references != references[0])[0]
            step_time = float(times[changed[0]]) if changed.size else float(times[0])
        initial_level = references[0] if initial_level is None else initial_level
        final_level = references[-1] if final_level is None else final_level
    if step_time is None:
        step_time = float(times[0])
    after = times >= step_time
    if not np.any(after):
        raise ValueError(f"step time {step_time:g} s lies after the last sample")
    start = int(np.argmax(after))
    times_after, values_after = times[start:], values[start:]
    tail = _tail(times_after, tail_window)
    if initial_level is None:
        initial_level = float(values[start])
    if final_level is None:
        final_level = float(np.mean(values_after[tail]))
    initial_level, final_level = float(initial_level), float(final_level)
    lower, upper = rise_fractions
    figures = {
        "step time [s]": float(step_time),
        f"initial level [{unit}]": initial_level,
        f"final level [{unit}]": final_level,
        "rise time [s]": math.nan,
        "peak time [s]": math.nan,
        "overshoot [%]": math.nan,
        "settling time [s]": math.nan,
    }
    if final_level != initial_level:
        figures["rise time [s]"] = rise_time(
            times_after, values_after, initial_level, final_level, lower, upper
        )
        figures["peak time [s]"] = (
            peak_time(times_after, values_after, initial_level, final_level) - step_time
        )
        figures["overshoot [%]"] = overshoot_percent(values_after, initial_level, final_level)
        figures["settling time [s]"] = (
            settling_time(
                times_after,
                values_after,
                final_level,
                final_level - initial_level,
                settling_band,
            )
            - step_time
        )
    if has_target:
        figures[f"steady-state error [{unit}]"] = float(final_level - np.mean(values_after[tail]))
    return figures


def _pair(estimate: ArrayLike, reference: ArrayLike) -> np.ndarray:
    a = np.asarray(estimate, dtype=float)
    b = np.asarray(reference, dtype=float)
    if a.shape != b.shape:
        raise ValueError(f"signals need the same shape, got {a.shape} and {b.shape}")
    if a.size == 0:
        raise ValueError("signals are empty")
    return a - b


def _progress(
    time: ArrayLike, response: ArrayLike, initial_level: float, final_level: float
) -> tuple[np.ndarray, np.ndarray]:
    """Times and the response normalised to 0 at the initial and 1 at the final level."""
    step_size = final_level - initial_level
    if step_size == 0:
        raise ValueError("initial and final level are equal: there is no step")
    times = np.asarray(time, dtype=float)
    values = np.asarray(response, dtype=float)
    if values.shape != times.shape or values.size == 0:
        raise ValueError(
            f"time and response need equal, non-zero lengths, got {times.size} and {values.size}"
        )
    return times, (values - initial_level) / step_size


def _first_crossing(times: np.ndarray, progress: np.ndarray, level: float) -> float:
    """First instant the progress reaches ``level``, linearly interpolated; NaN if never."""
    reached = np.nonzero(progress >= level)[0]
    if reached.size == 0:
        return math.nan
    index = int(reached[0])
    if index == 0:
        return float(times[0])
    before, after = progress[index - 1], progress[index]
    fraction = (level - before) / (after - before)
    return float(times[index - 1] + fraction * (times[index] - times[index - 1]))


def _tail(times: np.ndarray, window: float | None) -> np.ndarray:
    """Boolean mask of the final ``window`` seconds (default last 10 %), never empty."""
    if window is None:
        window = 0.1 * (times[-1] - times[0])
    mask = times >= times[-1] - window
    mask[-1] = True
    return mask


def _shifted_correlations(x: np.ndarray, y: np.ndarray, shifts: np.ndarray) -> np.ndarray:
    """Pearson correlation of ``x[n]`` with ``y[n + k]`` over their overlap, per shift k."""
    from scipy import signal as sp_signal  # loaded on first use: it is slow to import

    count = x.size
    # Centre both to limit cancellation in the running sums.
    x = x - x.mean()
    y = y - y.mean()
    # full correlation: entry count - 1 + k holds sum_n x[n] * y[n + k]
    cross = sp_signal.correlate(y, x, mode="full")[count - 1 + shifts]
    zero = np.zeros(1)
    cx, cy = np.concatenate([zero, np.cumsum(x)]), np.concatenate([zero, np.cumsum(y)])
    cxx = np.concatenate([zero, np.cumsum(x * x)])
    cyy = np.concatenate([zero, np.cumsum(y * y)])
    # overlap: x[a:b] with y[a + k:b + k]
    a = np.maximum(0, -shifts)
    b = np.minimum(count, count - shifts)
    n = (b - a).astype(float)
    sx, sy = cx[b] - cx[a], cy[b + shifts] - cy[a + shifts]
    sxx, syy = cxx[b] - cxx[a], cyy[b + shifts] - cyy[a + shifts]
    covariance = cross - sx * sy / n
    variance_x = sxx - sx * sx / n
    variance_y = syy - sy * sy / n
    scale = np.sqrt(np.maximum(variance_x, 0.0) * np.maximum(variance_y, 0.0))
    tiny = 1e-12 * max(float(np.sum(x * x)), float(np.sum(y * y)), 1e-300)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(scale > tiny, covariance / scale, np.nan)
