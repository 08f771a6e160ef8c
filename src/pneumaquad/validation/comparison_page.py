"""docs/thesis-comparison.md: the closed-loop claims of thesis 4.3 and 5.5 beside our
figures for both controller sets, with the figures that explain them.

Written by ``pneumaquad report --thesis-comparison --output docs`` (the page and its PNGs
under ``images/``).
"""

from __future__ import annotations

import datetime
import math
from pathlib import Path

import numpy as np

from pneumaquad import __version__
from pneumaquad.params import load_rig
from pneumaquad.params.conversions import METRE_PER_INCH
from pneumaquad.reporting.cost_report import cost_table_markdown
from pneumaquad.reporting.html import format_value
from pneumaquad.reporting.plotting import DPI, plt
from pneumaquad.rig import signals
from pneumaquad.rig.simulate import simulate_rigs
from pneumaquad.validation.calibration import THESIS_ALPHA_GAIN_SCALE
from pneumaquad.validation.comparison import (
    CONTROLLER_SETS,
    WALK_DISTANCE,
    Comparison,
    targets_of,
)
from pneumaquad.validation.published import PUBLISHED
from pneumaquad.validation.rig_loop import SINE_AMPLITUDE, SINE_MEAN, STEP_DWELL, STEP_LEVELS

__all__ = ["COMMAND", "PAGE_NAME", "comparison_markdown", "write_comparison_page"]

PAGE_NAME = "thesis-comparison.md"
COMMAND = "pneumaquad report --thesis-comparison --output docs"
RIG_FIGURE = "images/thesis-rig-loop.png"
WALKING_FIGURE = "images/thesis-alpha-walking.png"


def _summary_table(comparison: Comparison) -> list[str]:
    labels = [s.label for s in CONTROLLER_SETS]
    per_set = {label: targets_of(comparison.sets[label]) for label in labels}
    lines = ["| claim | thesis | target | " + " | ".join(labels) + " |",
             "|---|---|---|" + "---|" * len(labels)]
    for index, row in enumerate(per_set[labels[0]]):
        cells = []
        for label in labels:
            target = per_set[label][index]
            mark = "met" if target.met else "missed"
            unit = "" if target.unit == "-" else f" {target.unit}"
            shown = target.shown or f"{format_value(target.value, 3)}{unit}"
            cells.append(f"{shown} ({mark})")
        lines.append(f"| {row.claim} | {row.published} | {row.target} | " + " | ".join(cells)
                     + " |")
    return lines


def _rig_section(comparison: Comparison) -> list[str]:
    lines = ["| controller set | Kp, Ki, Kd | step tau per step [s] | mean tau [s] (sd) | "
             "lag at 1 / 3 / 5 rad/s [s] |", "|---|---|---|---|---|"]
    for controller_set in CONTROLLER_SETS:
        figures = comparison.sets[controller_set.label].rig
        gains = load_rig(controller_set.rig).controller
        lines.append(
            f"| {controller_set.label} (`{controller_set.rig}`) | "
            f"{gains.proportional_gain:.4g} V/m, {gains.integral_gain:.4g} V/(m s), "
            f"{gains.derivative_gain:.4g} V s/m | "
            + ", ".join(f"{t:.3f}" for t in figures.time_constants)
            + f" | {figures.time_constant:.3f} ({figures.time_constant_spread:.3f}) | "
            + " / ".join(f"{lag:.3f}" for lag in figures.sine_lags) + " |")
    return lines


def _joint_section(comparison: Comparison) -> list[str]:
    lines = ["| controller set | joint | fast-sine lag [s] | sine RMSE [deg] | step rise "
             "[s] | step tau [s] | overshoot [%] | step RMSE [deg] |",
             "|---|---|---|---|---|---|---|---|"]
    for controller_set in CONTROLLER_SETS:
        for joint, f in comparison.sets[controller_set.label].joints.items():
            lines.append(f"| {controller_set.label} | {joint} | {f.sine_lag:.3f} | "
                         f"{f.sine_rmse:.2f} | {f.rise_time:.3f} | {f.time_constant:.3f} | "
                         f"{f.overshoot:.1f} | {f.step_rmse:.2f} |")
    return lines


