"""A rig experiment end to end: run folder, recording, summary and plot."""

import math
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from pneumaquad.io.run_folder import RunFolderWriter
from pneumaquad.io.stage_clock import StageClock
from pneumaquad.params.schema import RigSetup
from pneumaquad.reporting.plotting import plot_rig_run
from pneumaquad.rig.metrics import general_metrics, step_metrics, tracking_metrics
from pneumaquad.rig.simulate import RIG_COLUMNS, RigDivergedError, RigResult, simulate_rig


def run_rig_experiment(
    setup: RigSetup,
    folder: Path,
    signal: np.ndarray,
    closed_loop: bool,
    description: str,
    step_time: float | None = None,
    progress: Callable[[int, int], None] | None = None,
    extra: dict[str, Any] | None = None,
    clock: StageClock | None = None,
) -> tuple[RigResult, dict[str, Any]]:
    """Run one rig experiment and write its run folder (through
    :class:`~pneumaquad.io.run_folder.RunFolderWriter`, docs/run-folder.md).

    The folder receives ``parameters.toml`` (resolved, SI, loadable again),
    ``recording.csv`` (flushed as the run goes) and ``recording.parquet``,
    ``summary.json`` and ``rig.png`` (position, pressures and command, like thesis
    figures 25–28). An interrupted run (Ctrl-C) still writes all of them for the part
    that ran, with ``"interrupted": true`` in the summary. A run that goes non-finite
    writes them for the rows before it, with the message under ``"error"`` in the
    summary, and then raises.

    Returns
    -------
    (RigResult, summary dict)

    Raises
    ------
    RigDivergedError
        After writing the folder, when a recorded value became non-finite.
    """
    clock = StageClock() if clock is None else clock
    writer = RunFolderWriter(folder)
    with clock.stage("run folder"):
        writer.write_parameters(setup)
    failure: RigDivergedError | None = None
    recorder = writer.recorder(RIG_COLUMNS, background=True)
    try:
        result = simulate_rig(setup, signal, closed_loop, recorder=recorder,
                              progress=progress, clock=clock)
    except RigDivergedError as error:
        failure, result = error, error.result
    finally:
        closing = time.perf_counter()
        recorder.close()
        closed = time.perf_counter() - closing
        clock.add("recording", closed)
    run_wall = result.wall_time + closed  # from the first step to the recording written
    recording = result.recording
    simulated = float(recording["time [s]"][-1]) if recording["time [s]"].size else 0.0
    summary: dict[str, Any] = {
        "description": description,
        "parameter set": setup.actuator.meta.name,
        "integrator": result.integrator,
        "control step [s]": setup.simulation.control_step,
        "substeps": setup.simulation.substeps,
        "friction model": setup.actuator.friction.model,
        "valve model": setup.actuator.valve.model,
        "closed loop": closed_loop,
        "interrupted": result.interrupted,
        "steps": int(recording["time [s]"].size),
        "wall time [s]": run_wall,
        "real-time factor": simulated / run_wall if run_wall > 0 else math.nan,
    }
    if extra:
        summary.update(extra)
    if failure is not None:
        summary["error"] = str(failure)
    if recording["time [s]"].size:
        with clock.stage("metrics"):
            summary.update(general_metrics(recording))
            if failure is None and closed_loop:
                summary.update(tracking_metrics(recording, setup.actuator.cylinder.stroke))
            elif failure is None and step_time is not None:
                summary.update(step_metrics(recording, step_time))
        with clock.stage("plot"):
            plot_rig_run(recording, folder / "rig.png", title=description)
    with clock.stage("run folder"):
        writer.write_summary(summary)
    if failure is not None:
        raise failure
    return result, summary
