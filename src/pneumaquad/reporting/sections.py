"""Sections of a run report: each adds headings, tables and figures to an :class:`HtmlPage`.

Figures are written as PNG files into the report folder and embedded in the page; every
number with a unit is shown in the report's :class:`~.display_units.DisplayUnits`.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from pneumaquad.analysis.compare import comparison_rows
from pneumaquad.io.run_folder import TIMING_NAME, write_json
from pneumaquad.params import RigSetup, RobotParameters
from pneumaquad.reporting.plotting import plot_rig_run
from pneumaquad.reporting.robot_plots import plot_body, plot_joints, plot_walking

from .comparison import (
    COMPARISON_HEADERS,
    MeasuredComparison,
    comparison_table_rows,
    plot_errors,
    plot_measured_vs_simulated,
)
from .curve_plots import plot_area_curves, plot_friction_curves, plot_input_pressure_curves
from .curves import group_equal
from .display_units import DisplayUnits
from .html import HtmlPage, table_markdown
from .parameters import (
    PARAMETER_HEADERS,
    actuator_rows,
    flatten_summary,
    rig_parameter_rows,
    robot_parameter_rows,
    shown_rows,
)
from .run_folder import LoadedRun

__all__ = [
    "COMPARISON_NAME",
    "add_comparison",
    "add_model_curves",
    "add_parameters",
    "add_summary",
    "add_time_histories",
    "add_walking",
    "commanded_joints",
    "velocity_limit",
]

#: The figures of a report against measured data, beside its report.html.
COMPARISON_NAME = "comparison.json"
#: Keys of a step's row that hold the command (a position or a voltage, no unit in the key).
_COMMAND_KEYS = ("initial command", "final command")


def closed_loop(run: LoadedRun) -> bool:
    """Whether a rig run followed a position reference (its summary says so, or failing
    that its recording has a finite reference)."""
    if "closed loop" in run.summary:
        return bool(run.summary["closed loop"])
    reference = run.recording.get("reference position [m]")
    return reference is not None and bool(np.all(np.isfinite(reference)))

def add_parameters(page: HtmlPage, run: LoadedRun, units: DisplayUnits) -> None:
    """Key run parameters (and, for robots, one table per distinct actuator set)."""
    page.heading("Run parameters")
    page.paragraph(
        "Key values of the resolved parameters.toml (which holds them in SI), shown in "
        "this report's units; pressures absolute unless marked gauge.", note=True
    )
    if isinstance(run.parameters, RigSetup):
        atmosphere = run.parameters.actuator.gas.atmospheric_pressure
        page.table(PARAMETER_HEADERS, shown_rows(rig_parameter_rows(run.parameters),
                                                 units.with_atmosphere(atmosphere)))
        return
    assert isinstance(run.parameters, RobotParameters)
    page.table(
        PARAMETER_HEADERS,
        shown_rows(robot_parameter_rows(run.parameters, run.summary, run.folder.model_file),
                   units),
    )
    for labels, actuator in group_equal(run.actuators):
        page.heading(f"Actuator of the {labels} joints ({actuator.meta.name})", level=3)
        shown = units.with_atmosphere(actuator.gas.atmospheric_pressure)
        page.table(PARAMETER_HEADERS, shown_rows(actuator_rows(actuator), shown))


def add_summary(page: HtmlPage, run: LoadedRun, units: DisplayUnits) -> None:
    """The metrics of summary.json as a two-column table (nested tables flattened), each
    key's unit in the report's units (summary.json itself is SI)."""
    page.heading("Metrics (summary.json)")
    if not run.summary:
        page.paragraph("No summary.json in the run folder.", note=True)
        return
    page.table(("metric", "value"), units.rows(flatten_summary(run.summary)), digits=6)


def commanded_joints(run: LoadedRun) -> list[str]:
    """Joints under closed-loop control (keys of summary "angle rmse [deg]"); failing
    that, joints whose reference moves; failing that, the front-right leg."""
    controlled = run.summary.get("angle rmse [deg]")
    if isinstance(controlled, dict) and controlled:
        return [str(name) for name in controlled]
    suffix = " reference [rad]"
    moving = [
        column.removesuffix(suffix)
        for column, values in run.recording.items()
        if column.endswith(suffix) and values.size and np.ptp(values) > 1e-9
    ]
    if moving:
        return moving
    return [
        c.removesuffix(suffix)
        for c in run.recording
        if c.startswith("front_right") and c.endswith(suffix)
    ]


def add_time_histories(page: HtmlPage, run: LoadedRun, folder: Path,
                       units: DisplayUnits) -> None:
    """Rig: position, pressures and command (Fig. 25–28). Robot: per commanded leg,
    reference vs angle and both pressures (Fig. 38–45); the body when it is free."""
    page.heading("Time histories")
    recording = run.recording
    if recording["time [s]"].size < 2:
        page.paragraph("The recording has fewer than two samples: nothing to plot.", note=True)
        return
    if run.kind == "rig":
        path = plot_rig_run(recording, folder / "rig.png", title=run.description,
                            units=units)
        page.figure(
            path,
            f"Position ({units.unit('small length')}), cap and rod pressures "
            f"({units.unit('pressure')}) and valve command (V) against time, as in thesis "
            "Fig. 25–28.",
        )
        return
    joints = commanded_joints(run)
    legs = list(dict.fromkeys(j.rsplit("_", 1)[0] for j in joints))
    for leg in legs:
        leg_joints = [j for j in joints if j.rsplit("_", 1)[0] == leg]
        path = plot_joints(
            recording,
            leg_joints,
            folder / f"joints-{leg}.png",
            f"{run.description}: {leg.replace('_', ' ')}",
            units,
        )
        page.figure(
            path,
            f"{leg.replace('_', ' ')}: reference and simulated angle (deg), "
            f"cap and rod pressure ({units.unit('pressure')}), as in thesis Fig. 38–45.",
        )
    feet = [
        c.removesuffix(" foot normal force [N]")
        for c in recording
        if c.endswith(" foot normal force [N]")
    ]
    if run.summary.get("configuration") != "fixed" and "thorax z [m]" in recording and feet:
        path = plot_body(recording, feet, folder / "body.png", run.description, units)
        page.figure(path, "Thorax height, attitude, foot normal forces and air consumed.")
    add_walking(page, run, folder, units)
    preview = run.path / "video.gif"
    snapshot = run.path / "first-frame.png"
    if preview.is_file() and preview.stat().st_size <= MAX_EMBEDDED_GIF:
        page.figure(preview, "The run's video (GIF preview; video.mp4 in the run folder).")
    elif snapshot.is_file():
        page.figure(snapshot, "First frame of the run's video.")


#: Largest GIF preview [bytes] embedded in a report (larger ones: the first frame).
MAX_EMBEDDED_GIF = 12 * 1024 * 1024


def add_walking(page: HtmlPage, run: LoadedRun, folder: Path, units: DisplayUnits) -> None:
    """The walking judgement of a ``robot walk`` run (summary "walking") and its figure:
    the run's walking.png (drawn in SI when the walk ran), or in other units the same
    figure drawn again from the recording, without the tip-over margin the walk's plan
    gave (the table has its smallest and median)."""
    outcome = run.summary.get("walking")
    if not outcome:
        return
    page.heading("Walking", level=3)
    verdict = "success" if outcome.get("success") else "failure"
    page.paragraph(f"Outcome: {verdict} ({', '.join(outcome.get('reasons', []))}).")
    rows = flatten_summary({key: value for key, value in outcome.items()
                            if key not in ("success", "reasons")})
    page.table(["quantity", "value"], [(key, value or "none" if isinstance(value, str)
                                        else value) for key, value in units.rows(rows)])
    figure = run.path / "walking.png"
    if not figure.is_file():
        return
    if units.system == "si":
        page.figure(figure, "Thorax travel, static margin of the loaded feet and of the feet "
                            "the gait holds down (tip-over margin), foot heights.")
        return
    legs = [c.removesuffix(" foot z [m]") for c in run.recording if c.endswith(" foot z [m]")]
    needed = ("thorax x [m]", "thorax y [m]", "stability margin [m]")
    if legs and all(column in run.recording for column in needed):
        path = plot_walking(run.recording, legs, folder / "walking.png", None,
                            run.description, units)
        page.figure(path, "Thorax travel, static margin of the loaded feet, foot heights "
                          "(the tip-over margin of the feet the gait holds down is in the "
                          "run folder's walking.png, drawn in SI).")


def velocity_limit(run: LoadedRun, default: float = 0.3) -> float:
    """Half width [m/s] of the friction plot: 1.2 × the largest recorded piston speed,
    within 0.02–2 m/s; ``default`` without a velocity column."""
    speeds = [
        float(np.nanmax(np.abs(values)))
        for column, values in run.recording.items()
        if column.endswith("velocity [m/s]") and values.size
    ]
    speeds = [s for s in speeds if math.isfinite(s) and s > 0]
    if not speeds:
        return default
    return float(np.clip(1.2 * max(speeds), 0.02, 2.0))


def add_model_curves(page: HtmlPage, run: LoadedRun, folder: Path,
                     units: DisplayUnits) -> None:
    """Friction law (Fig. 15–16), equivalent areas (Fig. 24), input pressures (Fig. 23)."""
    page.heading("Model curves from the run's parameters")
    if not run.actuators:
        page.paragraph("No actuator parameters could be loaded.", note=True)
        return
    parameters = run.parameters
    if isinstance(parameters, RobotParameters) and parameters.simulation.seal_friction == "mujoco":
        page.paragraph(
            "Seal friction of this run lives in MuJoCo's constraint solver (dry friction "
            "with the Stribeck breakaway below); the curve is the actuator file's law.",
            note=True,
        )
    limit = velocity_limit(run)
    path = plot_friction_curves(run.actuators, folder / "friction.png", limit, units)
    page.figure(
        path,
        "Friction force against piston velocity of the configured model "
        "(thesis eq 4.2.1–4.2.6, Fig. 15–16); LuGre at steady state. Right: "
        "zoom on the breakaway peak.",
    )
    path = plot_area_curves(run.actuators, folder / "valve-area.png", units)
    page.figure(
        path,
        "Equivalent orifice area cd·A of each chamber's port against the "
        "centered voltage, one polynomial per side of the offset (thesis "
        "Fig. 24, App. B.1.2).",
    )
    path = plot_input_pressure_curves(run.actuators, folder / "input-pressure.png", units)
    page.figure(
        path,
        "Steady-state input pressure seen by each port against the valve "
        "command (thesis eq 4.2.7–4.2.11, Fig. 23).",
    )


def add_comparison(
    page: HtmlPage,
    run: LoadedRun,
    comparison: MeasuredComparison,
    measured: dict[str, np.ndarray],
    source: str,
    folder: Path,
    units: DisplayUnits,
) -> None:
    """Measured vs simulated figures, the metric table and per-step figures; the metric
    table also as comparison.md (in the report's units) and, in SI, comparison.json."""
    page.heading("Measured vs simulated")
    page.paragraph(
        f"Measured data: {source}. Time offset added to the measured time: "
        f"{comparison.time_offset:g} s. RMSE % is of the stroke for position and "
        "of the measured range for pressures; lag > 0 means the simulation "
        "follows late."
    )
    path = plot_measured_vs_simulated(
        run.recording,
        measured,
        folder / "measured-vs-simulated.png",
        comparison.time_offset,
        run.description,
        units,
    )
    page.figure(path, f"Measured and simulated position ({units.unit('small length')}) and "
                      f"pressures ({units.unit('pressure')}).")
    rows = comparison_table_rows(comparison.comparisons, units)
    page.table(COMPARISON_HEADERS, rows)
    if comparison.step_time is not None:
        page.paragraph(
            f"τ: first-order fits (thesis eq 4.3.1) from the step at {comparison.step_time:g} s.",
            note=True,
        )
    path = plot_errors(comparison, folder / "measured-error.png", units)
    page.figure(path, "Simulated minus measured on the common time grid.")
    if comparison.steps_simulated:
        page.heading("Position figures per step", level=3)
        page.paragraph(
            "Steps found in the simulated reference (closed loop) or valve command "
            "(open loop); the commands are positions or voltages accordingly.",
            note=True,
        )
        command_unit = "m" if closed_loop(run) else "V"
        labelled = [("simulated", row) for row in comparison.steps_simulated]
        labelled += [("measured", row) for row in comparison.steps_measured]
        labelled.sort(key=lambda item: (item[1].get("step", 0), item[0] != "simulated"))
        keys = list(dict.fromkeys(k for _, row in labelled for k in row))
        named = [f"{k} [{command_unit}]" if k in _COMMAND_KEYS else k for k in keys]
        shown = [units.rows([(name, row.get(k, math.nan)) for name, k in zip(named, keys,
                                                                             strict=True)])
                 for _, row in labelled]
        page.table(
            ["data", *(name for name, _ in shown[0])] if shown else ["data"],
            [[label, *(value for _, value in cells)]
             for (label, _), cells in zip(labelled, shown, strict=True)],
        )
    (folder / "comparison.md").write_text(table_markdown(COMPARISON_HEADERS, rows, digits=4),
                                          encoding="utf-8")
    document = {
        "signals": comparison_rows(comparison.comparisons),
        "steps simulated": comparison.steps_simulated,
        "steps measured": comparison.steps_measured,
        "time offset [s]": comparison.time_offset,
        "source": source,
    }
    write_json(folder / COMPARISON_NAME, document)


def add_network_timing(page: HtmlPage, run: LoadedRun, units: DisplayUnits) -> None:
    """A networked run's packet timing (``timing.json``, ``rtt.png``, ``timeline.png``):
    round trips, pauses, losses, duplicates, reorders, malformed datagrams, jitter."""
    timing = run.timing
    if timing is None:
        if (run.path / TIMING_NAME).is_file():  # unreadable: the report's notes say why
            page.heading("Network timing")
            page.paragraph(f"{TIMING_NAME} cannot be read (see the notes above).", note=True)
        return
    page.heading("Network timing")
    page.paragraph(
        "Per-datagram log of the co-simulation (packets.parquet), summarised: the round "
        "trips, the pauses between datagrams (the thesis tracked these with Wireshark, "
        "5.3.1), and what was dropped and why."
    )
    page.table(("figure", "value"), units.rows(flatten_summary(timing)), digits=6)
    for name, caption in (
        ("rtt.png", "Round-trip times (histogram) with median, p99 and the control period."),
        ("timeline.png", "Inter-arrival gaps and pauses over the run."),
    ):
        if (run.path / name).is_file():
            page.figure(run.path / name, caption)
