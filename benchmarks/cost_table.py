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

from _bench import machine_line, table, write_json
from pneumaquad.params import load_rig
from pneumaquad.reporting.component_costs import component_costs
from pneumaquad.reporting.cost_report import cost_table_markdown
from pneumaquad.reporting.cost_table import measure_cost_table

INCH = 0.0254
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

    part_rows = []
    for part in component_costs(load_rig("thesis-rig"), args.repeats):
        part_rows.append(
            [
                part.name,
                f"{part.ns_per_call:.1f}",
                f"{part.replacement_ns_per_call:.1f}",
                part.calls_per_step,
                f"{part.saving_us:.2f}",
                f"{100 * part.saving_us / complete:.1f}",
            ]
        )
        figures[f"component: {part.name}"] = {
            "ns_per_call": part.ns_per_call,
            "replacement_ns_per_call": part.replacement_ns_per_call,
            "calls_per_step": part.calls_per_step,
            "saving_us": part.saving_us,
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
