"""Running the rig: the fixed-step compiled loop over N rigs, and the adaptive reference.

Both integrators sample the same way: at every control step k the controller (or the
open-loop signal) sets the valve command u_k from the state at t_k; the command is held
until t_{k+1}; row k of the recording is the state at t_{k+1} with the command u_k.

The fixed-step loop (:func:`run_rig_chunk`) advances N independent rigs held in one
actuator bank (:func:`pneumaquad.rig.model.rig_bank`: one parameter, state, supply and
controller record per rig), one recording row per rig per step; :func:`simulate_rigs` runs
N at once (a sweep of supply pressures, loads or gains) and :func:`simulate_rig` one. Each
rig's recording is the one it has run alone. The adaptive reference is
:mod:`pneumaquad.rig.reference`.

Every row is checked as it is computed: the first non-finite value (NaN or inf) stops
the run with :class:`RigDivergedError`, naming the quantity and the time, after the rows
before it have gone to the recorder.
"""

import math
import time
from collections.abc import Sequence

import numpy as np

from pneumaquad.core.bank import ActuatorArrays, ControllerArrays, scaled_pid_update
from pneumaquad.core.control.pid import PID_GAINS_DTYPE, pid_update
from pneumaquad.core.jit import compiled
from pneumaquad.core.kernel import advance_rigs
from pneumaquad.core.layout import STEP_WORK_DTYPE
from pneumaquad.io.interruption import deferred_interrupt
from pneumaquad.io.run_folder import RunRecorder
from pneumaquad.io.stage_clock import StageClock
from pneumaquad.params.schema import RigSetup
from pneumaquad.rig.model import rig_bank
from pneumaquad.rig.recording import (
    N_COLUMNS,
    NORMAL_PRESSURE,
    NORMAL_TEMPERATURE,
    RIG_COLUMNS,
    RIG_RECORDING,
    RIG_ROW_DTYPE,
    ProgressCallback,
    RigDivergedError,
    RigResult,
    as_columns,
    first_non_finite,
    first_non_finite_of_rigs,
    new_rows,
    record_rows,
    skipped_columns,
    stop_diverged,
    write_row,
)
from pneumaquad.rig.reference import ReferenceSolverError, simulate_rig_reference

__all__ = [  # the recording's names are re-exported for the callers of this module
    "NORMAL_PRESSURE",
    "NORMAL_TEMPERATURE",
    "N_COLUMNS",
    "RIG_COLUMNS",
    "RIG_RECORDING",
    "RIG_ROW_DTYPE",
    "ReferenceSolverError",
    "RigDivergedError",
    "RigResult",
    "delay_steps",
    "first_non_finite",
    "new_rows",
    "open_loop_delays",
    "run_rig_chunk",
    "simulate_rig",
    "simulate_rig_reference",
    "simulate_rigs",
    "write_row",
]


@compiled(nogil=True)
def run_rig_chunk(actuators: ActuatorArrays, controllers: ControllerArrays,
                  closed_loop: bool, signals: np.ndarray, start: int, count: int,
                  control_step: float, substeps: int, records: np.ndarray,
                  delays: np.ndarray, start_positions: np.ndarray) -> None:
    """Run ``count`` control steps of N rigs from step ``start``; fill
    ``records[:, start:start + count]``.

    A rig with a measurement delay of d control steps gives its PID at step k the piston
    position at t_{k-d}: row k - d - 1 of its recording, or its start position for
    k ≤ d (at rest before the run). With d = 0 the PID reads the state itself.

    Parameters
    ----------
    actuators, controllers : ActuatorArrays, ControllerArrays
        The bundles of a rig bank (:func:`pneumaquad.rig.model.rig_bank`): N rigs, each
        with its own supply record, or all on one shared supply record.
    closed_loop : bool
        Whether ``signals`` are piston references [m] for the PIDs (else valve commands
        [V]).
    signals : ndarray (N, steps)
        Row i: the signal of rig i per control step.
    start, count : int
        First step and number of steps.
    control_step : float
        [s].
    substeps : int
        Heun substeps per control step.
    records : ndarray (N, >= start + count) of RIG_ROW_DTYPE
        Row k of rig i is filled after step k (:func:`write_row`); rows before ``start``
        hold the history a measurement delay reads.
    delays : ndarray (N,) of int
        Measurement delay of each rig's PID [control steps] (:func:`delay_steps`).
    start_positions : ndarray (N,)
        Piston position of each rig at t = 0 [m] (what a delayed PID sees first).
    """
    params, state, supply, outputs = actuators
    work = np.empty(params.shape[0], STEP_WORK_DTYPE)
    commands, references = controllers.commands, controllers.references
    rigs = params.shape[0]
    shared = supply.shape[0] == 1
    scaled = np.empty(1, PID_GAINS_DTYPE)[0]
    for j in range(count):
        k = start + j
        for i in range(rigs):
            if closed_loop:
                references[i] = signals[i, k]
                measured = state[i].position
                if delays[i] > 0:
                    row = k - delays[i] - 1
                    measured = records[i, row].position if row >= 0 else start_positions[i]
                if controllers.gain_scale[i] == 1.0:  # the same numbers, no scaled copy
                    commands[i] = pid_update(controllers.gains[i], controllers.pid_state[i],
                                             references[i], measured, control_step)
                else:
                    commands[i] = scaled_pid_update(controllers, i, measured,
                                                    control_step, scaled)
            else:
                commands[i] = signals[i, k]
        advance_rigs(params, state, commands, control_step, substeps, supply, outputs, work)
        for i in range(rigs):
            reference = references[i] if closed_loop else math.nan
            write_row(records[i], k, (k + 1) * control_step, commands[i], reference,
                      params[i], state[i], outputs[i], supply[0 if shared else i])


