"""Model curves from a run's parameters: friction law, valve areas, input pressures.

Pure functions returning arrays (SI) that the report plots like the thesis's figures:

* friction force against piston velocity of the configured model (Fig. 15–16, eq 4.2.1–
  4.2.6; LuGre at its steady state);
* the valve's equivalent orifice area cd·A against the centered voltage, per port and per
  side of the offset (Fig. 24, App. B.1.2: one 4th-order polynomial per side, clipped at 0);
* the steady-state input pressure seen by each port against the voltage (Fig. 23,
  eq 4.2.7–4.2.11).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import TypeVar

import numpy as np
from numpy.typing import ArrayLike

from pneumaquad.core.actuator import FRICTION_CODES, chamber_ports
from pneumaquad.core.physics.friction import FRICTION_LUGRE, friction_force, stribeck_curve
from pneumaquad.core.valve_fit import evaluate_equivalent_area, input_pressure
from pneumaquad.params import ActuatorParameters, FrictionParameters, ValveParameters

__all__ = [
    "AreaCurve",
    "PressureCurve",
    "area_curves",
    "centered_voltage_range",
    "friction_curve",
    "friction_zoom_limit",
    "group_equal",
    "input_pressure_curves",
]

T = TypeVar("T")


@dataclass(frozen=True)
class AreaCurve:
    """Equivalent orifice area of one valve port on one side of the offset.

    Attributes
    ----------
    chamber : {"cap", "rod"}
        Chamber the port feeds.
    port : int
        Valve port number (1 or 2); 0 for the simple (linear) valve model.
    side : {"negative", "positive"}
        Side of the offset (centered voltage ≤ 0 or > 0).
    voltage : numpy.ndarray
        Centered voltage [V].
    area : numpy.ndarray
        Equivalent area cd·A [m^2].
    """

    chamber: str
    port: int
    side: str
    voltage: np.ndarray
    area: np.ndarray

    @property
    def label(self) -> str:
        """Legend text, e.g. ``"cap (port 2), u_c ≤ 0"``."""
        port = f"port {self.port}" if self.port else "linear"
        side = "u_c ≤ 0" if self.side == "negative" else "u_c > 0"
        return f"{self.chamber} ({port}), {side}"


@dataclass(frozen=True)
class PressureCurve:
    """Steady-state input pressure of one chamber's port against the centered voltage.

    Attributes
    ----------
    chamber : {"cap", "rod"}
    port : int
        Valve port (0 for the simple valve).
    voltage : numpy.ndarray
        Centered voltage [V].
    pressure : numpy.ndarray
        Absolute input pressure [Pa].
    high_cutoff, low_cutoff : float
        C_HP, C_LP [V] (NaN for the simple valve).
    """

    chamber: str
    port: int
    voltage: np.ndarray
    pressure: np.ndarray
    high_cutoff: float
    low_cutoff: float


def friction_curve(friction: FrictionParameters, velocity: ArrayLike) -> np.ndarray:
    """Friction force of the configured model at each velocity (positive opposes +v).

    Uses the kernel's own :func:`pneumaquad.core.physics.friction.friction_force`. LuGre is
    evaluated at its steady state, bristle deflection z = g(v)·sign(v)/σ0, where it equals
    g(v)·sign(v) + Cv·v.

    Parameters
    ----------
    friction : FrictionParameters
        Validated friction parameters (SI).
    velocity : array_like
        Piston velocities [m/s].

    Returns
    -------
    numpy.ndarray
        Friction force [N], same shape as ``velocity``.
    """
    v = np.asarray(velocity, dtype=float)
    code = FRICTION_CODES[friction.model]
    f = friction
    out = np.empty(v.size)
    for index, speed in enumerate(v.ravel()):
        deflection = 0.0
        if code == FRICTION_LUGRE and speed != 0.0:
            g = stribeck_curve(
                speed, f.static_force, f.coulomb_force, f.stribeck_velocity, f.stribeck_exponent
            )
            deflection = float(np.sign(speed)) * g / f.bristle_stiffness
        out[index] = friction_force(
            code,
            float(speed),
            deflection,
            f.static_force,
            f.coulomb_force,
            f.viscous_coefficient,
            f.stribeck_velocity,
            f.stribeck_exponent,
            f.tanh_coefficient,
            f.damping_coefficient,
            f.bristle_stiffness,
            f.bristle_damping,
        )
    return out.reshape(v.shape)


def friction_zoom_limit(friction: FrictionParameters, full_range: float) -> float:
    """Half width [m/s] of a velocity window that shows the breakaway peak.

    Four Stribeck velocities or three tanh lengths 3/k_tanh, whichever is wider, for the
    models with a Stribeck curve; a tenth of ``full_range`` otherwise.
    """
    if friction.model in ("stribeck_tanh", "lugre"):
        window = max(4.0 * friction.stribeck_velocity, 3.0 / friction.tanh_coefficient)
        return min(window, full_range)
    return 0.1 * full_range


def centered_voltage_range(valve: ValveParameters, count: int = 801) -> np.ndarray:
    """Centered voltages spanning the valve's input range [V]: min−offset … max−offset."""
    low = valve.min_voltage - valve.offset_voltage
    high = valve.max_voltage - valve.offset_voltage
    voltages = np.linspace(low, high, count)
    if low < 0.0 < high:  # put the offset itself on the grid
        voltages = np.union1d(voltages, [0.0])
    return voltages


