"""Plots of robot runs: joint tracking with both chamber pressures (like thesis Fig. 38-45)
and the body: thorax height and attitude, foot forces and air consumed."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from pneumaquad.reporting.plotting import DPI, pascals_to_psi, plt

__all__ = ["plot_body", "plot_joints", "plot_walking"]


def plot_joints(recording: dict[str, np.ndarray], joints: Sequence[str], path: Path,
                title: str = "") -> Path:
    """Per joint: reference vs actual angle [deg] above cap and rod pressure [psia].

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
                pressure_axis.plot(time, pascals_to_psi(pressure), colour, lw=1.0, label=side)
        pressure_axis.set_ylabel("Pressure (psia)")
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
              title: str = "") -> Path:
    """Thorax height [m], roll/pitch [deg], foot normal forces [N] and air consumed [NL]."""
    time = recording["time [s]"]
    fig, axes = plt.subplots(4, 1, figsize=(8.0, 8.5), sharex=True)
    axes[0].plot(time, recording["thorax z [m]"], "C0")
    axes[0].set_ylabel("Thorax height (m)")
    axes[1].plot(time, np.degrees(recording["thorax roll [rad]"]), "C1", label="roll")
    axes[1].plot(time, np.degrees(recording["thorax pitch [rad]"]), "C2", label="pitch")
    axes[1].set_ylabel("Attitude (deg)")
    for leg in legs:
        axes[2].plot(time, recording[f"{leg} foot normal force [N]"], lw=1.0,
                     label=leg.replace("_", " "))
    axes[2].set_ylabel("Foot force (N)")
    axes[3].plot(time, recording["air consumed [NL]"], "C4")
    axes[3].set_ylabel("Air consumed (NL)")
    axes[3].set_xlabel("Time (s)")
    return _save(fig, axes, path, title)


def plot_walking(recording: dict[str, np.ndarray], legs: Sequence[str], path: Path,
                 tip_over: np.ndarray | None = None, title: str = "") -> Path:
    """Walking: thorax travel [m], static margins [mm] over time, foot heights [mm].

    ``tip_over`` (same length as the recording, NaN outside the walk) is the margin in the
    support of the feet the gait holds down; the recorded margin uses the loaded feet.
    """
    time = recording["time [s]"]
    fig, axes = plt.subplots(3, 1, figsize=(8.0, 7.5), sharex=True)
    axes[0].plot(time, recording["thorax x [m]"], "C0", label="x")
    axes[0].plot(time, recording["thorax y [m]"], "C1", label="y")
    axes[0].set_ylabel("Thorax (m)")
    margin = 1000.0 * recording["stability margin [m]"]
    axes[1].plot(time, margin, "C3", lw=0.8, label="loaded feet (> 1 N)")
    if tip_over is not None:
        axes[1].plot(time, 1000.0 * tip_over, "C2", lw=1.2, label="feet the gait holds down")
    axes[1].axhline(0.0, color="k", lw=0.8)
    axes[1].set_ylim(max(-200.0, float(np.nanmin(margin, initial=0.0))) - 10.0, 150.0)
    axes[1].set_ylabel("Static margin (mm)")
    for leg in legs:
        axes[2].plot(time, 1000.0 * recording[f"{leg} foot z [m]"], lw=1.0,
                     label=leg.replace("_", " "))
    axes[2].set_ylabel("Foot height (mm)")
    axes[2].set_xlabel("Time (s)")
    return _save(fig, axes, path, title)


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
