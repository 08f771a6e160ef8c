"""Pydantic models of the parameter sets (see docs/parameters.md). All values are SI.

Dimensional fields accept a quantity string (``"50.3 psig"``) or, when the models are
built in Python, a plain SI float. When validating a file the loader passes the
context ``{"from_file": True, "atmospheric_pressure": <Pa or None>}``: plain numbers
are then rejected for dimensional fields and gauge pressures are resolved.
"""

from __future__ import annotations

import math
from functools import cached_property
from typing import Annotated, Any, Literal

from pydantic import StrictBool, field_validator
from pydantic import model_validator as _model_validator

from .errors import MISSING
from .fields import (
    MAX_FORCE,
    MAX_GRAVITY,
    MAX_VOLTAGE,
    AbsolutePressure,
    Acceleration,
    Area,
    BoundedVoltage,
    Bounds,
    Conductance,
    ControlStep,
    CrossFieldError,
    Damping,
    Force,
    HeatTransfer,
    InverseVelocity,
    NonNegativeLength,
    NonNegativeMass,
    Number,
    OpenFraction,
    ParameterModel,
    Polynomial,
    PositiveLength,
    QuantityField,
    SpecificHeat,
    StepCount,
    Stiffness,
    Temperature,
    Time,
    TimeConstant,
    Velocity,
    Voltage,
    Volume,
    described,
    non_negative_bounds,
    not_bool,
    positive_bounds,
)
from .units import QuantityError, convert_quantity

__all__ = [
    "ActuatorParameters",
    "ControllerParameters",
    "CylinderParameters",
    "FrictionParameters",
    "GasParameters",
    "Meta",
    "RigControllerParameters",
    "RigParameters",
    "RigSetup",
    "SimpleValveParameters",
    "SimulationParameters",
    "SupplyParameters",
    "ThermodynamicsParameters",
    "ValveParameters",
    "ValvePortParameters",
    "orientation_to_angle",
]




def _check(items: list[tuple[str, Any, str]]) -> None:
    if items:
        raise CrossFieldError(items)


def _fail(key: str, value: Any, expected: str) -> None:
    raise CrossFieldError([(key, value, expected)])


class Meta(ParameterModel):
    """Set identification: ``name``, ``description``, ``source`` (free text)."""

    name: str = described(
        "Name of the set (a shipped set's file stem, e.g. `thesis-rig`).",
        "not in thesis: bookkeeping")
    description: str = described(
        "What the set describes (free text).",
        "not in thesis: bookkeeping")
    source: str = described(
        "Where its values come from (free text).",
        "not in thesis: bookkeeping")


class GasParameters(ParameterModel):
    """Air properties (thesis eq 4.1.4–4.1.11): k, R [J/(kg K)], cp, Ts [K], patm [Pa]."""

    heat_capacity_ratio: Annotated[
        Number, Bounds(1.0, 5.0 / 3.0, upper_text="5/3")
    ] = described(
        "Ratio of specific heats k of air (eq 4.1.5, 4.1.8–4.1.10).",
        "eq 4.1.8; App. B.1.1 l.11 (rig), App. C.1.1 (joints)")
    gas_constant: SpecificHeat = described(
        "Gas constant R of air (eq 4.1.7–4.1.10).",
        "eq 4.1.7; App. B.1.1 l.19 (rig), App. C.1.1 (joints)")
    specific_heat_cp: SpecificHeat = described(
        "Specific heat at constant pressure cp of air (eq 4.1.10).",
        "thesis 4.1.2; App. B.1.1 l.13 (rig), App. C.1.1 (joints)")
    supply_temperature: Temperature = described(
        "Temperature Ts of the air entering a chamber (the upstream temperature of eq "
        "4.1.5–4.1.6 when charging).",
        "App. B.1.1 l.21 (rig), App. C.1.1 (joints)")
    atmospheric_pressure: AbsolutePressure = described(
        "Atmospheric pressure: acts on the rod side of the piston (eq 4.1.11) and is added to "
        "gauge pressures (`psig`, `barg`).",
        "eq 4.1.11; App. B.1.1 l.27 (rig), App. C.1.1 (joints)")
    critical_pressure_ratio: OpenFraction = described(
        "Critical pressure ratio: below it the orifice flow is choked (eq 4.1.4–4.1.6).",
        "eq 4.1.4; App. B.1.1 l.34 (rig), App. C.1.1 (joints)")


