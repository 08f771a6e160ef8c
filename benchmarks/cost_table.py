"""Thesis Table 3 (section 5.5.3) measured on the compiled rig kernel.

Daepp (2011) timed the Simulink target (task execution time, TET) of a Gamma-joint model
with components removed one at a time. This script times ``run_rig_chunk`` (PID + rig
kernel + recording row, the whole fixed-step loop of ``simulate_rig``) per 1 ms step for
the same removals, all in one run and interleaved across repeats, and prints the thesis's
own figures beside ours (the measurement is :func:`pneumaquad.reporting.cost_table.
measure_cost_table`, also behind ``pneumaquad report cost-table``). A second table times
the removed components in isolation.

Run: ``.venv/bin/python benchmarks/cost_table.py [--json out.json]``.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from numba import njit

from _bench import machine_line, stats, table, write_json
from pneumaquad.core.physics.valve import input_pressure, polynomial_area, simple_valve_area
from pneumaquad.core.pneumatics import friction_of, friction_slope_of
from pneumaquad.params import RigSetup, load_rig
from pneumaquad.reporting.cost_report import cost_table_markdown
from pneumaquad.reporting.cost_table import measure_cost_table
from pneumaquad.rig.model import pack_rig_parameters

INCH = 0.0254
@njit(cache=False)
def polynomial_loop(centered, negative, positive):
    total = 0.0
    for u in centered:
        total += polynomial_area(u, negative, positive)
    return total


@njit(cache=False)
def linear_loop(centered, max_area, leak_area, full_scale):
    total = 0.0
    for u in centered:
        total += 0.09 * simple_valve_area(u, max_area, leak_area, full_scale)
    return total


@njit(cache=False)
def tanh_pressure_loop(centered, supply, exhaust, high, low):
    total = 0.0
    for u in centered:
        total += input_pressure(u, supply, exhaust, high, low)
    return total


@njit(cache=False)
def plain_pressure_loop(centered, supply, exhaust):
    total = 0.0
    for u in centered:
        total += supply if u >= 0.0 else exhaust
    return total


@njit(cache=False)
def friction_loop(p, velocities):
    """Friction force and its slope, as rig_mechanics_substep evaluates them per substep."""
    total = 0.0
    for v in velocities:
        total += friction_of(p, v, 0.0) + friction_slope_of(p, v, 0.0)
    return total


def component_costs(setup: RigSetup, repeats: int) -> list[tuple[str, float, float, int]]:
    """(component, ns per call, ns per call of its replacement, calls per 1 ms step)."""
    n = 50000
    wave = np.sin(np.linspace(0.0, 60.0 * np.pi, n))
    centered, velocities = 2.0 * wave, 0.05 * wave
    row = pack_rig_parameters(setup)[0]
    viscous = pack_rig_parameters(load_rig("thesis-rig", overrides=['friction.model="viscous"']))[0]
    neg = row["cap_polynomial_negative"].copy()
    pos = row["cap_polynomial_positive"].copy()
    ps, pe = row["supply_pressure"], row["exhaust_pressure"]
    hi, lo = row["cap_high_pressure_cutoff"], row["cap_low_pressure_cutoff"]
    calls = {
        "poly": lambda: polynomial_loop(centered, neg, pos),
        "linear": lambda: linear_loop(centered, 1e-5, 2e-7, 5.0),
        "tanh": lambda: tanh_pressure_loop(centered, ps, pe, hi, lo),
        "plain": lambda: plain_pressure_loop(centered, ps, pe),
        "stribeck": lambda: friction_loop(row, velocities),
        "viscous": lambda: friction_loop(viscous, velocities),
    }
    ns = {}
    for name, call in calls.items():
        call()
        samples = []
        for _ in range(repeats):
            start = time.perf_counter()
            call()
            samples.append((time.perf_counter() - start) / n * 1e9)
        ns[name] = stats(samples).median
    sub = setup.simulation.substeps
    # The valve map (areas and input pressures, cap and rod) is evaluated once per
    # control step when there is no spool lag; the friction law once per substep.
    return [
        ("area polynomials -> linear area", ns["poly"], ns["linear"], 2),
        ("tanh input pressures -> plain", ns["tanh"], ns["plain"], 2),
        ("Stribeck-tanh -> viscous (force + slope)", ns["stribeck"], ns["viscous"], sub),
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--duration", type=float, default=10.0, help="simulated time [s]")
    parser.add_argument("--amplitude", type=float, default=0.4 * INCH, help="sine [m]")
    parser.add_argument("--frequency", type=float, default=0.5, help="sine [Hz]")
    parser.add_argument("--repeats", type=int, default=25)
    parser.add_argument("--json", default=None, help="write the figures to this file")
    args = parser.parse_args()

    cost = measure_cost_table(
        "thesis-rig", args.duration, args.repeats, args.amplitude, args.frequency
    )
    print(f"Table 3 on the rig kernel  ({machine_line()})")
    print(
        f"thesis-rig, closed-loop sine half stroke ± {args.amplitude / INCH:g} in at "
        f"{args.frequency:g} Hz, {args.duration:g} s of {cost.control_step * 1e3:g} ms steps, "
        f"{cost.substeps} substeps; mean, std and min over {args.repeats} interleaved "
        "repeats of the whole run (pneumaquad.reporting.cost_table)\n"
    )
    print(cost_table_markdown(cost))
    print("\nHow each case was made:")
    for row in cost.rows:
        print(f"  {row.case}: {row.how}")
    complete = cost.rows[0].mean_us
    figures: dict[str, object] = {
        row.case: {
            "mean_us": row.mean_us,
            "std_us": row.std_us,
            "min_us": row.min_us,
            "change_percent": row.change_percent,
            "thesis_us": row.thesis_us,
        }
        for row in cost.rows
    }

    parts = component_costs(load_rig("thesis-rig"), args.repeats)
    part_rows = []
    for name, full, simpler, per_step in parts:
        saving = (full - simpler) * per_step / 1e3
        part_rows.append(
            [
                name,
                f"{full:.1f}",
                f"{simpler:.1f}",
                per_step,
                f"{saving:.2f}",
                f"{100 * saving / complete:.1f}",
            ]
        )
        figures[f"component: {name}"] = {
            "ns_per_call": full,
            "replacement_ns_per_call": simpler,
            "calls_per_step": per_step,
            "saving_us": saving,
        }
    print("\nisolated component costs (compiled loops on smooth inputs; estimates):")
    print(
        table(
            [
                "component -> replacement",
                "ns/call",
                "repl. ns/call",
                "calls/step",
                "saving [µs/step]",
                "of complete [%]",
            ],
            part_rows,
        )
    )
    write_json(args.json, {"figures": figures, "reference": "Daepp 2011, Table 3 (5.5.3)"})


if __name__ == "__main__":
    main()
