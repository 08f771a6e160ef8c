"""Running a robot experiment: phases of commands, the run folder, summary and plots.

An experiment is a list of :class:`Phase` objects. Each phase sets which joints are under
closed-loop control, which get an open-loop valve voltage and which are left with their
valve at its offset, and gives the joint-angle references as a function of time. The
runner plays them at the control rate and writes the run folder through
:class:`pneumaquad.io.run_folder.RunFolderWriter` (docs/run-folder.md):

``parameters.toml``   resolved robot parameters (SI, loadable again)
``model.xml``         the MuJoCo model (open it in MuJoCo's viewer)
``recording.csv``     flushed while running; ``recording.parquet`` at the end
``trajectory.npz``    time and qpos at the recording rate, for replay and video
``summary.json``      metrics, air consumption, tank endurance, timing
``joints.png`` ...    plots; ``video.mp4``/``first-frame.png`` when a video is asked for

Ctrl-C stops at the next chunk; everything above is still written for the part that ran.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from pneumaquad.io.interruption import deferred_interrupt
from pneumaquad.io.run_folder import RunFolderWriter
from pneumaquad.io.stage_clock import StageClock
from pneumaquad.io.tables import RowBuffer

from .coupling import MODE_CLOSED_LOOP, MODE_OPEN_LOOP, MODE_UNCOMMANDED
from .recording import fill_recording_row, recording_columns
from .simulation import RobotSimulation, SimulationDivergedError

__all__ = ["Phase", "RobotRun", "reference_table", "run_phases", "tank_endurance"]

ReferenceFunction = Callable[[np.ndarray], np.ndarray]


@dataclass
class Phase:
    """One stretch of an experiment.

    Attributes
    ----------
    name : str
    duration : float
        [s]
    references : callable or ndarray
        ``f(times) -> (len(times), joints)`` angles [rad], or a constant (joints,) array.
    closed_loop : ndarray of bool
        Joints under position control.
    open_loop_voltage : ndarray, optional
        (joints,) valve voltages [V] for joints in open loop (NaN = not open loop).
    feedback : bool
        Call ``references`` once per recorded chunk, with that chunk's times, instead of
        once for the whole phase: a reference function that reads the simulation's
        state (e.g. :class:`.stance_control.StanceController`) closes a loop at the
        recording rate.
    gate : callable, optional
        ``gate(simulation) -> (reason or None, details)``, called when the phase is about
        to begin: the details (a JSON-able dict) go to the summary's ``"checks"`` under
        the phase's name; a reason (str) ends the run there, before this phase (the
        summary's ``"stopped before"``: the phase and the reason). E.g. a walk that
        begins only from a verified stance (:class:`.stance_check.StanceCheck`).
    """

    name: str
    duration: float
    references: ReferenceFunction | np.ndarray
    closed_loop: np.ndarray
    open_loop_voltage: np.ndarray | None = None
    feedback: bool = False
    gate: Callable[[RobotSimulation], tuple[str | None, dict[str, Any]]] | None = None

    def modes(self) -> np.ndarray:
        """Per-joint control mode codes of :mod:`pneumaquad.robot.coupling`."""
        modes = np.where(self.closed_loop, MODE_CLOSED_LOOP, MODE_UNCOMMANDED)
        if self.open_loop_voltage is not None:
            modes = np.where(np.isfinite(self.open_loop_voltage), MODE_OPEN_LOOP, modes)
        return modes


@dataclass
class RobotRun:
    """Outcome of :func:`run_phases`: recording arrays, summary, interruption flag."""

    recording: dict[str, np.ndarray]
    summary: dict[str, Any]
    interrupted: bool
    wall_time: float
    folder: Path
    extra_files: list[Path] = field(default_factory=list)


def tank_endurance(simulation: RobotSimulation, mean_flow: float) -> float:
    """Time [s] the actuator files' tank lasts at a mean air flow [kg/s] (thesis 1.1).

    The usable air is what the tank holds above the regulated supply pressure at the
    tank temperature (ideal gas): m = V·(p0 − ps)/(R·T).
    """
    supply = simulation.robot.actuators["alpha"].supply
    if supply.tank_volume is None or supply.tank_initial_pressure is None or mean_flow <= 0:
        return math.nan
    temperature = supply.tank_temperature or float(simulation.params[0]["supply_temperature"])
    usable = (
        supply.tank_volume
        * (supply.tank_initial_pressure - supply.supply_pressure)
        / (simulation.params[0]["gas_constant"] * temperature)
    )
    return usable / mean_flow


def reference_table(phase: Phase, start: float, steps: int, step: float,
                    count: int) -> np.ndarray:
    """The references (steps, count) [rad] of ``phase`` for the ``steps`` control steps
    of ``step`` [s] after simulation time ``start`` [s] (a reference function called
    with those times, or the phase's constant references repeated)."""
    times = start + step * np.arange(1, steps + 1)
    if callable(phase.references):
        table = np.asarray(phase.references(times), dtype=float)
    else:
        table = np.broadcast_to(np.asarray(phase.references, dtype=float), (steps, count))
    return np.ascontiguousarray(table.reshape(steps, count))


def run_phases(
    simulation: RobotSimulation,
    phases: list[Phase],
    folder: Path,
    description: str,
    progress: Callable[[float, float], None] | None = None,
    extra_summary: dict[str, Any] | None = None,
    clock: StageClock | None = None,
    on_sample: Callable[[float, np.ndarray], None] | None = None,
) -> RobotRun:
    """Play ``phases`` on ``simulation`` and write the run folder (module docstring).

    ``clock`` (optional) receives the wall time of each stage: ``"simulation"`` (the
    compiled steps: MuJoCo, actuators and joint controllers), ``"references"`` (planned
    references) or ``"walking feedback"`` (reference functions that read the state once
    per chunk), ``"recording"`` (rows, CSV and Parquet, trajectory) and ``"run folder"``.
    The summary's ``"wall time [s]"`` is the whole run from the first phase to the
    recording written.

    ``on_sample(time, qpos)`` (optional) is called with each sample of ``trajectory.npz`` as
    it is recorded, the first one after ``model.xml`` has been written: simulated time [s]
    and joint positions (nq,), a row it must not modify (e.g. a video worker that renders
    while the run goes, :meth:`pneumaquad.robot.video_worker.VideoWorker.add_sample`).
    """
    clock = StageClock() if clock is None else clock
    robot = simulation.robot
    writer = RunFolderWriter(folder)
    with clock.stage("run folder"):
        writer.write_parameters(robot.parameters)
        writer.write_model(robot.to_xml())
    every = robot.parameters.simulation.recording_every
    dt = simulation.control_step
    count = robot.joint_count
    total = sum(p.duration for p in phases)
    samples = sum(-(-round(p.duration / dt) // every) for p in phases) + 1
    times = np.empty(samples)
    qpos = np.empty((samples, simulation.model.nq))
    recorded = 0
    interrupted = False
    started = time.perf_counter()
    columns = recording_columns(simulation)
    phase_starts = []
    controlled = np.zeros(count, dtype=bool)
    failure: Exception | None = None
    stopped_before: dict[str, str] | None = None
    checks: dict[str, dict[str, Any]] = {}
    stepping = feedback_seconds = reference_seconds = recording_seconds = 0.0
    chunks = 0
    with writer.recorder(columns, background=True) as recorder, \
            deferred_interrupt() as stop:
        rows_out = RowBuffer(recorder)

        def record(reference_angles: np.ndarray) -> None:
            nonlocal recorded
            fill_recording_row(simulation, reference_angles, rows_out.row())
            rows_out.commit()
            times[recorded] = simulation.time
            qpos[recorded] = simulation.data.qpos
            recorded += 1
            if on_sample is not None:
                on_sample(times[recorded - 1], qpos[recorded - 1])

        record(simulation.reference_angles)
        try:
            for phase in phases:
                reason = None
                if phase.gate is not None:
                    reason, checks[phase.name] = phase.gate(simulation)
                if reason is not None:
                    stopped_before = {"phase": phase.name, "reason": reason}
                    break
                phase_starts.append((phase.name, simulation.time))
                controlled |= np.asarray(phase.closed_loop, dtype=bool)
                modes = phase.modes()
                voltages = phase.open_loop_voltage
                steps = round(phase.duration / dt)
                if not phase.feedback:
                    begun = time.perf_counter()
                    table = reference_table(phase, simulation.time, steps, dt, count)
                    reference_seconds += time.perf_counter() - begun
                simulation.joint_control["mode"] = modes
                simulation.stop_force_tracking()  # a feedback phase may track forces
                if voltages is not None:
                    simulation.open_loop_voltage[:] = np.where(
                        np.isfinite(voltages), voltages, simulation.open_loop_voltage
                    )
                done = 0
                while done < steps and not stop.requested:
                    chunk = min(every, steps - done)
                    begun = time.perf_counter()
                    if phase.feedback:
                        rows = reference_table(phase, simulation.time, chunk, dt, count)
                        fed = time.perf_counter()
                        feedback_seconds += fed - begun
                        simulation.step(chunk, rows, 0)
                    else:
                        rows = table[done : done + chunk]
                        fed = begun
                        simulation.step(chunk, table, done)
                    stepped = time.perf_counter()
                    stepping += stepped - fed
                    done += chunk
                    chunks += 1
                    record(rows[-1])
                    recording_seconds += time.perf_counter() - stepped
                    if progress is not None and done % (every * 20) == 0:
                        progress(simulation.time, total)
                if stop.requested:
                    interrupted = True
                    break
        except SimulationDivergedError as error:
            failure = error  # keep what was recorded before it; re-raised below
        finally:
            rows_out.flush()
        recording = recorder.to_arrays()
        closing = time.perf_counter()
    recording_seconds += time.perf_counter() - closing  # the Parquet file
    begun = time.perf_counter()
    writer.write_trajectory(times[:recorded], qpos[:recorded])
    recording_seconds += time.perf_counter() - begun
    wall = time.perf_counter() - started
    clock.add("simulation", stepping, chunks)
    if reference_seconds:
        clock.add("references", reference_seconds)
    if feedback_seconds:
        clock.add("walking feedback", feedback_seconds)
    clock.add("recording", recording_seconds, recorded)
    with clock.stage("run folder"):
        summary = _summary(
            simulation, recording, description, wall, interrupted, phase_starts, controlled
        )
        if extra_summary:
            summary.update(extra_summary)
        if checks:
            summary["checks"] = checks
        if stopped_before is not None:
            summary["stopped before"] = stopped_before
        summary["diverged"] = failure is not None
        summary["divergences [count]"] = simulation.divergences
        if failure is not None:
            summary["error"] = str(failure)
            summary["diverged at [s]"] = failure.time
        writer.write_summary(summary)
    if failure is not None:
        failure.folder = folder
        raise failure
    return RobotRun(recording, summary, interrupted, wall, folder)


def _phase_air(
    simulation: RobotSimulation,
    recording: dict[str, np.ndarray],
    phase_starts: list[tuple[str, float]],
    normal_litres_per_kg: float,
) -> dict[str, dict[str, float]]:
    """Start, duration, air and tank endurance of each phase (thesis 1.1 motivation)."""
    times = recording["time [s]"]
    air = recording["air consumed [kg]"]
    end_time = float(times[-1])
    phases = {}
    bounds = [start for _, start in phase_starts[1:]] + [end_time]
    for (name, start), end in zip(phase_starts, bounds, strict=True):
        duration = end - start
        if duration <= 0.0:
            continue
        used = float(np.interp(end, times, air) - np.interp(start, times, air))
        flow = used / duration
        phases[name] = {
            "start [s]": start,
            "duration [s]": duration,
            "air consumed [NL]": used * normal_litres_per_kg,
            "mean air flow [NL/min]": flow * normal_litres_per_kg * 60.0,
            "tank endurance at this flow [s]": tank_endurance(simulation, flow),
        }
    return phases


def _summary(
    simulation: RobotSimulation,
    recording: dict[str, np.ndarray],
    description: str,
    wall: float,
    interrupted: bool,
    phase_starts: list[tuple[str, float]],
    controlled: np.ndarray,
) -> dict[str, Any]:
    robot = simulation.robot
    simulated = float(recording["time [s]"][-1] - recording["time [s]"][0])
    air = simulation.air_consumed()
    per_joint = simulation.air_consumed_per_joint()
    mean_flow = air / simulated if simulated > 0 else math.nan
    normal_litres_per_kg = (
        simulation.params[0]["gas_constant"] * 273.15 / 101325.0 * 1000.0
    )
    summary: dict[str, Any] = {
        "description": description,
        "parameter set": robot.parameters.meta.name,
        "configuration": robot.configuration,
        "environment": robot.environment,
        "seal friction": robot.parameters.simulation.seal_friction,
        "control step [s]": simulation.control_step,
        "substeps": simulation.substeps,
        "interrupted": interrupted,
        "simulated time [s]": simulated,
        "wall time [s]": wall,
        "real-time factor": simulated / wall if wall > 0 else math.nan,
        "air consumed [kg]": air,
        "air consumed [NL]": air * normal_litres_per_kg,
        "mean air flow [NL/min]": mean_flow * normal_litres_per_kg * 60.0,
        "air consumed per joint [NL]": {
            name: float(value * normal_litres_per_kg)
            for name, value in zip(robot.joint_names, per_joint, strict=True)
        },
        "tank endurance at this mean flow [s]": tank_endurance(simulation, mean_flow),
    }
    summary["phases"] = _phase_air(simulation, recording, phase_starts, normal_litres_per_kg)
    errors = {}
    for name, closed in zip(robot.joint_names, controlled, strict=True):
        reference = recording[f"{name} reference [rad]"]
        angle = recording[f"{name} angle [rad]"]
        if closed:
            errors[name] = float(np.degrees(np.sqrt(np.mean((angle - reference) ** 2))))
    summary["angle rmse [deg]"] = errors
    return summary