class SupplyParameters(ParameterModel):
    """Supply [Pa absolute]; the tank fields are required only for ``model="tank"``."""

    model: Literal["ideal", "tank"] = described(
        "`ideal`: a regulated supply at `supply_pressure`; `tank`: a finite tank behind that "
        "regulator, whose pressure falls with the air drawn.",
        "not in thesis: the rig used a regulated shop supply (`ideal`); the tank answers the "
        "air-consumption motivation of thesis 1.1")
    supply_pressure: AbsolutePressure = described(
        "Regulated supply pressure Ps, absolute; above `exhaust_pressure`.",
        "eq 4.1.2; App. B.1.1 l.24 (rig), App. C.1.1 (joints)")
    exhaust_pressure: AbsolutePressure = described(
        "Exhaust pressure Pe the chambers discharge to, absolute.",
        "eq 4.1.3; App. B.1.1 l.25 (rig), App. C.1.1 (joints, measured)")
    tank_volume: Annotated[Volume, positive_bounds(10.0, "m^3")] | None = described(
        "Tank volume; required with `model = \"tank\"`.",
        "not in thesis: a typical portable cylinder in the shipped sets",
        default=None)
    tank_initial_pressure: AbsolutePressure | None = described(
        "Tank pressure at the start, absolute; at least `supply_pressure`; required with `model "
        "= \"tank\"`.",
        "not in thesis: a typical portable cylinder in the shipped sets",
        default=None)
    tank_temperature: Temperature | None = described(
        "Temperature of the (isothermal) tank; required with `model = \"tank\"`.",
        "not in thesis: a typical portable cylinder in the shipped sets",
        default=None)

    @_model_validator(mode="after")
    def _cross(self) -> SupplyParameters:
        bad = []
        if self.supply_pressure <= self.exhaust_pressure:
            bad.append(
                (
                    "supply_pressure",
                    self.supply_pressure,
                    f"should be above exhaust_pressure ({self.exhaust_pressure:g} Pa)",
                )
            )
        if self.model == "tank":
            for name in ("tank_volume", "tank_initial_pressure", "tank_temperature"):
                if getattr(self, name) is None:
                    bad.append((name, MISSING, 'is required when supply.model = "tank"'))
        tank_p = self.tank_initial_pressure
        if tank_p is not None and tank_p < self.supply_pressure:
            bad.append(
                (
                    "tank_initial_pressure",
                    tank_p,
                    f"should be at least supply_pressure ({self.supply_pressure:g} Pa)",
                )
            )
        _check(bad)
        return self


class CylinderParameters(ParameterModel):
    """Cylinder geometry [m, m², kg] (thesis App. B.1.1 lines 43–54)."""

    bore: PositiveLength = described(
        "Piston diameter.",
        "App. B.1.1 l.45 (rig), App. C.1.1 (joints)")
    rod_diameter: PositiveLength = described(
        "Rod diameter; smaller than `bore`.",
        "App. B.1.1 l.44 (rig), App. C.1.1 (joints)")
    stroke: PositiveLength = described(
        "Piston stroke.",
        "App. B.1.1 l.46 (rig), App. C.1.1 (joints; alpha 3.75 in)")
    cap_dead_length: PositiveLength = described(
        "Dead volume of the cap chamber as a length of the piston area (part of x_abs in eq "
        "4.1.7, 4.1.10).",
        "App. B.1.1 l.49 (rig), App. C.1.1 (joints)")
    rod_dead_length: PositiveLength = described(
        "Dead volume of the rod chamber as a length of the annulus (part of x_abs in eq 4.1.7, "
        "4.1.10).",
        "App. B.1.1 l.48 (rig, measured), App. C.1.1 (joints)")
    slider_area: Annotated[Area, non_negative_bounds(1.0, "m^2")] = described(
        "Area of the position sensor's slider, subtracted from the piston area: Ap = π·bore²/4 "
        "− slider_area.",
        "App. B.1.1 l.51–52 (rig), App. C.1.1 (joints)")
    piston_mass: NonNegativeMass = described(
        "Moving mass of piston and rod.",
        "not in thesis: the rig models only its attached load (App. B.1.1 l.47); on the robot "
        "the moving mass is the linkage's `moving_mass`")

    @property
    def cap_area(self) -> float:
        """Cap-side piston area π·bore²/4 − slider_area [m²] (``Ap``, B.1.1 l.52)."""
        return math.pi * self.bore**2 / 4 - self.slider_area

    @property
    def rod_cross_section(self) -> float:
        """Rod cross-section π·rod²/4 [m²] (``Arod``, B.1.1 l.53)."""
        return math.pi * self.rod_diameter**2 / 4

    @property
    def rod_area(self) -> float:
        """Rod-side annulus area cap_area − rod_cross_section [m²] (``Ar``, B.1.1 l.54)."""
        return self.cap_area - self.rod_cross_section

    @_model_validator(mode="after")
    def _cross(self) -> CylinderParameters:
        if self.rod_diameter >= self.bore:
            _fail(
                "rod_diameter", self.rod_diameter, f"should be smaller than bore ({self.bore:g} m)"
            )
        if self.rod_area <= 0:
            _fail("slider_area", self.slider_area, "leaves no positive rod-side area")
        return self


