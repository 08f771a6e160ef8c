"""The representative demo: a set of rig experiments and a report folder.

``pneumaquad demo`` runs the thesis's open-loop step protocol both ways, a fixed-piston
(spacer) test inside the underlap band, closed-loop tracking, the slow-sine stiction
comparison (Stribeck-tanh creeps, LuGre sticks), the fixed-step integrator against the
Radau reference, and a finite tank running down. Each experiment gets its own run folder;
``report.md`` and ``report.html`` (figures embedded) summarise them, in SI units: the
sections give their figures in SI (keys ``"quantity [unit]"``) and draw in the report's
display units (:mod:`pneumaquad.reporting.display_units`), as do the sub-reports.
"""

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from pneumaquad.core.actuator import chamber_ports
from pneumaquad.core.valve_fit import input_pressure
from pneumaquad.demo.stiction_plot import plot_stiction_comparison
from pneumaquad.io.run_folder import SUMMARY_NAME, write_json
from pneumaquad.params import load_rig
from pneumaquad.params.conversions import METRE_PER_INCH as INCH
from pneumaquad.reporting.display_units import SI, DisplayUnits
from pneumaquad.reporting.html import HtmlPage
from pneumaquad.reporting.plotting import (
    plot_comparison,
    plot_difference,
    plot_held_pressures,
    plot_tank_run,
)
from pneumaquad.reporting.rig_experiment import run_rig_experiment
from pneumaquad.rig import signals
from pneumaquad.rig.simulate import RigResult


def _rms(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.mean((a - b) ** 2)))


class DemoReport:
    """Collects sections (text, figure, key figures) and writes report.md/report.html.

    Sections give their key figures in SI (``"quantity [unit]"`` keys, as summary.json
    does); the pages show them in ``units`` (the demo's: SI, pressures in kPa), and the
    figures are drawn in the same units (:attr:`units`).
    """

    def __init__(self, folder: Path, units: DisplayUnits = SI) -> None:
        self.folder = folder
        self.units = units
        self.sections: list[dict[str, Any]] = []

    def add(self, title: str, text: str, figure: Path, figures: dict[str, Any]) -> None:
        self.sections.append({"title": title, "text": text, "figure": figure, "figures": figures})

    def write(self) -> Path:
        lines = [
            "# pneumaquad demo",
            "",
            "Single-DoF test rig of Daepp (2011), ch. 4 (parameter set `thesis-rig`), and the "
            "quadruped on 12 pneumatic joints, ch. 5 (`crr-quadruped`). "
            "Each section links its run folder (recording.csv/.parquet, summary.json, "
            "parameters.toml).",
            "",
        ]
        page = HtmlPage("pneumaquad demo")
        for section in self.sections:
            figure = section["figure"]
            relative = figure.relative_to(self.folder)
            lines += [
                f"## {section['title']}",
                "",
                section["text"],
                "",
                "| figure | value |",
                "|---|---|",
            ]
            shown = self.units.rows(list(section["figures"].items()))
            lines += [f"| {key} | {_format(value)} |" for key, value in shown]
            lines += ["", f"![{section['title']}]({relative.as_posix()})", ""]
            page.heading(section["title"])
            page.paragraph(section["text"])
            page.table(["figure", "value"], [(key, _format(value)) for key, value in shown])
            page.figure(figure, section["title"])
        (self.folder / "report.md").write_text("\n".join(lines), encoding="utf-8")
        page.write(self.folder / "report.html")
        key_figures = {s["title"]: s["figures"] for s in self.sections}
        # the demo folder holds run folders; its own summary is the report's key figures
        write_json(self.folder / SUMMARY_NAME, key_figures)
        return self.folder / "report.html"


def _format(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.4g}"
    return str(value)


def run_demo(folder: Path, progress: Callable[[int, int], None] | None = None) -> Path:
    """Run the demo experiments into ``folder`` and write the report; returns report.html."""
    folder.mkdir(parents=True, exist_ok=True)
    report = DemoReport(folder)
    from pneumaquad.demo.reports import REPORT_SECTIONS
    from pneumaquad.demo.sections import ROBOT_SECTIONS
    from pneumaquad.demo.study_section import STUDY_SECTIONS

    steps = [
        _open_loop_steps, _spacer, _tracking, _stiction, _reference_solver, _tank,
        *STUDY_SECTIONS, *ROBOT_SECTIONS, *REPORT_SECTIONS,
    ]
    for index, experiment in enumerate(steps):
        experiment(folder, report)
        if progress is not None:
            progress(index + 1, len(steps))
    return report.write()


