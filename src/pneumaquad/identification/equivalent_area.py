"""Equivalent orifice areas fitted around the rig simulator (thesis 4.2.3).

For each open-loop step at a voltage u the thesis hand-tuned a discharge coefficient until
the simulated pressures and position matched the measurement (Fig. 24). Here the area of
each port at u (or one factor on both base polynomials' values there) is found by bounded
least squares, re-simulating the rig from the recorded state before the step.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from pneumaquad import layout
from pneumaquad.actuator import supply_state
from pneumaquad.control.pid import N_CONTROLLER_STATES
from pneumaquad.params.schema import RigSetup
from pneumaquad.physics.chamber import chamber_volume_cap, chamber_volume_rod
from pneumaquad.physics.valve import centered_voltage
from pneumaquad.rig.model import pack_rig_parameters, rig_controller_gains, rig_initial_state
from pneumaquad.rig.simulate import N_COLUMNS, RIG_COLUMNS, run_rig_chunk
from pneumaquad.valve_fit import evaluate_equivalent_area

from .preprocess import FilterSettings, IdentificationError, prepare_signals, select_step
from .report import FitResult, covariance_from_jacobian, r_squared

__all__ = ["AREA_MODES", "EquivalentAreaFit", "equivalent_area_for_step"]

#: Parametrisations of `equivalent_area_for_step`.
AREA_MODES = ("per_port", "scale")
_MIN_AREA, _MAX_AREA = 1e-11, 1e-4  # bounds of a fitted equivalent area [m^2]
_COMPARED = tuple(
    RIG_COLUMNS.index(name) for name in ("cap pressure [Pa]", "rod pressure [Pa]", "position [m]")
)


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


@dataclass(frozen=True)
class _StartState:
    """Rig state at rest before a step: position [m], pressures [Pa], temperatures [K]."""

    position: float
    cap_pressure: float
    rod_pressure: float
    cap_temperature: float
    rod_temperature: float


def _simulate_from(setup: RigSetup, start: _StartState, command: np.ndarray) -> np.ndarray:
    """Open-loop rig rows (RIG_COLUMNS) from a state at rest with given gas temperatures.

    `pneumaquad.rig.simulate.simulate_rig` starts at the supply temperature; in the
    adiabatic model a chamber that has just filled or emptied can be tens of kelvin off
    it, which changes its mass for the same pressure, so the start state is built here.
    """
    params = pack_rig_parameters(setup)
    state = rig_initial_state(setup, params)
    row = params[0]
    if row[layout.P_SPACER] != 1.0:
        state[0, layout.S_POSITION] = start.position
    position = state[0, layout.S_POSITION]
    cap_volume = chamber_volume_cap(position, row[layout.P_CAP_AREA], row[layout.P_CAP_DEAD])
    rod_volume = chamber_volume_rod(
        position, row[layout.P_STROKE], row[layout.P_ROD_AREA], row[layout.P_ROD_DEAD]
    )
    state[0, layout.S_CAP_PRESSURE] = start.cap_pressure
    state[0, layout.S_ROD_PRESSURE] = start.rod_pressure
    gas = row[layout.P_R]
    state[0, layout.S_CAP_MASS] = start.cap_pressure * cap_volume / (gas * start.cap_temperature)
    state[0, layout.S_ROD_MASS] = start.rod_pressure * rod_volume / (gas * start.rod_temperature)
    rows = np.zeros((command.size, N_COLUMNS))
    run_rig_chunk(
        params,
        state,
        supply_state(setup.actuator),
        rig_controller_gains(setup),
        np.zeros(N_CONTROLLER_STATES),
        False,
        np.ascontiguousarray(command, dtype=float),
        0,
        command.size,
        setup.simulation.control_step,
        setup.simulation.substeps,
        rows,
    )
    return rows


def equivalent_area_for_step(
    setup: RigSetup,
    recording: Mapping[str, np.ndarray],
    *,
    step_time: float | None = None,
    duration: float = 0.6,
    mode: str = "per_port",
    position_weight: float = 1.0,
    max_evaluations: int = 60,
    initial_temperatures: tuple[float, float] | None = None,
    filters: FilterSettings | None = None,
) -> EquivalentAreaFit:
    """Fit the equivalent orifice areas at one open-loop step's voltage (thesis 4.2.3).

    The rig is simulated from the recorded state just before the step (filtered position
    and pressures, at rest, see ``initial_temperatures``) with the recorded command over
    ``duration``; each port's area at the step voltage is an unknown
    (``mode="per_port"``), or one factor scales both base polynomials' values there
    (``mode="scale"``). Bounded least squares
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
    initial_temperatures : (float, float), optional
        Cap and rod gas temperatures before the step [K]. By default the recording's
        ``"cap temperature [K]"``/``"rod temperature [K]"`` (simulated recordings), else
        the supply temperature (measured data after a long hold).
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
    initial = {
        port: float(np.clip(area, 10 * _MIN_AREA, 0.1 * _MAX_AREA))
        for port, area in initial.items()
    }
    before = start - 1
    temperatures = [
        float(recording[name][before]) if name in recording else ambient
        for name, ambient in (
            ("cap temperature [K]", setup.actuator.gas.supply_temperature),
            ("rod temperature [K]", setup.actuator.gas.supply_temperature),
        )
    ]
    if initial_temperatures is not None:
        temperatures = [float(value) for value in initial_temperatures]
    start_state = _StartState(
        position=float(np.clip(signals.position[before], 0.0, setup.actuator.cylinder.stroke)),
        cap_pressure=float(signals.cap_pressure[before]),
        rod_pressure=float(signals.rod_pressure[before]),
        cap_temperature=temperatures[0],
        rod_temperature=temperatures[1],
    )
    stroke = setup.actuator.cylinder.stroke
    span = setup.actuator.supply.supply_pressure - setup.actuator.supply.exhaust_pressure

    def areas_of(unknowns: np.ndarray) -> dict[int, float]:
        if mode == "scale":
            return {port: initial[port] * math.exp(unknowns[0]) for port in ports}
        return {port: math.exp(value) for port, value in zip(ports, unknowns, strict=True)}

    def simulate(unknowns: np.ndarray) -> list[np.ndarray]:
        rows = _simulate_from(
            _with_areas(setup, centered, areas_of(unknowns)), start_state, command
        )
        return [rows[:, index] for index in _COMPARED]

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