class SimpleValveParameters(ParameterModel):
    """Linear-area valve [m², V] and its ISO 6358 form [m³/(s·Pa)]."""

    max_area: Annotated[Area, positive_bounds(1.0, "m^2")] = described(
        "Geometric orifice area A(u) of eq 4.1.1 at `full_scale_voltage` from the offset (the "
        "simple valve's linear area).",
        "App. B.2 l.13 (a 0.002 m × 0.005 m slot at 5 V)")
    leak_area: Annotated[Area, non_negative_bounds(1.0, "m^2")] = described(
        "Orifice area at the offset voltage.",
        "App. B.2 l.12")
    full_scale_voltage: Annotated[Voltage, positive_bounds(MAX_VOLTAGE, "V")] = described(
        "Voltage from the offset at which the area reaches `max_area`.",
        "App. B.2 l.13")
    cap_discharge_coefficient: Annotated[Number, positive_bounds(1.0)] = described(
        "Discharge coefficient cd of the cap port (eq 4.1.1).",
        "eq 4.1.1; App. B.1.1 l.39 (rig), App. C.1.1 (joints)")
    rod_discharge_coefficient: Annotated[Number, positive_bounds(1.0)] = described(
        "Discharge coefficient cd of the rod port (eq 4.1.1).",
        "eq 4.1.1; App. B.1.1 l.40 (rig), App. C.1.1 (joints)")
    sonic_conductance: Annotated[Conductance, positive_bounds(1e-5, "m^3/(s*Pa)")] = described(
        "ISO 6358 sonic conductance C at full opening (`flow_form = \"iso6358\"`).",
        "not in thesis: ISO 6358 flow form; the shipped value is illustrative")
    leak_conductance: Annotated[Conductance, non_negative_bounds(1e-5, "m^3/(s*Pa)")] = described(
        "ISO 6358 sonic conductance at the offset voltage.",
        "not in thesis: ISO 6358 flow form; the shipped value is illustrative")
    iso_critical_ratio: Annotated[Number, Bounds(0.0, 1.0, lower_inclusive=True,
                                                 upper_inclusive=False)] = described(
        "ISO 6358 critical pressure ratio b.",
        "not in thesis: ISO 6358 flow form; the shipped value is illustrative")


class ValvePortParameters(ParameterModel):
    """Underlapped port: area polynomials [m², highest power first], cutoffs [V]."""

    area_positive: Polynomial = described(
        "Equivalent orifice area for centered voltages above the offset: a 4th-order polynomial "
        "in centered volts, highest power first (thesis 4.2.3.1).",
        "App. B.1.2 Port_2 l.44 (port 2); port 1 fitted by the App. B.2 procedure to its "
        "printed data")
    area_negative: Polynomial = described(
        "Equivalent orifice area for centered voltages below the offset, as `area_positive`.",
        "App. B.1.2 Port_2 l.48 (port 2); port 1 fitted by the App. B.2 procedure to its "
        "printed data")
    high_pressure_cutoff: BoundedVoltage = described(
        "High-pressure cutoff C_HP of the port's tanh input-pressure curve, in centered volts "
        "(eq 4.2.7–4.2.11).",
        "eq 4.2.9–4.2.11; App. B.1.2 Port_2 l.21 (port 2; port 1's is not printed: port 2's "
        "mirrored about the offset)")
    low_pressure_cutoff: BoundedVoltage = described(
        "Low-pressure cutoff C_LP of the tanh input-pressure curve, in centered volts; differs "
        "from `high_pressure_cutoff`.",
        "eq 4.2.9–4.2.11; App. B.1.2 Port_2 l.22 (port 2; port 1 mirrored)")

    @_model_validator(mode="after")
    def _cross(self) -> ValvePortParameters:
        if self.high_pressure_cutoff == self.low_pressure_cutoff:
            _fail(
                "low_pressure_cutoff",
                self.low_pressure_cutoff,
                "should differ from high_pressure_cutoff",
            )
        return self


