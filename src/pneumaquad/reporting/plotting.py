"""Figures of rig runs in the style of Daepp (2011), figures 25-28.

Recordings are mappings of SI column names (``"time [s]"``, ``"position [m]"``,
``"cap pressure [Pa]"``, ...) to arrays. Each figure is drawn in the display units it is
given (:mod:`pneumaquad.reporting.display_units`: SI by default, or the thesis's inches
and psia), converted here and only here.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import matplotlib

from pneumaquad.reporting.display_units import SI, DisplayUnits

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

DPI = 150

TIME = "time [s]"
COMMAND = "command [V]"
REFERENCE = "reference position [m]"
POSITION = "position [m]"
VELOCITY = "velocity [m/s]"
CAP_PRESSURE = "cap pressure [Pa]"
ROD_PRESSURE = "rod pressure [Pa]"
SUPPLY_PRESSURE = "supply pressure [Pa]"
TANK_PRESSURE = "tank pressure [Pa]"
FRICTION_FORCE = "friction force [N]"
PNEUMATIC_FORCE = "pneumatic force [N]"
AIR_CONSUMED = "air consumed [NL]"

Recording = Mapping[str, np.ndarray]


def _column(recording: Recording, name: str) -> np.ndarray | None:
    values = recording.get(name)
    if values is None:
        return None
    values = np.asarray(values, dtype=float)
    return values if values.size else None


def _time(recording: Recording) -> np.ndarray:
    time = _column(recording, TIME)
    if time is None:
        raise KeyError(f"recording has no {TIME!r} column")
    return time


def _finish(
    fig: Figure, axes: list[Axes], path: Path, title: str, xlabel: str = "Time (s)"
) -> Path:
    for ax in axes:
        ax.grid(True, alpha=0.35)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(loc="best", fontsize="small", framealpha=0.85)
    axes[-1].set_xlabel(xlabel)
    if title:
        fig.suptitle(title)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    return path


def plot_rig_run(recording: Recording, path: Path, title: str = "",
                 units: DisplayUnits = SI) -> Path:
    """Plot one rig run: position, chamber pressures and valve command vs time.

    Parameters
    ----------
    recording
        Column name → array; only ``"time [s]"`` is required.
    path
        Output PNG path (parent folders are created).
    title
        Figure title.
    units
        Display units (position as a small length, absolute pressures).

    Returns
    -------
    Path
        The written PNG.
    """
    time = _time(recording)
    fig, axes = plt.subplots(
        3, 1, sharex=True, figsize=(8, 8), height_ratios=[3, 3, 1.6], layout="constrained"
    )
    ax_pos, ax_p, ax_u = axes

    position = _column(recording, POSITION)
    if position is not None:
        ax_pos.plot(time, units.value(position, "small length"), color="C0", lw=1.6,
                    label="Position")
    reference = _column(recording, REFERENCE)
    if reference is not None and bool(np.any(np.isfinite(reference))):
        ax_pos.plot(time, units.value(reference, "small length"), color="k", ls="--", lw=1.1,
                    label="Reference")
    ax_pos.set_ylabel(units.axis("Position", "small length"))

    cap = _column(recording, CAP_PRESSURE)
    if cap is not None:
        ax_p.plot(time, units.value(cap, "pressure"), color="C3", lw=1.5, label="Cap chamber")
    rod = _column(recording, ROD_PRESSURE)
    if rod is not None:
        ax_p.plot(time, units.value(rod, "pressure"), color="C2", lw=1.5, label="Rod chamber")
    supply = _column(recording, SUPPLY_PRESSURE)
    if supply is not None:
        ax_p.plot(time, units.value(supply, "pressure"), color="0.35", lw=0.9, ls=":",
                  zorder=3, label="Supply")
    ax_p.set_ylabel(units.axis("Pressure", "pressure"))

    command = _column(recording, COMMAND)
    if command is not None:
        ax_u.plot(time, command, color="C4", lw=1.3, label="Valve command")
    ax_u.set_ylabel("Command (V)")

    return _finish(fig, list(axes), path, title)


def plot_comparison(recordings: Mapping[str, Recording], path: Path, title: str = "",
                    units: DisplayUnits = SI) -> Path:
    """Overlay several runs: position and cap/rod pressures vs time.

    Each run gets one colour; cap pressure is solid and rod pressure dashed.

    Parameters
    ----------
    recordings
        Run label → recording (e.g. ``{"measured": ..., "simulated": ...}``).
    path
        Output PNG path.
    title
        Figure title.
    units
        Display units.
    """
    fig, axes = plt.subplots(2, 1, sharex=True, figsize=(8, 6.5), layout="constrained")
    ax_pos, ax_p = axes
    for index, (label, recording) in enumerate(recordings.items()):
        colour = f"C{index % 10}"
        time = _time(recording)
        position = _column(recording, POSITION)
        if position is not None:
            ax_pos.plot(time, units.value(position, "small length"), color=colour, lw=1.5,
                        label=label)
        cap = _column(recording, CAP_PRESSURE)
        if cap is not None:
            ax_p.plot(time, units.value(cap, "pressure"), color=colour, lw=1.4,
                      label=f"{label} cap")
        rod = _column(recording, ROD_PRESSURE)
        if rod is not None:
            ax_p.plot(time, units.value(rod, "pressure"), color=colour, lw=1.4, ls="--",
                      label=f"{label} rod")
    ax_pos.set_ylabel(units.axis("Position", "small length"))
    ax_p.set_ylabel(units.axis("Pressure", "pressure"))
    return _finish(fig, list(axes), path, title)


def plot_difference(candidate: Recording, reference: Recording, path: Path,
                    labels: tuple[str, str] = ("fixed step", "reference"),
                    title: str = "", units: DisplayUnits = SI) -> Path:
    """Two runs of the same experiment that agree closely: the position of both, then the
    candidate's difference from the reference in position (µm, or thousandths of an inch)
    and in the cap and rod pressures, which an overlay would hide.

    Parameters
    ----------
    candidate, reference
        Recordings on the same time grid (the candidate's times are used).
    path
        Output PNG path.
    labels
        Names of the candidate and of the reference.
    title
        Figure title.
    units
        Display units.
    """
    time = _time(candidate)
    fig, axes = plt.subplots(3, 1, sharex=True, figsize=(8, 8), height_ratios=[3, 2, 2],
                             layout="constrained")
    ax_pos, ax_dx, ax_dp = axes
    for label, recording, style in ((labels[1], reference, "-"), (labels[0], candidate, "--")):
        ax_pos.plot(time, units.value(recording[POSITION], "small length"), ls=style, lw=1.5,
                    label=label)
    ax_pos.set_ylabel(units.axis("Position", "small length"))
    difference = units.value(candidate[POSITION] - reference[POSITION], "tiny length")
    ax_dx.plot(time, difference, color="C0", lw=1.2)
    ax_dx.set_ylabel(units.axis("Position difference\n", "tiny length"))
    for column, colour, name in ((CAP_PRESSURE, "C3", "cap"), (ROD_PRESSURE, "C2", "rod")):
        ax_dp.plot(time, units.value(candidate[column] - reference[column],
                                     "pressure difference"),
                   color=colour, lw=1.2, label=name)
    ax_dp.set_ylabel(units.axis("Pressure difference\n", "pressure difference"))
    for axis in (ax_dx, ax_dp):
        axis.axhline(0.0, color="k", lw=0.6)
    return _finish(fig, list(axes), path, title)


def plot_held_pressures(recordings: Mapping[str, Recording], targets: Mapping[str, tuple],
                        path: Path, title: str = "", units: DisplayUnits = SI) -> Path:
    """Chamber pressures of runs with the piston held, each beside the levels it should
    settle at (dotted): ``targets`` maps a run's label to its (cap, rod) pressures [Pa].
    No position panel: the piston does not move."""
    fig, ax = plt.subplots(figsize=(8, 5), layout="constrained")
    for index, (label, recording) in enumerate(recordings.items()):
        colour = f"C{index % 10}"
        time = _time(recording)
        ax.plot(time, units.value(recording[CAP_PRESSURE], "pressure"), color=colour, lw=1.5,
                label=f"{label} cap")
        ax.plot(time, units.value(recording[ROD_PRESSURE], "pressure"), color=colour, lw=1.5,
                ls="--", label=f"{label} rod")
        for level in targets.get(label, ()):
            ax.axhline(units.value(level, "pressure"), color=colour, lw=0.9, ls=":")
    ax.plot([], [], color="0.4", lw=0.9, ls=":", label="input-pressure curve (eq 4.2.7)")
    ax.set_ylabel(units.axis("Pressure", "pressure"))
    return _finish(fig, [ax], path, title)


def plot_tank_run(recording: Recording, set_point: float, path: Path,
                  title: str = "", units: DisplayUnits = SI) -> Path:
    """A run drawn from a finite tank: position and reference, the tank pressure beside
    the regulated supply and the regulator's set point ``set_point`` [Pa], and the air
    consumed (NL) over time."""
    time = _time(recording)
    fig, axes = plt.subplots(3, 1, sharex=True, figsize=(8, 8), layout="constrained")
    ax_pos, ax_p, ax_air = axes
    ax_pos.plot(time, units.value(recording[POSITION], "small length"), color="C0", lw=1.2,
                label="Position")
    ax_pos.plot(time, units.value(recording[REFERENCE], "small length"), color="k", ls="--",
                lw=0.9, label="Reference")
    ax_pos.set_ylabel(units.axis("Position", "small length"))
    ax_p.plot(time, units.value(recording[TANK_PRESSURE], "pressure"), color="C1", lw=1.6,
              label="Tank")
    ax_p.plot(time, units.value(recording[SUPPLY_PRESSURE], "pressure"), color="C0", lw=1.2,
              label="Regulated supply")
    ax_p.axhline(units.value(set_point, "pressure"), color="0.35", ls=":", lw=1.0,
                 label="Regulator set point")
    ax_p.set_ylabel(units.axis("Pressure", "pressure"))
    ax_air.plot(time, recording[AIR_CONSUMED], color="C4", lw=1.5, label="Air consumed")
    ax_air.set_ylabel("Air (NL)")
    return _finish(fig, list(axes), path, title)


def plot_friction_curve(
    curves: Mapping[str, tuple[np.ndarray, np.ndarray]],
    path: Path,
    title: str = "",
    units: DisplayUnits = SI,
) -> Path:
    """Plot friction force against piston velocity for one or more models.

    Parameters
    ----------
    curves
        Label → ``(velocity [m/s], friction force [N])``. Points are sorted by
        velocity before plotting.
    path
        Output PNG path.
    title
        Figure title.
    units
        Display units.
    """
    fig, ax = plt.subplots(figsize=(7, 4.5), layout="constrained")
    for label, (velocity, force) in curves.items():
        v = np.asarray(velocity, dtype=float)
        f = np.asarray(force, dtype=float)
        order = np.argsort(v, kind="stable")
        ax.plot(units.value(v[order], "velocity"), units.value(f[order], "force"), lw=1.5,
                label=label)
    ax.axhline(0.0, color="0.5", lw=0.6)
    ax.axvline(0.0, color="0.5", lw=0.6)
    ax.set_ylabel(units.axis("Friction force", "force"))
    return _finish(fig, [ax], path, title, xlabel=units.axis("Velocity", "velocity"))
