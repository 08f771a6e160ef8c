"""Equivalent orifice areas fitted around the rig simulator (thesis 4.2.3).

For each open-loop step at a voltage u the thesis hand-tuned a discharge coefficient until
the simulated pressures and position matched the measurement (Fig. 24). Here the area of
each port at u (or one factor on both base polynomials' values there) is found by bounded
least squares, re-simulating the rig from the recorded state before the step.

The simulation runs on the recording's own time base: any uniform sample rate works (the
simulation step divides the sample period, so every recorded sample falls on a simulated
one); time stamps that are not uniform are refused with an error saying so.

In the adiabatic chamber model (eq 4.1.7, 4.1.10) a chamber that has just filled is far
above the supply temperature (about 380 K after the thesis protocol's 5 s hold) and one
that has just emptied below it, and for the same pressure its gas mass is lower or higher
by that ratio. Starting the step at the supply temperature then biases the fitted areas
(docs/analysis.md). `start_temperatures_from_hold` estimates the temperatures by
simulating the recorded hold before the step.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from pneumaquad.analysis import find_steps
from pneumaquad.analysis.filters import sample_rate_of
from pneumaquad.analysis.fits import FitResult, covariance_from_jacobian, r_squared
from pneumaquad.core.physics.chamber import chamber_volume_cap, chamber_volume_rod
from pneumaquad.core.physics.valve import centered_voltage
from pneumaquad.core.valve_fit import evaluate_equivalent_area
from pneumaquad.params.schema import RigSetup
from pneumaquad.rig.model import rig_bank
from pneumaquad.rig.simulate import RIG_COLUMNS, new_rows, open_loop_delays, run_rig_chunk

from .preprocess import REQUIRED_COLUMNS, IdentificationError, select_step

__all__ = [
    "AREA_MODES",
    "MAX_AREA_RELATIVE_ERROR",
    "MAX_AREA_RESIDUAL",
    "START_TEMPERATURE_SOURCES",
    "EquivalentAreaFit",
    "SimulationGrid",
    "equivalent_area_for_step",
    "simulation_grid",
    "start_temperatures_from_hold",
    "uniform_sample_period",
]

#: Parametrisations of `equivalent_area_for_step`.
AREA_MODES = ("per_port", "scale")
#: Where the gas temperatures at the start of a fitted step come from.
START_TEMPERATURE_SOURCES = ("auto", "recorded", "hold", "supply")
#: Largest relative standard error of a fitted area before the fit counts as failed [-].
MAX_AREA_RELATIVE_ERROR = 0.25
#: Largest RMS of the normalised residuals before the fit counts as failed [-]: 3 % of
#: Ps - Pe (about 10 kPa) or of the stroke; sensor noise alone is a few tenths of a percent.
MAX_AREA_RESIDUAL = 0.03
_MIN_AREA, _MAX_AREA = 1e-11, 1e-4  # bounds of a fitted equivalent area [m^2]
_BOUND_MARGIN = 1e-3  # log-area distance from a bound that counts as "at the bound"
_COMPARED = tuple(
    RIG_COLUMNS.index(name) for name in ("cap pressure [Pa]", "rod pressure [Pa]", "position [m]")
)
_TEMPERATURE_COLUMNS = ("cap temperature [K]", "rod temperature [K]")


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
        residuals are normalised (pressures by Ps - Pe, position by the stroke);
        ``fit.problems`` says why the fit is not to be trusted, if it is not.
    pressure_rmse, position_rmse : float
        Errors of the fitted simulation [Pa], [m].
    start_temperatures : (float, float)
        Cap and rod gas temperatures the step was simulated from [K].
    temperature_source : str
        Where they came from: ``"recorded"``, ``"hold"``, ``"supply"`` or ``"given"``.
    sample_period : float
        The recording's sample period [s].
    """

    centered_voltage: float
    areas: dict[int, float]
    initial_areas: dict[int, float]
    fit: FitResult
    pressure_rmse: float
    position_rmse: float
    start_temperatures: tuple[float, float] = (math.nan, math.nan)
    temperature_source: str = ""
    sample_period: float = math.nan

    @property
    def failed(self) -> bool:
        """True when the fit's checks say its areas are not to be trusted."""
        return self.fit.failed