class ValveParameters(ParameterModel):
    """Proportional valve (MPYE-5): voltages [V], time constant [s], sub-tables."""

    model: Literal["underlapped", "simple"] = described(
        "`underlapped`: the thesis's fitted valve (equivalent-area polynomials and "
        "input-pressure curves, method 4 of thesis 4.2.3); `simple`: linear area, constant cd, "
        "leak area, plain supply and exhaust.",
        "thesis 4.2.3")
    flow_form: Literal["orifice", "iso6358"] = described(
        "Mass-flow law: compressible `orifice` flow, choked and unchoked (eq 4.1.1–4.1.6), or "
        "ISO 6358 (`iso6358`: C, b).",
        "eq 4.1.1–4.1.6 (orifice); ISO 6358 not in thesis")
    area_curve: Literal["polynomial", "linear"] = described(
        "Underlapped valve: the fitted port `polynomial`s, or the simple valve's `linear` slot "
        "area.",
        "Table 3 (\"simple equivalent area\")",
        default="polynomial")
    input_pressure: Literal["tanh", "switched"] = described(
        "Underlapped valve: `tanh` input-pressure curves (eq 4.2.7), or plain supply and "
        "exhaust (`switched`).",
        "eq 4.2.7; Table 3 (\"simple pressure estimates\")",
        default="tanh")
    offset_voltage: BoundedVoltage = described(
        "Command at which the spool is centred; centered volts are measured from it. Within "
        "[`min_voltage`, `max_voltage`].",
        "thesis 4.2.1, 4.2.3 (Fig. 17)")
    min_voltage: BoundedVoltage = described(
        "Lowest command: commands saturate here.",
        "thesis 4.2.1 (MPYE-5: 0–10 V)")
    max_voltage: BoundedVoltage = described(
        "Highest command; above `min_voltage`.",
        "thesis 4.2.1 (MPYE-5: 0–10 V)")
    spool_time_constant: TimeConstant = described(
        "Time constant of a first-order spool lag; 0 turns it off.",
        "not in thesis: spool dynamics neglected (0)")
    area_scale: Annotated[Number, Bounds(0.0, 100.0, lower_inclusive=False,
                                         upper_inclusive=True)] = described(
        "Factor on the valve's orifice areas, every model and form: a larger or smaller "
        "valve of the same characteristic (the input-pressure curves are kept). 1: the "
        "valve as fitted.",
        "not in thesis: valve sizing (studies)",
        default=1.0)
    laminar_pressure_ratio: Annotated[Number, Bounds(0.9, 1.0, upper_inclusive=False)] = described(
        "Pressure ratio above which the flow turns laminar, a numerical regularisation near "
        "equal pressures (docs/physics.md).",
        "not in thesis: numerical")
    cap_port: Literal[1, 2] = described(
        "Which underlapped port, 1 or 2, feeds the cap chamber.",
        "not in thesis: port 2 is connected to the supply for positive centered voltage, so it "
        "extends the piston")
    simple: SimpleValveParameters = described(
        "The simple valve's area and discharge coefficients, and the ISO 6358 form.",
        "App. B.2 (area), App. B.1.1 l.39–40 (cd)")
    port1: ValvePortParameters = described(
        "Underlapped valve, port 1.",
        "App. B.2 (fitted from its printed data)")
    port2: ValvePortParameters = described(
        "Underlapped valve, port 2.",
        "App. B.1.2 Port_2")

    @field_validator("cap_port", mode="before")
    @classmethod
    def _cap_port(cls, value: Any) -> Any:
        return not_bool(value)

    @_model_validator(mode="after")
    def _cross(self) -> ValveParameters:
        bad = []
        if self.min_voltage >= self.max_voltage:
            bad.append(
                (
                    "max_voltage",
                    self.max_voltage,
                    f"should be above min_voltage ({self.min_voltage:g} V)",
                )
            )
        elif not self.min_voltage <= self.offset_voltage <= self.max_voltage:
            bad.append(
                (
                    "offset_voltage",
                    self.offset_voltage,
                    f"should be within [min_voltage, max_voltage] = "
                    f"[{self.min_voltage:g} V, {self.max_voltage:g} V]",
                )
            )
        _check(bad)
        return self


