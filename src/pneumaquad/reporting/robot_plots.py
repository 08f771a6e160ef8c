"""Plots of robot runs: joint tracking with both chamber pressures (like thesis Fig. 38-45)
and the body: thorax height and attitude, foot forces and air consumed; the walk. Each is
drawn in the display units it is given (SI by default; angles in degrees either way)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from pneumaquad.gait.stability import STANCE_FORCE
from pneumaquad.reporting.display_units import SI, DisplayUnits
from pneumaquad.reporting.plotting import DPI, plt

__all__ = ["plot_body", "plot_joints", "plot_walking"]


def plot_joints(recording: dict[str, np.ndarray], joints: Sequence[str], path: Path,
                title: str = "", units: DisplayUnits = SI) -> Path:
    """Per joint: reference vs actual angle [deg] above cap and rod pressure (absolute).

    The reference is drawn only while the joint is under closed-loop control.
    """
    time = recording["time [s]"]
    fig, axes = plt.subplots(2, len(joints), figsize=(4.2 * len(joints), 5.6), sharex=True,
                             squeeze=False)
    for column, joint in enumerate(joints):
        angle_axis, pressure_axis = axes[0, column], axes[1, column]
        reference = np.degrees(recording[f"{joint} reference [rad]"])
        mode = recording.get(f"{joint} control mode [-]")
        if mode is not None:
            reference = np.where(mode == 1.0, reference, np.nan)
        if np.any(np.isfinite(reference)):
            angle_axis.plot(time, reference, "k--", lw=1.0, label="reference")
        angle_axis.plot(time, np.degrees(recording[f"{joint} angle [rad]"]), "C0", lw=1.2,
                        label="simulated")
        angle_axis.set_title(joint.replace("_", " "))
        angle_axis.set_ylabel("Angle (deg)")
        _at_least_span(angle_axis, MIN_ANGLE_SPAN)
        for side, colour in (("cap", "C3"), ("rod", "C2")):
            pressure = recording.get(f"{joint} {side} pressure [Pa]")
            if pressure is not None:
                pressure_axis.plot(time, units.value(pressure, "pressure"), colour, lw=1.0,
                                   label=side)
        pressure_axis.set_ylabel(units.axis("Pressure", "pressure"))
        pressure_axis.set_xlabel("Time (s)")
    return _save(fig, axes.ravel(), path, title)


#: Least y span of an angle panel [deg]: a joint held still shows a flat line, not its
#: micro-degree noise magnified with an offset.
MIN_ANGLE_SPAN = 4.0


def _at_least_span(axis, span: float) -> None:
    """Widen ``axis``'s y range about its middle to at least ``span``, in plain numbers."""
    low, high = axis.get_ylim()
    if high - low < span:
        middle = 0.5 * (low + high)
        axis.set_ylim(middle - 0.5 * span, middle + 0.5 * span)
    axis.ticklabel_format(axis="y", useOffset=False, style="plain")


def plot_body(recording: dict[str, np.ndarray], legs: Sequence[str], path: Path,
              title: str = "", units: DisplayUnits = SI) -> Path:
    """Thorax height, roll/pitch [deg], foot normal forces and air consumed [NL]."""
    time = recording["time [s]"]
    fig, axes = plt.subplots(4, 1, figsize=(8.0, 8.5), sharex=True)
    axes[0].plot(time, units.value(recording["thorax z [m]"], "length"), "C0")
    axes[0].set_ylabel(units.axis("Thorax height", "length"))
    axes[1].plot(time, np.degrees(recording["thorax roll [rad]"]), "C1", label="roll")
    axes[1].plot(time, np.degrees(recording["thorax pitch [rad]"]), "C2", label="pitch")
    axes[1].set_ylabel("Attitude (deg)")
    for leg in legs:
        axes[2].plot(time, units.value(recording[f"{leg} foot normal force [N]"], "force"),
                     lw=1.0, label=leg.replace("_", " "))
    axes[2].set_ylabel(units.axis("Foot force", "force"))
    axes[3].plot(time, recording["air consumed [NL]"], "C4")
    axes[3].set_ylabel("Air consumed (NL)")
    axes[3].set_xlabel("Time (s)")
    return _save(fig, axes, path, title)


