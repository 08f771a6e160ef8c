"""Where a robot run's compiled steps spend their time: MuJoCo, actuators, controllers.

A run's control steps are compiled together (:mod:`pneumaquad.robot.stepping`): MuJoCo's
two step halves, the 12 actuators' kernel and the joint controllers with the coupling run
in one call per chunk, so a clock around the call sees only their sum. For ``--profile``,
:func:`split_simulation_time` times each part alone for a few thousand steps on copies of
the run's final state — bare ``mj_step``, the kernel, the control step without MuJoCo —
and shares the measured time of the chunks out in those proportions
(``benchmarks/robot_speed.py`` times the same parts). The parts are
estimates (each timed alone, warm in the cache); what they do not explain (the chunk
ends: a Python call per chunk and MuJoCo's force stages) is reported as such.
"""

from __future__ import annotations

import time

import mujoco

from pneumaquad.core.jit import compiled
from pneumaquad.core.kernel import advance_actuators
from pneumaquad.io.stage_clock import StageClock

from .coupling import robot_control_step
from .simulation import RobotSimulation

__all__ = ["bare_mujoco_seconds", "control_step_seconds", "kernel_seconds",
           "split_simulation_time"]


@compiled
def _kernel_loop(count, params, state, commands, positions, velocities, control_step,
                 substeps, supply, outputs):
    """``count`` kernel calls on all actuators, as the control step makes them (no
    friction output: the seal friction is MuJoCo's)."""
    for _ in range(count):
        advance_actuators(params, state, commands, positions, velocities, control_step,
                          substeps, supply, outputs, False)


@compiled
def _control_loop(count, mujoco_arrays, cylinders, actuators, controllers, trace, coupling,
                  settings):
    """``count`` control steps without MuJoCo's step."""
    for _ in range(count):
        robot_control_step(mujoco_arrays, cylinders, actuators, controllers, trace, coupling,
                           settings)


def bare_mujoco_seconds(simulation: RobotSimulation, steps: int,
                        data: mujoco.MjData | None = None) -> float:
    """Seconds per control step of bare ``mj_step`` (its physics steps), run on a copy of
    ``data`` (default: the simulation's own: same pose, contacts and motor forces)."""
    model = simulation.model
    copy = mujoco.MjData(model)
    mujoco.mj_copyData(copy, model, simulation.data if data is None else data)
    begun = time.perf_counter()
    mujoco.mj_step(model, copy, nstep=steps * simulation.physics_steps)
    return (time.perf_counter() - begun) / steps


def kernel_seconds(simulation: RobotSimulation, steps: int) -> float:
    """Seconds per control step of the actuators' kernel alone, as the control step calls
    it, on copies of the simulation's actuator arrays."""
    state, supply = simulation.state.copy(), simulation.supply.copy()
    outputs, commands = simulation.outputs.copy(), simulation.commands.copy()
    positions, velocities = simulation.positions.copy(), simulation.velocities.copy()
    arguments = (simulation.params, state, commands, positions, velocities,
                 simulation.control_step, simulation.substeps, supply, outputs)
    _kernel_loop(1, *arguments)  # load the compiled code
    begun = time.perf_counter()
    _kernel_loop(steps, *arguments)
    return (time.perf_counter() - begun) / steps


def control_step_seconds(simulation: RobotSimulation, steps: int) -> float:
    """Seconds per control step without MuJoCo's step (kernel, controllers, coupling), on
    copies of the simulation's arrays (its state is left as is)."""
    bundles = [bundle._make(array.copy() for array in bundle) for bundle in (
        simulation.mujoco, simulation.cylinders, simulation.actuators, simulation.controllers,
        simulation.trace)]
    coupling = simulation.coupling.copy()
    coupling["pending"] = 1  # the kernel integrates every step, as in a run
    _control_loop(1, *bundles, coupling, simulation.step_settings)
    begun = time.perf_counter()
    _control_loop(steps, *bundles, coupling, simulation.step_settings)
    return (time.perf_counter() - begun) / steps


def split_simulation_time(simulation: RobotSimulation, clock: StageClock,
                          control_steps: int, calibration_steps: int = 2000) -> None:
    """Add the estimated parts of the clock's ``"simulation"`` stage to ``clock``.

    Parameters
    ----------
    simulation : RobotSimulation
        The simulation after its run (its state is copied, not changed).
    clock : StageClock
        Holds the run's ``"simulation"`` stage [s]; receives ``"simulation: MuJoCo
        (estimated)"``, ``"simulation: actuators (estimated)"``, ``"simulation:
        controllers and coupling (estimated)"`` and ``"simulation: chunk ends and
        calls (rest)"``.
    control_steps : int
        Control steps the run made.
    calibration_steps : int
        Steps each part is timed for.
    """
    measured = clock.seconds.get("simulation", 0.0)
    if measured <= 0.0 or control_steps <= 0:
        return
    kernel = kernel_seconds(simulation, calibration_steps)
    parts = {"MuJoCo": bare_mujoco_seconds(simulation, calibration_steps),
             "actuators": kernel,
             "controllers and coupling": max(
                 control_step_seconds(simulation, calibration_steps) - kernel, 0.0)}
    estimated = {name: seconds * control_steps for name, seconds in parts.items()}
    scale = min(1.0, measured / sum(estimated.values()))  # never more than was measured
    for name, seconds in estimated.items():
        clock.add(f"simulation: {name} (estimated)", seconds * scale, control_steps)
    rest = measured - scale * sum(estimated.values())
    clock.add("simulation: chunk ends and calls (rest)", rest)
