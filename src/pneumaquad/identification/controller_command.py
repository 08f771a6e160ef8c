"""PID gains from a recorded valve command: linear least squares on the PID's own terms.

For a given derivative filter time constant τ_d and lag, the PID's command
(`pneumaquad.core.control.pid.pid_update`) is linear in its gains:

    u_k - u_0 = Kp·e_k + Ki·I_k - Kd·v_k,

with e_k = r_k - y_k the error on the position the controller saw (the recorded position
shifted by the lag, interpolated linearly where the lag is not a whole number of samples,
the first sample before the recording), I_k = Σ e_j·T the integral of the error and v_k
the measured rate: the difference of the shifted position over one sample through the
first-order filter v_k = v_{k-1} + T/(τ_d + T)·(raw_k - v_{k-1}), all as `pid_update`
computes them, at the recording's sample period T. The integral's anti-windup makes it
depend on the gains: the search freezes it where the recorded command sits at a valve
limit with the error pushing further; the final fit keeps it as the PID with the fitted
gains would (frozen where its output would pass a limit, clamped to ±integral_limit) and
fits again until the gains no longer change.

The lag is searched in whole controller periods T_c (the parameter set's control step),
from one: a command can only have been computed at a controller tick, and a recorded
command is held over the period before its time stamp (the importer's and the
simulator's convention), so it was computed at the start of that period at the latest.
At T = T_c this is the controller's arithmetic exactly. A recording slower than the loop
(a 1 kHz loop logged at 500 Hz) is reconstructed as if the loop had run at T: the rate is
a difference over T, half a sample later on average than the controller's over T_c, the
filter and the sum run at T, and the command of a row was computed half a sample before
it, which a lag of one T_c expresses. The rate's extra half sample, (T - T_c)/2, adds to
the filter's delay (τ_d at DC, at any rate): the τ_d fitted at T is that much shorter,
and is given back with it added. docs/analysis.md gives what the rest costs.

Samples whose recorded command sits at a valve limit are left out of the regression (a
saturated command carries no information on the gains), and so is the first
`START_EXCLUDED` of each recording (the controller's state before the first row is not
known: its filtered rate, and the positions a lag reaches back to). Every lag is tried on
a grid of τ_d, then τ_d is refined by a bounded scalar search at the three best lags; the
standard errors come from the regression's Jacobian, with τ_d's column by finite
differences.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

import numpy as np
from scipy import optimize, signal

from pneumaquad.analysis.fits import (
    FitResult,
    check_standard_errors,
    covariance_from_jacobian,
    r_squared,
)
from pneumaquad.params.schema import RigSetup

from .controller_data import (
    FILTER_KEY,
    GAIN_KEYS,
    OFFSET_KEY,
    ClosedLoopRecording,
    ControllerFit,
    delay_from_lag,
)
from .preprocess import IdentificationError

__all__ = [
    "FILTER_GRID",
    "fit_pid_from_command",
    "pid_regressors",
    "shifted",
]

#: Derivative filter time constants tried first [s]; the best is refined between its
#: neighbours.
FILTER_GRID = (0.0, 2e-4, 5e-4, 1e-3, 2e-3, 3e-3, 5e-3, 7e-3, 1e-2, 1.5e-2, 2e-2, 3e-2,
               5e-2, 0.1)
#: Distance from a valve limit that counts as saturated, as a share of the valve's range
#: [-] (0.1 V of 0-10 V: a logged command carries noise; a sample that only passes
#: through the band is lost, one held at the limit must not be taken for a free one).
SATURATION_BAND = 0.01
#: Lags at which τ_d is refined after the grid.
REFINED_LAGS = 3
#: Least share of the command's variance the PID must explain [-].
MIN_R_SQUARED = 0.95
#: Start of each recording left out of the regression [s]: the controller's state when
#: the recording began (its filtered rate, the positions before the first row) is unknown.
START_EXCLUDED = 0.05
#: Times the integral is kept again with the latest gains (`_Regression.solve_consistent`).
_CLAMP_ITERATIONS = 20


def shifted(values: np.ndarray, samples: float) -> np.ndarray:
    """``values`` delayed by ``samples`` (≥ 0, a fraction allowed) [-]: linear
    interpolation between rows, the first value before the recording starts."""
    whole = math.floor(samples)
    fraction = samples - whole
    padded = np.concatenate([np.full(whole + 1, values[0]), values])
    later = padded[1:values.size + 1]  # values[k - whole]
    if fraction == 0.0:
        return later.copy()
    earlier = padded[:values.size]  # values[k - whole - 1]
    return (1.0 - fraction) * later + fraction * earlier


def _pid_integral(error: np.ndarray, period: float, free_output: np.ndarray,
                  integral_gain: float, limits: tuple[float, float],
                  integral_limit: float) -> np.ndarray:
    """The integral term [V] as `pid_update` keeps it: the candidate I + Ki·e·T clamped
    to ±``integral_limit`` [V], kept unless the output with it, ``free_output`` [V] (the
    command without the integral) plus the candidate, passes a valve limit with the error
    pushing further."""
    low, high = limits
    total = 0.0
    out = np.empty(error.size)
    steps = (integral_gain * period * error).tolist()
    for k, (step, free, e) in enumerate(zip(steps, free_output.tolist(), error.tolist(),
                                            strict=True)):
        candidate = min(max(total + step, -integral_limit), integral_limit)
        output = free + candidate
        if not ((output > high and e > 0.0) or (output < low and e < 0.0)):
            total = candidate
        out[k] = total
    return out


def pid_regressors(recording: ClosedLoopRecording, lag: float, filter_time_constant: float,
                   limits: tuple[float, float], gains: Sequence[float] | None = None,
                   integral_limit: float = math.inf) -> np.ndarray:
    """The PID's terms per sample, as `pid_update` forms them, at the recording's rate.

    Parameters
    ----------
    recording : ClosedLoopRecording
        With its command.
    lag : float
        From the position the command was computed from to the command's time stamp [s].
    filter_time_constant : float
        Derivative filter τ_d [s].
    limits : (float, float)
        Valve limits [V].
    gains : (Kp, Ki, Kd, u_0), optional
        Gains [V/m, V/(m s), V s/m] and offset [V] to keep the integral with, as
        `pid_update` does (frozen where the output with it would pass a limit with the
        error pushing further, clamped to ±``integral_limit``). Without them the integral
        is frozen where the recorded command sits at a limit (within `SATURATION_BAND`)
        with the error pushing further, and not clamped.
    integral_limit : float
        The integral clamp [V].

    Returns
    -------
    numpy.ndarray (samples, 3)
        Columns e [m], Σe·T [m s] (the integral term over Ki) and -v [m/s]: the command
        is u_0 + [Kp, Ki, Kd] · row.
    """
    period = recording.period
    seen = shifted(recording.position, lag / period)
    before = shifted(recording.position, lag / period + 1.0)
    error = recording.reference - seen
    raw_rate = (seen - before) / period
    blend = period / (filter_time_constant + period)
    rate = signal.lfilter([blend], [1.0, blend - 1.0], raw_rate)
    low, high = limits
    if gains is not None and gains[1] > 0.0:
        kp, ki, kd, offset = gains
        free = offset + kp * error - kd * rate
        integral = _pid_integral(error, period, free, ki, limits, integral_limit) / ki
    else:
        band = SATURATION_BAND * (high - low)
        command = recording.command
        frozen = ((command >= high - band) & (error > 0.0)) | (
            (command <= low + band) & (error < 0.0))
        integral = np.cumsum(np.where(frozen, 0.0, error * period))
    return np.column_stack([error, integral, -rate])


class _Regression:
    """The stacked regression of several recordings for one (lag, τ_d)."""

    def __init__(self, recordings: Sequence[ClosedLoopRecording], setup: RigSetup,
                 fit_offset: bool) -> None:
        valve = setup.actuator.valve
        self.recordings = recordings
        self.limits = (valve.min_voltage, valve.max_voltage)
        self.offset = valve.offset_voltage
        self.fit_offset = fit_offset
        self.integral_limit = setup.controller.integral_limit
        commands = np.concatenate([r.command for r in recordings])
        settled = np.concatenate([r.time - r.time[0] >= START_EXCLUDED for r in recordings])
        band = SATURATION_BAND * (valve.max_voltage - valve.min_voltage)
        self.used = settled & (commands > valve.min_voltage + band) & (
            commands < valve.max_voltage - band)
        self.target = (commands - (0.0 if fit_offset else self.offset))[self.used]

    def columns(self, lag: float, tau: float,
                coefficients: np.ndarray | None = None) -> np.ndarray:
        """The regression's columns; with ``coefficients`` the integral kept as the PID
        with those gains keeps it."""
        gains = None
        if coefficients is not None:
            offset = coefficients[3] if self.fit_offset else self.offset
            gains = (*coefficients[:3], offset)
        blocks = [pid_regressors(r, lag, tau, self.limits, gains, self.integral_limit)
                  for r in self.recordings]
        terms = np.concatenate(blocks)[self.used]
        if self.fit_offset:
            terms = np.column_stack([terms, np.ones(terms.shape[0])])
        return terms

    def solve(self, lag: float, tau: float,
              coefficients: np.ndarray | None = None) -> tuple[np.ndarray, float]:
        terms = self.columns(lag, tau, coefficients)
        solution, *_ = np.linalg.lstsq(terms, self.target, rcond=None)
        residual = self.target - terms @ solution
        return solution, float(residual @ residual)

    def solve_consistent(self, lag: float, tau: float) -> np.ndarray:
        """Coefficients whose own PID keeps the integral of the regression (freeze and
        clamp), by fixed-point iteration from the band rule."""
        coefficients, _ = self.solve(lag, tau)
        for _ in range(_CLAMP_ITERATIONS):
            updated, _ = self.solve(lag, tau, coefficients)
            if np.allclose(updated, coefficients, rtol=1e-10, atol=0.0):
                return updated
            coefficients = updated
        return coefficients


def _best_filter(regression: _Regression, lag: float, grid: Sequence[float]) -> tuple[float, float]:
    """(τ_d, SSR): the best of ``grid``, refined between its neighbours."""
    costs = [regression.solve(lag, tau)[1] for tau in grid]
    best = int(np.argmin(costs))
    if len(grid) == 1:
        return grid[0], costs[0]
    low = grid[max(best - 1, 0)]
    high = grid[min(best + 1, len(grid) - 1)]
    found = optimize.minimize_scalar(lambda tau: regression.solve(lag, tau)[1],
                                     bounds=(low, high), method="bounded",
                                     options={"xatol": 1e-6})
    if found.fun < costs[best]:
        return float(found.x), float(found.fun)
    return grid[best], costs[best]


def _search_lag(regression: _Regression, lags: Sequence[float],
                grid: Sequence[float]) -> tuple[float, float, dict[float, float]]:
    """(lag [s], τ_d [s], residual sum of squares per lag on the τ_d grid [V^2]): every
    lag on the τ_d grid, then τ_d refined at the three best lags (a grid point far from
    a lag's own τ_d could favour its neighbour), the best of those."""
    table = {lag: min(regression.solve(lag, tau)[1] for tau in grid) for lag in lags}
    finalists = sorted(table, key=table.__getitem__)[:REFINED_LAGS]
    refined = {lag: _best_filter(regression, lag, grid) for lag in finalists}
    best = min(refined, key=lambda lag: refined[lag][1])
    return best, refined[best][0], table


def fit_pid_from_command(
    recordings: Sequence[ClosedLoopRecording],
    setup: RigSetup,
    *,
    fit_filter: bool = True,
    delay: float | None = None,
    max_delay: float = 0.05,
    fit_offset: bool = False,
) -> ControllerFit:
    """Identify the PID from recordings with the valve command (the command method).

    Parameters
    ----------
    recordings : sequence of ClosedLoopRecording
        With commands, all at one sample period.
    setup : RigSetup
        Gives the valve offset and limits, the integral clamp, the controller period
        (``simulation.control_step``) and the filter time constant held when it is not
        fitted.
    fit_filter : bool
        Search the derivative filter time constant (held at the set's value where the
        data do not determine it); False holds it.
    delay : float, optional
        Measurement delay [s] to assume; None searches 0 … ``max_delay``.
    max_delay : float
        Longest delay searched [s].
    fit_offset : bool
        Fit the valve offset (it then also absorbs an integral that was not zero when
        the recording began) instead of taking the set's.

    Returns
    -------
    ControllerFit

    Raises
    ------
    IdentificationError
        No command column, different sample periods, or fewer unsaturated samples than
        unknowns.
    """
    if any(r.command is None for r in recordings):
        raise IdentificationError("the command method needs the valve command (column "
                                  "'command [V]') in every recording")
    period = recordings[0].period
    if any(abs(r.period - period) > 1e-3 * period for r in recordings):
        raise IdentificationError(
            "the recordings have different sample periods "
            f"({sorted({round(r.period, 9) for r in recordings})} s); fit them separately")
    control_step = setup.simulation.control_step
    regression = _Regression(recordings, setup, fit_offset)
    unknowns = 4 + int(fit_offset)
    if regression.target.size <= 4 * unknowns:
        raise IdentificationError(
            f"only {regression.target.size} samples have a command inside the valve's "
            "range: the recording is saturated almost throughout")
    tau_held = setup.controller.derivative_filter_time_constant
    # the rate's difference over one sample lags the controller's over T_c by (T - T_c)/2,
    # which the filter's delay (its τ_d) takes up: τ_d at the recording's rate is shorter
    same_rate = math.isclose(period, control_step, rel_tol=1e-3)
    shift = 0.0 if same_rate else 0.5 * (period - control_step)
    reconstructed_held = max(tau_held - shift, 0.0)
    grid = FILTER_GRID if fit_filter else (reconstructed_held,)
    if delay is None:
        lags = [i * control_step for i in range(1, round(max_delay / control_step) + 2)]
    else:
        lags = [(1 + round(delay / control_step)) * control_step]
    lag, tau, table = _search_lag(regression, lags, grid)
    notes = []
    estimate = _estimate(regression, lag, tau, fit_filter)
    if fit_filter and not _filter_determined(estimate, period):
        notes.append(_filter_note(estimate, tau_held))
        fit_filter = False
        estimate = _estimate(regression, lag, reconstructed_held, False)
    measurement_delay = delay_from_lag(lag, control_step) if delay is None else (
        round(delay / control_step) * control_step)
    if not same_rate:
        notes.append(
            f"the recording's sample period {period * 1e3:.4g} ms differs from the "
            f"controller period {control_step * 1e3:.4g} ms of the parameter set: the "
            "integral and the filter are reconstructed at the recording's rate")
    if fit_filter and not same_rate:
        corrected = max(tau + shift, 0.0)
        notes.append(
            f"τ_d at the recording's rate is {tau * 1e3:.4g} ms; its rate, a difference over "
            f"one sample, lags the controller's by (T - T_c)/2 = {shift * 1e3:.3g} ms more, "
            f"so the controller's τ_d is {corrected * 1e3:.4g} ms")
        estimate = dataclasses.replace(
            estimate, parameters={**estimate.parameters, FILTER_KEY: corrected})
        tau = corrected
    fit = _with_checks(estimate)
    return ControllerFit(
        fit=fit, method="command",
        filter_time_constant=float(tau if fit_filter else tau_held),
        filter_fitted=FILTER_KEY in fit.parameters, measurement_delay=measurement_delay,
        delay_fitted=delay is None, lag=float(lag), sample_period=period,
        control_step=control_step, notes=tuple(notes),
        details={"residual per lag [V^2]": {f"{k * 1e3:.4g} ms": v for k, v in table.items()},
                 "samples used": int(regression.target.size)})


def _estimate(regression: _Regression, lag: float, tau: float, with_filter: bool) -> FitResult:
    """The regression at (lag, τ_d) with the clamp, its statistics and standard errors
    (τ_d's Jacobian column by central differences when ``with_filter``)."""
    coefficients = regression.solve_consistent(lag, tau)
    terms = regression.columns(lag, tau, coefficients)
    residual = regression.target - terms @ coefficients
    jacobian = terms
    keys = list(GAIN_KEYS) + ([OFFSET_KEY] if regression.fit_offset else [])
    values = list(coefficients)
    if with_filter:
        step = max(1e-3 * tau, 1e-3 * regression.recordings[0].period)
        low = max(tau - step, 0.0)
        high = tau + step
        shift_low = regression.columns(lag, low, coefficients) @ coefficients
        shift_high = regression.columns(lag, high, coefficients) @ coefficients
        jacobian = np.column_stack([terms, (shift_high - shift_low) / (high - low)])
        keys.append(FILTER_KEY)
        values.append(tau)
    covariance = covariance_from_jacobian(jacobian, residual)
    errors = np.sqrt(np.abs(np.diag(covariance)))
    return FitResult(
        name="PID from the valve command",
        parameters={key: float(value) for key, value in zip(keys, values, strict=True)},
        standard_errors={key: float(error) for key, error in zip(keys, errors, strict=True)},
        r_squared=r_squared(residual, regression.target),
        residual_rms=float(np.sqrt(np.mean(residual**2))),
        n_points=int(residual.size),
        residual_unit="V",
        details={"lag [s]": lag},
    )


def _filter_determined(estimate: FitResult, period: float) -> bool:
    """Whether the data pin τ_d: below the longest one searched, with a finite standard
    error below a quarter of τ_d or of the sample period, whichever is larger."""
    tau = estimate.parameters[FILTER_KEY]
    error = estimate.standard_errors[FILTER_KEY]
    return (tau < FILTER_GRID[-1] * (1.0 - 1e-6) and math.isfinite(error)
            and error <= 0.25 * max(tau, period))


def _filter_note(estimate: FitResult, held: float) -> str:
    tau = estimate.parameters[FILTER_KEY]
    error = estimate.standard_errors[FILTER_KEY]
    return (f"the data do not determine the derivative filter (τ_d = {tau * 1e3:.3g} ± "
            f"{error * 1e3:.2g} ms): held at the parameter set's {held * 1e3:.3g} ms")


def _with_checks(estimate: FitResult) -> FitResult:
    """The fit with its problems: gains (and a fitted offset) the data do not determine,
    and a command the PID does not explain."""
    checked_keys = [key for key in estimate.parameters if key != FILTER_KEY]
    subset = FitResult(estimate.name, {k: estimate.parameters[k] for k in checked_keys},
                       {k: estimate.standard_errors[k] for k in checked_keys},
                       estimate.r_squared, estimate.residual_rms, estimate.n_points)
    problems = list(check_standard_errors(subset).problems)
    problems += [f"{estimate.name}: {key} = {estimate.parameters[key]:.4g} is negative: the "
                 "controller has no such term, or it is not this PID"
                 for key in GAIN_KEYS if estimate.parameters[key] < 0.0]
    if not estimate.r_squared >= MIN_R_SQUARED:
        problems.append(
            f"{estimate.name}: the PID explains {estimate.r_squared:.1%} of the command's "
            f"variance (less than {MIN_R_SQUARED:.0%}): the controller is not this PID, or "
            "the columns do not belong together")
    return FitResult(estimate.name, estimate.parameters, estimate.standard_errors,
                     estimate.r_squared, estimate.residual_rms, estimate.n_points,
                     estimate.residual_unit, estimate.details, tuple(problems))
