"""Measured-versus-simulated comparison of a rig run for the report (thesis 4.3).

Wraps :func:`pneumaquad.analysis.compare.compare_recordings`: position and chamber
pressures are aligned on a common grid, compared (RMSE, RMSE in % of the stroke or of the
measured range, max error, lag, first-order τ after a single step) and, for step trains,
split into steps with :func:`pneumaquad.analysis.segmentation.metrics_per_step`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pneumaquad.analysis.compare import (
    AlignedRecordings,
    SignalComparison,
    compare_recordings,
)
from pneumaquad.analysis.segmentation import find_steps, metrics_per_step
from pneumaquad.reporting.display_units import SI, DisplayUnits
from pneumaquad.reporting.plotting import DPI, plot_comparison, plt

from .run_folder import ReportError

__all__ = [
    "COMPARED_SIGNALS",
    "MeasuredComparison",
    "compare_with_measured",
    "comparison_table_rows",
    "plot_errors",
    "plot_measured_vs_simulated",
]

#: Signals compared when both recordings have them.
COMPARED_SIGNALS = (
    "position [m]",
    "cap pressure [Pa]",
    "rod pressure [Pa]",
    "supply pressure [Pa]",
)
#: Command jump [V] and reference jump [fraction of stroke] that make a step.
COMMAND_STEP_THRESHOLD = 0.05
REFERENCE_STEP_FRACTION = 0.01

Recording = Mapping[str, np.ndarray]


@dataclass(frozen=True)
class MeasuredComparison:
    """Outcome of :func:`compare_with_measured`.

    Attributes
    ----------
    comparisons : list of SignalComparison
        One per compared signal (SI units).
    aligned : AlignedRecordings
        Both recordings on the common grid.
    step_time : float or None
        Instant of the single step the τ fits start from [s]; None for no step or a train.
    steps_simulated, steps_measured : list of dict
        Per-step position figures (keys name their units) when the run has steps.
    time_offset : float
        Offset added to the measured time stamps [s].
    """

    comparisons: list[SignalComparison]
    aligned: AlignedRecordings
    step_time: float | None
    steps_simulated: list[dict[str, float]]
    steps_measured: list[dict[str, float]]
    time_offset: float


def _driver(simulated: Recording, stroke: float) -> tuple[str, np.ndarray, float, str] | None:
    """(column, values, threshold, levels_from) of what drove the run, or None."""
    reference = np.asarray(simulated.get("reference position [m]", []), dtype=float)
    if reference.size and np.all(np.isfinite(reference)):
        return "reference position [m]", reference, REFERENCE_STEP_FRACTION * stroke, "command"
    command = np.asarray(simulated.get("command [V]", []), dtype=float)
    if command.size and np.all(np.isfinite(command)):
        return "command [V]", command, COMMAND_STEP_THRESHOLD, "response"
    return None


def compare_with_measured(
    simulated: Recording,
    measured: Recording,
    stroke: float,
    time_offset: float = 0.0,
) -> MeasuredComparison:
    """Compare a simulated rig recording with a measured one.

    Parameters
    ----------
    simulated, measured : mapping of str to numpy.ndarray
        SI recordings (``"time [s]"``, ``"position [m]"``, pressures in Pa absolute).
    stroke : float
        Cylinder stroke [m]: the span of the position RMSE percentage and the scale of
        the reference-step threshold.
    time_offset : float
        Added to the measured time stamps [s].

    Returns
    -------
    MeasuredComparison

    Raises
    ------
    ReportError
        When no signal is common to both, or the recordings cannot be aligned.
    """
    signals = [s for s in COMPARED_SIGNALS if s in simulated and s in measured]
    if not signals:
        raise ReportError(
            "the measured data has none of the compared signals "
            f"({', '.join(COMPARED_SIGNALS)}); it has {sorted(measured)}"
        )
    driver = _driver(simulated, stroke)
    steps = []
    if driver is not None:
        steps = find_steps(simulated["time [s]"], driver[1], driver[2])
    step_time = steps[0].start_time if len(steps) == 1 else None
    try:
        comparisons, aligned = compare_recordings(
            simulated,
            measured,
            signals=signals,
            time_offset=time_offset,
            spans={"position [m]": stroke},
            step_time=step_time,
        )
    except ValueError as error:
        raise ReportError(f"cannot compare with the measured data: {error}") from None
    per_sim: list[dict[str, float]] = []
    per_meas: list[dict[str, float]] = []
    if driver is not None and steps and "position [m]" in signals:
        column, _, threshold, levels_from = driver
        command = aligned.simulated[column]
        for rows, recording in ((per_sim, aligned.simulated), (per_meas, aligned.measured)):
            rows += metrics_per_step(
                aligned.time,
                recording["position [m]"],
                command,
                threshold,
                levels_from=levels_from,
                unit="m",
            )
    return MeasuredComparison(
        comparisons, aligned, step_time, per_sim, per_meas, float(time_offset)
    )


#: Headers of :func:`comparison_table_rows`.
COMPARISON_HEADERS = (
    "signal",
    "unit",
    "RMSE",
    "RMSE [% of range]",
    "max abs error",
    "lag [s]",
    "τ simulated [s]",
    "τ measured [s]",
)


def comparison_table_rows(comparisons: list[SignalComparison],
                          units: DisplayUnits = SI) -> list[list[object]]:
    """Rows (signal, unit, RMSE, RMSE %, max error, lag, τ sim, τ meas) in the display
    units: the errors of a length as a small length, of a pressure as a difference."""
    rows: list[list[object]] = []
    for c in comparisons:
        name = c.signal[: c.signal.rindex("[")].strip()
        si = c.signal[c.signal.rindex("[") + 1 : -1]
        rmse, unit = units.error(c.rmse, si)
        largest, _ = units.error(c.max_abs_error, si)
        rows.append(
            [
                name,
                unit,
                rmse,
                c.rmse_percent,
                largest,
                c.lag,
                c.simulated_time_constant,
                c.measured_time_constant,
            ]
        )
    return rows


def plot_measured_vs_simulated(
    simulated: Recording,
    measured: Recording,
    path: Path,
    time_offset: float = 0.0,
    title: str = "",
    units: DisplayUnits = SI,
) -> Path:
    """Measured and simulated position and (absolute) pressures against time."""
    shifted = dict(measured)
    shifted["time [s]"] = np.asarray(measured["time [s]"], dtype=float) + time_offset
    return plot_comparison({"measured": shifted, "simulated": simulated}, path, title, units)


def plot_errors(comparison: MeasuredComparison, path: Path, units: DisplayUnits = SI) -> Path:
    """Simulated minus measured on the common grid: position and pressure differences."""
    aligned = comparison.aligned
    names = [c.signal for c in comparison.comparisons]
    fig, axes = plt.subplots(2, 1, figsize=(8, 5.5), sharex=True, layout="constrained")
    for name in names:
        error = aligned.simulated[name] - aligned.measured[name]
        if name == "position [m]":
            axes[0].plot(aligned.time, units.value(error, "small length"), color="C0", lw=1.2)
        else:
            axes[1].plot(aligned.time, units.value(error, "pressure difference"), lw=1.2,
                         label=name.removesuffix(" [Pa]"))
    axes[0].set_ylabel(units.axis("Position error", "small length"))
    axes[1].set_ylabel(units.axis("Pressure error", "pressure difference"))
    axes[1].set_xlabel("Time (s)")
    for ax in axes:
        ax.grid(True, alpha=0.35)
        ax.axhline(0.0, color="0.5", lw=0.6)
    if axes[1].get_legend_handles_labels()[0]:
        axes[1].legend(loc="best", fontsize="small")
    fig.suptitle("Simulated minus measured")
    path = Path(path)
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    return path
