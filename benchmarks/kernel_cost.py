"""Cost of ``pneumaquad.core.kernel.step_actuators`` per actuator per 1 ms control step.

Measures N = 1, 12 and 1000 externally driven actuators (crr-gamma parameters) with the
full model (underlapped valve + Stribeck-tanh friction + adiabatic chambers) and, in the
same run, the simple valve + viscous friction as a reference. Pistons move sinusoidally
and valve commands swing around the offset, each actuator with its own phase, so the
valves are never idle. Two loops are timed:

* ``python``: one ``step_actuators`` call per control step from a Python loop, as a robot
  simulator would call it (includes numba's dispatch overhead, a few µs per call);
* ``compiled``: the same calls from a jitted loop (kernel cost only).

The issue's target is ≤ 1 µs per actuator-step at 12 actuators on one core (the kernel
is serial). Compile cost is measured separately in fresh interpreters: first call vs
later calls with an empty numba cache folder, then again reusing that folder (the kernels
are ``@njit(cache=True)``, so the second process loads machine code from disk), and with
the project's own cache (``src/pneumaquad/__pycache__``).

Run: ``.venv/bin/python benchmarks/kernel_cost.py [--json out.json]``.
"""

from __future__ import annotations

import argparse
import re
import tempfile
import time
from dataclasses import dataclass

import numpy as np
from numba import njit

from _bench import Stats, machine_line, run_child, stats, table, write_json
from pneumaquad.core import layout
from pneumaquad.core.actuator import initial_state, new_outputs, pack_parameters, supply_state
from pneumaquad.core.kernel import step_actuators
from pneumaquad.core.pneumatics import (
    flow_constants,
    pneumatic_rates,
    port_flow,
    valve_connections,
)
from pneumaquad.params import load_actuator, load_rig

TARGET_NS = 1000.0
TARGET_COUNT = 12
MODELS = {
    "full": (),
    "simple": ('valve.model="simple"', 'friction.model="viscous"'),
}


@njit(cache=False)
def compiled_loop(
    params, state, commands, positions, velocities, control_step, substeps, supply, outputs
):
    """All control steps of a workload in one compiled call."""
    for k in range(commands.shape[0]):
        step_actuators(
            params,
            state,
            commands[k],
            positions[k],
            velocities[k],
            control_step,
            substeps,
            supply,
            outputs,
        )


@dataclass
class Workload:
    """Inputs of ``steps`` control steps for ``count`` actuators."""

    params: np.ndarray
    state: np.ndarray
    supply: np.ndarray
    commands: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray


def build_workload(
    row: np.void,
    supply: np.ndarray,
    count: int,
    steps: int,
    control_step: float,
    command_amplitude: float,
) -> Workload:
    """Sinusoidal piston motion (1 Hz, ±35 % stroke) and commands (3 Hz around the offset)."""
    stroke = row["stroke"]
    times = np.arange(steps)[:, None] * control_step
    phases = np.linspace(0.0, 2.0 * np.pi, count, endpoint=False)[None, :]
    omega = 2.0 * np.pi * 1.0
    amplitude = 0.35 * stroke
    positions = 0.5 * stroke + amplitude * np.sin(omega * times + phases)
    velocities = amplitude * omega * np.cos(omega * times + phases)
    commands = row["offset_voltage"] + command_amplitude * np.sin(
        2 * np.pi * 3.0 * times + phases)
    middle = 0.5 * (row["supply_pressure"] + row["exhaust_pressure"])
    params = np.full(count, row, dtype=layout.ACTUATOR_PARAMETERS_DTYPE)
    state = np.zeros(count, layout.ACTUATOR_STATE_DTYPE)
    for i in range(count):
        initial_state(row, positions[0, i], middle, middle, out=state[i])
    return Workload(params, state, supply, commands, positions, velocities)


