"""Cost of one ``doStep`` of the actuator FMU against the in-process kernel step.

Setup: the FMU of ``crr-gamma`` (``pneumaquad export fmu``: underlapped valve,
Stribeck-tanh friction, adiabatic chambers, 1 ms kernel step with 5 substeps) run by FMPy
in a co-simulation loop against a mass on a spring integrated in plain Python (25 kg,
15 kN/m, exchange every 1 ms, a 2 V 1.5 Hz sine about the valve offset), and the same load
driven by the in-process kernel (``step_actuators`` called from Python, one call per
exchange). Per round, after a warm-up, each loop runs ``--steps`` exchanges; the rounds
alternate so that other load on the machine hits both alike. Printed, as min / median /
max over the rounds, in µs per exchange:

* **doStep**: the FMI call alone (FMPy's ctypes call, pythonfmu's binary, the slave's
  Python code, the kernel);
* **doStep + I/O**: the whole exchange: ``setReal`` of the three inputs, ``doStep``,
  ``getReal`` of three outputs;
* **kernel step**: the ``step_actuators`` call from Python (numba dispatch included);

the ratios of the medians, doStep / kernel step and exchange / kernel step, and the
largest differences between the two runs' chamber pressures (share of the supply
pressure) and forces (share of the force range). Nothing is asserted. Runs in a few
seconds.

Run: ``.venv/bin/python benchmarks/fmu_speed.py [--steps 2000] [--repeats 7] [--json out.json]``.
"""

from __future__ import annotations

import argparse
import math
import tempfile
import time
from pathlib import Path

import fmpy
import numpy as np
from fmpy.fmi2 import FMU2Slave

from _bench import machine_line, stats, table, write_json
from pneumaquad.core.actuator import (
    initial_state,
    new_outputs,
    pack_parameter_array,
    supply_state,
)
from pneumaquad.core.kernel import step_actuators
from pneumaquad.core.layout import ACTUATOR_STATE_DTYPE
from pneumaquad.core.pneumatics import friction_of, state_outputs
from pneumaquad.interop.fmu_export import export_fmu
from pneumaquad.params import load_actuator

SET = "crr-gamma"
MASS = 25.0  # kg
STIFFNESS = 15000.0  # N/m
STEP = 1e-3  # s
INPUTS = ("valve_voltage", "piston_position", "piston_velocity")
OUTPUTS = ("piston_force", "cap_pressure", "rod_pressure")


def command(time_s: float) -> float:
    """Valve voltage [V]: a 2 V, 1.5 Hz sine about the 5.25 V offset."""
    return 5.25 + 2.0 * math.sin(2.0 * math.pi * 1.5 * time_s)


class FmuLoop:
    """The FMU against the mass on a spring, restartable (FMI reset) for each round."""

    def __init__(self, folder: Path) -> None:
        fmu_file = export_fmu(SET, folder / "gamma.fmu")
        description = fmpy.read_model_description(str(fmu_file))
        unpacked = fmpy.extract(str(fmu_file), str(folder / "unpacked"))
        self.variables = {v.name: v for v in description.modelVariables}
        self.fmu = FMU2Slave(guid=description.guid, unzipDirectory=unpacked,
                             modelIdentifier=description.coSimulation.modelIdentifier,
                             instanceName="benchmark")
        self.fmu.instantiate()
        self.start_position = float(self.variables["piston_position"].start)
        self.started = False

    def start(self, value: str) -> float:
        return float(self.variables[value].start)

    def run(self, steps: int) -> tuple[float, float, np.ndarray]:
        """One round from rest (FMI reset): the median times [s] of doStep alone and of
        the whole exchange, and the (steps, 3) outputs."""
        fmu = self.fmu
        if self.started:
            fmu.reset()
        self.started = True
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        inputs = [self.variables[name].valueReference for name in INPUTS]
        outputs = [self.variables[name].valueReference for name in OUTPUTS]
        position, velocity, rest = self.start_position, 0.0, self.start_position
        fmu.setReal(inputs, [command(0.0), position, velocity])
        fmu.exitInitializationMode()
        force = fmu.getReal(outputs)[0]
        step_times, exchange_times, rows = [], [], []
        clock = time.perf_counter
        for n in range(steps):
            begun = clock()
            fmu.setReal(inputs, [command(n * STEP), position, velocity])
            stepped = clock()
            fmu.doStep(n * STEP, STEP)
            done = clock()
            values = fmu.getReal(outputs)
            ended = clock()
            step_times.append(done - stepped)
            exchange_times.append(ended - begun)
            velocity += STEP * (force - STIFFNESS * (position - rest)) / MASS
            position += STEP * velocity
            force = values[0]
            rows.append(values)
        return float(np.median(step_times)), float(np.median(exchange_times)), np.array(rows)

    def close(self) -> None:
        self.fmu.terminate()
        self.fmu.freeInstance()


