"""Compact parameter tables of a run: rows of (group, parameter, SI value, SI unit).

Only the parameters a reader of a report needs to tell runs apart are listed (supply,
cylinder, valve, friction, controller, step sizes; for robots the configuration, masses
and per-joint controllers); the full resolved set is ``parameters.toml`` in the run folder.
:func:`shown_rows` converts the rows to a report's display units
(:mod:`pneumaquad.reporting.display_units`).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from pneumaquad.params import (
    JOINT_NAMES,
    ActuatorParameters,
    FrictionParameters,
    RigSetup,
    RobotParameters,
)
from pneumaquad.reporting.display_units import DisplayUnits

__all__ = [
    "PARAMETER_HEADERS",
    "Row",
    "actuator_rows",
    "flatten_summary",
    "friction_rows",
    "rig_parameter_rows",
    "robot_parameter_rows",
    "shown_rows",
]

#: (group, parameter, value in SI, SI unit: "Pa" absolute, "Pa gauge" for the gauge reading
#: of an absolute pressure, "" for text and counts, "-" for ratios).
Row = tuple[str, str, Any, str]

#: Headers of a parameter table as a report shows it.
PARAMETER_HEADERS = ("group", "parameter", "value", "unit")


def shown_rows(rows: list[Row], units: DisplayUnits) -> list[Row]:
    """The rows with their values and units in ``units`` (gauge pressures against
    ``units.atmosphere``); text, counts and units the display does not change pass
    through."""
    return [(group, name, *units.cell(value, unit, name)) for group, name, value, unit in rows]


def friction_rows(group: str, friction: FrictionParameters) -> list[Row]:
    """The friction model and the values that model uses (thesis 4.2.2)."""
    f = friction
    rows: list[Row] = [(group, "friction model", f.model, "")]
    uses_stribeck = f.model in ("stribeck_tanh", "lugre")
    if uses_stribeck:
        rows.append((group, "static force Fs", f.static_force, "N"))
    if f.model != "viscous":
        rows.append((group, "Coulomb force Fc", f.coulomb_force, "N"))
    if f.model in ("stribeck_tanh", "lugre", "coulomb_viscous"):
        rows.append((group, "viscous coefficient Cv", f.viscous_coefficient, "N s/m"))
    if uses_stribeck:
        rows += [
            (group, "Stribeck velocity vS", f.stribeck_velocity, "m/s"),
            (group, "Stribeck exponent i", f.stribeck_exponent, "-"),
        ]
    if f.model == "stribeck_tanh":
        rows.append((group, "tanh coefficient k_tanh", f.tanh_coefficient, "s/m"))
    if f.model == "viscous":
        rows.append((group, "damping b", f.damping_coefficient, "N s/m"))
    if f.model == "lugre":
        rows += [
            (group, "bristle stiffness σ0", f.bristle_stiffness, "N/m"),
            (group, "bristle damping σ1", f.bristle_damping, "N s/m"),
        ]
    return rows


def actuator_rows(actuator: ActuatorParameters, group: str = "") -> list[Row]:
    """Supply, cylinder, valve, friction and thermodynamics rows of one actuator (the
    supply pressure also as the gauge reading: show the rows with the actuator's
    ``gas.atmospheric_pressure``)."""
    a = actuator
    s, c, v = a.supply, a.cylinder, a.valve

    def g(name: str) -> str:
        return f"{group} {name}".strip()

    rows: list[Row] = [
        (g("supply"), "supply model", s.model, ""),
        (g("supply"), "supply pressure", s.supply_pressure, "Pa"),
        (g("supply"), "supply pressure, gauge", s.supply_pressure, "Pa gauge"),
        (g("supply"), "exhaust pressure", s.exhaust_pressure, "Pa"),
        (g("supply"), "atmospheric pressure", a.gas.atmospheric_pressure, "Pa"),
        (g("cylinder"), "bore", c.bore, "m"),
        (g("cylinder"), "rod diameter", c.rod_diameter, "m"),
        (g("cylinder"), "stroke", c.stroke, "m"),
        (g("cylinder"), "cap area", c.cap_area, "m²"),
        (g("cylinder"), "rod area", c.rod_area, "m²"),
        (g("valve"), "valve model", v.model, ""),
        (g("valve"), "flow form", v.flow_form, ""),
        (g("valve"), "offset voltage", v.offset_voltage, "V"),
        (g("valve"), "spool time constant", v.spool_time_constant, "s"),
    ]
    if v.model == "underlapped":
        rows.append((g("valve"), "cap port", v.cap_port, ""))
        for number, port in ((1, v.port1), (2, v.port2)):
            rows.append(
                (
                    g("valve"),
                    f"port {number} cutoffs C_HP / C_LP",
                    f"{port.high_pressure_cutoff:g} / {port.low_pressure_cutoff:g}",
                    "V",
                )
            )
    else:
        sv = v.simple
        rows += [
            (g("valve"), "max area", sv.max_area, "m²"),
            (g("valve"), "leak area", sv.leak_area, "m²"),
            (
                g("valve"),
                "cd cap / rod",
                f"{sv.cap_discharge_coefficient:g} / {sv.rod_discharge_coefficient:g}",
                "-",
            ),
        ]
    rows += friction_rows(g("friction"), a.friction)
    rows.append((g("thermodynamics"), "model", a.thermodynamics.model, ""))
    return rows


def _controller_rows(group: str, k: Any) -> list[Row]:
    """The PID gains of one position controller (thesis 4.3, 5.4)."""
    return [
        (group, "Kp", k.proportional_gain, "V/m"),
        (group, "Ki", k.integral_gain, "V/(m s)"),
        (group, "Kd", k.derivative_gain, "V s/m"),
    ]


def rig_parameter_rows(setup: RigSetup) -> list[Row]:
    """Key parameters of a rig run (actuator, load, controller, simulation)."""
    r, k, sim = setup.rig, setup.controller, setup.simulation
    rows = actuator_rows(setup.actuator)
    rows += [
        ("rig", "load mass", r.load_mass, "kg"),
        ("rig", "orientation", r.orientation, ""),
        ("rig", "spacer (piston held)", r.spacer, ""),
        ("rig", "initial position", r.initial_position, "m"),
        *_controller_rows("controller", k),
        ("controller", "integral limit", k.integral_limit, "V"),
        ("simulation", "control step", sim.control_step, "s"),
        ("simulation", "substeps", sim.substeps, ""),
        ("simulation", "integrator", sim.integrator, ""),
    ]
    return rows


def _capsule_mass(link: Any) -> float:
    if link.mass is not None:
        return float(link.mass)
    radius = link.diameter / 2
    return link.density * (math.pi * radius**2 * link.length + 4 / 3 * math.pi * radius**3)


def _model_masses(model_xml: Path) -> dict[str, float] | None:
    """Body masses [kg] of a run's MuJoCo model (thorax, front-right links, total)."""
    try:
        import mujoco

        model = mujoco.MjModel.from_xml_path(str(model_xml))
    except Exception:  # an unreadable model only loses the mass rows
        return None
    masses = {}
    for name in ("thorax", "front_right_coxa", "front_right_femur", "front_right_tibia"):
        body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name)
        if body >= 0:
            masses[name] = float(model.body_mass[body])
    masses["whole model"] = float(model.body_mass.sum())
    return masses


