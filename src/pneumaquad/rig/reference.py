"""The rig's adaptive stiff reference: ``scipy.integrate.solve_ivp`` (Radau or LSODA).

Samples like the fixed-step loop of :mod:`pneumaquad.rig.simulate`: at every control step
k the controller (or the open-loop signal) sets the valve command u_k from the state at
t_k; the command is held until t_{k+1}; row k of the recording is the state at t_{k+1}
with the command u_k. One rig per run, held in an actuator bank
(:func:`pneumaquad.rig.model.rig_bank`) like the fixed-step rigs.
"""

import math
import time
from typing import NamedTuple

import numpy as np

from pneumaquad.core.control.pid import pid_update
from pneumaquad.core.jit import compiled
from pneumaquad.core.kernel import rig_rates
from pneumaquad.core.layout import (
    ACTUATOR_STATE_DTYPE,
    SUPPLY_TANK,
    float_view,
    state_field_index,
)
from pneumaquad.core.physics.force import end_stop_force
from pneumaquad.core.physics.friction import FRICTION_LUGRE
from pneumaquad.core.pneumatics import (
    clear_outputs,
    finish_outputs,
    friction_of,
    supply_pressure_now,
)
from pneumaquad.io.interruption import deferred_interrupt
from pneumaquad.io.run_folder import RunRecorder
from pneumaquad.params.schema import RigSetup
from pneumaquad.rig.model import rig_bank
from pneumaquad.rig.recording import (
    RIG_COLUMNS,
    ProgressCallback,
    RigResult,
    as_columns,
    first_non_finite,
    new_rows,
    record_rows,
    skipped_columns,
    stop_diverged,
    write_row,
)

__all__ = [
    "ReferenceSolverError",
    "finish_reference_interval",
    "simulate_rig_reference",
    "supply_pressure_of",
]


class ReferenceSolverError(ValueError):
    """The adaptive reference cannot integrate this configuration."""


#: Names of the kernel states (ACTUATOR_STATE_DTYPE fields), for messages of the
#: adaptive reference.
_STATE_NAMES = {
    "cap_pressure": "cap pressure [Pa]",
    "rod_pressure": "rod pressure [Pa]",
    "cap_mass": "cap mass [kg]",
    "rod_mass": "rod mass [kg]",
    "spool_voltage": "spool voltage [V]",
    "bristle_deflection": "bristle deflection [m]",
    "air_consumed": "air consumed [kg]",
    "position": "position [m]",
    "velocity": "velocity [m/s]",
}


def _tolerance_scales(p: np.void) -> np.ndarray:
    """Typical magnitude of each state (in its unit), to turn the relative atol into
    absolute ones: a float vector in state-field order (the solver's view)."""
    scales = np.ones(1, ACTUATOR_STATE_DTYPE)
    mass = (
        p["supply_pressure"]
        * p["cap_area"]
        * (p["stroke"] + p["cap_dead_length"])
        / (p["gas_constant"] * p["supply_temperature"])
    )
    scales["cap_pressure"] = p["supply_pressure"]
    scales["rod_pressure"] = p["supply_pressure"]
    scales["cap_mass"] = mass
    scales["rod_mass"] = mass
    scales["spool_voltage"] = 1.0
    scales["bristle_deflection"] = (
        max(p["static_force"], 1e-3) / max(p["bristle_stiffness"], 1.0)
    )
    scales["air_consumed"] = mass
    scales["position"] = p["stroke"]
    scales["velocity"] = 0.1
    return float_view(scales)[0]


def _active_states(p: np.void) -> np.ndarray:
    """Columns of the solver's state vector (:func:`pneumaquad.core.layout.float_view` of
    the state record) that the reference ODE integrates for this configuration.

    States that feed nothing back (air consumed; the spool without lag; the bristle
    outside LuGre; the piston in spacer mode) are left out: their all-zero Jacobian
    columns make scipy's finite-difference Jacobian scaling overflow and Radau's Newton
    iteration fail.
    """
    names = ["cap_pressure", "rod_pressure", "cap_mass", "rod_mass"]
    spacer = p["spacer"] != 0
    if p["spool_time_constant"] > 0.0:
        names.append("spool_voltage")
    if p["friction_model"] == FRICTION_LUGRE and not spacer:
        names.append("bristle_deflection")
    if not spacer:
        names += ["position", "velocity"]
    return np.array([state_field_index(name) for name in names])