def area_curves(valve: ValveParameters, voltage: ArrayLike | None = None) -> list[AreaCurve]:
    """Equivalent area of each chamber's port, per side of the offset (thesis Fig. 24).

    Underlapped valve: the port's polynomials (App. B.1.2 l.42–50), negative side for
    u_c ≤ 0 and positive side for u_c > 0, clipped at zero. Simple valve (or
    ``area_curve = "linear"``): cd·(A_max·|u_c|/u_fs + A_leak) with the cap and rod
    discharge coefficients (thesis Fig. 18).

    Parameters
    ----------
    valve : ValveParameters
        Validated valve parameters.
    voltage : array_like, optional
        Centered voltages [V]; default :func:`centered_voltage_range`.

    Returns
    -------
    list of AreaCurve
        Cap negative, cap positive, rod negative, rod positive.
    """
    u = centered_voltage_range(valve) if voltage is None else np.asarray(voltage, dtype=float)
    sides = (("negative", u[u <= 0.0]), ("positive", u[u > 0.0]))
    curves = []
    if valve.model == "simple" or valve.area_curve == "linear":
        simple = valve.simple
        for chamber, cd in (
            ("cap", simple.cap_discharge_coefficient),
            ("rod", simple.rod_discharge_coefficient),
        ):
            for side, x in sides:
                area = cd * (
                    simple.max_area * np.abs(x) / simple.full_scale_voltage + simple.leak_area
                )
                curves.append(AreaCurve(chamber, 0, side, x, area))
        return curves
    cap_port, rod_port = chamber_ports(valve)
    numbers = {"cap": valve.cap_port, "rod": 3 - valve.cap_port}
    for chamber, port in (("cap", cap_port), ("rod", rod_port)):
        for side, x in sides:
            area = evaluate_equivalent_area(port.area_negative, port.area_positive, x)
            curves.append(AreaCurve(chamber, numbers[chamber], side, x, area))
    return curves


def input_pressure_curves(
    actuator: ActuatorParameters, voltage: ArrayLike | None = None
) -> list[PressureCurve]:
    """Steady-state input pressure of each chamber's port (thesis Fig. 23, eq 4.2.7).

    Underlapped valve: the tanh curve between exhaust and supply with the port's cutoffs.
    Simple valve: supply on the filling side of the offset, exhaust on the other (cap fills
    for u_c ≥ 0).

    Parameters
    ----------
    actuator : ActuatorParameters
        Supply/exhaust pressures and valve.
    voltage : array_like, optional
        Centered voltages [V]; default :func:`centered_voltage_range`.

    Returns
    -------
    list of PressureCurve
        Cap, then rod.
    """
    valve, supply = actuator.valve, actuator.supply
    u = centered_voltage_range(valve) if voltage is None else np.asarray(voltage, dtype=float)
    ps, pe = supply.supply_pressure, supply.exhaust_pressure
    if valve.model == "simple" or valve.input_pressure == "switched":
        cap = np.where(u >= 0.0, ps, pe)
        rod = np.where(u >= 0.0, pe, ps)
        nan = float("nan")
        return [
            PressureCurve("cap", 0, u, cap, nan, nan),
            PressureCurve("rod", 0, u, rod, nan, nan),
        ]
    cap_port, rod_port = chamber_ports(valve)
    numbers = {"cap": valve.cap_port, "rod": 3 - valve.cap_port}
    curves = []
    for chamber, port in (("cap", cap_port), ("rod", rod_port)):
        high, low = port.high_pressure_cutoff, port.low_pressure_cutoff
        pressure = input_pressure(u, ps, pe, high, low)
        curves.append(PressureCurve(chamber, numbers[chamber], u, pressure, high, low))
    return curves


def group_equal(items: Mapping[str, T]) -> list[tuple[str, T]]:
    """Merge labels whose values are equal: ``{"a": x, "b": x, "c": y}`` → ``[("a, b", x),
    ("c", y)]`` (first-seen order)."""
    groups: list[tuple[list[str], T]] = []
    for label, value in items.items():
        for labels, seen in groups:
            if seen == value:
                labels.append(label)
                break
        else:
            groups.append(([label], value))
    return [(", ".join(labels), value) for labels, value in groups]