def time_once(work: Workload, control_step: float, substeps: int, compiled: bool) -> float:
    """Seconds per ``step_actuators`` call over the workload, from a fresh state."""
    outputs = new_outputs(work.params.shape[0])
    state, supply = work.state.copy(), work.supply.copy()
    cmd, pos, vel = work.commands, work.positions, work.velocities
    start = time.perf_counter()
    if compiled:
        compiled_loop(work.params, state, cmd, pos, vel, control_step, substeps, supply, outputs)
    else:
        for k in range(cmd.shape[0]):
            step_actuators(
                work.params,
                state,
                cmd[k],
                pos[k],
                vel[k],
                control_step,
                substeps,
                supply,
                outputs,
            )
    seconds = (time.perf_counter() - start) / cmd.shape[0]
    if not np.all(np.isfinite(layout.float_view(state))):
        raise FloatingPointError("kernel state is not finite")
    return seconds


def time_interleaved(
    works: dict[str, Workload], control_step: float, substeps: int, repeats: int, compiled: bool
) -> dict[str, Stats]:
    """Seconds per call for each workload; one warm-up each, then repeats taken in turn."""
    samples: dict[str, list[float]] = {name: [] for name in works}
    for work in works.values():
        time_once(work, control_step, substeps, compiled)
    for _ in range(repeats):
        for name, work in works.items():
            samples[name].append(time_once(work, control_step, substeps, compiled))
    return {name: stats(values) for name, values in samples.items()}


@njit(cache=False)
def valve_loop(p, centered, supply_pressure):
    total = 0.0
    for u in centered:
        a, b, c, d = valve_connections(p, u, supply_pressure)
        total += a + b + c + d
    return total


@njit(cache=False)
def rates_loop(p, pressures, velocities, source, conductance):
    total = 0.0
    mass = 4e-5
    constants = flow_constants(p)  # once per actuator and control step in the kernels
    for i in range(pressures.shape[0]):
        dpc, dpr, fc, fr, draw = pneumatic_rates(
            p,
            constants,
            pressures[i],
            pressures[-1 - i],
            mass,
            mass,
            0.02,
            velocities[i],
            source,
            conductance,
            pressures[i] * 0.9,
            conductance,
        )
        total += dpc + dpr + fc + fr + draw
    return total


@njit(cache=False)
def flow_loop(p, upstream, downstream):
    total = 0.0
    constants = flow_constants(p)
    for i in range(upstream.shape[0]):
        flow, crossing = port_flow(p, constants, 5e-7, upstream[i], downstream[i], 298.0)
        total += flow + crossing
    return total


def breakdown(row: np.void, substeps: int, repeats: int) -> dict[str, float]:
    """ns per actuator-step spent in the valve map and the chamber rates (quick profile)."""
    n = 20000
    wave = np.sin(np.linspace(0.0, 40.0 * np.pi, n))  # smooth, like a driven actuator
    centered = 2.0 * wave
    exhaust, supply = row["exhaust_pressure"], row["supply_pressure"]
    pressures = exhaust + (supply - exhaust) * (0.5 + 0.45 * wave)
    velocities = 0.1 * np.cos(np.linspace(0.0, 40.0 * np.pi, n))
    figures = {}
    for name, call, per_step in (
        (
            # once per control step; once per substep only with a spool lag
            "valve_connections (1 per step)",
            lambda: valve_loop(row, centered, supply),
            1,
        ),
        (
            "pneumatic_rates (2 per substep)",
            lambda: rates_loop(row, pressures, velocities, supply, 5e-7),
            2 * substeps,
        ),
        (
            "  of which port_flow (4 per substep)",
            lambda: flow_loop(row, pressures, pressures[::-1].copy()),
            4 * substeps,
        ),
    ):
        call()
        samples = []
        for _ in range(repeats):
            start = time.perf_counter()
            call()
            samples.append((time.perf_counter() - start) / n)
        figures[name] = stats(samples).median * 1e9 * per_step
    return figures


