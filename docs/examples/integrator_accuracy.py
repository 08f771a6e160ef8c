"""Measure the fixed-step integrator against the adaptive reference (README "Accuracy of the
fixed-step integrator", docs/physics.md "Integration").

The runs of the tests in tests/test_rig.py (``test_fixed_step_matches_radau_*``), each
simulated with the fixed step (the shipped 5 substeps of 0.2 ms, and 10 substeps) and with
scipy's Radau (rtol 1e-6) on the same sampled controller; prints the RMS differences in
position and in the worse chamber's pressure, in mm / kPa and as a share of the stroke /
of the absolute supply pressure. Then the wall time (best of 3) of the full 10 s thesis step
protocol at 6 V with the shipped Stribeck-tanh friction, with Radau, LSODA and the fixed
step.

    .venv/bin/python docs/examples/integrator_accuracy.py
"""

from __future__ import annotations

import time

import numpy as np

from pneumaquad.params import load_rig
from pneumaquad.rig import signals
from pneumaquad.rig.simulate import simulate_rig

INCH = 0.0254


def thesis_step(setup, voltage: float, step_time: float = 5.0, duration: float = 10.0):
    """The thesis open-loop step protocol: opposite saturation, then the step."""
    valve = setup.actuator.valve
    return signals.thesis_step_command(
        voltage,
        valve.offset_voltage,
        valve.min_voltage,
        valve.max_voltage,
        setup.simulation.control_step,
        step_time=step_time,
        duration=duration,
    )


def sine(setup):
    """1 Hz, 0.3 in sine about mid-stroke for 2.5 s."""
    stroke = setup.actuator.cylinder.stroke
    return signals.sine(stroke / 2, 0.3 * INCH, 1.0, 2.5, setup.simulation.control_step)


RUNS = (
    (
        "open-loop step to 6 V, 1.5 s after the step, Stribeck-tanh",
        (),
        lambda s: thesis_step(s, 6.0, step_time=1.0, duration=2.5),
        False,
    ),
    (
        "full 10 s thesis step protocol at 6 V, LuGre",
        ('friction.model="lugre"',),
        lambda s: thesis_step(s, 6.0),
        False,
    ),
    ("closed-loop 1 Hz sine, 2.5 s, LuGre", ('friction.model="lugre"',), sine, True),
    ("closed-loop 1 Hz sine, 2.5 s, Stribeck-tanh", (), sine, True),
)


def run(overrides, signal_for, closed_loop):
    setup = load_rig("thesis-rig", list(overrides))
    return setup, simulate_rig(setup, signal_for(setup), closed_loop).recording


def rms(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.mean((a - b) ** 2)))


def main() -> None:
    for label, overrides, signal_for, closed_loop in RUNS:
        setup, radau = run((*overrides, 'simulation.integrator="radau"'), signal_for, closed_loop)
        stroke = setup.actuator.cylinder.stroke
        supply = setup.actuator.supply.supply_pressure
        print(label)
        for substeps in (5, 10):
            _, fixed = run((*overrides, f"simulation.substeps={substeps}"), signal_for, closed_loop)
            position = rms(fixed["position [m]"], radau["position [m]"])
            pressure = max(
                rms(fixed[f"{side} pressure [Pa]"], radau[f"{side} pressure [Pa]"])
                for side in ("cap", "rod")
            )
            print(
                f"  {substeps:2d} substeps: position {1e3 * position:.4f} mm "
                f"({100 * position / stroke:.3f} % of stroke), pressure {pressure / 1e3:.3f} kPa "
                f"({100 * pressure / supply:.3f} % of supply)"
            )
    for integrator in ("radau", "lsoda", "fixed"):
        overrides = (f'simulation.integrator="{integrator}"',)
        walls = []
        for _ in range(3):
            clock = time.perf_counter()
            run(overrides, lambda s: thesis_step(s, 6.0), False)
            walls.append(time.perf_counter() - clock)
        print(
            f"10 s protocol at 6 V, Stribeck-tanh, {integrator}: "
            f"{min(walls):.2f} s wall (best of 3)"
        )


if __name__ == "__main__":
    main()