def _run(
    folder: Path,
    name: str,
    overrides: list[str],
    signal_of,
    closed_loop: bool,
    description: str,
    step_time: float | None = None,
) -> tuple[RigResult, dict]:
    setup = load_rig("thesis-rig", overrides)
    signal = signal_of(setup)
    return run_rig_experiment(setup, folder / name, signal, closed_loop, description, step_time)


def _open_loop_steps(folder: Path, report: DemoReport) -> None:
    figures: dict[str, Any] = {}
    recordings = {}
    for volts in (6.0, 4.5):
        name = f"step-{volts:.2f}V".replace(".", "_")
        result, summary = _run(
            folder,
            name,
            [],
            lambda s, v=volts: signals.thesis_step_command(
                v, 5.25, 0.0, 10.0, s.simulation.control_step
            ),
            False,
            f"open-loop step to {volts} V (thesis protocol)",
            step_time=5.0,
        )
        recordings[f"{volts} V"] = result.recording
        figures[f"{volts} V: motion onset after step [s]"] = summary["motion onset delay [s]"]
        figures[f"{volts} V: stiction peak force [N]"] = summary["stiction peak force [N]"]
        figures[f"{volts} V: time moving [s]"] = summary["time moving [s]"]
    path = plot_comparison(
        recordings,
        folder / "open-loop-steps.png",
        "Open-loop steps (5 s opposite saturation, then the step)",
        report.units,
    )
    report.add(
        "Open-loop steps",
        "Thesis protocol of 4.2.3: the cap and rod pressures build "
        "until the net force beats static friction (the stiction peak, Fig. 12), drop "
        "while the piston moves, and settle on the input-pressure curves at the end "
        "stop.",
        path,
        figures,
    )


def _spacer(folder: Path, report: DemoReport) -> None:
    figures: dict[str, Any] = {}
    recordings = {}
    targets: dict[str, tuple[float, ...]] = {}
    setup = load_rig("thesis-rig")
    supply = setup.actuator.supply
    valve = setup.actuator.valve
    cap_port, rod_port = chamber_ports(valve)
    for volts in (5.55, 4.85):
        name = f"spacer-{volts:.2f}V".replace(".", "_")
        result, _ = _run(
            folder,
            name,
            ["rig.spacer=true"],
            lambda s, v=volts: signals.constant(v, 8000),
            False,
            f"fixed piston at {volts} V",
        )
        recording = result.recording
        centered = volts - valve.offset_voltage
        levels = []
        for label, port, column in (
            ("cap", cap_port, "cap pressure [Pa]"),
            ("rod", rod_port, "rod pressure [Pa]"),
        ):
            expected = float(
                input_pressure(
                    centered,
                    supply.supply_pressure,
                    supply.exhaust_pressure,
                    port.high_pressure_cutoff,
                    port.low_pressure_cutoff,
                )
            )
            figures[f"{volts} V {label}: settled [Pa]"] = float(recording[column][-1])
            figures[f"{volts} V {label}: eq 4.2.7 curve [Pa]"] = expected
            levels.append(expected)
        recordings[f"{volts} V"] = recording
        targets[f"{volts} V"] = tuple(levels)
    path = plot_held_pressures(
        recordings, targets, folder / "spacer.png",
        "Fixed piston inside the underlap band: chamber pressures and their curves",
        report.units,
    )
    report.add(
        "Fixed piston (spacer)",
        "With the piston held (thesis 4.2.1), a command inside "
        "the ±0.75 V underlap band leaves each chamber between supply and exhaust, on "
        "the tanh input-pressure curve of eq 4.2.7–4.2.11 (Fig. 23).",
        path,
        figures,
    )


def _tracking(folder: Path, report: DemoReport) -> None:
    figures: dict[str, Any] = {}
    for name, builder, label in (
        (
            "sine-0_5Hz",
            lambda s: signals.sine(0.875 * INCH, 0.4 * INCH, 0.5, 10.0, s.simulation.control_step),
            "0.5 Hz sine",
        ),
        (
            "step-train",
            lambda s: signals.step_train(
                [0.4 * INCH, 1.4 * INCH, 0.6 * INCH, 1.2 * INCH, 0.875 * INCH],
                2.0,
                s.simulation.control_step,
            ),
            "step train",
        ),
    ):
        _result, summary = _run(folder, name, [], builder, True, f"closed-loop {label}")
        figures[f"{label}: RMSE [mm]"] = summary["rmse [m]"] * 1e3
        figures[f"{label}: RMSE [% stroke]"] = summary["rmse [% stroke]"]
        figures[f"{label}: lag [s]"] = summary["lag [s]"]
        figures[f"{label}: real-time factor"] = summary["real-time factor"]
    report.add(
        "Closed-loop tracking",
        "Position PID (1 ms sample, anti-windup, gains in the "
        "parameter file) tracking a sine and a step train, like thesis Figs. 27–28.",
        folder / "sine-0_5Hz" / "rig.png",
        figures,
    )