class FrictionParameters(ParameterModel):
    """Friction models (thesis 4.2.2): forces [N], N·s/m, m/s, s/m, N/m."""

    model: Literal["stribeck_tanh", "viscous", "coulomb", "coulomb_viscous", "lugre"] = described(
        "Friction law: `stribeck_tanh` (eq 4.2.6), `viscous` (eq 4.2.5), `coulomb` (eq 4.2.1), "
        "`coulomb_viscous` (eq 4.2.4), or `lugre` (a bristle model that sticks; not in the "
        "thesis).",
        "thesis 4.2.2; App. B.1.1 l.60 (rig), App. C.1.1 (joints)")
    static_force: Annotated[Force, non_negative_bounds(MAX_FORCE, "N")] = described(
        "Static (breakaway) friction force Fs.",
        "eq 4.2.4, 4.2.6; App. B.1.1 l.61 (rig), App. C.1.1 (joints)")
    coulomb_force: Annotated[Force, non_negative_bounds(MAX_FORCE, "N")] = described(
        "Coulomb friction force Fc; at most `static_force`.",
        "eq 4.2.1, 4.2.4, 4.2.6; App. B.1.1 l.62–63 (rig), App. C.1.1 (joints)")
    viscous_coefficient: Damping = described(
        "Viscous coefficient Cv of eq 4.2.4 and 4.2.6; LuGre's σ2.",
        "eq 4.2.6; App. B.1.1 l.64 (rig), App. C.1.1 (joints); its velocity unit is not "
        "printed, in/s taken (docs/physics.md)")
    stribeck_velocity: Annotated[Velocity, positive_bounds(10.0, "m/s")] = described(
        "Stribeck velocity vS.",
        "eq 4.2.6; App. B.1.1 l.67 (rig), App. C.1.1 (joints); unit not printed, in/s taken")
    stribeck_exponent: Annotated[Number, positive_bounds(10.0)] = described(
        "Stribeck exponent i.",
        "eq 4.2.6; App. B.1.1 l.66 (rig), App. C.1.1 (joints)")
    tanh_coefficient: Annotated[InverseVelocity, positive_bounds(1e6, "s/m")] = described(
        "Steepness k_tanh of the tanh about zero velocity.",
        "eq 4.2.6; App. B.1.1 l.65 (rig), App. C.1.1 (joints); unit not printed, s/in taken")
    damping_coefficient: Damping = described(
        "Coefficient of the viscous-only model (Cv of eq 4.2.5).",
        "eq 4.2.5; App. B.1.1 l.57 (rig), App. C.1.1 (joints)")
    bristle_stiffness: Stiffness = described(
        "LuGre bristle stiffness σ0.",
        "not in thesis: LuGre model")
    bristle_damping: Damping = described(
        "LuGre bristle damping σ1.",
        "not in thesis: LuGre model")

    @_model_validator(mode="after")
    def _cross(self) -> FrictionParameters:
        if self.coulomb_force > self.static_force:
            _fail(
                "coulomb_force",
                self.coulomb_force,
                f"should not exceed static_force ({self.static_force:g} N)",
            )
        return self


class ThermodynamicsParameters(ParameterModel):
    """Chamber thermodynamics: polytropic n, h [W/(m² K)], wall temperature [K]."""

    model: Literal["adiabatic", "polytropic", "heat_transfer"] = described(
        "Chamber thermodynamics: `adiabatic` (eq 4.1.10), `polytropic` (exponent n in place of "
        "k), or `heat_transfer` (heat exchange with the wall).",
        "thesis 4.1.2 (adiabatic); the others not in thesis")
    polytropic_exponent: Annotated[
        Number, Bounds(1.0, 5.0 / 3.0, lower_inclusive=True, upper_text="5/3")
    ] = described(
        "Polytropic exponent n of the `polytropic` model; at most `gas.heat_capacity_ratio`.",
        "not in thesis")
    heat_transfer_coefficient: HeatTransfer = described(
        "Wall heat-transfer coefficient h of the `heat_transfer` model.",
        "not in thesis")
    wall_temperature: Temperature = described(
        "Cylinder wall temperature of the `heat_transfer` model.",
        "not in thesis")