CHILD = r"""
import json, sys, time
t0 = time.perf_counter()
import numpy as np
from pneumaquad.core.actuator import (
    initial_state, new_outputs, pack_parameter_array, supply_state)
from pneumaquad.core.kernel import step_actuators
from pneumaquad.params import load_actuator
t1 = time.perf_counter()
cfg = json.loads(sys.argv[1])
n = cfg["count"]
params = pack_parameter_array([load_actuator("crr-gamma")] * n)
row = params[0]
mid = 0.5 * (row["supply_pressure"] + row["exhaust_pressure"])
state = np.array([initial_state(row, 0.02, mid, mid)] * n)
supply = supply_state(load_actuator("crr-gamma"))
out = new_outputs(n)
cmd = np.full(n, row["offset_voltage"] + 1.0)
pos = np.full(n, 0.02)
vel = np.full(n, 0.05)
t2 = time.perf_counter()
step_actuators(params, state, cmd, pos, vel, 1e-3, cfg["substeps"], supply, out)
first = time.perf_counter() - t2
later = []
for _ in range(200):
    t = time.perf_counter()
    step_actuators(params, state, cmd, pos, vel, 1e-3, cfg["substeps"], supply, out)
    later.append(time.perf_counter() - t)
print(json.dumps({"import_s": t1 - t0, "setup_s": t2 - t1, "first_call_s": first,
                  "later_call_s": float(np.median(later))}))
"""


def compile_cost(substeps: int) -> dict[str, dict[str, float]]:
    """First call vs later calls in fresh interpreters: cold cache, warm cache, project cache."""
    argument = {"count": TARGET_COUNT, "substeps": substeps}
    results = {}
    with tempfile.TemporaryDirectory(prefix="numba-cache-") as folder:
        results["cold (empty NUMBA_CACHE_DIR)"] = run_child(
            CHILD, argument, {"NUMBA_CACHE_DIR": folder}
        )
        results["warm (same NUMBA_CACHE_DIR)"] = run_child(
            CHILD, argument, {"NUMBA_CACHE_DIR": folder}
        )
    results["project cache (__pycache__)"] = run_child(CHILD, argument, {})
    return results


#: Packed double-precision arithmetic (x86 SSE/AVX/AVX-512): vaddpd, mulpd, vfmadd231pd …
_PACKED = re.compile(r"\bv?(?:add|sub|mul|div|sqrt|max|min|fn?m(?:add|sub)\d*)pd\b")
#: The scalar forms of the same operations: vaddsd, mulsd …
_SCALAR = re.compile(r"\bv?(?:add|sub|mul|div|sqrt|max|min|fn?m(?:add|sub)\d*)sd\b")
_LANES = {"xmm": 2, "ymm": 4, "zmm": 8}


