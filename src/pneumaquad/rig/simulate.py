"""Running the rig: the fixed-step compiled loop and the adaptive stiff reference.

Both integrators sample the same way: at every control step k the controller (or the
open-loop signal) sets the valve command u_k from the state at t_k; the command is held
until t_{k+1}; row k of the recording is the state at t_{k+1} with the command u_k.

Every row is checked as it is computed: the first non-finite value (NaN or inf) stops
the run with :class:`RigDivergedError`, naming the quantity and the time, after the rows
before it have gone to the recorder.
"""

import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from pneumaquad.core import layout
from pneumaquad.core.actuator import supply_state
from pneumaquad.core.control.pid import new_pid_state, pid_update
from pneumaquad.core.jit import compiled
from pneumaquad.core.kernel import rig_rates, step_rigs
from pneumaquad.core.physics.force import end_stop_force
from pneumaquad.core.physics.friction import FRICTION_LUGRE
from pneumaquad.core.pneumatics import finish_outputs, friction_of, supply_pressure_now
from pneumaquad.io.interruption import deferred_interrupt
from pneumaquad.io.recording import RunRecorder
from pneumaquad.params.schema import RigSetup
from pneumaquad.rig.model import pack_rig_parameters, rig_controller_gains, rig_initial_state

#: The rig recording, defined once: (field of a row record, column header) in column
#: order. :func:`write_row` fills the fields by name; the headers name the columns.
RIG_RECORDING = (
    ("time", "time [s]"),
    ("command", "command [V]"),
    ("reference", "reference position [m]"),
    ("position", "position [m]"),
    ("velocity", "velocity [m/s]"),
    ("cap_pressure", "cap pressure [Pa]"),
    ("rod_pressure", "rod pressure [Pa]"),
    ("cap_temperature", "cap temperature [K]"),
    ("rod_temperature", "rod temperature [K]"),
    ("cap_mass_flow", "cap mass flow [kg/s]"),
    ("rod_mass_flow", "rod mass flow [kg/s]"),
    ("cap_mass", "cap mass [kg]"),
    ("rod_mass", "rod mass [kg]"),
    ("friction_force", "friction force [N]"),
    ("pneumatic_force", "pneumatic force [N]"),
    ("end_stop_force", "end stop force [N]"),
    ("supply_pressure", "supply pressure [Pa]"),
    ("supply_mass_flow", "supply mass flow [kg/s]"),
    ("air_consumed", "air consumed [kg]"),
    ("tank_pressure", "tank pressure [Pa]"),
    ("net_force", "net force [N]"),
    ("air_consumed_normal_litres", "air consumed [NL]"),
)
RIG_ROW_DTYPE = np.dtype([(field, "f8") for field, _ in RIG_RECORDING])
RIG_COLUMNS = tuple(header for _, header in RIG_RECORDING)
N_COLUMNS = len(RIG_COLUMNS)

#: Normal conditions (DIN 1343) for normal litres: pressure [Pa] and temperature [K].
NORMAL_PRESSURE = 101325.0
NORMAL_TEMPERATURE = 273.15


class ReferenceSolverError(ValueError):
    """The adaptive reference cannot integrate this configuration."""


#: Columns that are NaN by design: the reference of an open-loop run, the tank pressure
#: of an ideal supply.
_REFERENCE_COLUMN = RIG_COLUMNS.index("reference position [m]")
_TANK_COLUMN = RIG_COLUMNS.index("tank pressure [Pa]")
#: Names of the kernel states, for messages of the adaptive reference.
_STATE_NAMES = {
    layout.S_CAP_PRESSURE: "cap pressure [Pa]",
    layout.S_ROD_PRESSURE: "rod pressure [Pa]",
    layout.S_CAP_MASS: "cap mass [kg]",
    layout.S_ROD_MASS: "rod mass [kg]",
    layout.S_SPOOL: "spool voltage [V]",
    layout.S_BRISTLE: "bristle deflection [m]",
    layout.S_AIR_CONSUMED: "air consumed [kg]",
    layout.S_POSITION: "position [m]",
    layout.S_VELOCITY: "velocity [m/s]",
}