def plot_walking(recording: dict[str, np.ndarray], legs: Sequence[str], path: Path,
                 tip_over: np.ndarray | None = None, title: str = "",
                 units: DisplayUnits = SI) -> Path:
    """Walking: thorax travel, static margins over time, foot heights (m and mm, or in).

    ``tip_over`` (same length as the recording, NaN outside the walk) is the margin in the
    support of the feet the gait holds down; the recorded margin uses the loaded feet.
    """
    time = recording["time [s]"]
    fig, axes = plt.subplots(3, 1, figsize=(8.0, 7.5), sharex=True)
    axes[0].plot(time, units.value(recording["thorax x [m]"], "length"), "C0", label="x")
    axes[0].plot(time, units.value(recording["thorax y [m]"], "length"), "C1", label="y")
    axes[0].set_ylabel(units.axis("Thorax", "length"))
    margin = units.value(recording["stability margin [m]"], "small length")
    loaded = units.text(STANCE_FORCE, "force", 2)
    axes[1].plot(time, margin, "C3", lw=0.8, label=f"loaded feet (> {loaded})")
    if tip_over is not None:
        axes[1].plot(time, units.value(tip_over, "small length"), "C2", lw=1.2,
                     label="feet the gait holds down")
    axes[1].axhline(0.0, color="k", lw=0.8)
    low, high, pad = (units.value(v, "small length") for v in MARGIN_AXIS)
    axes[1].set_ylim(max(low, float(np.nanmin(margin, initial=0.0))) - pad, high)
    axes[1].set_ylabel(units.axis("Static margin", "small length"))
    for leg in legs:
        axes[2].plot(time, units.value(recording[f"{leg} foot z [m]"], "small length"),
                     lw=1.0, label=leg.replace("_", " "))
    axes[2].set_ylabel(units.axis("Foot height", "small length"))
    axes[2].set_xlabel("Time (s)")
    return _save(fig, axes, path, title)


#: The static margin panel's lowest bottom, its top and the room below the lowest margin
#: [m]: a fall's margin does not squash the walk's.
MARGIN_AXIS = (-0.2, 0.15, 0.01)


def plot_waypoints(recording: dict[str, np.ndarray], waypoints: np.ndarray,
                   reached: np.ndarray, start: np.ndarray, path: Path,
                   units: DisplayUnits = SI) -> Path:
    """A waypoint walk over the ground: the thorax's path (with its sway), the waypoints
    (n, 2) [m] and where each walk ended, ``reached`` (m, 2) [m], both from ``start``
    (2,) [m, world]."""
    fig, axis = plt.subplots(figsize=(6.0, 6.0))
    axis.plot(units.value(recording["thorax x [m]"], "length"),
              units.value(recording["thorax y [m]"], "length"), "C0", lw=0.8,
              label="thorax (with its sway)")
    targets = start + np.vstack([np.zeros(2), waypoints])
    axis.plot(units.value(targets[:, 0], "length"), units.value(targets[:, 1], "length"),
              "k--o", ms=5, label="waypoints")
    ends = start + np.asarray(reached, dtype=float).reshape(-1, 2)
    axis.plot(units.value(ends[:, 0], "length"), units.value(ends[:, 1], "length"), "C3x",
              ms=9, ls="none", label="where a walk ended")
    axis.set_xlabel(units.axis("x", "length"))
    axis.set_ylabel(units.axis("y", "length"))
    axis.set_aspect("equal", adjustable="datalim")
    return _save(fig, [axis], path, "Waypoint walk: path, waypoints, where each walk ended")


def _save(fig, axes, path: Path, title: str) -> Path:
    for axis in axes:
        axis.grid(True, alpha=0.35)
        if axis.get_legend_handles_labels()[0]:
            axis.legend(loc="best", fontsize="small", framealpha=0.85)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    return path
