"""Valve identification for the underlapped valve model (thesis 4.2.3, App. B.2).

Three steps, as in the thesis:

1. Input-pressure curves from fixed-piston (spacer) tests: with the piston held, each
   chamber settles at its port's input pressure, so the steady-state pressures against
   the centered voltage give the tanh curves of eq 4.2.7-4.2.11. The library model
   (`pneumaquad.physics.valve.input_pressure`) has supply and exhaust pressure fixed and
   two shape parameters per port: the high and low pressure cutoffs C_HP, C_LP.
2. Equivalent orifice areas: for each open-loop step at a voltage u the thesis hand-tuned
   a discharge coefficient until simulated pressures and position matched. Here the areas
   at u are fitted by bounded least squares around the rig simulator.
3. Fourth-order polynomials through the areas, one per port and side of the offset
   (`pneumaquad.valve_fit`, App. B.2).

Voltages called *centered* are measured from the valve offset, after saturation.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import least_squares

from pneumaquad.params.schema import RigSetup
from pneumaquad.physics.valve import centered_voltage
from pneumaquad.rig.simulate import simulate_rig
from pneumaquad.valve_fit import (
    evaluate_equivalent_area,
    fit_equivalent_area_polynomials,
    input_pressure,
)

from .preprocess import FilterSettings, IdentificationError, prepare_signals, select_step
from .report import FitResult, covariance_from_jacobian, r_squared

__all__ = [
    "AREA_MODES",
    "AreaPolynomials",
    "EquivalentAreaFit",
    "InputPressureCurves",
    "SteadyStatePoints",
    "area_polynomial_updates",
    "chamber_port_numbers",
    "equivalent_area_for_step",
    "fit_area_polynomials",
    "fit_input_pressure_curve",
    "input_pressure_curves",
    "steady_state_points",
]

#: Parametrisations of `equivalent_area_for_step`.
AREA_MODES = ("per_port", "scale")
_MIN_AREA, _MAX_AREA = 1e-11, 1e-4  # bounds of a fitted equivalent area [m^2]


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
        for first, last in zip(bounds[:-1], bounds[1:], strict=True):
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


def fit_input_pressure_curve(
    centered_voltages: ArrayLike,
    pressures: ArrayLike,
    supply_pressure: float,
    exhaust_pressure: float,
) -> FitResult:
    """Least squares of the input-pressure curve, eq 4.2.7-4.2.11, for one port.

    Supply and exhaust pressure are held; the unknowns are the curve's centre and log
    width, so the cutoffs never coincide; the slope sign (supply at positive or negative
    voltage) is taken from the data. Standard errors of the cutoffs follow by the delta
    method.

    Parameters
    ----------
    centered_voltages : array_like
        [V].
    pressures : array_like
        Steady-state absolute pressures [Pa].
    supply_pressure, exhaust_pressure : float
        Absolute [Pa].

    Returns
    -------
    FitResult
        ``"high_pressure_cutoff [V]"``, ``"low_pressure_cutoff [V]"``.

    Raises
    ------
    IdentificationError
        With fewer than three points, or no convergence.
    """
    u = np.asarray(centered_voltages, dtype=float).ravel()
    p = np.asarray(pressures, dtype=float).ravel()
    if u.shape != p.shape or u.size < 3:
        raise IdentificationError("need at least three (voltage, pressure) pairs of equal length")
    span = supply_pressure - exhaust_pressure
    direction = float(np.sign(np.sum((u - u.mean()) * (p - p.mean())))) or 1.0
    middle = 0.5 * (supply_pressure + exhaust_pressure)
    start = [float(u[np.argmin(np.abs(p - middle))]), math.log(max(0.25 * np.ptp(u), 1e-3))]

    def cutoffs(unknowns: np.ndarray) -> tuple[float, float]:
        half_width = 0.5 * math.exp(unknowns[1])
        return unknowns[0] + direction * half_width, unknowns[0] - direction * half_width

    def residuals(unknowns: np.ndarray) -> np.ndarray:
        return input_pressure(u, supply_pressure, exhaust_pressure, *cutoffs(unknowns)) - p

    solution = least_squares(residuals, start, x_scale=[1.0, 1.0], f_scale=0.01 * span)
    if not solution.success:
        raise IdentificationError(f"input-pressure fit did not converge: {solution.message}")
    high, low = cutoffs(solution.x)
    half_width = 0.5 * math.exp(solution.x[1])
    gradient = np.array([[1.0, direction * half_width], [1.0, -direction * half_width]])
    covariance = gradient @ covariance_from_jacobian(solution.jac, solution.fun) @ gradient.T
    errors = np.sqrt(np.abs(np.diag(covariance)))
    keys = ("high_pressure_cutoff [V]", "low_pressure_cutoff [V]")
    return FitResult(
        name="input-pressure curve",
        parameters={keys[0]: float(high), keys[1]: float(low)},
        standard_errors={keys[0]: float(errors[0]), keys[1]: float(errors[1])},
        r_squared=r_squared(solution.fun, p),
        residual_rms=math.sqrt(float(solution.fun @ solution.fun) / p.size),
        n_points=int(p.size),
        residual_unit="Pa",
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
) -> InputPressureCurves:
    """Fit both ports' tanh input-pressure curves from fixed-piston recordings.

    The cap chamber's settled pressure is its port's input pressure (port
    ``valve.cap_port``), the rod chamber's that of the other port (thesis 4.2.3, Fig. 23).

    Parameters
    ----------
    recordings : iterable of mapping
        Fixed-piston (spacer) recordings at held commands, long enough to settle.
    setup : RigSetup
        Supply, exhaust, valve offset and range, port assignment.
    tail_fraction, command_threshold : float
        See `steady_state_points`.

    Returns
    -------
    InputPressureCurves
    """
    points = steady_state_points(
        recordings, setup, tail_fraction=tail_fraction, command_threshold=command_threshold
    )
    supply = setup.actuator.supply
    cap_port, rod_port = chamber_port_numbers(setup)
    fits = {
        port: fit_input_pressure_curve(
            points.centered_voltage, values, supply.supply_pressure, supply.exhaust_pressure
        )
        for port, values in ((cap_port, points.cap_pressure), (rod_port, points.rod_pressure))
    }
    return InputPressureCurves(points, dict(sorted(fits.items())))


@dataclass(frozen=True)
class EquivalentAreaFit:
    """Equivalent orifice areas of both ports at one step voltage.

    Attributes
    ----------
    centered_voltage : float
        [V].
    areas : dict of int to float
        Fitted equivalent area per port number [m^2].
    initial_areas : dict of int to float
        The base polynomials' values at the voltage [m^2].
    fit : FitResult
        ``"port1_area [m^2]"``/``"port2_area [m^2]"`` or ``"area_scale [-]"``;
        residuals are normalised (pressures by Ps - Pe, position by the stroke).
    pressure_rmse, position_rmse : float
        Errors of the fitted simulation [Pa], [m].
    """

    centered_voltage: float
    areas: dict[int, float]
    initial_areas: dict[int, float]
    fit: FitResult
    pressure_rmse: float
    position_rmse: float


def _with_areas(setup: RigSetup, centered: float, areas: Mapping[int, float]) -> RigSetup:
    """The setup with each port's polynomial on the side of ``centered`` made constant."""
    valve = setup.actuator.valve
    side = "area_positive" if centered > 0.0 else "area_negative"
    updates = {
        f"port{port}": getattr(valve, f"port{port}").model_copy(
            update={side: (0.0, 0.0, 0.0, 0.0, float(area))}
        )
        for port, area in areas.items()
    }
    actuator = setup.actuator.model_copy(update={"valve": valve.model_copy(update=updates)})
    return setup.model_copy(update={"actuator": actuator})