@compiled
def write_row(records, index, sample_time, command, reference, p, s, out, supply):
    """Fill record ``index`` of ``records`` (:data:`RIG_ROW_DTYPE`) from the state after a
    step."""
    row = records[index]
    row.time = sample_time
    row.command = command
    row.reference = reference
    row.position = s[layout.S_POSITION]
    row.velocity = s[layout.S_VELOCITY]
    row.cap_pressure = s[layout.S_CAP_PRESSURE]
    row.rod_pressure = s[layout.S_ROD_PRESSURE]
    row.cap_temperature = out[layout.O_CAP_TEMPERATURE]
    row.rod_temperature = out[layout.O_ROD_TEMPERATURE]
    row.cap_mass_flow = out[layout.O_CAP_FLOW]
    row.rod_mass_flow = out[layout.O_ROD_FLOW]
    row.cap_mass = s[layout.S_CAP_MASS]
    row.rod_mass = s[layout.S_ROD_MASS]
    row.friction_force = out[layout.O_FRICTION_FORCE]
    row.pneumatic_force = out[layout.O_PNEUMATIC_FORCE]
    row.end_stop_force = out[layout.O_END_STOP_FORCE]
    row.supply_pressure = supply_pressure_now(p, supply)
    row.supply_mass_flow = out[layout.O_SUPPLY_DRAW]
    row.air_consumed = s[layout.S_AIR_CONSUMED]
    row.tank_pressure = (
        supply[layout.SUPPLY_TANK_PRESSURE] if supply[layout.SUPPLY_MODEL] == 1.0 else math.nan
    )
    # eq 4.1.11 with friction: what accelerates the piston besides gravity and the stops
    row.net_force = out[layout.O_PNEUMATIC_FORCE] - out[layout.O_FRICTION_FORCE]
    normal_density = NORMAL_PRESSURE / (p[layout.P_R] * NORMAL_TEMPERATURE)
    row.air_consumed_normal_litres = s[layout.S_AIR_CONSUMED] / normal_density * 1000.0


def new_rows(count: int) -> tuple[np.ndarray, np.ndarray]:
    """``count`` zeroed recording rows: the records (:data:`RIG_ROW_DTYPE`) the compiled
    code fills, and the same memory as a ``(count, N_COLUMNS)`` float array."""
    records = np.zeros(count, RIG_ROW_DTYPE)
    return records, records.view(np.float64).reshape(count, N_COLUMNS)


@compiled
def run_rig_chunk(
    params,
    state,
    supply,
    gains,
    controller,
    closed_loop,
    signal,
    start,
    count,
    control_step,
    substeps,
    records,
):
    """Run ``count`` control steps from index ``start``; fill records[0:count]."""
    commands = np.zeros(1)
    outputs = np.zeros((1, layout.N_OUTPUTS))
    for j in range(count):
        k = start + j
        if closed_loop:
            reference = signal[k]
            command = pid_update(
                gains, controller, reference, state[0, layout.S_POSITION], control_step
            )
        else:
            reference = math.nan
            command = signal[k]
        commands[0] = command
        step_rigs(params, state, commands, control_step, substeps, supply, outputs)
        write_row(
            records,
            j,
            (k + 1) * control_step,
            command,
            reference,
            params[0],
            state[0],
            outputs[0],
            supply,
        )


@dataclass
class RigResult:
    """Outcome of a rig run: the recording as columns, and how the run went."""

    recording: dict[str, np.ndarray]
    interrupted: bool
    wall_time: float
    integrator: str


ProgressCallback = Callable[[int, int], None]


class RigDivergedError(RuntimeError):
    """A rig run produced a non-finite value; the rows before it were recorded.

    Attributes
    ----------
    quantity : str
        Recording column (``"cap pressure [Pa]"``) of the first non-finite value.
    time : float
        Sample time of the row holding it [s].
    result : RigResult
        The run up to the last finite row.
    """

    def __init__(self, quantity: str, time: float, result: RigResult) -> None:
        self.quantity = quantity
        self.time = time
        self.result = result
        rows = result.recording["time [s]"]
        kept = (
            f"the recording up to t = {rows[-1]:.6g} s is kept"
            if rows.size
            else "nothing before it was recorded"
        )
        super().__init__(
            f"the rig simulation stopped: {quantity} became non-finite at t = {time:.6g} s "
            f"({kept}); the parameters or the command drive the model where it cannot be "
            "integrated; try a smaller simulation.control_step, more simulation.substeps "
            "or other parameter values"
        )


def _skipped_columns(setup: RigSetup, closed_loop: bool) -> list[int]:
    skipped = [] if closed_loop else [_REFERENCE_COLUMN]
    if setup.actuator.supply.model != "tank":
        skipped.append(_TANK_COLUMN)
    return skipped