class ActuatorParameters(ParameterModel):
    """One valve + cylinder actuator: every table except rig/controller/simulation."""

    meta: Meta = described(
        "Identification of the set.",
        "not in thesis: bookkeeping")
    gas: GasParameters = described(
        "Air properties.",
        "thesis 4.1; App. B.1.1, C.1.1")
    supply: SupplyParameters = described(
        "Supply and exhaust.",
        "thesis 4.1.1; App. B.1.1, C.1.1")
    cylinder: CylinderParameters = described(
        "Cylinder geometry and moving mass.",
        "App. B.1.1, C.1.1")
    valve: ValveParameters = described(
        "Proportional valve (Festo MPYE-5).",
        "thesis 4.1.1, 4.2.3; App. B.1.2, B.2")
    friction: FrictionParameters = described(
        "Cylinder friction.",
        "thesis 4.2.2")
    thermodynamics: ThermodynamicsParameters = described(
        "Chamber thermodynamics.",
        "thesis 4.1.2")

    @_model_validator(mode="after")
    def _cross(self) -> ActuatorParameters:
        n, k = self.thermodynamics.polytropic_exponent, self.gas.heat_capacity_ratio
        if n > k:
            _fail(
                "thermodynamics.polytropic_exponent",
                n,
                f"should be within [1, gas.heat_capacity_ratio] = [1, {k:g}]",
            )
        return self


_NAMED_ORIENTATIONS = {"vertical_down": math.pi / 2, "vertical_up": -math.pi / 2, "horizontal": 0.0}


def orientation_to_angle(orientation: str) -> float:
    """Angle [rad] of the extension direction below the horizontal.

    Parameters
    ----------
    orientation : str
        ``"vertical_down"`` (+π/2), ``"vertical_up"`` (−π/2), ``"horizontal"`` (0), or
        an angle string such as ``"30 deg"``.

    Returns
    -------
    float
        The angle in radians.
    """
    if orientation in _NAMED_ORIENTATIONS:
        return _NAMED_ORIENTATIONS[orientation]
    return convert_quantity(orientation, "angle")


class RigParameters(ParameterModel):
    """Single-DoF test rig: load [kg], orientation, gravity, end stops, initial state."""

    load_mass: NonNegativeMass = described(
        "Mass attached to the rod.",
        "App. B.1.1 l.47")
    orientation: str = described(
        "Direction of extension: `\"vertical_down\"`, `\"vertical_up\"`, `\"horizontal\"`, or "
        "an angle below the horizontal such as `\"30 deg\"`.",
        "App. B.1.1 (vertical, downward facing)")
    gravity: Annotated[Acceleration, non_negative_bounds(MAX_GRAVITY, "m/s^2")] = described(
        "Gravitational acceleration.",
        "App. B.1.1 l.15")
    spacer: StrictBool = described(
        "Piston held at full extension by a spacer (the fixed-piston tests).",
        "thesis 4.2.1")
    end_stop_stiffness: Stiffness = described(
        "Stiffness of the end stops.",
        "not in thesis")
    end_stop_damping: Damping = described(
        "Damping of the end stops.",
        "not in thesis")
    initial_position: NonNegativeLength = described(
        "Piston position at the start, from the retracted end; at most `cylinder.stroke`.",
        "App. B.1.1 l.82")
    initial_cap_pressure: AbsolutePressure = described(
        "Cap chamber pressure at the start.",
        "App. B.1.1 l.84")
    initial_rod_pressure: AbsolutePressure = described(
        "Rod chamber pressure at the start.",
        "App. B.1.1 l.83")

    @field_validator("orientation")
    @classmethod
    def _orientation(cls, value: str) -> str:
        try:
            orientation_to_angle(value)
        except QuantityError as exc:
            raise QuantityError(
                f'{exc}, or one of "vertical_down", "vertical_up", "horizontal"'
            ) from None
        return value

    @cached_property
    def orientation_angle(self) -> float:
        """Angle of the extension direction below the horizontal [rad]."""
        return orientation_to_angle(self.orientation)