def uniform_sample_period(time: np.ndarray) -> float:
    """Sample period of a uniformly sampled recording [s].

    Parameters
    ----------
    time : numpy.ndarray
        Sample times [s].

    Returns
    -------
    float
        Mean sample interval [s].

    Raises
    ------
    IdentificationError
        If the times do not increase strictly or their spacing varies by more than 0.1 %
        (`pneumaquad.analysis.filters.sample_rate_of`): the step would be simulated on a
        wrong time base. Resample such a recording onto a uniform grid first.
    """
    try:
        return 1.0 / sample_rate_of(time)
    except ValueError as error:
        raise IdentificationError(
            f"the step recording's time base is unusable: {error}. The fit re-simulates the "
            "step sample by sample, so it needs uniform time stamps"
        ) from error


@dataclass(frozen=True)
class SimulationGrid:
    """Simulation time base for a recording.

    Attributes
    ----------
    steps_per_sample : int
        Simulation steps per recorded sample.
    step : float
        Simulation step [s]; the sample period over ``steps_per_sample``.
    substeps : int
        Integrator substeps per simulation step.
    """

    steps_per_sample: int
    step: float
    substeps: int


def simulation_grid(sample_period: float, control_step: float, substeps: int) -> SimulationGrid:
    """The simulation step that divides a sample period and is at most ``control_step``.

    Parameters
    ----------
    sample_period : float
        Recording's sample period [s].
    control_step : float
        The parameter file's control step [s], the longest simulation step used.
    substeps : int
        The parameter file's substeps per control step; the substep is kept at most
        ``control_step / substeps``.

    Returns
    -------
    SimulationGrid
        E.g. 2 ms samples with a 1 ms control step: 2 steps of 1 ms per sample;
        0.5 ms samples: 1 step of 0.5 ms.
    """
    steps_per_sample = max(1, math.ceil(sample_period / control_step - 1e-6))
    step = sample_period / steps_per_sample
    return SimulationGrid(
        steps_per_sample=steps_per_sample,
        step=step,
        substeps=max(1, math.ceil(substeps * step / control_step - 1e-6)),
    )


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


def _simulate_from(
    setup: RigSetup, start: _StartState, command: np.ndarray, grid: SimulationGrid
) -> np.ndarray:
    """Open-loop rig rows (RIG_COLUMNS) from a state at rest with given gas temperatures.

    ``command`` holds one value per simulation step of ``grid``; row k is the state one
    step after command k began (`pneumaquad.rig.simulate`). The start state is built here
    because `pneumaquad.rig.simulate.simulate_rig` starts at the supply temperature.
    """
    bank = rig_bank(setup)
    p, s = bank.params[0], bank.state[0]
    if p["spacer"] == 0:
        s["position"] = start.position
    position = s["position"]
    cap_volume = chamber_volume_cap(position, p["cap_area"], p["cap_dead_length"])
    rod_volume = chamber_volume_rod(position, p["stroke"], p["rod_area"], p["rod_dead_length"])
    s["cap_pressure"] = start.cap_pressure
    s["rod_pressure"] = start.rod_pressure
    gas = p["gas_constant"]
    s["cap_mass"] = start.cap_pressure * cap_volume / (gas * start.cap_temperature)
    s["rod_mass"] = start.rod_pressure * rod_volume / (gas * start.rod_temperature)
    records, rows = new_rows(command.size, 1)
    run_rig_chunk(
        bank.actuator_arrays,
        bank.controller_arrays,
        False,
        np.ascontiguousarray(command, dtype=float).reshape(1, -1),
        0,
        command.size,
        grid.step,
        grid.substeps,
        records,
        *open_loop_delays(1),
    )
    rows = rows[0]
    return rows


@dataclass(frozen=True)
class _StepSignals:
    """The columns a step fit reads, as float arrays, with their sample period [s]."""

    time: np.ndarray
    command: np.ndarray
    position: np.ndarray
    cap_pressure: np.ndarray
    rod_pressure: np.ndarray
    period: float


def _step_signals(recording: Mapping[str, np.ndarray]) -> _StepSignals:
    missing = [name for name in REQUIRED_COLUMNS if name not in recording]
    if missing:
        raise IdentificationError(
            f"the recording lacks the columns {missing}; it has {sorted(recording)}"
        )
    columns = [np.asarray(recording[name], dtype=float) for name in REQUIRED_COLUMNS]
    return _StepSignals(*columns, period=uniform_sample_period(columns[0]))


def _penetration_limit(setup: RigSetup) -> float:
    """Deepest end-stop penetration the supply can hold, Ps·A_cap / k_stop [m].

    A piston held against a stop sits slightly inside it; the recorded start position is
    kept there (up to this depth) rather than moved onto the stop, which would start the
    step with the stop's force missing.
    """
    stiffness = setup.rig.end_stop_stiffness
    if not stiffness > 0.0:
        return 0.0
    cylinder = setup.actuator.cylinder
    return setup.actuator.supply.supply_pressure * cylinder.cap_area / stiffness