def simd_width(work: Workload) -> dict[str, int]:
    """What the compiled ``step_actuators`` does with doubles, read from its machine code.

    Counts the packed (several doubles per instruction) and scalar double arithmetic
    instructions of the compiled kernel and the widest register a packed one uses:
    ``{"packed": …, "scalar": …, "lanes": 1, 2, 4 or 8}`` (1 when nothing is packed).
    The kernel is compiled afresh for this, with the package's options and the
    workload's types (numba shows no machine code of a function loaded from its cache).
    """
    fresh = njit(error_model="numpy")(step_actuators.py_func)
    fresh(work.params, work.state.copy(), work.commands[0], work.positions[0],
          work.velocities[0], 1e-3, 1, work.supply.copy(), new_outputs(work.params.shape[0]))
    assembly = "\n".join(fresh.inspect_asm().values())
    packed_lines = [line for line in assembly.splitlines() if _PACKED.search(line)]
    scalar = sum(1 for line in assembly.splitlines() if _SCALAR.search(line))
    lanes = 1
    for line in packed_lines:
        for register, width in _LANES.items():
            if register in line:
                lanes = max(lanes, width)
    return {"packed": len(packed_lines), "scalar": scalar, "lanes": lanes}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--counts", type=int, nargs="+", default=[1, 12, 1000])
    parser.add_argument(
        "--substeps",
        type=int,
        default=None,
        help="Heun substeps per step (default: thesis-rig simulation.substeps)",
    )
    parser.add_argument("--control-step", type=float, default=1e-3, help="[s]")
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument(
        "--actuator-steps",
        type=int,
        default=24000,
        help="actuator-steps per repeat (steps = this / N, at least --min-steps)",
    )
    parser.add_argument(
        "--min-steps",
        type=int,
        default=1000,
        help="control steps per repeat at least, for every N (default 1000: one whole "
        "cycle of the 1 Hz piston drive, so every N sees the same flow regimes)",
    )
    parser.add_argument(
        "--command-amplitude",
        type=float,
        default=2.0,
        help="valve command swing around the offset [V]",
    )
    parser.add_argument(
        "--sweep",
        type=int,
        nargs="*",
        default=[1, 2, 5, 10, 20],
        help="substep counts for the N=12 compiled sweep (empty: skip)",
    )
    parser.add_argument(
        "--no-compile-cost",
        action="store_true",
        help="skip the fresh-interpreter compile measurements",
    )
    parser.add_argument("--json", default=None, help="write the figures to this file")
    args = parser.parse_args()
    substeps = args.substeps or load_rig("thesis-rig").simulation.substeps
    dt = args.control_step

    print(f"step_actuators cost  ({machine_line()})")
    print(
        f"crr-gamma, {substeps} Heun substeps per {dt * 1e3:g} ms step, {args.repeats} "
        "repeats after a warm-up; figures are min / median / max over repeats\n"
    )
    rows, figures = [], {}
    medians: dict[tuple[str, int, str], float] = {}
    actuators = {m: load_actuator("crr-gamma", overrides=list(o)) for m, o in MODELS.items()}
    for count in args.counts:
        steps = max(args.actuator_steps // count, args.min_steps)
        works = {
            model: build_workload(
                pack_parameters(actuator),
                supply_state(actuator),
                count,
                steps,
                dt,
                args.command_amplitude,
            )
            for model, actuator in actuators.items()
        }
        for loop in ("python", "compiled"):
            timed = time_interleaved(works, dt, substeps, args.repeats, loop == "compiled")
            for model, per_call in timed.items():
                per_actuator = per_call.scaled(1e9 / count)
                medians[model, count, loop] = per_actuator.median
                figures[f"{model}/N={count}/{loop}"] = {
                    "ns_per_actuator_step": per_actuator,
                    "us_per_call": per_call.scaled(1e6),
                    "steps_per_repeat": steps,
                }
                rows.append(
                    [model, count, loop, per_actuator.spread(0), per_call.scaled(1e6).spread(2)]
                )
    rows.sort(key=lambda r: (list(MODELS).index(r[0]), r[1]))
    print(table(["model", "N", "loop", "ns/actuator-step", "µs/call"], rows))

    print("\nfull / simple (median over repeats of the paired ratio, ns per actuator-step):")
    for count in args.counts:
        for loop in ("python", "compiled"):
            pairs = zip(
                figures[f"full/N={count}/{loop}"]["ns_per_actuator_step"].samples,
                figures[f"simple/N={count}/{loop}"]["ns_per_actuator_step"].samples,
                strict=True,
            )
            ratio = stats([full / simple for full, simple in pairs])
            figures[f"ratio/N={count}/{loop}"] = ratio
            print(f"  N={count:<5} {loop:<8} {ratio.median:5.2f}x  ({ratio.spread(2)})")
    print("Python-loop overhead per call (python - compiled, fastest repeats, full model):")
    for count in [c for c in args.counts if c <= 100]:  # above: lost in the noise
        python = figures[f"full/N={count}/python"]["us_per_call"].min
        extra = python - figures[f"full/N={count}/compiled"]["us_per_call"].min
        print(f"  N={count:<5} {extra:+.2f} µs")
    if TARGET_COUNT in args.counts:
        best = medians["full", TARGET_COUNT, "compiled"]
        verdict = "met" if best <= TARGET_NS else "NOT met"
        print(
            f"\ntarget (issue): <= {TARGET_NS:.0f} ns per actuator-step at N={TARGET_COUNT} "
            f"on one core -> full model, compiled loop, median {best:.0f} ns: {verdict} "
            f"({best / TARGET_NS:.1f}x the target; fastest repeat "
            f"{figures[f'full/N={TARGET_COUNT}/compiled']['ns_per_actuator_step'].min:.0f} ns)"
        )

    vector = simd_width(works["full"])
    figures["simd"] = vector
    total = vector["packed"] + vector["scalar"]
    print(
        f"\nSIMD of the compiled step_actuators: {vector['packed']} of its {total} double "
        f"arithmetic instructions packed (up to {vector['lanes']} doubles: straight-line "
        "arithmetic of one actuator the compiler grouped), the rest one double each; the "
        "actuators' records are an array of structures and each actuator's step branches "
        "on its valve and friction regime, so the loop over actuators is not vectorised."
    )
    if 1000 in args.counts:
        per = medians["full", 1000, "compiled"]
        print(f"target (issue 14): <= 500 ns per actuator-step at N=1000 -> {per:.0f} ns: "
              f"{'met' if per <= 500 else 'NOT met'}")

    full_row = pack_parameters(load_actuator("crr-gamma"))
    if args.sweep:
        print(f"\nsubstep sweep, full model, N={TARGET_COUNT}, compiled loop:")
        sweep_rows = []
        supply = supply_state(load_actuator("crr-gamma"))
        steps = max(args.actuator_steps // TARGET_COUNT, 10)
        work = build_workload(full_row, supply, TARGET_COUNT, steps, dt, args.command_amplitude)
        for n_sub in args.sweep:
            timed = time_interleaved({"full": work}, dt, n_sub, args.repeats, True)
            per = timed["full"].scaled(1e9 / TARGET_COUNT)
            figures[f"sweep/substeps={n_sub}"] = per
            sweep_rows.append([n_sub, per.spread(0), f"{per.median / n_sub:.0f}"])
        print(table(["substeps", "ns/actuator-step", "ns/substep"], sweep_rows))

    parts = breakdown(full_row, substeps, args.repeats)
    figures["breakdown_ns_per_actuator_step"] = parts
    measured = medians.get(("full", TARGET_COUNT, "compiled"))
    print(f"\nquick profile, full model, {substeps} substeps (isolated compiled loops):")
    part_rows = [
        [name, f"{ns:.0f}", f"{100 * ns / measured:.0f} %" if measured else "-"]
        for name, ns in parts.items()
    ]
    print(table(["component", "ns/actuator-step", "share of measured"], part_rows))
    print(
        "(each component timed alone on smooth inputs; the estimates need not add up to the\n"
        " measured step, the rest is spool/Heun updates, outputs, friction and loop overhead)"
    )

    if not args.no_compile_cost:
        print(
            f"\ncompile / load cost, fresh interpreters, N={TARGET_COUNT} "
            "(kernels are @njit(cache=True)):"
        )
        costs = compile_cost(substeps)
        figures["compile"] = costs
        print(
            table(
                [
                    "numba cache",
                    "imports [s]",
                    "setup [s]",
                    "first call [s]",
                    "later call [µs]",
                    "process [s]",
                ],
                [
                    [
                        name,
                        f"{c['import_s']:.2f}",
                        f"{c['setup_s']:.2f}",
                        f"{c['first_call_s']:.3f}",
                        f"{c['later_call_s'] * 1e6:.1f}",
                        f"{c['process_wall_s']:.2f}",
                    ]
                    for name, c in costs.items()
                ],
            )
        )
        print(
            "setup = loading and packing parameters: first unit parsing, and numba's one-time\n"
            "start-up (~0.2 s) on the first jitted call (orifice_coefficients); 'first call'\n"
            "is then compiling or loading step_actuators alone."
        )
    write_json(
        args.json,
        {
            "substeps": substeps,
            "control_step": dt,
            "figures": figures,
            "target_ns_per_actuator_step": TARGET_NS,
        },
    )


if __name__ == "__main__":
    main()