def robot_parameter_rows(
    params: RobotParameters, summary: dict[str, Any], model_xml: Path | None = None
) -> list[Row]:
    """Key parameters of a robot run: configuration, masses, steps, per-joint controllers."""
    sim, contact = params.simulation, params.contact
    rows: list[Row] = [
        ("run", "configuration", summary.get("configuration", "?"), ""),
        ("run", "environment", summary.get("environment", "?"), ""),
        ("simulation", "control step", sim.control_step, "s"),
        ("simulation", "pneumatic substeps", sim.substeps, ""),
        ("simulation", "MuJoCo steps per control step", sim.physics_steps, ""),
        ("simulation", "integrator", sim.integrator, ""),
        ("simulation", "seal friction", sim.seal_friction, ""),
        (
            "contact",
            "ground / foot friction",
            f"{contact.ground_friction:g} / {contact.foot_friction:g}",
            "-",
        ),
    ]
    masses = _model_masses(model_xml) if model_xml is not None and model_xml.is_file() else None
    if masses is not None:
        rows += [("mass (model.xml)", name, value, "kg") for name, value in masses.items()]
    else:
        for name in ("thorax", "coxa1", "coxa2", "femur", "tibia"):
            rows.append(("mass (parameters)", name, _capsule_mass(getattr(params, name)), "kg"))
    for joint in JOINT_NAMES:
        k = getattr(params.controller, joint)
        rows += [
            *_controller_rows(f"{joint} controller", k),
            (f"{joint} controller", "gain scale", k.gain_scale, "-"),
            (f"{joint} controller", "force feedback gain", k.force_feedback_gain, "V/N"),
            (f"{joint} actuator", "parameter set", getattr(params.actuators, joint), ""),
            (f"{joint} linkage", "moving mass", params.linkages[joint].moving_mass, "kg"),
        ]
    return rows


def flatten_summary(summary: dict[str, Any], prefix: str = "") -> list[tuple[str, Any]]:
    """``summary.json`` as (key, value) rows; nested tables become ``"outer / inner"``."""
    rows: list[tuple[str, Any]] = []
    for key, value in summary.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict):
            rows += flatten_summary(value, f"{name} / ")
        elif isinstance(value, list):
            rows.append((name, ", ".join(str(item) for item in value)))
        else:
            rows.append((name, value))
    return rows