def _state_at(
    setup: RigSetup,
    signals: _StepSignals,
    samples: slice,
    temperatures: Sequence[float],
) -> _StartState:
    """Mean recorded position and pressures over ``samples``, at rest, with temperatures."""
    stroke = setup.actuator.cylinder.stroke
    limit = _penetration_limit(setup)
    return _StartState(
        position=float(np.clip(np.mean(signals.position[samples]), -limit, stroke + limit)),
        cap_pressure=float(np.mean(signals.cap_pressure[samples])),
        rod_pressure=float(np.mean(signals.rod_pressure[samples])),
        cap_temperature=float(temperatures[0]),
        rod_temperature=float(temperatures[1]),
    )


def _hold_temperatures(
    setup: RigSetup, signals: _StepSignals, step_index: int, grid: SimulationGrid
) -> tuple[float, float]:
    """Gas temperatures at sample ``step_index - 1`` from simulating the hold before it."""
    supply_temperature = setup.actuator.gas.supply_temperature
    changes = [
        segment.start_index
        for segment in find_steps(signals.time, signals.command, 0.05)
        if segment.start_index < step_index
    ]
    first = changes[-1] if changes else 0
    before = step_index - 1
    if before <= first:
        return supply_temperature, supply_temperature
    start = _state_at(
        setup, signals, slice(first, first + 1), (supply_temperature, supply_temperature)
    )
    command = np.repeat(signals.command[first + 1 : step_index], grid.steps_per_sample)
    rows = _simulate_from(setup, start, command, grid)
    return tuple(
        float(rows[-1, RIG_COLUMNS.index(name)]) for name in _TEMPERATURE_COLUMNS
    )  # type: ignore[return-value]


def start_temperatures_from_hold(
    setup: RigSetup,
    recording: Mapping[str, np.ndarray],
    *,
    step_time: float | None = None,
) -> tuple[float, float]:
    """Cap and rod gas temperatures just before a step, by simulating the hold before it.

    The constant-command segment before the step (the thesis protocol's hold at the
    opposite saturation, 4.2.3) is simulated open loop with the adiabatic chamber model
    (eq 4.1.7, 4.1.10) from the recorded position and pressures at its start and the supply
    temperature there. Without heat transfer a filled chamber ends well above the supply
    temperature; the estimate hardly depends on the valve areas, since the hold runs until
    the pressures have settled.

    Parameters
    ----------
    setup : RigSetup
        Parameters of the simulation (valve areas at the hold voltage, gas).
    recording : mapping of str to numpy.ndarray
        An open-loop step recording (columns of `preprocess.REQUIRED_COLUMNS`), uniformly
        sampled.
    step_time : float, optional
        Time of the step [s]; by default the first command step.

    Returns
    -------
    (float, float)
        Cap and rod gas temperatures [K]; the supply temperature for both when the
        recording holds no sample before the step's previous one.

    Raises
    ------
    IdentificationError
        For missing columns, non-uniform time stamps or no step.
    """
    signals = _step_signals(recording)
    grid = simulation_grid(
        signals.period, setup.simulation.control_step, setup.simulation.substeps
    )
    step = select_step(signals.time, signals.command, step_time)
    return _hold_temperatures(setup, signals, step.start_index, grid)


def _start_temperatures(
    source: str | float | Sequence[float],
    setup: RigSetup,
    recording: Mapping[str, np.ndarray],
    signals: _StepSignals,
    step_index: int,
    grid: SimulationGrid,
) -> tuple[tuple[float, float], str]:
    """Resolve the ``start_temperature`` argument to temperatures [K] and their source."""
    supply_temperature = setup.actuator.gas.supply_temperature
    if not isinstance(source, str):
        values = np.atleast_1d(np.asarray(source, dtype=float)).ravel()
        if values.size == 1:
            values = np.repeat(values, 2)
        if values.size != 2 or not np.all(np.isfinite(values)) or np.any(values <= 0.0):
            raise IdentificationError(
                f"start_temperature {source!r} should be one or two (cap, rod) temperatures "
                "above 0 K"
            )
        return (float(values[0]), float(values[1])), "given"
    if source not in START_TEMPERATURE_SOURCES:
        raise IdentificationError(
            f"start_temperature {source!r} is not one of {START_TEMPERATURE_SOURCES} "
            "or a temperature"
        )
    recorded = all(name in recording for name in _TEMPERATURE_COLUMNS)
    if source == "recorded" and not recorded:
        raise IdentificationError(
            f"start_temperature 'recorded' needs the columns {list(_TEMPERATURE_COLUMNS)}, "
            "which the recording lacks; use 'hold' or a temperature"
        )
    if source == "recorded" or (source == "auto" and recorded):
        before = step_index - 1
        values = tuple(float(recording[name][before]) for name in _TEMPERATURE_COLUMNS)
        return values, "recorded"  # type: ignore[return-value]
    if source == "supply":
        return (supply_temperature, supply_temperature), "supply"
    return _hold_temperatures(setup, signals, step_index, grid), "hold"


