"""The one fit-result type of the package, and least-squares fits of step responses.

`FitResult` holds what every fit of the package returns (the step fits here, the friction,
input-pressure, equivalent-area and area-polynomial fits of `pneumaquad.identification`):
the fitted values keyed ``"name [unit]"``, their standard errors, R², the residual RMS and
its unit, the number of residuals, details, and the problems that make a fit untrustworthy
(its success flag and messages). `covariance_from_jacobian`, `r_squared` and
`check_standard_errors` are the statistics all of them share.

The step fits: first order, second order, and their sum.

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

import dataclasses
import math
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

__all__ = [
    "FIRST_ORDER",
    "FIRST_PLUS_SECOND_ORDER",
    "MAX_RELATIVE_STANDARD_ERROR",
    "SECOND_ORDER",
    "START_TIME",
    "FitError",
    "FitResult",
    "check_standard_errors",
    "covariance_from_jacobian",
    "evaluate_step_fit",
    "first_order_response",
    "fit_first_order",
    "fit_first_plus_second_order",
    "fit_second_order",
    "fit_step",
    "format_r_squared",
    "parameter_name_and_unit",
    "r_squared",
    "second_order_response",
]

FIRST_ORDER = "first order"
SECOND_ORDER = "second order"
FIRST_PLUS_SECOND_ORDER = "first + second order"

#: Damping ratios closer to 1 than this use the critically damped closed form.
_CRITICAL_DAMPING_TOLERANCE = 1e-6


class FitError(ValueError):
    """A step fit could not be made: unusable data or the optimiser did not converge."""


#: Largest standard error, as a share of the value, of a parameter `check_standard_errors`
#: accepts [-].
MAX_RELATIVE_STANDARD_ERROR = 0.25
_KEY_PATTERN = re.compile(r"^(?P<name>[^\[\]]+?)\s*\[(?P<unit>[^\[\]]+)\]$")


@dataclass(frozen=True)
class FitResult:
    """Outcome of one least-squares fit: the result type of every fit of the package.

    Attributes
    ----------
    name : str
        What was fitted, e.g. ``"coulomb-viscous friction"`` or, for a step fit, its model
        (`FIRST_ORDER`, `SECOND_ORDER`, `FIRST_PLUS_SECOND_ORDER`).
    parameters : Mapping of str to float
        Fitted values keyed ``"name [unit]"`` in SI, e.g. ``"coulomb_force [N]"``
        (``"-"`` for pure numbers; a step fit's levels, ``"final value"`` and the
        amplitudes, are in the unit of the fitted signal and carry no brackets).
    standard_errors : Mapping of str to float
        One-sigma standard errors, same keys; ``inf`` where not identifiable. They assume
        independent residuals, so for time series they are lower bounds.
    r_squared : float
        Coefficient of determination 1 - SS_res/SS_tot [-] (NaN where undefined).
    residual_rms : float
        Root-mean-square residual, in ``residual_unit``.
    n_points : int
        Number of residuals fitted.
    residual_unit : str
        Unit of the residuals (``"N"``, ``"Pa"``, ...; empty: the fitted signal's unit).
    details : Mapping of str to Any
        Extra information (initial values, which parameters were held, a step fit's
        ``"start time [s]"``, ...).
    problems : tuple of str
        Why the fit is not to be trusted, one sentence each naming the parameter (a
        standard error that says the data do not determine it, a value at a bound, large
        residuals); empty for a fit that passed its checks (see `failed`).
    """

    name: str
    parameters: Mapping[str, float]
    standard_errors: Mapping[str, float]
    r_squared: float
    residual_rms: float
    n_points: int
    residual_unit: str = ""
    details: Mapping[str, Any] = field(default_factory=dict)
    problems: tuple[str, ...] = ()

    @property
    def failed(self) -> bool:
        """True when the fit's own checks say its values are not to be trusted."""
        return bool(self.problems)

    def value(self, name: str) -> float:
        """Fitted value of a parameter by its name without the unit (``"coulomb_force"``).

        Keys without a ``[unit]`` (a step fit's levels) are matched as they are.
        """
        for key, value in self.parameters.items():
            match = _KEY_PATTERN.match(key.strip())
            if (match["name"] if match else key) == name:
                return value
        raise KeyError(f"{name!r} is not a parameter of the {self.name} fit")

    def rows(self) -> list[tuple[str, float, float]]:
        """(key, value, standard error) per parameter, for tables."""
        return [(key, value, self.standard_errors[key]) for key, value in self.parameters.items()]


def check_standard_errors(
    fit: FitResult, max_relative_error: float = MAX_RELATIVE_STANDARD_ERROR
) -> FitResult:
    """The fit with a problem added for each parameter the data do not determine.

    A parameter fails when its standard error is not finite or exceeds
    ``max_relative_error`` times its absolute value.

    Parameters
    ----------
    fit : FitResult
        Any fit.
    max_relative_error : float
        Largest acceptable standard error as a share of the value [-].

    Returns
    -------
    FitResult
        A copy with ``problems`` extended (the same object when nothing is added).
    """
    problems = []
    for key, value, error in fit.rows():
        if not (math.isfinite(error) and error <= max_relative_error * abs(value)):
            problems.append(
                f"{fit.name}: {key} = {value:.4g} has the standard error {error:.2g}, more "
                f"than {max_relative_error:.0%} of its value: the data do not determine it"
            )
    if not problems:
        return fit
    return dataclasses.replace(fit, problems=(*fit.problems, *problems))


def format_r_squared(value: float) -> str:
    """R² with four decimals, or ``"n/a"`` where it is not defined (NaN)."""
    return "n/a" if math.isnan(value) else f"{value:.4f}"


def parameter_name_and_unit(key: str) -> tuple[str, str]:
    """Split ``"coulomb_force [N]"`` into ``("coulomb_force", "N")``.

    Raises
    ------
    ValueError
        If the key has no ``[unit]`` suffix.
    """
    match = _KEY_PATTERN.match(key.strip())
    if match is None:
        raise ValueError(f"parameter key {key!r} should look like 'name [unit]'")
    return match["name"], match["unit"].strip()


def covariance_from_jacobian(jacobian: np.ndarray, residuals: np.ndarray) -> np.ndarray:
    """Parameter covariance s²·(JᵀJ)⁻¹ of a least-squares fit, via the SVD.

    Parameters
    ----------
    jacobian : numpy.ndarray
        d(residual)/d(parameter) at the solution, shape (n_residuals, n_parameters).
    residuals : numpy.ndarray
        Residuals at the solution; s² = SS_res / (n_residuals - n_parameters).

    Returns
    -------
    numpy.ndarray
        Covariance (n_parameters, n_parameters); all ``inf`` if J is rank deficient.
    """
    jacobian = np.atleast_2d(np.asarray(jacobian, dtype=float))
    count, unknowns = jacobian.shape
    residual_variance = float(residuals @ residuals) / max(count - unknowns, 1)
    _, singular, vt = np.linalg.svd(jacobian, full_matrices=False)
    threshold = np.finfo(float).eps * max(jacobian.shape) * (singular[0] if singular.size else 0)
    if singular.size < unknowns or np.any(singular <= threshold):
        return np.full((unknowns, unknowns), np.inf)
    return (vt.T / singular**2) @ vt * residual_variance


def r_squared(residuals: np.ndarray, observed: np.ndarray) -> float:
    """1 - SS_res/SS_tot [-] (NaN when the observations are constant)."""
    total = float(np.sum((observed - np.mean(observed)) ** 2))
    if total == 0.0:
        return math.nan
    return 1.0 - float(residuals @ residuals) / total


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


#: ``FitResult.details`` key of a step fit's t = 0 of the model [s]
START_TIME = "start time [s]"


def evaluate_step_fit(fit: FitResult, time: ArrayLike) -> np.ndarray:
    """A step fit's curve at absolute times ``time`` [s] (unit of the fitted signal).

    Parameters
    ----------
    fit : FitResult
        From `fit_first_order`, `fit_second_order`, `fit_first_plus_second_order` or
        `fit_step` (its ``name`` is the model, ``details["start time [s]"]`` its t = 0).
    time : array_like
        Absolute times [s].
    """
    function, names = _MODELS[fit.name]
    elapsed = np.asarray(time, dtype=float) - fit.details[START_TIME]
    return function(elapsed, *(fit.parameters[name] for name in names))


def fit_first_order(
    time: ArrayLike, response: ArrayLike, start_time: float | None = None
) -> FitResult:
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
    FitResult
        Parameters ``"final value"`` (K0), ``"amplitude"`` (A0), ``"time constant [s]"``;
        named after the model, ``details["start time [s]"]`` is the t0 used (evaluate the
        curve with `evaluate_step_fit`); ``residual_unit`` empty: the signal's unit.

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
) -> FitResult:
    """Fit a damped second-order step response (`second_order_response`).

    Returns
    -------
    FitResult
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
) -> FitResult:
    """Fit a first-order plus a second-order response, as for closed-loop steps (thesis l. 820).

    ``y = K - A1 · exp(-t/τ) - A2 · r2(t; ωn, ζ)`` where ``r2`` is one minus the unit step
    response of the standard second-order system. Several starting points are tried and the
    one with the smallest residual is kept.

    Returns
    -------
    FitResult
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
    best: FitResult | None = None
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
) -> FitResult:
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
) -> FitResult:
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
        from scipy.optimize import least_squares  # slow to import: loaded on first use

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
    errors = np.sqrt(np.diag(covariance_from_jacobian(solution.jac, residual)))
    # d(parameter) = parameter * d(log parameter) for the log-fitted ones.
    errors = np.where(is_positive, errors * parameters, errors)
    return FitResult(
        name=model,
        parameters=MappingProxyType(dict(zip(names, map(float, parameters), strict=True))),
        standard_errors=MappingProxyType(dict(zip(names, map(float, errors), strict=True))),
        r_squared=r_squared(residual, y),
        residual_rms=math.sqrt(residual_sum / y.size),
        n_points=int(y.size),
        details=MappingProxyType({START_TIME: start}),
    )
