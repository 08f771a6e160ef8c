"""Steps per second of the Gymnasium environment against the plain coupled simulation.

Setup: ``pneumaquad/Quadruped-v0`` (``crr-quadruped``, quadruped on flat ground, 12
cylinders with the full actuator model) with ``action="angles"`` and the default control
period of 20 ms (20 simulation steps of 1 ms), reset with seed 0 (the robot settled
standing in the walking pose). The same action is held throughout: the initial pose as
joint-angle references. Measured, in interleaved rounds after one warm-up each, from
the same snapshot of the simulation each round:

* **env (gymnasium.make)**: ``env.step(action)`` through the wrappers ``gymnasium.make``
  adds (order enforcing, time limit set out of reach, the passive checker);
* **env (QuadrupedEnv)**: the same on the unwrapped environment;
* **plain simulation**: the environment's own ``RobotSimulation`` driven as a script
  would, with no observation, reward or wrapper: ``sim.command_angles(action)`` and
  ``sim.step(20)`` per control period.

Each round times every loop by wall clock and by the process's CPU time
(``time.process_time``: on a machine shared with other jobs the CPU time is what this
process spent, the wall time also holds the waits for a core). It prints environment
steps per second (one step = one 20 ms control period), the real-time factor, and the
ratio env / plain of each round, by CPU time and by wall time (issue target: ≥ 80 %),
with the best round of each loop. Nothing is asserted. Runs in about half a minute.

Run: ``.venv/bin/python benchmarks/gym_speed.py [--steps 200] [--repeats 15] [--json out.json]``.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable

import gymnasium
import numpy as np

import pneumaquad.interop as interop
from _bench import Stats, machine_line, stats, table, write_json

TARGET_RATIO = 0.8


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=int, default=200, help="environment steps per round")
    parser.add_argument("--repeats", type=int, default=15, help="rounds")
    parser.add_argument("--json", default=None, help="write the figures to this file")
    args = parser.parse_args()
    n = args.steps

    start = time.perf_counter()
    env = gymnasium.make(interop.ENV_ID, action="angles", max_episode_steps=10**9)
    raw: interop.QuadrupedEnv = env.unwrapped  # type: ignore[assignment]
    env.reset(seed=0)
    setup_s = time.perf_counter() - start
    sim = raw.sim
    action = raw.initial_angles.copy()
    steps = raw.steps_per_action
    snapshot = sim.snapshot()

    def through(step: Callable[[np.ndarray], object]) -> tuple[float, float]:
        sim.restore(snapshot)
        wall, cpu = time.perf_counter(), time.process_time()
        for _ in range(n):
            step(action)
        return (time.perf_counter() - wall) / n, (time.process_time() - cpu) / n

    def plain() -> tuple[float, float]:
        sim.restore(snapshot)
        wall, cpu = time.perf_counter(), time.process_time()
        for _ in range(n):
            sim.command_angles(action)
            sim.step(steps)
        return (time.perf_counter() - wall) / n, (time.process_time() - cpu) / n

    calls: dict[str, Callable[[], tuple[float, float]]] = {
        "env (gymnasium.make)": lambda: through(env.step),
        "env (QuadrupedEnv)": lambda: through(raw.step),
        "plain simulation": plain,
    }
    for call in calls.values():  # warm-up
        call()
    samples: dict[str, list[tuple[float, float]]] = {name: [] for name in calls}
    for _ in range(args.repeats):
        for name, call in calls.items():
            samples[name].append(call())
    clocks = ("wall", "cpu")
    figures: dict[str, dict[str, Stats]] = {
        clock: {name: stats([value[k] for value in values]) for name, values in samples.items()}
        for k, clock in enumerate(clocks)}
    rates = {clock: {name: stats([1.0 / value for value in figure.samples])
                     for name, figure in figures[clock].items()} for clock in clocks}
    envs = ("env (gymnasium.make)", "env (QuadrupedEnv)")
    ratios = {clock: {name: stats([p / e for e, p in zip(
        figures[clock][name].samples, figures[clock]["plain simulation"].samples, strict=True)])
        for name in envs} for clock in clocks}

    period = raw.control_period
    print(f"Gymnasium environment speed  ({machine_line()})")
    print(f"{interop.ENV_ID}, action='angles', control period {period * 1e3:g} ms "
          f"({steps} simulation steps), {n} steps per round, {args.repeats} rounds after "
          f"a warm-up; setup (make, reset, compile or load) {setup_s:.1f} s\n")
    print(table(
        ["loop", "steps/s CPU median", "steps/s CPU best", "steps/s wall median",
         "µs/step CPU median", "× real time (CPU median)"],
        [[name, f"{rate.median:.0f}", f"{rate.max:.0f}",
          f"{rates['wall'][name].median:.0f}", f"{1e6 * figures['cpu'][name].median:.0f}",
          f"{rate.median * period:.1f}"]
         for name, rate in rates["cpu"].items()],
    ))  # fmt: skip
    print()
    for name in envs:
        cpu, wall = ratios["cpu"][name], ratios["wall"][name]
        best = (figures["cpu"]["plain simulation"].min / figures["cpu"][name].min)
        verdict = "met" if cpu.median >= TARGET_RATIO else "NOT met"
        print(f"{name} / plain simulation: CPU time median {100 * cpu.median:.0f} % "
              f"(rounds {100 * cpu.min:.0f}–{100 * cpu.max:.0f} %, best rounds "
              f"{100 * best:.0f} %), wall time median {100 * wall.median:.0f} %  -> target "
              f"≥ {100 * TARGET_RATIO:.0f} %: {verdict}")
    write_json(args.json, {"steps": n, "control_period": period, "seconds_per_step": figures,
                           "steps_per_second": rates, "ratio_to_plain": ratios})
    env.close()


if __name__ == "__main__":
    main()