def delay_steps(setup: RigSetup) -> int:
    """The rig controller's measurement delay in whole control steps:
    ``round(controller.measurement_delay / simulation.control_step)``."""
    return round(setup.controller.measurement_delay / setup.simulation.control_step)


def open_loop_delays(rigs: int) -> tuple[np.ndarray, np.ndarray]:
    """:func:`run_rig_chunk`'s ``delays`` and ``start_positions`` for ``rigs`` rigs whose
    PIDs are not used (open loop) or see the present state: zeros."""
    return np.zeros(rigs, dtype=np.int64), np.zeros(rigs)


def simulate_rig(
    setup: RigSetup,
    signal: np.ndarray,
    closed_loop: bool,
    recorder: RunRecorder | None = None,
    progress: ProgressCallback | None = None,
    chunk_steps: int = 500,
    clock: StageClock | None = None,
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
    clock : StageClock, optional
        Receives the wall time of the compiled steps (``"simulation"``) and of checking
        and recording the rows (``"recording"``), fixed step only.

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
    signals = np.asarray(signal, dtype=float).reshape(1, -1)
    return _simulate_fixed([setup], signals, closed_loop, [recorder], progress,
                           chunk_steps, several=False, clock=clock)[0]


def simulate_rigs(
    setups: RigSetup | Sequence[RigSetup],
    signals: np.ndarray,
    closed_loop: bool,
    recorders: Sequence[RunRecorder | None] | None = None,
    progress: ProgressCallback | None = None,
    chunk_steps: int = 500,
) -> list[RigResult]:
    """Simulate N rigs at once, each as :func:`simulate_rig` would alone.

    Parameters
    ----------
    setups : RigSetup or sequence of N RigSetup
        One setup for every rig, or one per rig (e.g. a sweep of supply pressures). They
        share the integrator, and with the fixed step the control step and substeps.
    signals : ndarray (N, steps)
        Row i: rig i's valve command [V] (open loop) or position reference [m] (closed
        loop) per control step.
    closed_loop : bool
        Whether ``signals`` are position references for the PIDs.
    recorders : sequence of N RunRecorder or None, optional
        Each rig's recorder (rows as they are computed).
    progress : callable, optional
        Called with (steps done, total steps).
    chunk_steps : int
        Steps per compiled call; Ctrl-C is honoured between chunks.

    Returns
    -------
    list of RigResult
        One per rig, in order; each recording identical to the rig's run alone. The
        fixed step advances all rigs in one compiled loop; the adaptive reference runs
        them one after the other.

    Raises
    ------
    ValueError
        Signals not (N, steps) for N setups, or setups that differ in integrator,
        control step or substeps.
    RigDivergedError
        A rig's recording became non-finite (``rig`` names it; every rig stops there and
        each recorder has its rig's finite rows).
    """
    signals = np.asarray(signals, dtype=float)
    if signals.ndim != 2:
        raise ValueError(f"signals should be (rigs, steps), got shape {signals.shape}")
    count = signals.shape[0]
    setups = [setups] * count if isinstance(setups, RigSetup) else list(setups)
    recorders = [None] * count if recorders is None else list(recorders)
    if len(setups) != count or len(recorders) != count:
        raise ValueError(f"{count} signal rows for {len(setups)} setups and "
                         f"{len(recorders)} recorders")
    integrators = {setup.simulation.integrator for setup in setups}
    if len(integrators) > 1:
        raise ValueError(f"rigs run together share simulation.integrator, got "
                         f"{sorted(integrators)}")
    if integrators != {"fixed"}:
        return [simulate_rig_reference(setup, signal, closed_loop, recorder, progress)
                for setup, signal, recorder in zip(setups, signals, recorders, strict=True)]
    steps = {(s.simulation.control_step, s.simulation.substeps) for s in setups}
    if len(steps) > 1:
        raise ValueError("rigs run together share simulation.control_step and "
                         f"simulation.substeps, got {sorted(steps)}")
    return _simulate_fixed(setups, signals, closed_loop, recorders, progress, chunk_steps,
                           several=True)


def _simulate_fixed(setups: list[RigSetup], signals: np.ndarray, closed_loop: bool,
                    recorders: list[RunRecorder | None], progress: ProgressCallback | None,
                    chunk_steps: int, several: bool,
                    clock: StageClock | None = None) -> list[RigResult]:
    """The fixed-step run of :func:`simulate_rigs` (``several``: name the rig of a
    divergence; ``clock``: time the compiled steps and the recording)."""
    begun = time.perf_counter()
    bank = rig_bank(setups)
    rigs, total = signals.shape
    signals = np.ascontiguousarray(signals, dtype=float)
    records, rows = new_rows(total, rigs)
    dt = setups[0].simulation.control_step
    substeps = setups[0].simulation.substeps
    checked = np.ones((rigs, N_COLUMNS), dtype=bool)
    for i, setup in enumerate(setups):
        checked[i, skipped_columns(setup, closed_loop)] = False
    delays = np.array([delay_steps(setup) for setup in setups], dtype=np.int64)
    start_positions = bank.state["position"].copy()
    # The first call of a compiled function in a process loads its machine code (about
    # 10 ms each): zero steps here, so that the run's stages time the run.
    run_rig_chunk(bank.actuator_arrays, bank.controller_arrays, closed_loop, signals, 0, 0,
                  dt, substeps, records, delays, start_positions)
    first_non_finite_of_rigs(rows, 0, 0, checked)
    if clock is not None:
        clock.add("set-up (rig bank, compiled code loaded)", time.perf_counter() - begun)
    done = 0
    interrupted = False
    started = time.perf_counter()
    with deferred_interrupt() as stop:
        try:
            while done < total and not stop.requested:
                count = min(chunk_steps, total - done)
                begun = time.perf_counter()
                run_rig_chunk(bank.actuator_arrays, bank.controller_arrays, closed_loop,
                              signals, done, count, dt, substeps, records, delays,
                              start_positions)
                computed = time.perf_counter()
                _record_chunk(rows, done, count, checked, recorders, started, several)
                if clock is not None:
                    clock.add("simulation", computed - begun)
                    clock.add("recording", time.perf_counter() - computed)
                done += count
                if progress is not None:
                    progress(done, total)
        except KeyboardInterrupt:
            interrupted = True
        interrupted = interrupted or stop.requested
    wall = time.perf_counter() - started
    return [RigResult(as_columns(rows[i, :done]), interrupted, wall, "fixed")
            for i in range(rigs)]


def _record_chunk(rows: np.ndarray, done: int, count: int, checked: np.ndarray,
                  recorders: list[RunRecorder | None], started: float, several: bool) -> None:
    """Check the chunk's rows of every rig for non-finite values (in the columns
    ``checked``, (N, N_COLUMNS) of bool) and hand them to the recorders; on one, the
    finite rows go out and :class:`RigDivergedError` names the rig that diverged first
    (the earliest row; the lowest index among equals)."""
    found = first_non_finite_of_rigs(rows, done, done + count, checked)
    diverged = [i for i in range(rows.shape[0]) if found[i, 0] >= 0]
    for i, recorder in enumerate(recorders):
        if found[i, 0] < 0:
            record_rows(recorder, rows[i, done:done + count])
    if not diverged:
        return
    first = min(diverged, key=lambda i: found[i, 0])
    for i in diverged:
        if i != first:
            record_rows(recorders[i], rows[i, done:done + found[i, 0]])
    row, column = int(found[first, 0]), int(found[first, 1])
    stop_diverged(recorders[first], rows[first], done, done + row, RIG_COLUMNS[column],
                  float(rows[first, done + row, 0]), started, "fixed",
                  first if several else None)
