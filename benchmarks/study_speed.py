"""Speed of a rig study: one process against the process pool, and the study's own cost.

The study is studies/thesis-variability-step.toml (the thesis's 10 s step protocol with
friction drawn from the thesis's spread) cut to ``--cases`` cases, run in fresh folders:

(a) in this process, rigs batched through the vectorised kernel (the study's batch size)
    and one rig at a time (batch 1): thesis step protocols per minute on one core;
(b) on the local pool of ``--workers`` processes: cases/s, and the parallel efficiency
    (pool cases/s) / (workers × one-process cases/s), pool start-up included;
(c) the same cases run directly (parameters loaded, signal built, rigs simulated in the
    same batches, metrics computed) without the study: the study's overhead per case
    (drawing the design, scheduling, writing the Parquet rows, reading back what is done)
    as a share of a case, and the design's part of it.

Every path is warmed first (a short study in this process: compiled code, pyarrow and the
pandas it loads), so one-off process start-up is not counted as overhead per case; the
pool's start-up (spawning and warming its workers) is part of its wall time.

Each path runs ``--repeats`` times, interleaved; the tables give the fastest (the least
disturbed by other work on the machine) and the range.

``--robot`` measures (b) on a robot study instead (the quadruped standing up, one case per
supply pressure), e.g. ``--robot --cases 16``; ``--robot-study FILE`` on a study file as
it is (e.g. the shipped ``studies/walk-sizing.toml``, 27 walks). Both also print the CPU
time the pool's workers used against the one process's, and the workers' start-up.

Run: ``.venv/bin/python benchmarks/study_speed.py [--cases 512] [--workers N]
[--repeats 3] [--robot | --robot-study FILE] [--json out.json]``. Nothing asserts on
wall-clock time.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import re
import resource
import tempfile
import time
from pathlib import Path

import numpy as np

from _bench import machine_line, table, write_json
from pneumaquad.params import load_rig
from pneumaquad.rig import signals
from pneumaquad.rig.metrics import general_metrics, step_metrics
from pneumaquad.rig.simulate import simulate_rigs
from pneumaquad.studies import (
    default_workers,
    load_study,
    parse_study,
    pool_executor,
    run_study,
    serial_executor,
    study_cases,
)
from pneumaquad.studies.case_runs import warm_up
from pneumaquad.studies.run_options import parse_run_options

STUDY = Path(__file__).resolve().parents[1] / "studies" / "thesis-variability-step.toml"


def _study(cases: int, batch: int | None = None):
    text = re.sub(r"(?m)^cases = \d+", f"cases = {cases}", STUDY.read_text(encoding="utf-8"))
    spec = parse_study(text, str(STUDY))
    return spec if batch is None else dataclasses.replace(spec, batch=batch)


def _timed_study(spec, executor, failures: int = 0) -> float:
    """Wall time of the study run afresh [s]; every case ran, ``failures`` of them
    recorded as failed (a study file's refused cases)."""
    with tempfile.TemporaryDirectory() as folder:
        result = run_study(spec, Path(folder) / "study", executor)
    assert result.ran == spec.cases and result.failed == failures
    return result.wall_time


#: A robot study for ``--robot``: the quadruped stands up (1 s hold, no body commands) at
#: supply pressures spread over 45-60 psig, one case each.
ROBOT_STUDY = """
[study]
name = "stand-speed"
sampling = "latin-hypercube"
cases = {cases}
seed = 1
metrics = ["checks.stance check.verified", "phases.stand up.air consumed [NL]"]

[run]
kind = "robot-stand"
hold = "1 s"
posture = false

[vary."actuators.supply_pressure"]
distribution = "uniform"
low = "45 psig"
high = "60 psig"
"""


def _children_cpu() -> float:
    """CPU seconds used so far by this process's finished child processes."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def robot_efficiency(spec, workers: int, repeats: int, json_path: str | None) -> None:
    """Parallel efficiency of the pool on a robot study (``--robot``, ``--robot-study``)."""
    warm_up(spec.run.kind)
    walls: dict[str, list[float]] = {"serial": [], "pool": []}
    cpu: list[float] = []
    with tempfile.TemporaryDirectory() as folder:  # the failed cases, counted once
        failures = run_study(spec, Path(folder) / "study", serial_executor).failed
    for _ in range(repeats):
        walls["serial"].append(_timed_study(spec, serial_executor, failures))
        before = _children_cpu()
        walls["pool"].append(_timed_study(spec, pool_executor(workers), failures))
        cpu.append(_children_cpu() - before)
    serial, pooled = min(walls["serial"]), min(walls["pool"])
    cases = spec.cases
    print(machine_line())
    print(f"robot study {spec.name} ({spec.run.kind}), {cases} cases, {workers} workers, "
          f"fastest of {repeats}: one process {serial:.2f} s ({cases / serial:.2f} cases/s), "
          f"pool {pooled:.2f} s ({cases / pooled:.2f} cases/s, start-up included)")
    print(f"the pool's workers used {min(cpu):.1f} s of CPU for what takes {serial:.1f} s in "
          f"one process (+{min(cpu) - serial:.1f} s: their start-up and running side by "
          "side)")
    print(f"parallel efficiency of the pool: {100 * serial / (workers * pooled):.0f} %")
    write_json(json_path, {"study": spec.name, "cases": cases, "workers": workers,
                           "walls [s]": walls, "worker cpu [s]": cpu,
                           "parallel efficiency": serial / (workers * pooled)})


def _direct(spec) -> float:
    """The same cases without the study: load, build, simulate in batches, metrics [s]."""
    started = time.perf_counter()
    cases = study_cases(spec)
    for first in range(0, len(cases), spec.batch):
        batch = cases[first:first + spec.batch]
        setups = [load_rig(spec.run.params, [*spec.run.overrides, *c.overrides])
                  for c in batch]
        options = parse_run_options(spec.run.kind, spec.run.options)
        valve = setups[0].actuator.valve
        command = signals.thesis_step_command(
            options["voltage"], valve.offset_voltage, valve.min_voltage, valve.max_voltage,
            setups[0].simulation.control_step, options["step_time"], options["duration"])
        results = simulate_rigs(setups, np.tile(command, (len(batch), 1)), False)
        for result in results:
            general_metrics(result.recording)
            step_metrics(result.recording, options["step_time"])
    return time.perf_counter() - started


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", type=int, default=512)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--workers", type=int, default=default_workers())
    parser.add_argument("--robot", action="store_true",
                        help="measure the pool on a robot stand-up study instead")
    parser.add_argument("--robot-study", metavar="FILE",
                        help="measure the pool on this robot study file as it is")
    parser.add_argument("--json")
    arguments = parser.parse_args()
    cases, workers = arguments.cases, arguments.workers
    if arguments.robot_study:
        robot_efficiency(load_study(arguments.robot_study), workers, arguments.repeats,
                         arguments.json)
        return
    if arguments.robot:
        robot_efficiency(parse_study(ROBOT_STUDY.format(cases=cases)), workers,
                         arguments.repeats, arguments.json)
        return
    load_before = " ".join(f"{value:.2f}" for value in os.getloadavg())
    warm_up("rig-step")
    _timed_study(_study(16), serial_executor)
    batched, alone_spec = _study(cases), _study(cases, batch=1)
    walls: dict[str, list[float]] = {"design": [], "serial": [], "alone": [], "direct": [],
                                     "pool": []}
    for _ in range(arguments.repeats):
        drawn = time.perf_counter()
        study_cases(batched)
        walls["design"].append(time.perf_counter() - drawn)
        walls["serial"].append(_timed_study(batched, serial_executor))
        walls["alone"].append(_timed_study(alone_spec, serial_executor))
        walls["direct"].append(_direct(batched))
        walls["pool"].append(_timed_study(batched, pool_executor(workers)))
    design, serial, direct, pooled = (min(walls[k]) for k in ("design", "serial", "direct",
                                                              "pool"))
    serial_rate, pool_rate = cases / serial, cases / pooled
    efficiency = pool_rate / (workers * serial_rate)
    overhead = (serial - direct) / cases  # drawing the design included

    def row(label: str, key: str) -> list[str]:
        fastest = min(walls[key])
        return [label, f"{fastest:.2f} ({fastest:.2f}-{max(walls[key]):.2f})",
                f"{cases / fastest:.1f}", f"{60 * cases / fastest:.0f}"]

    print(machine_line())
    print(f"load average before the run: {load_before}")
    print(f"study: {STUDY.name}, {cases} cases of 10 s simulated, batch {batched.batch}, "
          f"{workers} workers, fastest of {arguments.repeats}")
    print(table(["run", "wall [s] (range)", "cases/s", "protocols/min"], [
        row("one process, batched", "serial"),
        row("one process, one rig at a time", "alone"),
        row("same cases without the study", "direct"),
        row(f"pool of {workers} (start-up included)", "pool"),
    ]))
    print(f"parallel efficiency of the pool: {100 * efficiency:.0f} %")
    print(f"study overhead per case: {1e3 * overhead:.2f} ms = "
          f"{100 * overhead / (direct / cases):.1f} % of a case, of which drawing the "
          f"design ({batched.sampling}, {design:.2f} s once) {1e3 * design / cases:.2f} ms")
    write_json(arguments.json, {
        "cases": cases, "workers": workers, "batch": batched.batch,
        "walls [s]": walls, "parallel efficiency": efficiency,
        "overhead per case [s]": overhead,
    })


if __name__ == "__main__":
    main()