def first_non_finite(rows: np.ndarray, skipped: list[int]) -> tuple[int, int] | None:
    """(row, column) of the first non-finite value of ``rows`` outside ``skipped`` columns.

    Rows are searched in order, and within the first bad row the first column in
    :data:`RIG_COLUMNS` order is named; ``None`` when every value is finite.
    """
    bad = ~np.isfinite(rows)
    bad[:, skipped] = False
    bad_rows = np.flatnonzero(bad.any(axis=1))
    if bad_rows.size == 0:
        return None
    row = int(bad_rows[0])
    return row, int(np.flatnonzero(bad[row])[0])


def _as_columns(rows: np.ndarray) -> dict[str, np.ndarray]:
    return {name: rows[:, index].copy() for index, name in enumerate(RIG_COLUMNS)}


def _record(recorder: RunRecorder | None, block: np.ndarray) -> None:
    if recorder is not None and block.shape[0]:
        recorder.append(block)


def _stop_diverged(recorder: RunRecorder | None, rows: np.ndarray, flushed: int, good: int,
                   quantity: str, when: float, started: float, integrator: str) -> None:
    """Record rows ``flushed:good`` (the last good one is ``good - 1``) and raise
    :class:`RigDivergedError` naming ``quantity`` and ``when`` [s]."""
    _record(recorder, rows[flushed:good])
    result = RigResult(_as_columns(rows[:good]), False, time.perf_counter() - started,
                       integrator)
    raise RigDivergedError(quantity, when, result)


def simulate_rig(
    setup: RigSetup,
    signal: np.ndarray,
    closed_loop: bool,
    recorder: RunRecorder | None = None,
    progress: ProgressCallback | None = None,
    chunk_steps: int = 500,
) -> RigResult:
    """Simulate the rig with the integrator named in ``setup.simulation.integrator``.

    Parameters
    ----------
    setup : RigSetup
        Validated rig parameters.
    signal : numpy.ndarray
        Per control step: valve command [V] (open loop) or position reference [m]
        (closed loop).
    closed_loop : bool
        Whether ``signal`` is a position reference for the PID.
    recorder : RunRecorder, optional
        Receives rows (RIG_COLUMNS) as they are computed, so an interrupted run keeps
        them.
    progress : callable, optional
        Called with (steps done, total steps).
    chunk_steps : int
        Steps per compiled call; Ctrl-C is honoured between chunks.

    Returns
    -------
    RigResult
        On KeyboardInterrupt the result holds the rows computed so far and
        ``interrupted`` is True.

    Raises
    ------
    RigDivergedError
        A value of the recording became non-finite; the rows before it were recorded
        and travel in the error's ``result``.
    """
    if setup.simulation.integrator != "fixed":
        return simulate_rig_reference(setup, signal, closed_loop, recorder, progress)
    params = pack_rig_parameters(setup)
    state = rig_initial_state(setup, params)
    supply = supply_state(setup.actuator)
    gains = rig_controller_gains(setup)
    controller = new_pid_state()
    total = int(signal.shape[0])
    records, rows = new_rows(total)
    dt = setup.simulation.control_step
    substeps = setup.simulation.substeps
    skipped = _skipped_columns(setup, closed_loop)
    done = 0
    interrupted = False
    started = time.perf_counter()
    with deferred_interrupt() as stop:
        try:
            while done < total and not stop.requested:
                count = min(chunk_steps, total - done)
                run_rig_chunk(
                    params,
                    state,
                    supply,
                    gains,
                    controller,
                    closed_loop,
                    np.asarray(signal, dtype=float),
                    done,
                    count,
                    dt,
                    substeps,
                    records[done : done + count],
                )
                found = first_non_finite(rows[done : done + count], skipped)
                if found is not None:
                    row, column = found
                    _stop_diverged(recorder, rows, done, done + row, RIG_COLUMNS[column],
                                   float(rows[done + row, 0]), started, "fixed")
                _record(recorder, rows[done : done + count])
                done += count
                if progress is not None:
                    progress(done, total)
        except KeyboardInterrupt:
            interrupted = True
        interrupted = interrupted or stop.requested
    wall = time.perf_counter() - started
    return RigResult(_as_columns(rows[:done]), interrupted, wall, "fixed")