class ControllerParameters(ParameterModel):
    """PID position controller: gains [V/m, V/(m s), V s/m], filter [s], clamp [V]."""

    proportional_gain: Annotated[
        float, QuantityField("proportional_gain"), non_negative_bounds(1e5, "V/m")
    ] = described(
        "Proportional gain Kp: valve volts per metre of piston position error.",
        "not in thesis: the gains are not printed (our tuning)")
    integral_gain: Annotated[
        float, QuantityField("integral_gain"), non_negative_bounds(1e7, "V/(m*s)")
    ] = described(
        "Integral gain Ki.",
        "not in thesis: the gains are not printed (our tuning)")
    derivative_gain: Annotated[
        float, QuantityField("derivative_gain"), non_negative_bounds(1e4, "V*s/m")
    ] = described(
        "Derivative gain Kd.",
        "not in thesis: the gains are not printed (our tuning)")
    derivative_filter_time_constant: TimeConstant = described(
        "Time constant of the first-order filter on the derivative term.",
        "not in thesis: our tuning")
    integral_limit: Annotated[Voltage, non_negative_bounds(MAX_VOLTAGE, "V")] = described(
        "Anti-windup clamp on the integral term.",
        "not in thesis: our tuning")


#: Longest measurement delay of the rig's controller [s].
MAX_MEASUREMENT_DELAY = 0.1


class RigControllerParameters(ControllerParameters):
    """The rig's PID controller and the delay of its position measurement [s] (the
    robot's joint controllers have none): the PID sees the piston position of
    round(measurement_delay / control_step) control steps earlier."""

    measurement_delay: Annotated[Time, non_negative_bounds(MAX_MEASUREMENT_DELAY, "s")] = described(
        "Delay of the position the controller sees (a loop delay: sampling, filtering, "
        "transmission), rounded to whole control steps.",
        "not in thesis: its loop ran on an xPC target at 1 kHz; 0 s by default",
        0.0)


class SimulationParameters(ParameterModel):
    """Integration settings: control step [s], substeps, integrator, tolerances."""

    control_step: ControlStep = described(
        "Sample time of the controller and the recorder.",
        "App. B.1.1 l.77 (dt = 1 ms)")
    substeps: StepCount = described(
        "Integrator steps per control step (the fixed-step integrator).",
        "not in thesis: the error against the Radau reference is in docs/physics.md")
    integrator: Literal["fixed", "radau", "lsoda"] = described(
        "`fixed` step (Heun substeps), or the adaptive `radau` or `lsoda` reference (scipy); "
        "the adaptive ones need a continuous friction model.",
        "not in thesis: the thesis's Simulink model used ode5, a fixed-step Dormand-Prince "
        "solver (5.5.4, 6.6.3)")
    relative_tolerance: OpenFraction = described(
        "Relative tolerance of the adaptive reference integrators.",
        "not in thesis")
    absolute_tolerance: OpenFraction = described(
        "Absolute tolerance of the adaptive integrators, as a fraction of each state's typical "
        "size.",
        "not in thesis")


class RigSetup(ParameterModel):
    """A complete single-DoF rig run: actuator, rig, controller and simulation."""

    actuator: ActuatorParameters = described(
        "The actuator tables (`meta`, `gas`, `supply`, `cylinder`, `valve`, `friction`, "
        "`thermodynamics`), written at the top level of the file.",
        "App. B.1.1")
    rig: RigParameters = described(
        "The rig: load, orientation, end stops and initial state.",
        "thesis 4.2.1; App. B.1.1")
    controller: RigControllerParameters = described(
        "PID position controller of closed-loop runs.",
        "thesis 4.3 (closed-loop tracking)")
    simulation: SimulationParameters = described(
        "Integration settings.",
        "App. B.1.1 l.77")

    @_model_validator(mode="after")
    def _cross(self) -> RigSetup:
        stroke = self.actuator.cylinder.stroke
        if self.rig.initial_position > stroke:
            _fail(
                "rig.initial_position",
                self.rig.initial_position,
                f"should be within [0, cylinder.stroke] = [0, {stroke:g} m]",
            )
        if self.rig.load_mass + self.actuator.cylinder.piston_mass <= 0.0 and not self.rig.spacer:
            _fail(
                "rig.load_mass",
                self.rig.load_mass,
                "should make the moving mass (rig.load_mass + cylinder.piston_mass) positive",
            )
        friction = self.actuator.friction.model
        if self.simulation.integrator != "fixed" and friction in ("coulomb", "coulomb_viscous"):
            _fail(
                "simulation.integrator",
                self.simulation.integrator,
                f'should be "fixed" with the set-valued friction.model = "{friction}" '
                '(adaptive solvers need "stribeck_tanh", "lugre" or "viscous")',
            )
        return self