def _walking_section(comparison: Comparison) -> list[str]:
    lines = ["| controller set | alpha gain | joint | RMSE [deg] | lag [s] | RMSE, lag "
             "removed [deg] | error above 3 Hz [deg] |", "|---|---|---|---|---|---|---|"]
    for controller_set in CONTROLLER_SETS:
        for scale, rows in comparison.sets[controller_set.label].walking.items():
            for f in rows:
                lines.append(f"| {controller_set.label} | {scale:g} | {f.joint} | "
                             f"{f.rmse:.2f} | {f.lag:.3f} | {f.shifted_rmse:.2f} | "
                             f"{f.oscillation:.2f} |")
    return lines


def _alpha_finding(comparison: Comparison) -> str:
    sentences = []
    for controller_set in CONTROLLER_SETS:
        walking = comparison.sets[controller_set.label].walking
        full, reduced = walking[1.0][0], walking[THESIS_ALPHA_GAIN_SCALE][0]
        verb = "falls" if reduced.rmse < full.rmse else "rises"
        sentences.append(
            f"With {controller_set.phrase} the alpha RMSE {verb} from {full.rmse:.2f}° to "
            f"{reduced.rmse:.2f}° at 75 % gain; its part above 3 Hz goes from "
            f"{full.oscillation:.2f}° to {reduced.oscillation:.2f}° and its lag from "
            f"{full.lag:.3f} s to {reduced.lag:.3f} s.")
    return " ".join(sentences)


def _walk_section(comparison: Comparison) -> list[str]:
    lines = ["| controller set | outcome | travelled [m] | air [NL/m] | joints at a limit |",
             "|---|---|---|---|---|"]
    for controller_set in CONTROLLER_SETS:
        walk = comparison.sets[controller_set.label].walk
        outcome = "success" if walk.get("success") else (
            "failure (" + "; ".join(walk.get("reasons", [])) + ")")
        limits = ", ".join(walk.get("joints at a limit", [])) or "none"
        lines.append(f"| {controller_set.label} | {outcome} | "
                     f"{walk.get('distance travelled [m]', math.nan):.3f} | "
                     f"{walk.get('air per metre [NL/m]', math.nan):.2f} | {limits} |")
    return lines


def _default_verdict(comparison: Comparison) -> str:
    tuned, thesis = (comparison.sets[c.label].walk.get("success", False)
                     for c in CONTROLLER_SETS)
    if tuned and not thesis:
        return ("Our tuning stays the default: it walks and the thesis set does not. The "
                "thesis set's slower joints and alpha's limit cycle at full gain are what "
                "the thesis's figures ask of a controller, not what walking needs.")
    if thesis and not tuned:
        return "The thesis set walks where our tuning does not."
    return "Both sets have the same walking outcome; our tuning stays the default."


def _component_section(comparison: Comparison) -> list[str]:
    complete = comparison.cost_table.rows[0].min_us
    lines = ["| component -> replacement | ns per call | replacement ns | calls per 1 ms step "
             "| saving [µs/step] | of the complete step [%] | transcendental calls |",
             "|---|---|---|---|---|---|---|"]
    for part in comparison.components:
        lines.append(f"| {part.name} | {part.ns_per_call:.1f} | "
                     f"{part.replacement_ns_per_call:.1f} | {part.calls_per_step} | "
                     f"{part.saving_us:.3f} | {100 * part.saving_us / complete:.1f} | "
                     f"{part.transcendentals} |")
    return lines