def _tolerance_scales(params: np.ndarray) -> np.ndarray:
    """Typical magnitude of each state, to turn the relative atol into absolute ones."""
    p = params[0]
    scales = np.ones(layout.N_STATES)
    scales[layout.S_CAP_PRESSURE] = p[layout.P_PS]
    scales[layout.S_ROD_PRESSURE] = p[layout.P_PS]
    mass = (
        p[layout.P_PS]
        * p[layout.P_CAP_AREA]
        * (p[layout.P_STROKE] + p[layout.P_CAP_DEAD])
        / (p[layout.P_R] * p[layout.P_TS])
    )
    scales[layout.S_CAP_MASS] = mass
    scales[layout.S_ROD_MASS] = mass
    scales[layout.S_SPOOL] = 1.0
    scales[layout.S_BRISTLE] = max(p[layout.P_FS], 1e-3) / max(p[layout.P_SIGMA0], 1.0)
    scales[layout.S_AIR_CONSUMED] = mass
    scales[layout.S_POSITION] = p[layout.P_STROKE]
    scales[layout.S_VELOCITY] = 0.1
    return scales


def _active_states(p: np.ndarray) -> np.ndarray:
    """Indices of the states the reference ODE integrates for this configuration.

    States that feed nothing back (air consumed; the spool without lag; the bristle
    outside LuGre; the piston in spacer mode) are left out: their all-zero Jacobian
    columns make scipy's finite-difference Jacobian scaling overflow and Radau's Newton
    iteration fail.
    """
    states = [
        layout.S_CAP_PRESSURE,
        layout.S_ROD_PRESSURE,
        layout.S_CAP_MASS,
        layout.S_ROD_MASS,
    ]
    if p[layout.P_SPOOL_TAU] > 0.0:
        states.append(layout.S_SPOOL)
    if int(p[layout.P_FRICTION_MODEL]) == FRICTION_LUGRE and p[layout.P_SPACER] != 1.0:
        states.append(layout.S_BRISTLE)
    if p[layout.P_SPACER] != 1.0:
        states += [layout.S_POSITION, layout.S_VELOCITY]
    return np.array(states)


def _active_rates(_time, values, p, full_state, active, command, supply_pressure, _scales):
    """Rates of the active states (scipy signature; the scales are for the Jacobian)."""
    state = full_state.copy()
    state[active] = values
    return rig_rates(p, state, command, supply_pressure)[active]


def _active_jacobian(_time, values, p, full_state, active, command, supply_pressure, scales):
    """Forward-difference Jacobian of :func:`_active_rates` with steps set by state scale.

    scipy's own estimate adapts its steps per column and overflows on columns that have no
    effect at the current state (a chamber's mass at equilibrium, for one), after which
    Radau's Newton iteration keeps failing. Steps of 1e-7 of each state's typical
    magnitude avoid that.
    """
    state = full_state.copy()
    state[active] = values
    base = rig_rates(p, state, command, supply_pressure)[active]
    jacobian = np.empty((active.size, active.size))
    for column, index in enumerate(active):
        step = 1e-7 * max(abs(values[column]), scales[column])
        perturbed = state.copy()
        perturbed[index] += step
        jacobian[:, column] = rig_rates(p, perturbed, command, supply_pressure)[active] - base
        jacobian[:, column] /= step
    return jacobian


def _drawn_mass(p, full_state, active, times, values, command, supply_pressure) -> float:
    """Mass drawn from the supply over an interval: trapezoid rule on the solver's steps."""
    rates = np.empty(times.size)
    state = full_state.copy()
    for index in range(times.size):
        state[active] = values[:, index]
        rates[index] = rig_rates(p, state, command, supply_pressure)[layout.S_AIR_CONSUMED]
    return float(np.sum(0.5 * (rates[1:] + rates[:-1]) * np.diff(times)))