def equivalent_area_for_step(
    setup: RigSetup,
    recording: Mapping[str, np.ndarray],
    *,
    step_time: float | None = None,
    duration: float = 0.6,
    mode: str = "per_port",
    position_weight: float = 1.0,
    max_evaluations: int = 60,
    start_temperature: str | float | Sequence[float] = "auto",
    rest_window: float = 0.02,
    max_relative_error: float = MAX_AREA_RELATIVE_ERROR,
    max_residual: float = MAX_AREA_RESIDUAL,
) -> EquivalentAreaFit:
    """Fit the equivalent orifice areas at one open-loop step's voltage (thesis 4.2.3).

    The rig is simulated from the recorded state just before the step (position and
    pressures averaged over ``rest_window`` before it, at rest, gas temperatures per
    ``start_temperature``) with the recorded
    command over ``duration``, on the recording's own time base (`simulation_grid`); each
    port's area at the step voltage is an unknown (``mode="per_port"``), or one factor
    scales both base polynomials' values there (``mode="scale"``). Bounded least squares
    (`scipy.optimize.least_squares`, log areas) minimises the cap and rod pressure errors
    over Ps - Pe plus ``position_weight`` times the position error over the stroke at the
    recorded samples: the thesis's hand tuning on pressures with position as the final
    check. The rest of the setup (friction, input-pressure curves) is taken as known.

    Sample k of the recording is compared with the simulated state at its time stamp; the
    command recorded at sample k is taken as held over the sample period before it (the
    convention of `pneumaquad.rig.simulate`), so the step acts from the last sample before
    the jump.

    The fit checks itself (``fit.problems``): an area whose relative standard error is
    not finite or above ``max_relative_error``, an area at the search bounds
    [1e-11, 1e-4] m^2, an RMS normalised residual above ``max_residual``, or no
    convergence.

    Parameters
    ----------
    setup : RigSetup
        Base parameters; its polynomials give the initial areas, its control step and
        substeps the longest simulation step and substep.
    recording : mapping of str to numpy.ndarray
        An open-loop step recording (columns of `preprocess.REQUIRED_COLUMNS`), sampled
        uniformly at any rate.
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
    start_temperature : str, float or (float, float)
        Cap and rod gas temperatures before the step: ``"recorded"`` (the recording's
        ``"cap temperature [K]"``/``"rod temperature [K]"``, simulated recordings),
        ``"hold"`` (`start_temperatures_from_hold`), ``"supply"`` (the supply temperature,
        right for gas that has cooled back after a long hold), ``"auto"`` (recorded if
        the columns exist, else hold), or temperatures [K] (one for both chambers).
    rest_window : float
        The start state is the mean of the raw samples over this time before the step
        (at least one sample) [s]; averaging lowers the noise, and unlike a zero-phase
        filter it mixes in nothing from after the step.
    max_relative_error : float
        Largest acceptable relative standard error of a fitted area or factor [-].
    max_residual : float
        Largest acceptable RMS of the normalised residuals [-].

    Returns
    -------
    EquivalentAreaFit

    Raises
    ------
    IdentificationError
        For an unknown mode or temperature source, non-uniform time stamps, or no
        samples before the step.
    """
    if mode not in AREA_MODES:
        raise IdentificationError(f"mode {mode!r} is not one of {AREA_MODES}")
    if not duration > 0.0:
        raise IdentificationError(f"duration must be positive, got {duration!r} s")
    signals = _step_signals(recording)
    period = signals.period
    grid = simulation_grid(period, setup.simulation.control_step, setup.simulation.substeps)
    step = select_step(signals.time, signals.command, step_time)
    start = step.start_index
    if start < 1:
        raise IdentificationError("the recording has no sample before the step")
    count = min(max(1, round(duration / period)), step.end_index - start)
    window = slice(start, start + count)
    command = np.repeat(signals.command[window], grid.steps_per_sample)
    compared_rows = slice(grid.steps_per_sample - 1, None, grid.steps_per_sample)
    measured = [
        values[window] for values in (signals.cap_pressure, signals.rod_pressure, signals.position)
    ]
    valve = setup.actuator.valve
    centered = float(
        centered_voltage(
            step.final_level, valve.offset_voltage, valve.min_voltage, valve.max_voltage
        )
    )
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
    temperatures, temperature_source = _start_temperatures(
        start_temperature, setup, recording, signals, start, grid
    )
    stroke = setup.actuator.cylinder.stroke
    rest_samples = max(1, round(rest_window / period))
    start_state = _state_at(
        setup, signals, slice(max(0, start - rest_samples), start), temperatures
    )
    span = setup.actuator.supply.supply_pressure - setup.actuator.supply.exhaust_pressure

    def areas_of(unknowns: np.ndarray) -> dict[int, float]:
        if mode == "scale":
            return {port: initial[port] * math.exp(unknowns[0]) for port in ports}
        return {port: math.exp(value) for port, value in zip(ports, unknowns, strict=True)}

    def simulate(unknowns: np.ndarray) -> list[np.ndarray]:
        rows = _simulate_from(
            _with_areas(setup, centered, areas_of(unknowns)), start_state, command, grid
        )[compared_rows]
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
        lower = [math.log(_MIN_AREA / max(initial.values()))]
        upper = [math.log(_MAX_AREA / max(initial.values()))]
        names = ["area_scale [-]"]
    else:
        start_values = np.log([initial[port] for port in ports])
        lower, upper = [math.log(_MIN_AREA)] * 2, [math.log(_MAX_AREA)] * 2
        names = [f"port{port}_area [m^2]" for port in ports]
    from scipy.optimize import least_squares  # SciPy loads on first use: it is slow to import
    solution = least_squares(
        residuals,
        start_values,
        bounds=(lower, upper),
        diff_step=1e-3,
        xtol=1e-4,
        ftol=1e-6,
        max_nfev=max_evaluations,
    )
    areas = areas_of(solution.x)
    with np.errstate(invalid="ignore", over="ignore"):
        log_errors = np.sqrt(np.abs(np.diag(covariance_from_jacobian(solution.jac, solution.fun))))
    log_errors[~np.isfinite(log_errors)] = math.inf
    values = [math.exp(solution.x[0])] if mode == "scale" else [areas[port] for port in ports]
    parameters = dict(zip(names, values, strict=True))
    # d(value) = value * d(log value): the standard error of a value is value * log error
    standard_errors = {
        name: float(value * error) if math.isfinite(error) else math.inf
        for name, value, error in zip(names, values, log_errors, strict=True)
    }
    residual_rms = math.sqrt(float(solution.fun @ solution.fun) / solution.fun.size)
    where = f"at {centered:+.3f} V (step at {step.start_time:.4g} s)"
    problems = []
    if solution.status <= 0:
        problems.append(f"equivalent area {where}: least squares stopped: {solution.message}")
    for index, name in enumerate(names):
        label = name.split(" [")[0].replace("_", " ")
        if min(solution.x[index] - lower[index], upper[index] - solution.x[index]) < (
            _BOUND_MARGIN
        ):
            problems.append(
                f"{label} {where}: {values[index]:.3g} lies at the search bound "
                f"[{_MIN_AREA:g}, {_MAX_AREA:g}] m^2, so the step does not determine it"
            )
        elif not log_errors[index] <= max_relative_error:
            problems.append(
                f"{label} {where}: relative standard error {log_errors[index]:.2g} exceeds "
                f"{max_relative_error:g}, so the step does not determine it (the pressures "
                "hardly depend on it there; use mode 'scale' or more steps nearby)"
            )
    if residual_rms > max_residual:
        problems.append(
            f"equivalent area {where}: RMS normalised residual {residual_rms:.3g} exceeds "
            f"{max_residual:g}: the simulated step does not follow the recording (wrong "
            "friction or input-pressure parameters, or the start temperatures?)"
        )
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
        residual_rms=residual_rms,
        n_points=int(solution.fun.size),
        residual_unit="-",
        details={
            "evaluations": int(solution.nfev),
            "mode": mode,
            "start_temperatures [K]": temperatures,
            "temperature_source": temperature_source,
            "sample_period [s]": period,
        },
        problems=tuple(problems),
    )
    return EquivalentAreaFit(
        centered_voltage=centered,
        areas=areas,
        initial_areas=initial,
        fit=fit,
        pressure_rmse=math.sqrt(float(np.mean(pressure_errors**2))),
        position_rmse=math.sqrt(float(np.mean((simulated[2] - measured[2]) ** 2))),
        start_temperatures=temperatures,
        temperature_source=temperature_source,
        sample_period=period,
    )
