"""Wall time of thesis-rig simulations: fixed-step loop, compile/load cost, Radau reference.

(a) 10 s of simulated closed-loop sine tracking on the thesis rig (mean = half stroke,
    amplitude 0.4 in, 0.5 Hz) with ``simulate_rig`` after compilation; target ≤ 0.2 s.
(b) The first call in a fresh interpreter (numba compiling, or loading the on-disk cache
    of the ``@njit(cache=True)`` kernels) and a second call in the same interpreter, for
    two fresh interpreters in a row: with the project's cache (``__pycache__`` beside the
    sources), and with a cold cache (``NUMBA_CACHE_DIR`` set to an empty temporary folder
    for the first interpreter and reused by the second).
(c) The adaptive Radau reference (``simulation.integrator="radau"``) on the first second
    of the same run, its cost per simulated second against the fixed step.

Run: ``.venv/bin/python benchmarks/rig_speed.py [--json out.json]``.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from typing import Any

import numpy as np

from _bench import Stats, machine_line, run_child, stats, table, write_json
from pneumaquad.params import RigSetup, load_rig
from pneumaquad.rig.signals import sine
from pneumaquad.rig.simulate import simulate_rig

INCH = 0.0254
TARGET_S = 0.2

CHILD = r"""
import json, sys, time
t0 = time.perf_counter()
from pneumaquad.params import load_rig
from pneumaquad.rig.signals import sine
from pneumaquad.rig.simulate import simulate_rig
t1 = time.perf_counter()
cfg = json.loads(sys.argv[1])
setup = load_rig("thesis-rig", overrides=cfg["overrides"])
reference = sine(setup.actuator.cylinder.stroke / 2, cfg["amplitude"], cfg["frequency"],
                 cfg["duration"], setup.simulation.control_step)
t2 = time.perf_counter()
simulate_rig(setup, reference, closed_loop=True)
t3 = time.perf_counter()
simulate_rig(setup, reference, closed_loop=True)
t4 = time.perf_counter()
print(json.dumps({"import_s": t1 - t0, "load_parameters_s": t2 - t1,
                  "first_call_s": t3 - t2, "second_call_s": t4 - t3}))
