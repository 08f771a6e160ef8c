"""Wall time of the coupled robot simulation: the whole quadruped standing on flat ground.

Setup: ``crr-quadruped`` as shipped, ``quadruped`` configuration (free thorax) on the
``flat`` environment; 12 cylinders with the full actuator model (underlapped valve,
Stribeck seal friction in MuJoCo's solver, adiabatic chambers), the shipped Heun
substeps and a 1 ms control step (one MuJoCo step per control step), four foot contacts.
The robot is put standing: every leg at alpha 0°, beta -20°, gamma 50°, the thorax
lowered until the lowest foot touches the ground, all joints commanded closed-loop to
those angles and left to settle for 1 s. Then, after a warm-up (numba compiles the
stepping loop on the first call), it measures:

* **full**: ``RobotSimulation.step(N)`` for N control steps in one call (controllers,
  pneumatic kernel, forces into MuJoCo and ``mj_step``, all inside one compiled loop):
  µs per control step and the real-time factor (simulated s / wall s);
* **full, chunks of 10**: the same in chunks of ``recording_every`` steps (10), one
  ``step`` call from Python per chunk; each chunk ends with MuJoCo's force stages and the
  chambers brought to the end time (``bring_to_present``, ``sample_actuators``), so that
  contact forces and actuator state read between chunks belong to the present instant;
* **full, recording**: the same chunks with one recording row read out after each, as an
  experiment runner would;
* **bare MuJoCo**: the same model and state stepped by ``mujoco.mj_step(m, d, nstep=N)``
  with ``data.ctrl`` held at the standing cylinder forces (plain constant joint motors;
  the same contacts, pose and seal-friction constraints), and the pneumatic overhead
  (full - bare) / bare. Without a controller the constant forces slowly extend the legs
  (the thorax rises a few cm over the 5 s), but the constraint rows stay the same (four
  elliptic foot contacts and 12 tendon friction rows);
* a **breakdown** per control step, each part timed alone in its own loop on the same
  12 rows: the pneumatic kernel as the robot runs it
  (``pneumaquad.core.kernel.advance_actuators`` without the friction output, from a
  compiled loop), the whole control step without MuJoCo (``robot_control_step``: linkage,
  PID, kernel, forces and friction written back) and hence the controller and coupling
  glue (control step - kernel), 12 ``pid_update`` calls alone, the chunk ends (chunks of
  10 - one chunk, per step) and the recording (one row of readouts, divided by
  ``recording_every``).

Every figure is the median and the best (min) of ``--repeats`` repeats, taken in
interleaved rounds after one warm-up each, like the other scripts in this folder;
differences and ratios are per round. Nothing is asserted. Targets (issue): ≥ 50× real
time, pneumatic overhead ≤ 20 % over bare MuJoCo. Runs in well under a minute.

Run: ``.venv/bin/python benchmarks/robot_speed.py [--steps 5000] [--repeats 5] [--json out.json]``.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable

import mujoco
import numpy as np
from numba import njit

from _bench import Stats, machine_line, stats, table, write_json
from pneumaquad.core.control.pid import pid_update
from pneumaquad.params import load_robot
from pneumaquad.robot.builder import build_robot
from pneumaquad.robot.profiling import (
    bare_mujoco_seconds,
    control_step_seconds,
    kernel_seconds,
)
from pneumaquad.robot.simulation import RobotSimulation

POSTURE_DEG = (0.0, -20.0, 50.0)
#: the standing quadruped's full coupled step on one core (issue 14; the earlier target was 50x)
TARGET_REAL_TIME = 60.0
TARGET_OVERHEAD = 0.20


@njit(cache=False)
def pid_loop(count, gains, pid_state, references, positions, dt):
    """``count`` control steps of the 12 PID updates alone."""
    total = 0.0
    for _ in range(count):
        for i in range(gains.shape[0]):
            total += pid_update(gains[i], pid_state[i], references[i], positions[i], dt)
    return total


def standing_simulation(overrides: list[str] | None = None) -> RobotSimulation:
    """The quadruped standing on flat ground, closed-loop, settled for 1 s."""
    robot = build_robot(load_robot("crr-quadruped", overrides or []), "quadruped", "flat")
    sim = RobotSimulation(robot)
    pose = np.tile(np.radians(POSTURE_DEG), len(robot.legs))
    sim.set_pose(pose)
    thorax = sim.data.qpos[0:3].copy()
    thorax[2] -= sim.foot_positions()[:, 2].min()  # lowest foot on the ground (z = 0)
    sim.set_pose(pose, thorax_position=thorax, thorax_quaternion=sim.data.qpos[3:7].copy())
    sim.command_angles(pose)
    sim.step(round(1.0 / sim.control_step))
    return sim


def interleaved(calls: dict[str, Callable[[], float]], repeats: int) -> dict[str, Stats]:
    """Each call (returns seconds per step) once to warm up, then ``repeats`` rounds in turn.

    Interleaving spreads a slow spell of a shared machine over all measurements, and
    keeps the per-round pairs (full vs bare, control step vs kernel) comparable.
    """
    for call in calls.values():
        call()
    samples: dict[str, list[float]] = {name: [] for name in calls}
    for _ in range(repeats):
        for name, call in calls.items():
            samples[name].append(call())
    return {name: stats(values) for name, values in samples.items()}


def time_full(sim: RobotSimulation, steps: int) -> float:
    start = time.perf_counter()
    sim.step(steps)
    return (time.perf_counter() - start) / steps


def recording_row(sim: RobotSimulation) -> tuple:
    """What one recording row reads out of the simulation."""
    return (
        sim.time,
        sim.joint_angles(),
        sim.joint_velocities(),
        sim.chamber_pressures(),
        sim.cylinder_forces(),
        sim.commands.copy(),
        sim.positions.copy(),
        sim.reference_positions.copy(),
        sim.foot_positions(),
        sim.data.qpos[0:7].copy(),
        sim.air_consumed(),
    )


def time_full_chunks(sim: RobotSimulation, steps: int, every: int) -> float:
    start = time.perf_counter()
    for _ in range(steps // every):
        sim.step(every)
    return (time.perf_counter() - start) / (steps // every * every)


def time_full_recording(sim: RobotSimulation, steps: int, every: int) -> float:
    rows = []
    start = time.perf_counter()
    for _ in range(steps // every):
        sim.step(every)
        rows.append(recording_row(sim))
    return (time.perf_counter() - start) / (steps // every * every)


def time_pid(sim: RobotSimulation, steps: int) -> float:
    references = sim.reference_positions.copy()
    positions = sim.positions + 1e-4 * np.sin(np.arange(sim.robot.joint_count))
    pid_state = sim.pid_state.copy()
    start = time.perf_counter()
    pid_loop(steps, sim.gains, pid_state, references, positions, sim.control_step)
    return (time.perf_counter() - start) / steps


def time_recording(sim: RobotSimulation, rows: int) -> float:
    start = time.perf_counter()
    for _ in range(rows):
        recording_row(sim)
    return (time.perf_counter() - start) / rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=int, default=5000, help="control steps per repeat")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--json", default=None, help="write the figures to this file")
    parser.add_argument("--set", action="append", default=[], dest="overrides",
                        help="parameter override, e.g. simulation.substeps=1")
    args = parser.parse_args()
    n = args.steps

    start = time.perf_counter()
    sim = standing_simulation(args.overrides)  # includes compiling the stepping loop on first use
    setup_s = time.perf_counter() - start
    dt = sim.control_step
    every = sim.robot.parameters.simulation.recording_every
    print(f"coupled robot simulation speed  ({machine_line()})")
    print(
        f"crr-quadruped, quadruped on flat ground, {sim.robot.joint_count} cylinders "
        f"(full valve model), {sim.substeps} Heun substeps, control step {dt * 1e3:g} ms, "
        f"{n} steps per repeat, {args.repeats} repeats after a warm-up"
    )
    print(f"setup (build, compile or load the stepping loop, 1 s settling): {setup_s:.1f} s")

    snapshot = mujoco.MjData(sim.model)
    mujoco.mj_copyData(snapshot, sim.model, sim.data)
    figures = interleaved(
        {
            "full": lambda: time_full(sim, n),
            "full, chunks of 10": lambda: time_full_chunks(sim, n, every),
            "full, recording every 10": lambda: time_full_recording(sim, n, every),
            "bare MuJoCo mj_step": lambda: bare_mujoco_seconds(sim, n, snapshot),
            "pneumatic kernel": lambda: kernel_seconds(sim, n),
            "control step w/o MuJoCo": lambda: control_step_seconds(sim, n),
            "12 pid_update": lambda: time_pid(sim, n),
            "recording row / 10": lambda: time_recording(sim, n // every) / every,
        },
        args.repeats,
    )
    contacts, rows = sim.data.ncon, sim.data.nefc
    height = float(sim.data.qpos[2])

    us = {name: value.scaled(1e6) for name, value in figures.items()}
    full, bare = us["full"], us["bare MuJoCo mj_step"]
    real_time = stats([dt * 1e6 / value for value in full.samples])
    overhead = stats([(f - b) / b for f, b in zip(full.samples, bare.samples, strict=True)])
    print(f"standing: thorax at {height:.3f} m, {contacts} contacts, {rows} constraint rows\n")

    print(table(
        ["measurement", "µs/step median", "µs/step best", "× real time (median)"],
        [
            [name, f"{value.median:.2f}", f"{value.min:.2f}", f"{dt * 1e6 / value.median:.0f}"]
            for name, value in us.items()
            if name in ("full", "full, chunks of 10", "full, recording every 10",
                        "bare MuJoCo mj_step")
        ],
    ))  # fmt: skip
    print(
        f"\nreal-time factor (full): median {real_time.median:.1f}×, best {real_time.max:.1f}×"
        f"  -> target ≥ {TARGET_REAL_TIME:.0f}×: "
        f"{'met' if real_time.median >= TARGET_REAL_TIME else 'NOT met'}"
    )
    print(
        f"pneumatic overhead (full - bare) / bare: median {100 * overhead.median:.0f} %, "
        f"best {100 * overhead.min:.0f} %  -> target ≤ {100 * TARGET_OVERHEAD:.0f} %: "
        f"{'met' if overhead.median <= TARGET_OVERHEAD else 'NOT met'}"
    )

    kernel = us["pneumatic kernel"]
    control = us["control step w/o MuJoCo"]
    chunks = us["full, chunks of 10"]
    glue = stats([c - k for c, k in zip(control.samples, kernel.samples, strict=True)])
    rest = stats([f - b - c for f, b, c in zip(
        full.samples, bare.samples, control.samples, strict=True)])
    chunk_ends = stats([c - f for c, f in zip(chunks.samples, full.samples, strict=True)])
    parts = [
        ["MuJoCo step (bare)", bare],
        ["pneumatic kernel (advance_actuators, 12 rows)", kernel],
        ["controller + coupling (control step - kernel)", glue],
        ["  of which 12 pid_update", us["12 pid_update"]],
        ["rest of the coupled step (full - bare - control step)", rest],
        ["chunk ends (chunks of 10 - full)", chunk_ends],
        ["recording (one row every 10 steps)", us["recording row / 10"]],
    ]
    summed = chunks.median + us["recording row / 10"].median
    print("\nbreakdown per control step (each part timed alone, or the difference of two"
          " measurements per round):")
    print(table(
        ["part", "µs median", "µs best", "share of full+recording"],
        [
            [name, f"{value.median:.2f}", f"{value.min:.2f}",
             f"{100 * value.median / us['full, recording every 10'].median:.0f} %"]
            for name, value in parts
        ],
    ))  # fmt: skip
    print(
        "rest of the coupled step: MuJoCo's two step halves called from the compiled loop,"
        " the stability check, cache effects;\nchunk ends: MuJoCo's force stages and the "
        "chambers brought to the end of each chunk, a Python call per chunk"
    )
    print(
        f"chunks of 10 + recording row {summed:.2f} µs vs measured full + recording "
        f"{us['full, recording every 10'].median:.2f} µs"
    )
    write_json(
        args.json,
        {
            "steps": n,
            "control_step": dt,
            "substeps": sim.substeps,
            "us_per_step": us,
            "real_time_factor": real_time,
            "pneumatic_overhead": overhead,
            "controller_glue_us": glue,
            "rest_of_step_us": rest,
            "chunk_ends_us": chunk_ends,
        },
    )


if __name__ == "__main__":
    main()
