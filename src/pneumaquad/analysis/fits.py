"""Least-squares fits of step responses: first order, second order, and their sum.

The thesis compared simulated and measured open-loop cap-pressure steps through the time
constant of a first-order fit, its eq (4.3.1) (transcript line 812), which reads with the
sign of the exponent made explicit

    y(t) = K0 - A0 · exp(-t / τ),

and reported the coefficients of determination R² of those fits (line 814). Closed-loop
position steps were fitted with a first-order response plus a second-order one, where the
first-order part dominated and its τ served for comparison (lines 820-822). Time ``t`` is
measured from the start of the fitted data (or from a given step instant).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import least_squares

__all__ = [
    "FIRST_ORDER",
    "FIRST_PLUS_SECOND_ORDER",
    "SECOND_ORDER",
    "FitError",
    "StepFit",
    "first_order_response",
    "fit_first_order",
    "fit_first_plus_second_order",
    "fit_second_order",
    "fit_step",
    "second_order_response",
]

FIRST_ORDER = "first order"
SECOND_ORDER = "second order"
FIRST_PLUS_SECOND_ORDER = "first + second order"

#: Damping ratios closer to 1 than this use the critically damped closed form.
_CRITICAL_DAMPING_TOLERANCE = 1e-6


class FitError(ValueError):
    """A step fit could not be made: unusable data or the optimiser did not converge."""


def first_order_response(
    elapsed: ArrayLike, final_value: float, amplitude: float, time_constant: float
) -> np.ndarray:
    """Thesis eq (4.3.1): ``K0 - A0 · exp(-t/τ)``.

    Parameters
    ----------
    elapsed : array_like
        Time since the step [s].
    final_value : float
        K0, the level approached (unit of the signal).
    amplitude : float
        A0, the distance from the level at ``t = 0`` to K0 (unit of the signal).
    time_constant : float
        τ [s], positive.
    """
    return final_value - amplitude * np.exp(-np.asarray(elapsed, dtype=float) / time_constant)


def second_order_response(
    elapsed: ArrayLike,
    final_value: float,
    amplitude: float,
    natural_frequency: float,
    damping_ratio: float,
) -> np.ndarray:
    """Step response of ``ωn² / (s² + 2ζωn s + ωn²)`` scaled to go from K - A to K.

    Valid for every damping ratio ζ > 0 (under-, critically and over-damped); starts at
    ``final_value - amplitude`` with zero slope.

    Parameters
    ----------
    elapsed : array_like
        Time since the step [s].
    final_value : float
        K, the level approached.
    amplitude : float
        A, the step size.
    natural_frequency : float
        ωn [rad/s], positive.
    damping_ratio : float
        ζ [-], positive.
    """
    t = np.asarray(elapsed, dtype=float)
    return final_value - amplitude * _second_order_remainder(t, natural_frequency, damping_ratio)


def _second_order_remainder(t: np.ndarray, natural_frequency: float, damping: float) -> np.ndarray:
    """1 - unit step response of the standard second-order system."""
    if abs(damping - 1.0) < _CRITICAL_DAMPING_TOLERANCE:
        return (1.0 + natural_frequency * t) * np.exp(-natural_frequency * t)
    root = np.emath.sqrt(damping * damping - 1.0)
    slow = natural_frequency * (damping - root)  # the two pole magnitudes
    fast = natural_frequency * (damping + root)
    remainder = (fast * np.exp(-slow * t) - slow * np.exp(-fast * t)) / (fast - slow)
    return np.real(remainder)


def _first_plus_second(
    t: np.ndarray,
    final_value,
    first_amplitude,
    time_constant,
    second_amplitude,
    natural_frequency,
    damping_ratio,
) -> np.ndarray:
    return (
        final_value
        - first_amplitude * np.exp(-t / time_constant)
        - second_amplitude * _second_order_remainder(t, natural_frequency, damping_ratio)
    )


_MODELS: dict[str, tuple[Callable[..., np.ndarray], tuple[str, ...]]] = {
    FIRST_ORDER: (first_order_response, ("final value", "amplitude", "time constant [s]")),
    SECOND_ORDER: (
        second_order_response,
        ("final value", "amplitude", "natural frequency [rad/s]", "damping ratio [-]"),
    ),
    FIRST_PLUS_SECOND_ORDER: (
        _first_plus_second,
        (
            "final value",
            "first-order amplitude",
            "time constant [s]",
            "second-order amplitude",
            "natural frequency [rad/s]",
            "damping ratio [-]",
        ),
    ),
}


@dataclass(frozen=True)
class StepFit:
    """Result of a step fit.

    Attributes
    ----------
    model : str
        `FIRST_ORDER`, `SECOND_ORDER` or `FIRST_PLUS_SECOND_ORDER`.
    parameters : Mapping of str to float
        Fitted parameters by name (names carry units; levels are in the signal's unit).
    standard_errors : Mapping of str to float
        One-sigma standard errors from the covariance estimate; infinite when the
        parameters are not identifiable from the data.
    r_squared : float
        Coefficient of determination 1 - SS_res / SS_tot [-].
    residual_rms : float
        Root-mean-square residual (unit of the signal).
    start_time : float
        Instant taken as t = 0 of the model [s].
    sample_count : int
        Number of samples fitted.
    """

    model: str
    parameters: Mapping[str, float]
    standard_errors: Mapping[str, float]
    r_squared: float
    residual_rms: float
    start_time: float
    sample_count: int = field(default=0)

    @property
    def time_constant(self) -> float:
        """τ [s] of the first-order part (NaN for a pure second-order fit)."""
        return float(self.parameters.get("time constant [s]", math.nan))

    def evaluate(self, time: ArrayLike) -> np.ndarray:
        """The fitted curve at absolute times ``time`` [s]."""
        function, names = _MODELS[self.model]
        elapsed = np.asarray(time, dtype=float) - self.start_time
        return function(elapsed, *(self.parameters[name] for name in names))


def fit_first_order(
    time: ArrayLike, response: ArrayLike, start_time: float | None = None
) -> StepFit:
    """Fit thesis eq (4.3.1), ``K0 - A0 · exp(-(t - t0)/τ)``, in the least-squares sense.

    Parameters
    ----------
    time : array_like
        Sample times [s].
    response : array_like
        Response samples (e.g. cap pressure [Pa]).
    start_time : float, optional
        t0 [s]; samples before it are ignored. Default ``time[0]``.

    Returns
    -------
    StepFit
        Parameters ``"final value"`` (K0), ``"amplitude"`` (A0), ``"time constant [s]"``.

    Raises
    ------
    FitError
        On too few or non-finite samples, a flat response, or no convergence.
    """
    t, y, start = _prepare(time, response, start_time, 3)
    final, amplitude, tau = _first_order_guess(t, y)
    return _fit(FIRST_ORDER, t, y, start, [final, amplitude, tau], [2])


def fit_second_order(
    time: ArrayLike, response: ArrayLike, start_time: float | None = None
) -> StepFit:
    """Fit a damped second-order step response (`second_order_response`).

    Returns
    -------
    StepFit
        Parameters ``"final value"``, ``"amplitude"``, ``"natural frequency [rad/s]"``,
        ``"damping ratio [-]"`` (kept positive).

    Raises
    ------
    FitError
        As `fit_first_order`.
    """
    t, y, start = _prepare(time, response, start_time, 4)
    final, amplitude, frequency, damping = _second_order_guess(t, y)
    return _fit(SECOND_ORDER, t, y, start, [final, amplitude, frequency, damping], [2, 3])


def fit_first_plus_second_order(
    time: ArrayLike, response: ArrayLike, start_time: float | None = None
) -> StepFit:
    """Fit a first-order plus a second-order response, as for closed-loop steps (thesis l. 820).

    ``y = K - A1 · exp(-t/τ) - A2 · r2(t; ωn, ζ)`` where ``r2`` is one minus the unit step
    response of the standard second-order system. Several starting points are tried and the
    one with the smallest residual is kept.

    Returns
    -------
    StepFit
        Parameters ``"final value"``, ``"first-order amplitude"``, ``"time constant [s]"``,
        ``"second-order amplitude"``, ``"natural frequency [rad/s]"``,
        ``"damping ratio [-]"``.

    Raises
    ------
    FitError
        As `fit_first_order`.
    """
    t, y, start = _prepare(time, response, start_time, 6)
    final, amplitude, tau = _first_order_guess(t, y)
    _, _, frequency, damping = _second_order_guess(t, y)
    best: StepFit | None = None
    last_error: FitError | None = None
    for share, frequency_factor in ((0.8, 1.0), (0.95, 3.0), (0.5, 1.0), (0.9, 10.0)):
        guess = [
            final,
            share * amplitude,
            tau,
            (1.0 - share) * amplitude,
            frequency * frequency_factor,
            min(damping, 0.5),
        ]
        try:
            candidate = _fit(FIRST_PLUS_SECOND_ORDER, t, y, start, guess, [2, 4, 5])
        except FitError as error:
            last_error = error
            continue
        if best is None or candidate.residual_rms < best.residual_rms:
            best = candidate
    if best is None:
        raise last_error if last_error is not None else FitError("fit failed")
    return best


def fit_step(
    time: ArrayLike,
    response: ArrayLike,
    model: str = FIRST_ORDER,
    start_time: float | None = None,
) -> StepFit:
    """Fit ``model`` (`FIRST_ORDER`, `SECOND_ORDER` or `FIRST_PLUS_SECOND_ORDER`)."""
    fitters = {
        FIRST_ORDER: fit_first_order,
        SECOND_ORDER: fit_second_order,
        FIRST_PLUS_SECOND_ORDER: fit_first_plus_second_order,
    }
    if model not in fitters:
        raise ValueError(f"unknown step model {model!r}; choose one of {sorted(fitters)}")
    return fitters[model](time, response, start_time)


def _prepare(
    time: ArrayLike, response: ArrayLike, start_time: float | None, parameter_count: int
) -> tuple[np.ndarray, np.ndarray, float]:
    times = np.asarray(time, dtype=float).ravel()
    values = np.asarray(response, dtype=float).ravel()
    if times.shape != values.shape:
        raise FitError(f"time has {times.size} samples but the response has {values.size}")
    if not (np.all(np.isfinite(times)) and np.all(np.isfinite(values))):
        bad = np.nonzero(~(np.isfinite(times) & np.isfinite(values)))[0]
        raise FitError(
            f"cannot fit non-finite samples: {bad.size} NaN/infinite values, first at "
            f"indices {bad[:5].tolist()}"
        )
    start = float(times[0]) if start_time is None else float(start_time)
    keep = times >= start
    times, values = times[keep], values[keep]
    if times.size <= parameter_count:
        raise FitError(
            f"need more than {parameter_count} samples after {start:g} s to fit "
            f"{parameter_count} parameters, got {times.size}"
        )
    if np.ptp(values) == 0:
        raise FitError("the response is constant: there is no step to fit")
    return times - start, values, start


def _first_order_guess(t: np.ndarray, y: np.ndarray) -> tuple[float, float, float]:
    final = float(np.mean(y[t >= 0.9 * t[-1]]))
    amplitude = final - float(y[0])
    if amplitude == 0:
        amplitude = final - float(y[np.argmax(np.abs(y - final))])
    progress = (y - (final - amplitude)) / amplitude
    reached = np.nonzero(progress >= 1.0 - math.exp(-1.0))[0]
    tau = float(t[reached[0]]) if reached.size and t[reached[0]] > 0 else 0.2 * t[-1]
    return final, amplitude, max(tau, t[1] - t[0] if t.size > 1 else 1e-6)


def _second_order_guess(t: np.ndarray, y: np.ndarray) -> tuple[float, float, float, float]:
    final, amplitude, tau = _first_order_guess(t, y)
    progress = (y - (final - amplitude)) / amplitude
    peak = int(np.argmax(progress))
    overshoot = float(progress[peak] - 1.0)
    if overshoot > 0.01 and t[peak] > 0:
        log_overshoot = -math.log(overshoot)
        damping = log_overshoot / math.hypot(math.pi, log_overshoot)
        frequency = math.pi / (t[peak] * math.sqrt(1.0 - damping * damping))
    else:
        damping, frequency = 0.9, 2.0 / tau
    return final, amplitude, frequency, damping


def _fit(
    model: str,
    t: np.ndarray,
    y: np.ndarray,
    start: float,
    guess: list[float],
    positive: list[int],
) -> StepFit:
    """Levenberg-Marquardt least squares; parameters listed in ``positive`` are fitted as
    logarithms, which keeps them positive without bounds."""
    function, names = _MODELS[model]
    is_positive = np.zeros(len(guess), dtype=bool)
    is_positive[positive] = True
    initial = np.asarray(guess, dtype=float)
    initial[is_positive] = np.log(np.maximum(np.abs(initial[is_positive]), 1e-9))

    def natural(unknowns: np.ndarray) -> np.ndarray:
        return np.where(is_positive, np.exp(np.where(is_positive, unknowns, 0.0)), unknowns)

    def residuals(unknowns: np.ndarray) -> np.ndarray:
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            values = function(t, *natural(unknowns)) - y
        return np.where(np.isfinite(values), values, 1e30)

    try:
        solution = least_squares(
            residuals, initial, method="lm", x_scale="jac", max_nfev=400 * len(guess)
        )
    except (ValueError, FloatingPointError) as error:
        raise FitError(f"{model} fit failed: {error}") from error
    parameters = natural(solution.x)
    if not solution.success or not np.all(np.isfinite(parameters)):
        raise FitError(f"{model} fit did not converge: {solution.message}")
    residual = solution.fun
    residual_sum = float(residual @ residual)
    total_sum = float(np.sum((y - y.mean()) ** 2))
    degrees_of_freedom = max(y.size - len(guess), 1)
    errors = _standard_errors(solution.jac, residual_sum / degrees_of_freedom)
    # d(parameter) = parameter * d(log parameter) for the log-fitted ones.
    errors = np.where(is_positive, errors * parameters, errors)
    return StepFit(
        model=model,
        parameters=MappingProxyType(dict(zip(names, map(float, parameters), strict=True))),
        standard_errors=MappingProxyType(dict(zip(names, map(float, errors), strict=True))),
        r_squared=1.0 - residual_sum / total_sum,
        residual_rms=math.sqrt(residual_sum / y.size),
        start_time=start,
        sample_count=int(y.size),
    )


def _standard_errors(jacobian: np.ndarray, residual_variance: float) -> np.ndarray:
    """sqrt(diag(s² (JᵀJ)⁻¹)) via the SVD; infinite for unidentifiable directions."""
    _, singular, vt = np.linalg.svd(jacobian, full_matrices=False)
    threshold = np.finfo(float).eps * max(jacobian.shape) * singular[0]
    if np.any(singular <= threshold):
        return np.full(jacobian.shape[1], np.inf)
    covariance = (vt.T / singular**2) @ vt * residual_variance
    return np.sqrt(np.diag(covariance))