"""


def reference_for(
    setup: RigSetup, amplitude: float, frequency: float, duration: float
) -> np.ndarray:
    """Sine position reference around half stroke [m]."""
    return sine(
        setup.actuator.cylinder.stroke / 2,
        amplitude,
        frequency,
        duration,
        setup.simulation.control_step,
    )


def time_runs(setup: RigSetup, reference: np.ndarray, repeats: int) -> tuple[Stats, float]:
    """Seconds per closed-loop run (after one warm-up run) and the RMS tracking error [m]."""
    simulate_rig(setup, reference, closed_loop=True)
    samples = []
    error = float("nan")
    for _ in range(repeats):
        start = time.perf_counter()
        result = simulate_rig(setup, reference, closed_loop=True)
        samples.append(time.perf_counter() - start)
        record = result.recording
        error = float(
            np.sqrt(np.mean((record["position [m]"] - record["reference position [m]"]) ** 2))
        )
    return stats(samples), error


def fresh_interpreters(argument: dict[str, Any], cold: bool) -> dict[str, dict[str, float]]:
    """Two fresh interpreters in a row, with the project cache or a cold temporary one."""
    if not cold:
        return {f"project cache, run {i}": run_child(CHILD, argument, {}) for i in (1, 2)}
    with tempfile.TemporaryDirectory(prefix="numba-cache-") as folder:
        env = {"NUMBA_CACHE_DIR": folder}
        return {f"cold cache, run {i}": run_child(CHILD, argument, env) for i in (1, 2)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--duration", type=float, default=10.0, help="fixed-step run [s]")
    parser.add_argument("--amplitude", type=float, default=0.4 * INCH, help="[m]")
    parser.add_argument("--frequency", type=float, default=0.5, help="[Hz]")
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--radau-duration", type=float, default=1.0, help="[s]")
    parser.add_argument("--radau-repeats", type=int, default=3)
    parser.add_argument(
        "--set",
        dest="overrides",
        action="append",
        default=[],
        help='parameter override for every run, e.g. friction.model="viscous"',
    )
    parser.add_argument(
        "--cache",
        choices=["project", "cold", "both", "none"],
        default="both",
        help="fresh-interpreter measurements to make (b)",
    )
    parser.add_argument("--json", default=None, help="write the figures to this file")
    args = parser.parse_args()

    setup = load_rig("thesis-rig", overrides=args.overrides)
    dt = setup.simulation.control_step
    reference = reference_for(setup, args.amplitude, args.frequency, args.duration)
    print(f"thesis-rig speed  ({machine_line()})")
    print(
        f"closed-loop sine: half stroke ± {args.amplitude / INCH:g} in at "
        f"{args.frequency:g} Hz, {dt * 1e3:g} ms control step, "
        f"{setup.simulation.substeps} substeps\n"
    )

    fixed, error = time_runs(setup, reference, args.repeats)
    steps = reference.shape[0]
    print(f"(a) fixed step, {args.duration:g} s simulated, {args.repeats} runs after a warm-up")
    print(
        table(
            ["figure", "min / median / max"],
            [
                ["wall time [s]", fixed.spread(4)],
                ["µs per control step", fixed.scaled(1e6 / steps).spread(2)],
                [
                    "faster than real time [x]",
                    stats([args.duration / s for s in fixed.samples]).spread(0),
                ],
            ],
        )
    )
    verdict = "met" if fixed.median <= TARGET_S else "NOT met"
    print(
        f"target: <= {TARGET_S} s for {args.duration:g} s simulated -> median "
        f"{fixed.median:.4f} s: {verdict}; RMS tracking error {error * 1e3:.3f} mm"
    )
    figures: dict[str, Any] = {
        "fixed": {"wall_s": fixed, "steps": steps, "rms_error_m": error, "target_s": TARGET_S}
    }

    if args.cache != "none":
        argument = {
            "overrides": args.overrides,
            "amplitude": args.amplitude,
            "frequency": args.frequency,
            "duration": args.duration,
        }
        runs: dict[str, dict[str, float]] = {}
        for mode in ("project", "cold"):
            if args.cache in (mode, "both"):
                runs.update(fresh_interpreters(argument, cold=mode == "cold"))
        print(
            "\n(b) fresh interpreters, same run (first call includes compiling or "
            "loading the numba cache)"
        )
        print(
            table(
                [
                    "interpreter",
                    "imports [s]",
                    "first call [s]",
                    "second call [s]",
                    "first - second [s]",
                    "process [s]",
                ],
                [
                    [
                        name,
                        f"{r['import_s']:.2f}",
                        f"{r['first_call_s']:.3f}",
                        f"{r['second_call_s']:.3f}",
                        f"{r['first_call_s'] - r['second_call_s']:.3f}",
                        f"{r['process_wall_s']:.2f}",
                    ]
                    for name, r in runs.items()
                ],
            )
        )
        print(
            "a warm first call is mostly numba's one-time start-up in a new process (~0.2 s,\n"
            "importing its lowering registries on the first jitted call), not the cache load."
        )
        for prefix in ("project cache", "cold cache"):
            one, two = runs.get(f"{prefix}, run 1"), runs.get(f"{prefix}, run 2")
            if one and two:
                print(
                    f"{prefix}: first call, run 1 / run 2 = "
                    f"{one['first_call_s'] / two['first_call_s']:.1f}x"
                )
        figures["fresh_interpreters"] = runs

    if args.radau_duration > 0:
        radau_setup = load_rig(
            "thesis-rig", overrides=[*args.overrides, 'simulation.integrator="radau"']
        )
        short = reference_for(radau_setup, args.amplitude, args.frequency, args.radau_duration)
        simulate_rig(radau_setup, short[:20], closed_loop=True)  # load rig_rates
        samples = []
        for _ in range(args.radau_repeats):
            start = time.perf_counter()
            result = simulate_rig(radau_setup, short, closed_loop=True)
            samples.append(time.perf_counter() - start)
        radau = stats(samples)
        fixed_short = simulate_rig(setup, short, closed_loop=True).recording
        gap = np.max(np.abs(result.recording["position [m]"] - fixed_short["position [m]"]))
        per_second_fixed = fixed.median / args.duration
        per_second_radau = radau.median / args.radau_duration
        print(
            f"\n(c) Radau reference, {args.radau_duration:g} s simulated, "
            f"{args.radau_repeats} runs (rtol {radau_setup.simulation.relative_tolerance:g})"
        )
        print(
            table(
                ["integrator", "wall per simulated second [s]", "ratio"],
                [
                    ["fixed (a)", f"{per_second_fixed:.4f}", "1"],
                    [
                        "radau",
                        f"{per_second_radau:.3f}  ({radau.spread(3)} per run)",
                        f"{per_second_radau / per_second_fixed:.0f}x",
                    ],
                ],
            )
        )
        print(
            f"largest position difference fixed vs Radau over {args.radau_duration:g} s: "
            f"{gap * 1e6:.2f} µm"
        )
        figures["radau"] = {
            "wall_s": radau,
            "duration_s": args.radau_duration,
            "ratio_per_simulated_second": per_second_radau / per_second_fixed,
            "max_position_difference_m": float(gap),
        }
    write_json(args.json, {"figures": figures})


if __name__ == "__main__":
    main()
