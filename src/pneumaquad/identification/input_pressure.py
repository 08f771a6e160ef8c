"""Input-pressure curves of the underlapped valve from fixed-piston tests (thesis 4.2.3).

With the piston held (the rig's spacer), each chamber settles at the input pressure its
valve port presents, so the settled pressures against the centered voltage trace the
tanh curves of eq 4.2.7-4.2.11 (Fig. 23). The library's model
(`pneumaquad.core.physics.valve.input_pressure`, array form `pneumaquad.core.valve_fit`) holds
supply and exhaust pressure and has two shape parameters per port: the high and low
pressure cutoffs C_HP and C_LP.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from pneumaquad.analysis.fits import FitResult, covariance_from_jacobian, r_squared
from pneumaquad.core.valve_fit import input_pressure
from pneumaquad.params.schema import RigSetup

from .preprocess import IdentificationError

__all__ = [
    "InputPressureCurves",
    "SteadyStatePoints",
    "chamber_port_numbers",
    "fit_input_pressure_curve",
    "input_pressure_curves",
    "steady_state_points",
]


def chamber_port_numbers(setup: RigSetup) -> tuple[int, int]:
    """(port feeding the cap chamber, port feeding the rod chamber), per ``valve.cap_port``."""
    cap = setup.actuator.valve.cap_port
    return cap, 3 - cap


def _centered(setup: RigSetup, command: ArrayLike) -> np.ndarray:
    valve = setup.actuator.valve
    saturated = np.clip(np.asarray(command, dtype=float), valve.min_voltage, valve.max_voltage)
    return saturated - valve.offset_voltage


@dataclass(frozen=True)
class SteadyStatePoints:
    """Settled chamber pressures of constant-command segments.

    Attributes
    ----------
    centered_voltage : numpy.ndarray
        [V].
    cap_pressure, rod_pressure : numpy.ndarray
        Mean absolute pressures over each segment's tail [Pa].
    cap_drift, rod_drift : numpy.ndarray
        Pressure change over the tail [Pa]; large values mean not yet settled.
    """

    centered_voltage: np.ndarray
    cap_pressure: np.ndarray
    rod_pressure: np.ndarray
    cap_drift: np.ndarray
    rod_drift: np.ndarray


def steady_state_points(
    recordings: Iterable[Mapping[str, np.ndarray]],
    setup: RigSetup,
    *,
    tail_fraction: float = 0.25,
    command_threshold: float = 0.05,
    min_samples: int = 20,
) -> SteadyStatePoints:
    """Steady-state pressures per held command, from fixed-piston recordings.

    Each recording may hold one voltage or a staircase; every constant-command segment
    of at least ``min_samples`` samples gives a point, the mean over its last
    ``tail_fraction``.

    Parameters
    ----------
    recordings : iterable of mapping
        Columns ``"command [V]"``, ``"cap pressure [Pa]"``, ``"rod pressure [Pa]"``,
        ``"time [s]"``.
    setup : RigSetup
        Valve offset and voltage range.
    tail_fraction : float
        Share of each segment averaged, in (0, 1].
    command_threshold : float
        Smallest command jump that starts a new segment [V].
    min_samples : int
        Shorter segments are skipped.

    Returns
    -------
    SteadyStatePoints

    Raises
    ------
    IdentificationError
        For missing columns or no usable segment.
    """
    if not 0.0 < tail_fraction <= 1.0:
        raise IdentificationError(f"tail_fraction must be in (0, 1], got {tail_fraction!r}")
    rows: list[tuple[float, float, float, float, float]] = []
    for recording in recordings:
        missing = [
            name
            for name in ("time [s]", "command [V]", "cap pressure [Pa]", "rod pressure [Pa]")
            if name not in recording
        ]
        if missing:
            raise IdentificationError(f"a spacer recording lacks the columns {missing}")
        command = np.asarray(recording["command [V]"], dtype=float)
        jumps = np.nonzero(np.abs(np.diff(command)) > command_threshold)[0] + 1
        bounds = [0, *jumps.tolist(), command.size]
        for first, last in itertools.pairwise(bounds):
            if last - first < min_samples:
                continue
            tail = slice(last - max(2, round(tail_fraction * (last - first))), last)
            pressures = [
                np.asarray(recording[name], dtype=float)[tail]
                for name in ("cap pressure [Pa]", "rod pressure [Pa]")
            ]
            halves = [np.array_split(values, 2) for values in pressures]
            rows.append(
                (
                    float(_centered(setup, np.median(command[first:last]))),
                    float(np.mean(pressures[0])),
                    float(np.mean(pressures[1])),
                    float(np.mean(halves[0][1]) - np.mean(halves[0][0])) * 2.0,
                    float(np.mean(halves[1][1]) - np.mean(halves[1][0])) * 2.0,
                )
            )
    if not rows:
        raise IdentificationError("no constant-command segment long enough in the recordings")
    columns = np.array(rows).T
    return SteadyStatePoints(*columns)


#: Largest standard error of a fitted cutoff before the fit counts as failed [V].
MAX_CUTOFF_ERROR = 0.05
#: Largest RMS residual of an input-pressure fit, as a share of supply - exhaust [-].
MAX_PRESSURE_RESIDUAL = 0.01
#: Largest pressure drift over a held voltage's averaged tail, share of supply - exhaust.
MAX_SETTLING_DRIFT = 0.01
#: A point lies in a curve's transition when it is this share of the span off both plateaus.
_PLATEAU_MARGIN = 0.02


def _curve_starts(voltages: np.ndarray) -> list[tuple[float, float]]:
    """Candidate (centre [V], log width [log V]) starts covering the data's voltage range.

    Centres at every held voltage and half-way between neighbours; widths from 0.05 V to
    four times the voltage range. One start is not enough: a start whose curve is steep
    next to the data leaves every point on a plateau, where the residuals do not depend on
    the width, and least squares stops there (the failure of a single start on a spacer
    sweep that reaches only one plateau of a port).
    """
    held = np.unique(voltages)
    centres = np.concatenate([held, 0.5 * (held[1:] + held[:-1])])
    widest = max(4.0 * float(np.ptp(held)), 4.0)
    widths = np.geomspace(0.05, widest, 12)
    return [(float(c), math.log(w)) for c in centres for w in widths]


def fit_input_pressure_curve(
    centered_voltages: ArrayLike,
    pressures: ArrayLike,
    supply_pressure: float,
    exhaust_pressure: float,
    *,
    port: int | None = None,
    max_cutoff_error: float = MAX_CUTOFF_ERROR,
    max_residual: float = MAX_PRESSURE_RESIDUAL,
) -> FitResult:
    """Least squares of the input-pressure curve, eq 4.2.7-4.2.11, for one port.

    Supply and exhaust pressure are held; the unknowns are the curve's centre and log
    width, so the cutoffs never coincide; the slope sign (supply at positive or negative
    voltage) is taken from the data. The fit starts from the best of a grid of centres and
    widths (`_curve_starts`), so a data set that reaches only one plateau of the port does
    not leave it stuck at a steep first guess. Standard errors of the cutoffs follow by
    the delta method.

    The fit checks itself: a cutoff whose standard error is not finite or exceeds
    ``max_cutoff_error``, an RMS residual above ``max_residual`` times Ps - Pe, or no
    convergence is listed in ``FitResult.problems`` (the values are then not to be used),
    and so are fewer than two points in the curve's transition (more than 2 % of the span
    off both plateaus): one such point and points on the plateaus fit a whole family of
    centres and widths, whatever the standard errors say.

    Parameters
    ----------
    centered_voltages : array_like
        [V].
    pressures : array_like
        Steady-state absolute pressures [Pa].
    supply_pressure, exhaust_pressure : float
        Absolute [Pa].
    port : int, optional
        Valve port number, named in the result and its problems.
    max_cutoff_error : float
        Largest acceptable standard error of a cutoff [V].
    max_residual : float
        Largest acceptable RMS residual as a share of supply - exhaust pressure [-].

    Returns
    -------
    FitResult
        ``"high_pressure_cutoff [V]"``, ``"low_pressure_cutoff [V]"``; named
        ``"input-pressure curve, port N"``; ``details["transition_points"]`` counts the
        points more than 2 % of the span off both plateaus.

    Raises
    ------
    IdentificationError
        With fewer than three points.
    """
    u = np.asarray(centered_voltages, dtype=float).ravel()
    p = np.asarray(pressures, dtype=float).ravel()
    if u.shape != p.shape or u.size < 3:
        raise IdentificationError("need at least three (voltage, pressure) pairs of equal length")
    span = supply_pressure - exhaust_pressure
    direction = float(np.sign(np.sum((u - u.mean()) * (p - p.mean())))) or 1.0
    label = "input-pressure curve" + (f", port {port}" if port is not None else "")
    who = f"port {port}" if port is not None else "input-pressure curve"

    def cutoffs(unknowns: np.ndarray) -> tuple[float, float]:
        half_width = 0.5 * math.exp(unknowns[1])
        return unknowns[0] + direction * half_width, unknowns[0] - direction * half_width

    def residuals(unknowns: np.ndarray) -> np.ndarray:
        return input_pressure(u, supply_pressure, exhaust_pressure, *cutoffs(unknowns)) - p

    starts = sorted(
        _curve_starts(u), key=lambda start: float(np.sum(residuals(np.array(start)) ** 2))
    )
    from scipy.optimize import least_squares  # SciPy loads on first use: it is slow to import

    solution = min(
        (least_squares(residuals, start, x_scale=[1.0, 1.0]) for start in starts[:3]),
        key=lambda candidate: candidate.cost,
    )
    high, low = cutoffs(solution.x)
    half_width = 0.5 * math.exp(solution.x[1])
    gradient = np.array([[1.0, direction * half_width], [1.0, -direction * half_width]])
    with np.errstate(invalid="ignore"):
        covariance = gradient @ covariance_from_jacobian(solution.jac, solution.fun) @ gradient.T
    errors = np.sqrt(np.abs(np.diag(covariance)))
    errors[~np.isfinite(errors)] = math.inf
    keys = ("high_pressure_cutoff [V]", "low_pressure_cutoff [V]")
    residual_rms = math.sqrt(float(solution.fun @ solution.fun) / p.size)
    off_plateaus = np.minimum(p - exhaust_pressure, supply_pressure - p) > _PLATEAU_MARGIN * span
    transition = int(np.count_nonzero(off_plateaus))
    coverage = (
        f"{transition} of {p.size} held voltages lie between the supply and exhaust "
        f"plateaus (voltages {np.array2string(np.sort(u), precision=2, separator=', ')} V); "
        f"hold voltages across the port's transition"
    )
    problems = []
    if transition < 2:
        problems.append(
            f"{who}: the two cutoffs need at least two held voltages in the transition "
            f"(more than {_PLATEAU_MARGIN:.0%} of the span off both plateaus); {coverage}"
        )
    if not solution.success:
        problems.append(f"{who}: the input-pressure fit did not converge ({solution.message})")
    for key, error in zip(keys, errors, strict=True):
        name = key.split(" [")[0]
        if not math.isfinite(error) or error > max_cutoff_error:
            problems.append(
                f"{who} {name}: standard error {error:.2g} V exceeds {max_cutoff_error:g} V, "
                f"so the data do not determine it; {coverage}"
            )
    if residual_rms > max_residual * span:
        problems.append(
            f"{who}: RMS residual {residual_rms:.4g} Pa exceeds {max_residual:.0%} of "
            f"supply - exhaust ({max_residual * span:.4g} Pa): the tanh curve of eq 4.2.7 "
            "does not describe the settled pressures (unsettled data, or wrong supply or "
            "exhaust pressure in the parameters?)"
        )
    return FitResult(
        name=label,
        parameters={keys[0]: float(high), keys[1]: float(low)},
        standard_errors={keys[0]: float(errors[0]), keys[1]: float(errors[1])},
        r_squared=r_squared(solution.fun, p),
        residual_rms=residual_rms,
        n_points=int(p.size),
        residual_unit="Pa",
        details={"transition_points": transition, "port": port},
        problems=tuple(problems),
    )


@dataclass(frozen=True)
class InputPressureCurves:
    """Fitted input-pressure curves of both ports and the points behind them.

    Attributes
    ----------
    points : SteadyStatePoints
    fits : dict of int to FitResult
        Per valve port number (1, 2).
    """

    points: SteadyStatePoints
    fits: dict[int, FitResult]


def input_pressure_curves(
    recordings: Iterable[Mapping[str, np.ndarray]],
    setup: RigSetup,
    *,
    tail_fraction: float = 0.25,
    command_threshold: float = 0.05,
    max_cutoff_error: float = MAX_CUTOFF_ERROR,
    max_residual: float = MAX_PRESSURE_RESIDUAL,
    max_drift: float = MAX_SETTLING_DRIFT,
) -> InputPressureCurves:
    """Fit both ports' tanh input-pressure curves from fixed-piston recordings.

    The cap chamber's settled pressure is its port's input pressure (port
    ``valve.cap_port``), the rod chamber's that of the other port (thesis 4.2.3, Fig. 23).
    Besides the checks of `fit_input_pressure_curve`, a held voltage whose chamber
    pressure still drifts by more than ``max_drift`` times Ps - Pe over its averaged tail
    is a problem of that port's fit (hold longer).

    Parameters
    ----------
    recordings : iterable of mapping
        Fixed-piston (spacer) recordings at held commands, long enough to settle.
    setup : RigSetup
        Supply, exhaust, valve offset and range, port assignment.
    tail_fraction, command_threshold : float
        See `steady_state_points`.
    max_cutoff_error, max_residual : float
        See `fit_input_pressure_curve` [V], [-].
    max_drift : float
        Largest acceptable drift over a tail, share of supply - exhaust pressure [-].

    Returns
    -------
    InputPressureCurves
        Fits named ``"input-pressure curve, port N (cap|rod chamber)"``.
    """
    points = steady_state_points(
        recordings, setup, tail_fraction=tail_fraction, command_threshold=command_threshold
    )
    supply = setup.actuator.supply
    span = supply.supply_pressure - supply.exhaust_pressure
    cap_port, rod_port = chamber_port_numbers(setup)
    fits = {}
    for port, chamber, values, drift in (
        (cap_port, "cap", points.cap_pressure, points.cap_drift),
        (rod_port, "rod", points.rod_pressure, points.rod_drift),
    ):
        fit = fit_input_pressure_curve(
            points.centered_voltage,
            values,
            supply.supply_pressure,
            supply.exhaust_pressure,
            port=port,
            max_cutoff_error=max_cutoff_error,
            max_residual=max_residual,
        )
        unsettled = [
            f"port {port}: the {chamber} pressure at {voltage:+.3f} V still drifts by "
            f"{change / 1e3:+.3g} kPa over the averaged tail (limit {max_drift:.0%} of supply "
            f"- exhaust, {max_drift * span / 1e3:.3g} kPa): hold each voltage longer"
            for voltage, change in zip(points.centered_voltage, drift, strict=True)
            if abs(change) > max_drift * span
        ]
        fits[port] = dataclasses.replace(
            fit,
            name=f"input-pressure curve, port {port} ({chamber} chamber)",
            details={**fit.details, "chamber": chamber},
            problems=(*fit.problems, *unsettled),
        )
    return InputPressureCurves(points, dict(sorted(fits.items())))