class _Scratch(NamedTuple):
    """Buffers of the right-hand side: a state record and its rates (arrays of one
    ACTUATOR_STATE_DTYPE record) with their float views (the solver's vectors) and the
    rates' record."""

    state: np.ndarray
    values: np.ndarray
    rates: np.ndarray
    rate_values: np.ndarray
    rate_record: np.void


def _new_scratch() -> _Scratch:
    state = np.zeros(1, ACTUATOR_STATE_DTYPE)
    rates = np.zeros(1, ACTUATOR_STATE_DTYPE)
    return _Scratch(state, float_view(state)[0], rates, float_view(rates)[0], rates[0])


def _evaluate(params, command, supply_pressure, scratch: _Scratch) -> np.ndarray:
    """:func:`~pneumaquad.core.kernel.rig_rates` at the scratch state; the rates as a
    float vector in state-field order (the scratch's, overwritten by the next call)."""
    rig_rates(params, scratch.state, command, supply_pressure, scratch.rates)
    return scratch.rate_values


def _active_rates(_time, values, params, full_state, active, command, supply_pressure,
                  _scales, scratch):
    """Rates of the active states (scipy signature; the scales are for the Jacobian)."""
    scratch.values[:] = full_state
    scratch.values[active] = values
    return _evaluate(params, command, supply_pressure, scratch)[active]


def _active_jacobian(_time, values, params, full_state, active, command, supply_pressure,
                     scales, scratch):
    """Forward-difference Jacobian of :func:`_active_rates` with steps set by state scale.

    scipy's own estimate adapts its steps per column and overflows on columns that have no
    effect at the current state (a chamber's mass at equilibrium, for one), after which
    Radau's Newton iteration keeps failing. Steps of 1e-7 of each state's typical
    magnitude avoid that.
    """
    state = full_state.copy()
    state[active] = values
    scratch.values[:] = state
    base = _evaluate(params, command, supply_pressure, scratch)[active]
    jacobian = np.empty((active.size, active.size))
    for column, index in enumerate(active):
        step = 1e-7 * max(abs(values[column]), scales[column])
        scratch.values[:] = state
        scratch.values[index] += step
        jacobian[:, column] = _evaluate(params, command, supply_pressure, scratch)[active] - base
        jacobian[:, column] /= step
    return jacobian


def _drawn_mass(params, full_state, active, times, values, command, supply_pressure,
                scratch) -> float:
    """Mass drawn from the supply over an interval: trapezoid rule on the solver's steps."""
    rates = np.empty(times.size)
    scratch.values[:] = full_state
    for index in range(times.size):
        scratch.values[active] = values[:, index]
        _evaluate(params, command, supply_pressure, scratch)
        rates[index] = scratch.rate_record["air_consumed"]
    return float(np.sum(0.5 * (rates[1:] + rates[:-1]) * np.diff(times)))


@compiled
def finish_reference_interval(params, state, before, supply, outputs, control_step, consumed,
                              records, index, sample_time, command, reference):
    """Bookkeeping of a control interval the adaptive solver integrated: the air it
    consumed, the supply's draw, the outputs and recording row ``index``
    (:func:`write_row`).

    ``params``, ``state`` (after the interval), ``before`` (the state before it),
    ``supply`` and ``outputs`` are arrays of one record; ``consumed`` is the air the
    cylinder drew over the interval [kg] (the solver does not integrate it), added to
    the state's ``air_consumed`` and drawn from the supply (an isothermal tank loses
    R·T·m/V).
    """
    p = params[0]
    s = state[0]
    out = outputs[0]
    tank = supply[0]
    s.air_consumed += consumed
    drawn = s.air_consumed - before[0].air_consumed
    tank.drawn_mass += drawn
    if tank.model == SUPPLY_TANK:
        tank.tank_pressure -= tank.gas_constant * tank.tank_temperature * drawn / tank.tank_volume
    clear_outputs(out)
    out.cap_mass_flow = s.cap_mass - before[0].cap_mass
    out.rod_mass_flow = s.rod_mass - before[0].rod_mass
    out.supply_mass_flow = drawn
    finish_outputs(p, s, s.position, control_step, out)
    if p.spacer != 0:
        out.end_stop_force = -(out.pneumatic_force + p.gravity_force)
    else:
        out.friction_force = friction_of(p, s.velocity, s.bristle_deflection)
        out.end_stop_force = end_stop_force(
            s.position, s.velocity, p.stroke, p.end_stop_stiffness, p.end_stop_damping
        )
    write_row(records, index, sample_time, command, reference, p, s, out, supply[0])


