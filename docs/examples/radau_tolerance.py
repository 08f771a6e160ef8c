"""Count the adaptive reference's right-hand-side evaluations (docs/physics.md, Integration).

thesis-rig, Radau, open-loop step to 6 V after 1 s at the opposite saturation, 3 s in all
(the piston reaches the extended end stop at about 1.8 s and rests there), once with the
shipped absolute tolerances (1e-6 of each state's typical size) and once with 1e-8.
Counts every evaluation of ``pneumaquad.core.kernel.rig_rates`` (the solver's and those of the
forward-difference Jacobian) per 1 ms control interval, and prints the mean per 100 ms.
The 1e-8 run takes a few minutes.

    .venv/bin/python docs/examples/radau_tolerance.py
"""

from __future__ import annotations

import time

import numpy as np

import pneumaquad.rig.simulate as rig_simulate
from pneumaquad.params import load_rig
from pneumaquad.rig import signals

calls = [0]
per_interval: list[int] = []
_rig_rates, _solve_ivp = rig_simulate.rig_rates, rig_simulate.solve_ivp


def counted_rates(*args):
    calls[0] += 1
    return _rig_rates(*args)


def counted_solve(*args, **kwargs):
    before = calls[0]
    solution = _solve_ivp(*args, **kwargs)
    per_interval.append(calls[0] - before)
    return solution


def main() -> None:
    rig_simulate.rig_rates, rig_simulate.solve_ivp = counted_rates, counted_solve
    for tolerance in (1e-6, 1e-8):
        setup = load_rig(
            "thesis-rig",
            ['simulation.integrator="radau"', f"simulation.absolute_tolerance={tolerance}"],
        )
        valve = setup.actuator.valve
        command = signals.thesis_step_command(
            6.0,
            valve.offset_voltage,
            valve.min_voltage,
            valve.max_voltage,
            setup.simulation.control_step,
            step_time=1.0,
            duration=3.0,
        )
        per_interval.clear()
        clock = time.perf_counter()
        rig_simulate.simulate_rig(setup, command, False)
        wall = time.perf_counter() - clock
        means = np.asarray(per_interval).reshape(-1, 100).mean(axis=1)
        print(f"absolute tolerance {tolerance:g}: {wall:.1f} s wall")
        print(f"  evaluations per ms, mean of each 100 ms: {np.round(means).astype(int)}")


if __name__ == "__main__":
    main()
