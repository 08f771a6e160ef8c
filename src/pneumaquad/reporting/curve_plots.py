"""Figures of the model curves (thesis Fig. 15–16, 23 and 24) from a run's parameters.

Each function takes label → actuator parameters (``{"rig": ...}`` or the robot's joint
types); actuators with equal sub-models share one curve, labelled with all their names.
Axes are in the display units given (:mod:`pneumaquad.reporting.display_units`: SI by
default, or the thesis's lbf, in/s, psia and in²); voltages in V either way.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np
from matplotlib.ticker import MaxNLocator

from pneumaquad.params import ActuatorParameters
from pneumaquad.reporting.display_units import SI, DisplayUnits
from pneumaquad.reporting.plotting import DPI, plt

from .curves import (
    area_curves,
    friction_curve,
    friction_zoom_limit,
    group_equal,
    input_pressure_curves,
)

__all__ = ["plot_area_curves", "plot_friction_curves", "plot_input_pressure_curves"]

_CHAMBER_COLOURS = {"cap": "C3", "rod": "C2"}
_GROUP_STYLES = ("-", "--", ":", "-.")


def _save(fig, path: Path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    return path


def _title(label: str) -> str:
    return "" if label == "rig" else f" ({label})"


def plot_friction_curves(
    actuators: Mapping[str, ActuatorParameters], path: Path, velocity_limit: float = 0.3,
    units: DisplayUnits = SI,
) -> Path:
    """Friction force against velocity of each configured model (thesis Fig. 15–16).

    Two panels: ±``velocity_limit`` and a zoom on the breakaway region near zero.

    Parameters
    ----------
    actuators : mapping of str to ActuatorParameters
        Label → actuator.
    path : Path
        Output PNG.
    velocity_limit : float
        Half width of the full-range panel [m/s].
    units : DisplayUnits
        Display units of force and velocity.
    """
    groups = group_equal({label: a.friction for label, a in actuators.items()})
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.3), layout="constrained")
    zoom = max(friction_zoom_limit(f, velocity_limit) for _, f in groups)
    for ax, limit in zip(axes, (velocity_limit, zoom), strict=True):
        velocity = np.linspace(-limit, limit, 1201)
        for index, (label, friction) in enumerate(groups):
            force = friction_curve(friction, velocity)
            ax.plot(
                units.value(velocity, "velocity"), units.value(force, "force"),
                color=f"C{index}", lw=1.5, label=f"{friction.model}{_title(label)}",
            )
        ax.axhline(0.0, color="0.5", lw=0.6)
        ax.axvline(0.0, color="0.5", lw=0.6)
        ax.grid(True, alpha=0.35)
        ax.set_xlabel(units.axis("Velocity", "velocity"))
        ax.xaxis.set_major_locator(MaxNLocator(nbins=6))
        ax.set_ylabel(units.axis("Friction force", "force"))
    axes[0].set_title("Full range", fontsize="medium")
    axes[1].set_title("Near zero velocity (breakaway)", fontsize="medium")
    axes[0].legend(loc="best", fontsize="small")
    fig.suptitle("Friction force vs piston velocity")
    return _save(fig, path)


def plot_area_curves(actuators: Mapping[str, ActuatorParameters], path: Path,
                     units: DisplayUnits = SI) -> Path:
    """Equivalent orifice area cd·A against centered voltage, per port and side (Fig. 24).

    Colour: chamber (cap red, rod green); the negative side of the offset is drawn solid,
    the positive side dashed; one panel per distinct valve.
    """
    groups = group_equal({label: a.valve for label, a in actuators.items()})
    fig, axes = plt.subplots(
        1, len(groups), figsize=(6.5 * len(groups), 4.5), layout="constrained", squeeze=False
    )
    for ax, (label, valve) in zip(axes[0], groups, strict=True):
        for curve in area_curves(valve):
            ax.plot(
                curve.voltage,
                units.value(curve.area, "small area"),
                color=_CHAMBER_COLOURS[curve.chamber],
                ls="-" if curve.side == "negative" else "--",
                lw=1.5,
                label=curve.label,
            )
        offset = valve.offset_voltage
        ax.axvline(0.0, color="0.5", lw=0.6)
        ax.grid(True, alpha=0.35)
        ax.set_xlabel("Centered voltage u_c (V)")
        ax.set_ylabel(units.axis("Equivalent area cd·A", "small area"))
        ax.secondary_xaxis(
            "top", functions=(lambda u, o=offset: u + o, lambda u, o=offset: u - o)
        ).set_xlabel("Command (V)")
        ax.set_title(f"{valve.model} valve{_title(label)}", fontsize="medium")
        ax.legend(loc="best", fontsize="small")
    fig.suptitle("Valve equivalent orifice area vs voltage")
    return _save(fig, path)


def plot_input_pressure_curves(actuators: Mapping[str, ActuatorParameters], path: Path,
                               units: DisplayUnits = SI) -> Path:
    """Steady-state input pressure of each port against voltage (thesis Fig. 23, eq 4.2.7).

    Absolute pressures against the command voltage, with the centered voltage on top and
    the supply and exhaust pressures as dotted lines.
    """
    groups = group_equal({label: (a.valve, a.supply) for label, a in actuators.items()})
    fig, axes = plt.subplots(
        1, len(groups), figsize=(6.5 * len(groups), 4.5), layout="constrained", squeeze=False
    )
    for ax, (label, (valve, supply)) in zip(axes[0], groups, strict=True):
        offset = valve.offset_voltage
        for curve in input_pressure_curves(
            next(a for a in actuators.values() if a.valve == valve and a.supply == supply)
        ):
            port = f"port {curve.port}" if curve.port else "simple valve"
            ax.plot(
                curve.voltage + offset,
                units.value(curve.pressure, "pressure"),
                color=_CHAMBER_COLOURS[curve.chamber],
                lw=1.6,
                label=f"{curve.chamber} ({port})",
            )
        for level, name in (
            (supply.supply_pressure, "supply"),
            (supply.exhaust_pressure, "exhaust"),
        ):
            shown = units.value(level, "pressure")
            ax.axhline(shown, color="0.4", ls=":", lw=0.9)
            ax.annotate(
                name,
                (valve.min_voltage, shown),
                fontsize="small",
                color="0.3",
                xytext=(2, 2),
                textcoords="offset points",
            )
        ax.axvline(offset, color="0.5", lw=0.6)
        ax.grid(True, alpha=0.35)
        ax.set_xlabel("Command (V)")
        ax.set_ylabel(units.axis("Input pressure", "pressure"))
        ax.secondary_xaxis(
            "top", functions=(lambda u, o=offset: u - o, lambda u, o=offset: u + o)
        ).set_xlabel("Centered voltage u_c (V)")
        ax.set_title(f"{valve.model} valve{_title(label)}", fontsize="medium")
        ax.legend(loc="center right", fontsize="small")
    fig.suptitle("Steady-state input pressure vs valve command")
    return _save(fig, path)