def comparison_markdown(comparison: Comparison) -> str:
    """The page's Markdown (figures referenced as :data:`RIG_FIGURE` and
    :data:`WALKING_FIGURE`)."""
    rows = comparison.cost_table.rows
    by_case = {row.case: row for row in rows}
    friction_min = 100 * (by_case["simple friction (viscous)"].min_us / rows[0].min_us - 1)
    valve_min = 100 * (by_case["simple valve"].min_us / rows[0].min_us - 1)
    published = ["| claim | thesis simulated | thesis measured | source |", "|---|---|---|---|"]
    published += [f"| {p.claim} | {p.simulated} | {p.measured} | {p.source} |"
                  for p in PUBLISHED]
    parts = [
        "# Closed-loop results beside the thesis (chapters 4.3 and 5.5)",
        "",
        f"Generated by `{COMMAND}` on {datetime.date.today().isoformat()} with pneumaquad "
        f"{__version__} ({comparison.wall_time:.0f} s on this machine). Every figure below "
        "is measured in "
        "that run; the protocols and the reading of the thesis's bounds are in "
        "`pneumaquad.validation` (`published`, `rig_loop`, `leg_loop`).",
        "",
        "Two controller sets. **Our tuning** is the default (`thesis-rig`, `crr-quadruped`). "
        "The **thesis set** (`thesis-rig-thesis-pid`, `crr-quadruped-thesis-pid`) has PID "
        "gains calibrated to the published closed-loop figures, because the thesis prints "
        "no gains. `docs/examples/thesis_calibration.py` re-derives them "
        "(`pneumaquad.validation.calibration`). The rig's gains fit the step time constant "
        "and the 1 rad/s lag. Gamma, which has the rig's cylinder, takes the rig's gains "
        "times one scale that fits its sine lag. Beta takes the rig's gains with a scale "
        "and a lower integral gain, for its lag and a step response slower than gamma's. "
        "Alpha takes the rig's gains scaled to the middle of the band where the walking "
        "motion limit-cycles at full gain but not at 75 %.",
        "",
        "## The closed-loop claims",
        "",
        *_summary_table(comparison),
        "",
        "How the thesis's bounds are read: the rig's sine-lag differences (0.02, 0.01 and "
        "0.005 s, at most 25 % of the measured lag) mean measured lags of at least 0.08, "
        "0.04 and 0.02 s. A first-order loop with the step's 0.082 s lags 0.080 s at "
        "1 rad/s, so that bound is tight and is held to ±20 %; at 3 and 5 rad/s only the "
        "bound is a target. The thesis's sine amplitudes and frequencies are not printed. "
        "The rig uses 0.875 ± 0.4 in. The leg uses the `fast-sine` protocol: 0.5 Hz, ±30 % "
        "of the joint's range.",
        "",
        "## Rig (4.3)",
        "",
        *_rig_section(comparison),
        "",
        f"![Rig step train and 1 rad/s sine with both controller sets]({RIG_FIGURE})",
        "",
        "## Leg joints (5.5.2)",
        "",
        *_joint_section(comparison),
        "",
        "RMSE here is against the reference. The thesis's RMSEs (2.6°, 1.5°, about 4°) are "
        "of the simulation against the robot's recordings, which we do not have.",
        "",
        "## The alpha gain in the walking motion (5.5.2.4)",
        "",
        *_walking_section(comparison),
        "",
        _alpha_finding(comparison),
        "",
        "The thesis measured its RMSE against the real leg, which did not oscillate, so "
        "damping the simulated limit cycle brought the simulation closer to the robot. We "
        "have only the reference to measure against. With the thesis set, alpha limit-cycles "
        "at full gain, as the thesis's alpha did (Fig. 44), and 75 % gain removes the cycle: "
        "the error falls, as in Fig. 45. Our tuning's alpha does not oscillate in this "
        "motion, so lowering its gain mostly adds lag: compare its RMSE with the lag "
        "removed at the two gains.",
        "",
        f"![Alpha in the walking motion at full and 75 % gain]({WALKING_FIGURE})",
        "",
        f"## Which set walks: the default walk of {WALK_DISTANCE:g} m",
        "",
        "`pneumaquad robot walk --distance 0.5` on flat ground with each set (the stand-up, "
        "the stance check and the crawl as shipped):",
        "",
        *_walk_section(comparison),
        "",
        _default_verdict(comparison),
        "",
        "## Table 3: what each component costs (5.5.3)",
        "",
        "The whole fixed-step rig loop (PID, kernel, recording row) per 1 ms step, with "
        f"components removed; {comparison.cost_table.repeats} interleaved repeats of a "
        "10 s closed-loop sine (`pneumaquad report --cost-table`):",
        "",
        cost_table_markdown(comparison.cost_table).rstrip(),
        "",
        f"By the fastest repeat (the steadier figure on a shared machine), the simple valve "
        f"saves {-valve_min:.1f} % and viscous friction {-friction_min:.1f} %. The thesis "
        "found 24 % and 11 %. Each component on its own, in a compiled loop:",
        "",
        *_component_section(comparison),
        "",
        "The ordering follows from where each part runs and what it evaluates. The valve "
        "map (two fourth-order polynomials and two tanh pressure curves) runs once per 1 ms "
        "control step. The friction law runs every substep (five per step), because the "
        "stiff law has to be resolved inside the step. It used to evaluate the Stribeck "
        "curve twice (an exp and a pow each), a tanh and a cosh, for the force and for the "
        "implicit step's slope. That made friction the larger cost: before the change, "
        "viscous friction saved 32 % of the step and the simple valve 9 % (the 0.3.0 "
        "cost table, measured on 2026-11-24). The law now takes one Stribeck "
        "curve and one tanh for both, with 1 - tanh² as the sech². For a moving piston it "
        "skips the exp and the tanh where their values are exactly 0 and ±1. The results "
        "are bit-identical in force and agree to rounding in the slope "
        "(`tests/test_physics_friction.py`). "
        + ("So friction now costs less than the valve, as in the thesis, whose Simulink "
           "blocks all ran at every solver step." if friction_min > valve_min else
           "Friction still costs more than the valve in this run."),
        "",
        "## Every quantitative claim of 4.3 and 5.5",
        "",
        *published,
        "",
        "Claims of simulation-versus-robot RMSE need the thesis's recordings. "
        "`pneumaquad report RUN --measured FILE --mapping MAP` compares a run with a lab "
        "recording once one is at hand.",
        "",
    ]
    return "\n".join(parts)