@compiled
def supply_pressure_of(params, supply) -> float:
    """:func:`~pneumaquad.core.pneumatics.supply_pressure_now` of a rig's arrays of one
    record [Pa]."""
    return supply_pressure_now(params[0], supply[0])


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
    A controller's ``measurement_delay`` is honoured as in the fixed-step loop (the PID
    sees the position of that many control steps earlier, the start position before).
    The right-hand side is :func:`pneumaquad.core.kernel.rig_rates`, built from the same
    physics functions as the compiled kernels. (The set-valued Coulomb models have no
    ODE form; parameter validation refuses them with an adaptive integrator.) The solver
    sees the rig's state record as a float vector (:func:`~pneumaquad.core.layout.float_view`,
    the same memory): the edge where named fields become columns.
    """
    from scipy import integrate  # SciPy's integrators load only for a reference run

    method = {"radau": "Radau", "lsoda": "LSODA"}.get(setup.simulation.integrator, "Radau")
    bank = rig_bank(setup)
    params, state, supply, outputs = bank.actuator_arrays
    p = params[0]
    active = _active_states(p)
    y = float_view(state)[0]  # the solver's view of the state record
    record = state[0]  # the state record (a view), for reading fields by name
    gains = bank.gains[0]
    controller = bank.pid_state[0]
    scratch = _new_scratch()
    dt = setup.simulation.control_step
    rtol = setup.simulation.relative_tolerance
    state_scales = _tolerance_scales(p)
    atol = setup.simulation.absolute_tolerance * state_scales
    scales = state_scales[active]
    total = int(signal.shape[0])
    records, rows = new_rows(total)
    delay = round(setup.controller.measurement_delay / dt)  # control steps
    start_position = float(record["position"])
    done = 0
    flushed = 0
    interrupted = False
    started = time.perf_counter()
    skipped = skipped_columns(setup, closed_loop)
    with deferred_interrupt() as stop:
        try:
            for k in range(total):
                if stop.requested:
                    break
                if closed_loop:
                    reference = float(signal[k])
                    measured = record["position"]
                    if delay > 0:  # the position at t_{k-delay}, as the fixed-step loop
                        measured = (records[k - delay - 1]["position"] if k > delay
                                    else start_position)
                    command = pid_update(gains, controller, reference, measured, dt)
                else:
                    reference = math.nan
                    command = float(signal[k])
                supply_pressure = supply_pressure_of(params, supply)
                before = state.copy()
                scratch.values[:] = y
                rates = _evaluate(params, command, supply_pressure, scratch)[active]
                failure = None
                if not math.isfinite(command):
                    failure = "command [V]"
                elif not np.isfinite(rates).all():
                    column = int(active[~np.isfinite(rates)][0])
                    failure = f"the rate of {_STATE_NAMES[ACTUATOR_STATE_DTYPE.names[column]]}"
                else:
                    try:
                        solution = integrate.solve_ivp(
                            _active_rates,
                            (0.0, dt),
                            y[active],
                            method=method,
                            rtol=rtol,
                            atol=atol[active],
                            jac=_active_jacobian,
                            args=(params, y, active, command, supply_pressure, scales, scratch),
                        )
                    except ValueError as error:  # scipy refuses NaN/inf in its iteration
                        failure = f"the solver's iteration ({error})"
                if failure is not None:
                    stop_diverged(recorder, rows, flushed, k, failure, k * dt, started,
                                   setup.simulation.integrator)
                if not solution.success:
                    record_rows(recorder, rows[flushed:k])
                    raise ReferenceSolverError(
                        f"solve_ivp failed at t = {k * dt:.4f} s: {solution.message}"
                    )
                consumed = _drawn_mass(
                    params, y, active, solution.t, solution.y, command, supply_pressure,
                    scratch,
                )
                y[active] = solution.y[:, -1]
                finish_reference_interval(params, state, before, supply, outputs, dt, consumed,
                                          records, k, (k + 1) * dt, command, reference)
                found = first_non_finite(rows[k : k + 1], skipped)
                if found is not None:
                    stop_diverged(recorder, rows, flushed, k, RIG_COLUMNS[found[1]],
                                   float(rows[k, 0]), started, setup.simulation.integrator)
                done = k + 1
                if done - flushed >= 100 or done == total:
                    record_rows(recorder, rows[flushed:done])
                    flushed = done
                    if progress is not None:
                        progress(done, total)
        except KeyboardInterrupt:
            interrupted = True
        interrupted = interrupted or stop.requested
        record_rows(recorder, rows[flushed:done])
    wall = time.perf_counter() - started
    return RigResult(as_columns(rows[:done]), interrupted, wall, setup.simulation.integrator)