def kernel_run(steps: int, position: float, cap: float, rod: float,
               substeps: int) -> tuple[float, np.ndarray]:
    """The same load on the in-process kernel: median time per kernel call [s] and the
    (steps, 3) outputs."""
    actuator = load_actuator(SET)
    params = pack_parameter_array([actuator])
    state = np.zeros(1, ACTUATOR_STATE_DTYPE)
    initial_state(params[0], position, cap, rod, out=state[0])
    supply, outputs = supply_state(actuator), new_outputs(1)
    state_outputs(params[0], state[0], position, outputs[0])
    force = outputs[0]["pneumatic_force"] - friction_of(params[0], 0.0, 0.0)
    commands, positions, velocities = np.zeros(1), np.zeros(1), np.zeros(1)
    velocity, rest = 0.0, position
    times, rows = [], []
    clock = time.perf_counter
    for n in range(steps):
        commands[0] = command(n * STEP)
        positions[0] = position
        velocities[0] = velocity
        begun = clock()
        step_actuators(params, state, commands, positions, velocities, STEP, substeps,
                       supply, outputs)
        times.append(clock() - begun)
        out = outputs[0]
        values = (out["pneumatic_force"] - out["friction_force"], state[0]["cap_pressure"],
                  state[0]["rod_pressure"])
        velocity += STEP * (force - STIFFNESS * (position - rest)) / MASS
        position += STEP * velocity
        force = values[0]
        rows.append(values)
    return float(np.median(times)), np.array(rows)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--json", default=None)
    arguments = parser.parse_args()
    print(machine_line())
    with tempfile.TemporaryDirectory(prefix="fmu-speed-") as folder:
        loop = FmuLoop(Path(folder))
        try:
            cap, rod = loop.start("initial.cap_pressure"), loop.start("initial.rod_pressure")
            substeps = int(loop.variables["simulation.substeps"].start)
            loop.run(200)  # warm-up of both loops
            kernel_run(200, loop.start_position, cap, rod, substeps)
            step_samples, exchange_samples, kernel_samples = [], [], []
            for _ in range(arguments.repeats):
                step, exchange, through_fmu = loop.run(arguments.steps)
                kernel, in_process = kernel_run(arguments.steps, loop.start_position, cap,
                                                rod, substeps)
                step_samples.append(step)
                exchange_samples.append(exchange)
                kernel_samples.append(kernel)
        finally:
            loop.close()
    micro = 1e6
    do_step, whole, kernel = (stats(s).scaled(micro) for s in
                              (step_samples, exchange_samples, kernel_samples))
    supply = load_actuator(SET).supply.supply_pressure
    pressure_error = np.max(np.abs(through_fmu[:, 1:] - in_process[:, 1:])) / supply
    force_error = (np.max(np.abs(through_fmu[:, 0] - in_process[:, 0]))
                   / np.ptp(in_process[:, 0]))
    print(f"\n{SET}: {arguments.steps} exchanges of {STEP * 1e3:g} ms per round, "
          f"{arguments.repeats} rounds (medians per round: min / median / max)\n")
    print(table(["per exchange", "µs"], [
        ["doStep", do_step.spread(1)],
        ["doStep + setReal + getReal", whole.spread(1)],
        ["kernel step (step_actuators from Python)", kernel.spread(1)],
    ]))
    print(f"\ndoStep / kernel step: {do_step.median / kernel.median:.1f}; "
          f"exchange / kernel step: {whole.median / kernel.median:.1f}")
    print(f"largest difference FMU - kernel: pressures {100 * pressure_error:.3g} % of the "
          f"supply pressure, force {100 * force_error:.3g} % of its range "
          f"({np.ptp(in_process[:, 0]):.4g} N)")
    write_json(arguments.json, {
        "set": SET, "steps": arguments.steps, "repeats": arguments.repeats,
        "doStep [us]": do_step, "exchange [us]": whole, "kernel step [us]": kernel,
        "pressure difference [share of supply]": float(pressure_error),
        "force difference [share of range]": float(force_error),
    })


if __name__ == "__main__":
    main()