def equivalent_area_for_step(
    setup: RigSetup,
    recording: Mapping[str, np.ndarray],
    *,
    step_time: float | None = None,
    duration: float = 0.6,
    mode: str = "per_port",
    position_weight: float = 1.0,
    max_evaluations: int = 60,
    filters: FilterSettings | None = None,
) -> EquivalentAreaFit:
    """Fit the equivalent orifice areas at one open-loop step's voltage (thesis 4.2.3).

    The rig is simulated from the recorded state just before the step (filtered position
    and pressures, at rest) with the recorded command over ``duration``; each port's area
    at the step voltage is an unknown (``mode="per_port"``), or one factor scales both
    base polynomials' values there (``mode="scale"``). Bounded least squares
    (`scipy.optimize.least_squares`, log areas) minimises the cap and rod pressure errors
    over Ps - Pe plus ``position_weight`` times the position error over the stroke: the
    thesis's hand tuning on pressures with position as the final check. The rest of the
    setup (friction, input-pressure curves) is taken as known.

    Parameters
    ----------
    setup : RigSetup
        Base parameters; its polynomials give the initial areas.
    recording : mapping of str to numpy.ndarray
        An open-loop step recording (columns of `preprocess.REQUIRED_COLUMNS`).
    step_time : float, optional
        Time of the step [s]; by default the first command step.
    duration : float
        Length of the fitted segment after the step [s]; short keeps the fit fast.
    mode : {"per_port", "scale"}
        The unknowns.
    position_weight : float
        Weight of the normalised position error against the pressure errors.
    max_evaluations : int
        Budget of simulations.
    filters : FilterSettings, optional
        Filters for the initial state.

    Returns
    -------
    EquivalentAreaFit

    Raises
    ------
    IdentificationError
        For an unknown mode, or no samples before the step.
    """
    if mode not in AREA_MODES:
        raise IdentificationError(f"mode {mode!r} is not one of {AREA_MODES}")
    signals = prepare_signals(recording, setup, filters)
    step = select_step(signals.time, signals.command, step_time)
    start = step.start_index
    if start < 1:
        raise IdentificationError("the recording has no sample before the step")
    control_step = setup.simulation.control_step
    count = min(round(duration / control_step), step.end_index - start)
    window = slice(start, start + count)
    command = np.asarray(recording["command [V]"], dtype=float)[window]
    measured = [
        np.asarray(recording[name], dtype=float)[window]
        for name in ("cap pressure [Pa]", "rod pressure [Pa]", "position [m]")
    ]
    centered = float(
        centered_voltage(
            step.final_level,
            setup.actuator.valve.offset_voltage,
            setup.actuator.valve.min_voltage,
            setup.actuator.valve.max_voltage,
        )
    )
    valve = setup.actuator.valve
    ports = (1, 2)
    initial = {
        port: float(
            evaluate_equivalent_area(
                getattr(valve, f"port{port}").area_negative,
                getattr(valve, f"port{port}").area_positive,
                centered,
            )
        )
        for port in ports
    }
    initial = {port: min(max(area, 10 * _MIN_AREA), 0.1 * _MAX_AREA) for port, area in initial.items()}
    stroke = setup.actuator.cylinder.stroke
    base = setup.model_copy(
        update={
            "rig": setup.rig.model_copy(
                update={
                    "initial_position": float(np.clip(signals.position[start - 1], 0.0, stroke)),
                    "initial_cap_pressure": float(signals.cap_pressure[start - 1]),
                    "initial_rod_pressure": float(signals.rod_pressure[start - 1]),
                }
            ),
            "simulation": setup.simulation.model_copy(update={"integrator": "fixed"}),
        }
    )
    span = setup.actuator.supply.supply_pressure - setup.actuator.supply.exhaust_pressure

    def areas_of(unknowns: np.ndarray) -> dict[int, float]:
        if mode == "scale":
            return {port: initial[port] * math.exp(unknowns[0]) for port in ports}
        return {port: math.exp(value) for port, value in zip(ports, unknowns, strict=True)}

    def simulate(unknowns: np.ndarray) -> list[np.ndarray]:
        run = simulate_rig(_with_areas(base, centered, areas_of(unknowns)), command, False)
        columns = ("cap pressure [Pa]", "rod pressure [Pa]", "position [m]")
        return [run.recording[name] for name in columns]

    def residuals(unknowns: np.ndarray) -> np.ndarray:
        simulated = simulate(unknowns)
        return np.concatenate(
            [
                (simulated[0] - measured[0]) / span,
                (simulated[1] - measured[1]) / span,
                position_weight * (simulated[2] - measured[2]) / stroke,
            ]
        )

    if mode == "scale":
        start_values = np.zeros(1)
        bounds = (
            [math.log(_MIN_AREA / max(initial.values()))],
            [math.log(_MAX_AREA / max(initial.values()))],
        )
    else:
        start_values = np.log([initial[port] for port in ports])
        bounds = ([math.log(_MIN_AREA)] * 2, [math.log(_MAX_AREA)] * 2)
    solution = least_squares(
        residuals,
        start_values,
        bounds=bounds,
        diff_step=1e-3,
        xtol=1e-4,
        ftol=1e-6,
        max_nfev=max_evaluations,
    )
    areas = areas_of(solution.x)
    errors = np.sqrt(np.abs(np.diag(covariance_from_jacobian(solution.jac, solution.fun))))
    if mode == "scale":
        factor = math.exp(solution.x[0])
        parameters = {"area_scale [-]": factor}
        standard_errors = {"area_scale [-]": float(factor * errors[0])}
    else:
        parameters = {f"port{port}_area [m^2]": areas[port] for port in ports}
        standard_errors = {
            f"port{port}_area [m^2]": float(areas[port] * error)
            for port, error in zip(ports, errors, strict=True)
        }
    simulated = simulate(solution.x)
    pressure_errors = np.concatenate([simulated[0] - measured[0], simulated[1] - measured[1]])
    observed = np.concatenate(
        [measured[0] / span, measured[1] / span, position_weight * measured[2] / stroke]
    )
    fit = FitResult(
        name=f"equivalent area at {centered:+.3f} V",
        parameters=parameters,
        standard_errors=standard_errors,
        r_squared=r_squared(solution.fun, observed),
        residual_rms=math.sqrt(float(solution.fun @ solution.fun) / solution.fun.size),
        n_points=int(solution.fun.size),
        residual_unit="-",
        details={"evaluations": int(solution.nfev), "mode": mode},
    )
    return EquivalentAreaFit(
        centered_voltage=centered,
        areas=areas,
        initial_areas=initial,
        fit=fit,
        pressure_rmse=math.sqrt(float(np.mean(pressure_errors**2))),
        position_rmse=math.sqrt(float(np.mean((simulated[2] - measured[2]) ** 2))),
    )