def _plot_rig(path: Path) -> None:
    setups = [load_rig(s.rig) for s in CONTROLLER_SETS]
    dt = setups[0].simulation.control_step
    steps = signals.step_train(STEP_LEVELS, STEP_DWELL, dt)
    period = 2.0 * math.pi
    sine = signals.sine(SINE_MEAN, SINE_AMPLITUDE, 1.0 / period, 3 * period, dt)
    figure, axes = plt.subplots(2, 1, figsize=(9, 6.5))
    for axis, reference, title in ((axes[0], steps, "step train"),
                                   (axes[1], sine, "sine at 1 rad/s")):
        results = simulate_rigs(setups, np.tile(reference, (len(setups), 1)), True)
        time = results[0].recording["time [s]"]
        axis.plot(time, results[0].recording["reference position [m]"] / METRE_PER_INCH,
                  "k--", lw=1, label="reference")
        for controller_set, result in zip(CONTROLLER_SETS, results, strict=True):
            axis.plot(time, result.recording["position [m]"] / METRE_PER_INCH, lw=1.2,
                      label=controller_set.label)
        axis.set_ylabel("piston position [in]")
        axis.set_title(f"Rig, closed loop: {title}")
        axis.grid(alpha=0.3)
        axis.legend(loc="upper right", fontsize=8)
    axes[1].set_xlabel("time [s]")
    figure.tight_layout()
    figure.savefig(path, dpi=DPI)
    plt.close(figure)


def _plot_walking(comparison: Comparison, path: Path) -> None:
    figure, axes = plt.subplots(len(CONTROLLER_SETS), 1, figsize=(9, 6.5), sharex=True)
    for axis, controller_set in zip(axes, CONTROLLER_SETS, strict=True):
        tracks = comparison.sets[controller_set.label].walking_tracks
        time, joints = tracks[1.0]
        window = time >= time[-1] - 6.0  # the fast cycles and the end of the medium ones
        axis.plot(time[window], np.degrees(joints["alpha"][1][window]), "k--", lw=1,
                  label="reference")
        for scale in (1.0, THESIS_ALPHA_GAIN_SCALE):
            time, joints = tracks[scale]
            window = time >= time[-1] - 6.0
            axis.plot(time[window], np.degrees(joints["alpha"][0][window]), lw=1.2,
                      label=f"alpha gain x{scale:g}")
        axis.set_ylabel("alpha angle [deg]")
        axis.set_title(f"Walking motion, {controller_set.label}")
        axis.grid(alpha=0.3)
        axis.legend(loc="upper right", fontsize=8)
    axes[-1].set_xlabel("time [s]")
    figure.tight_layout()
    figure.savefig(path, dpi=DPI)
    plt.close(figure)


def write_comparison_page(comparison: Comparison, folder: Path) -> Path:
    """Write ``folder/thesis-comparison.md`` and its two PNGs under ``folder/images``."""
    (folder / "images").mkdir(parents=True, exist_ok=True)
    _plot_rig(folder / RIG_FIGURE)
    _plot_walking(comparison, folder / WALKING_FIGURE)
    page = folder / PAGE_NAME
    page.write_text(comparison_markdown(comparison), encoding="utf-8")
    return page