def simulate_rig_reference(
    setup: RigSetup,
    signal: np.ndarray,
    closed_loop: bool,
    recorder: RunRecorder | None = None,
    progress: ProgressCallback | None = None,
) -> RigResult:
    """Adaptive stiff reference: ``scipy.integrate.solve_ivp`` (Radau or LSODA).

    Each control interval is integrated separately with the command held, from the same
    sampled state as the fixed-step loop, so the two differ only by integration error.
    The right-hand side is :func:`pneumaquad.core.kernel.rig_rates`, built from the same
    physics functions as the compiled kernels. (The set-valued Coulomb models have no
    ODE form; parameter validation refuses them with an adaptive integrator.)
    """
    method = {"radau": "Radau", "lsoda": "LSODA"}.get(setup.simulation.integrator, "Radau")
    params = pack_rig_parameters(setup)
    p = params[0]
    active = _active_states(p)
    y = rig_initial_state(setup, params)[0].copy()
    supply = supply_state(setup.actuator)
    gains = rig_controller_gains(setup)
    controller = new_pid_state()
    dt = setup.simulation.control_step
    rtol = setup.simulation.relative_tolerance
    state_scales = _tolerance_scales(params)
    atol = setup.simulation.absolute_tolerance * state_scales
    scales = state_scales[active]
    total = int(signal.shape[0])
    records, rows = new_rows(total)
    out = np.zeros(layout.N_OUTPUTS)
    done = 0
    flushed = 0
    interrupted = False
    started = time.perf_counter()
    spacer = p[layout.P_SPACER] == 1.0
    skipped = _skipped_columns(setup, closed_loop)
    with deferred_interrupt() as stop:
        try:
            for k in range(total):
                if stop.requested:
                    break
                if closed_loop:
                    reference = float(signal[k])
                    command = pid_update(gains, controller, reference, y[layout.S_POSITION], dt)
                else:
                    reference = math.nan
                    command = float(signal[k])
                supply_pressure = supply_pressure_now(p, supply)
                before = y.copy()
                rates = rig_rates(p, y, command, supply_pressure)[active]
                failure = None
                if not math.isfinite(command):
                    failure = "command [V]"
                elif not np.isfinite(rates).all():
                    state = int(active[~np.isfinite(rates)][0])
                    failure = f"the rate of {_STATE_NAMES[state]}"
                else:
                    try:
                        solution = solve_ivp(
                            _active_rates,
                            (0.0, dt),
                            y[active],
                            method=method,
                            rtol=rtol,
                            atol=atol[active],
                            jac=_active_jacobian,
                            args=(p, y, active, command, supply_pressure, scales),
                        )
                    except ValueError as error:  # scipy refuses NaN/inf in its iteration
                        failure = f"the solver's iteration ({error})"
                if failure is not None:
                    _stop_diverged(recorder, rows, flushed, k, failure, k * dt, started,
                                   setup.simulation.integrator)
                if not solution.success:
                    _record(recorder, rows[flushed:k])
                    raise ReferenceSolverError(
                        f"solve_ivp failed at t = {k * dt:.4f} s: {solution.message}"
                    )
                y[layout.S_AIR_CONSUMED] += _drawn_mass(
                    p, y, active, solution.t, solution.y, command, supply_pressure
                )
                y[active] = solution.y[:, -1]
                drawn = y[layout.S_AIR_CONSUMED] - before[layout.S_AIR_CONSUMED]
                supply[layout.SUPPLY_DRAWN_MASS] += drawn
                if supply[layout.SUPPLY_MODEL] == 1.0:
                    supply[layout.SUPPLY_TANK_PRESSURE] -= (
                        supply[layout.SUPPLY_GAS_CONSTANT]
                        * supply[layout.SUPPLY_TANK_TEMPERATURE]
                        * drawn
                        / supply[layout.SUPPLY_TANK_VOLUME]
                    )
                out[:] = 0.0
                out[layout.O_CAP_FLOW] = y[layout.S_CAP_MASS] - before[layout.S_CAP_MASS]
                out[layout.O_ROD_FLOW] = y[layout.S_ROD_MASS] - before[layout.S_ROD_MASS]
                out[layout.O_SUPPLY_DRAW] = drawn
                finish_outputs(p, y, y[layout.S_POSITION], dt, out)
                if spacer:
                    out[layout.O_END_STOP_FORCE] = -(
                        out[layout.O_PNEUMATIC_FORCE] + p[layout.P_GRAVITY_FORCE]
                    )
                else:
                    out[layout.O_FRICTION_FORCE] = friction_of(
                        p, y[layout.S_VELOCITY], y[layout.S_BRISTLE]
                    )
                    out[layout.O_END_STOP_FORCE] = end_stop_force(
                        y[layout.S_POSITION],
                        y[layout.S_VELOCITY],
                        p[layout.P_STROKE],
                        p[layout.P_STOP_STIFFNESS],
                        p[layout.P_STOP_DAMPING],
                    )
                write_row(records, k, (k + 1) * dt, command, reference, p, y, out, supply)
                found = first_non_finite(rows[k : k + 1], skipped)
                if found is not None:
                    _stop_diverged(recorder, rows, flushed, k, RIG_COLUMNS[found[1]],
                                   float(rows[k, 0]), started, setup.simulation.integrator)
                done = k + 1
                if done - flushed >= 100 or done == total:
                    _record(recorder, rows[flushed:done])
                    flushed = done
                    if progress is not None:
                        progress(done, total)
        except KeyboardInterrupt:
            interrupted = True
        interrupted = interrupted or stop.requested
        _record(recorder, rows[flushed:done])
    wall = time.perf_counter() - started
    return RigResult(_as_columns(rows[:done]), interrupted, wall, setup.simulation.integrator)