@dataclass(frozen=True)
class AreaPolynomials:
    """Equivalent-area polynomials of one port (App. B.2).

    Attributes
    ----------
    negative, positive : numpy.ndarray
        5 coefficients each, highest power first [m^2/V^n], for centered voltages
        <= 0 and > 0.
    residual_rms : float
        RMS of the fit residuals [m^2].
    n_points : int
        Points fitted.
    """

    negative: np.ndarray
    positive: np.ndarray
    residual_rms: float
    n_points: int


def fit_area_polynomials(
    voltages: ArrayLike, areas: Mapping[int, ArrayLike], order: int = 4
) -> dict[int, AreaPolynomials]:
    """Fourth-order polynomials per port and side of the offset (thesis 4.2.3.1, App. B.2).

    Uses `pneumaquad.valve_fit.fit_equivalent_area_polynomials`: ordinary least squares
    per side, the point at 0 V (if any) in both.

    Parameters
    ----------
    voltages : array_like
        Centered voltages [V] of the area points.
    areas : mapping of int to array_like
        Port number to its equivalent areas at ``voltages`` [m^2].
    order : int
        Polynomial order (4 in the thesis); each side needs more than ``order`` points.

    Returns
    -------
    dict of int to AreaPolynomials

    Raises
    ------
    IdentificationError
        With too few points on a side.
    """
    x = np.asarray(voltages, dtype=float).ravel()
    result = {}
    for port, values in areas.items():
        y = np.asarray(values, dtype=float).ravel()
        try:
            negative, positive = fit_equivalent_area_polynomials(x, y, order)
        except ValueError as error:
            raise IdentificationError(f"port {port}: {error}") from error
        fitted = evaluate_equivalent_area(negative, positive, x)
        result[port] = AreaPolynomials(
            negative=negative,
            positive=positive,
            residual_rms=float(np.sqrt(np.mean((fitted - y) ** 2))),
            n_points=int(y.size),
        )
    return result


def area_polynomial_updates(polynomials: Mapping[int, AreaPolynomials]) -> dict[str, list]:
    """Parameter-file updates ``{"valve.portN.area_negative": [...], ...}``."""
    updates: dict[str, list] = {}
    for port, fit in polynomials.items():
        updates[f"valve.port{port}.area_negative"] = [float(c) for c in fit.negative]
        updates[f"valve.port{port}.area_positive"] = [float(c) for c in fit.positive]
    return updates


def areas_table(fits: Sequence[EquivalentAreaFit]) -> tuple[np.ndarray, dict[int, np.ndarray]]:
    """Voltages and per-port areas of several step fits, for `fit_area_polynomials`."""
    voltages = np.array([fit.centered_voltage for fit in fits])
    return voltages, {port: np.array([fit.areas[port] for fit in fits]) for port in (1, 2)}