def _stiction(folder: Path, report: DemoReport) -> None:
    recordings = {}
    figures: dict[str, Any] = {}
    for model in ("stribeck_tanh", "lugre"):
        result, summary = _run(
            folder,
            f"slow-sine-{model}",
            [f'friction.model="{model}"'],
            lambda s: signals.sine(0.875 * INCH, 0.3 * INCH, 0.1, 20.0, s.simulation.control_step),
            True,
            f"slow closed-loop sine, {model} friction",
        )
        recordings[model] = result.recording
        speed = np.abs(result.recording["velocity [m/s]"][2000:])
        at_rest = float(np.mean(speed < 1e-5))
        figures[f"{model}: fraction of time at rest (speed < 10 µm/s)"] = at_rest
        figures[f"{model}: RMSE [mm]"] = summary["rmse [m]"] * 1e3
    path = plot_stiction_comparison(recordings, folder / "stiction.png", report.units)
    report.add(
        "Stiction at slow speed",
        "The thesis's stated failure (4.4.2, 5.5.2): with "
        "Stribeck-tanh friction, which is zero at zero velocity, a slow closed-loop "
        "sine never stops at its reversals — the piston creeps. LuGre friction holds "
        "it still until the force passes breakaway.",
        path,
        figures,
    )


def _reference_solver(folder: Path, report: DemoReport) -> None:
    recordings = {}
    for integrator in ("fixed", "radau"):
        result, _ = _run(
            folder,
            f"solver-{integrator}",
            [f'simulation.integrator="{integrator}"'],
            lambda s: signals.thesis_step_command(
                6.0, 5.25, 0.0, 10.0, s.simulation.control_step, 0.5, 2.0
            ),
            False,
            f"open-loop step, {integrator} integrator",
            step_time=0.5,
        )
        recordings[integrator] = result.recording
    fixed, radau = recordings["fixed"], recordings["radau"]
    figures = {
        "position RMSE [µm]": _rms(fixed["position [m]"], radau["position [m]"]) * 1e6,
        "cap pressure RMSE [Pa]": _rms(fixed["cap pressure [Pa]"], radau["cap pressure [Pa]"]),
        "rod pressure RMSE [Pa]": _rms(fixed["rod pressure [Pa]"], radau["rod pressure [Pa]"]),
    }
    simulation = load_rig("thesis-rig").simulation
    steps = f"{simulation.control_step * 1e3:g} ms, {simulation.substeps} substeps"
    path = plot_difference(
        fixed, radau, folder / "solver.png", ("fixed step", "Radau"),
        f"Fixed step ({steps}) against the Radau reference", report.units,
    )
    report.add(
        "Fixed step vs adaptive reference",
        f"The default integrator ({simulation.control_step * 1e3:g} ms control step, "
        f"{simulation.substeps} Heun substeps, linearly implicit piston velocity) against "
        f"scipy's Radau with rtol {simulation.relative_tolerance:g} on the same sampled "
        "controller; the lower panels show the differences.",
        path,
        figures,
    )


def _tank(folder: Path, report: DemoReport) -> None:
    overrides = [
        'supply.model="tank"',
        'supply.tank_volume="0.5 L"',
        'supply.tank_initial_pressure="8 bara"',
    ]
    result, summary = _run(
        folder,
        "tank-sine",
        overrides,
        lambda s: signals.sine(0.875 * INCH, 0.6 * INCH, 1.0, 40.0, s.simulation.control_step),
        True,
        "1 Hz sine from a 0.5 L tank at 8 bar",
    )
    recording = result.recording
    supply = load_rig("thesis-rig").actuator.supply.supply_pressure
    below = np.nonzero(recording["tank pressure [Pa]"] < supply)[0]
    figures = {
        "air consumed [NL]": summary["air consumed [NL]"],
        "air per second [NL/s]": summary["air consumed [NL]"] / summary["simulated time [s]"],
        "tank falls below the regulator set point at [s]": (
            float(recording["time [s]"][below[0]]) if below.size else float("nan")
        ),
        "final tank pressure [Pa]": float(recording["tank pressure [Pa]"][-1]),
        "RMSE [mm]": summary["rmse [m]"] * 1e3,
    }
    path = plot_tank_run(recording, supply, folder / "tank-sine" / "tank.png",
                         "1 Hz sine from a 0.5 L tank at 8 bar", report.units)
    report.add(
        "Finite tank supply",
        "A closed-loop 1 Hz sine drawn from a small tank "
        "through an ideal regulator: air consumed and the tank pressure over time; "
        "tracking degrades once the tank can no longer hold the regulated pressure.",
        path,
        figures,
    )
