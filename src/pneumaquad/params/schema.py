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

from annotated_types import Ge, Gt, Le, Lt
from pydantic import BaseModel, ConfigDict, StrictBool, StrictInt, field_validator
from pydantic import model_validator as _model_validator
from pydantic_core import core_schema

from .errors import MISSING
from .units import KINDS, Kind, QuantityError, convert_quantity

__all__ = [
    "ActuatorParameters",
    "ControllerParameters",
    "CylinderParameters",
    "FrictionParameters",
    "GasParameters",
    "Meta",
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


class CrossFieldError(ValueError):
    """Problems found by a model-level check: ``(sub_key, value, expected)`` triples."""

    def __init__(self, items: list[tuple[str, Any, str]]) -> None:
        self.items = items
        super().__init__("; ".join(f"{k}: {v!r} {m}" for k, v, m in items))


class QuantityField:
    """Annotation marker: a dimensional float stored in SI, parsed from a unit string."""

    def __init__(self, kind: str) -> None:
        self.kind: Kind = KINDS[kind]

    def __get_pydantic_core_schema__(self, source: Any, handler: Any) -> Any:
        return core_schema.with_info_before_validator_function(self._validate, handler(source))

    def _validate(self, value: Any, info: core_schema.ValidationInfo) -> float:
        ctx = info.context or {}
        plain = isinstance(value, (int, float)) and not isinstance(value, bool)
        if plain and not ctx.get("from_file"):
            if not math.isfinite(value):
                raise QuantityError(f"is not finite; expected {self.kind.expectation}")
            return float(value)
        return convert_quantity(value, self.kind, ctx.get("atmospheric_pressure"))


def _number(value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise QuantityError("is not a plain number; expected a number such as 1.4")
    if not math.isfinite(value):
        raise QuantityError("is not finite; expected a finite number")
    return float(value)


def _not_bool(value: Any) -> Any:
    if isinstance(value, bool):
        raise QuantityError("is a boolean; expected 1 or 2")
    return value


class _NumberField:
    def __get_pydantic_core_schema__(self, source: Any, handler: Any) -> Any:
        return core_schema.no_info_before_validator_function(_number, handler(source))


Number = Annotated[float, _NumberField()]
Pressure = Annotated[float, QuantityField("pressure")]
Length = Annotated[float, QuantityField("length")]
Area = Annotated[float, QuantityField("area")]
Volume = Annotated[float, QuantityField("volume")]
Mass = Annotated[float, QuantityField("mass")]
Force = Annotated[float, QuantityField("force")]
Time = Annotated[float, QuantityField("time")]
Temperature = Annotated[float, QuantityField("temperature"), Gt(0)]
Voltage = Annotated[float, QuantityField("voltage")]
SpecificHeat = Annotated[float, QuantityField("specific_heat"), Gt(0)]
Conductance = Annotated[float, QuantityField("conductance")]
Damping = Annotated[float, QuantityField("damping"), Ge(0)]
Stiffness = Annotated[float, QuantityField("stiffness"), Gt(0)]
Velocity = Annotated[float, QuantityField("velocity")]
InverseVelocity = Annotated[float, QuantityField("inverse_velocity")]
Acceleration = Annotated[float, QuantityField("acceleration")]
HeatTransfer = Annotated[float, QuantityField("heat_transfer"), Ge(0)]
Polynomial = tuple[Number, Number, Number, Number, Number]


class _Model(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")


def _check(items: list[tuple[str, Any, str]]) -> None:
    if items:
        raise CrossFieldError(items)


def _fail(key: str, value: Any, expected: str) -> None:
    raise CrossFieldError([(key, value, expected)])


class Meta(_Model):
    """Set identification: ``name``, ``description``, ``source`` (free text)."""

    name: str
    description: str
    source: str


class GasParameters(_Model):
    """Air properties (thesis eq 4.1.4–4.1.11): k, R [J/(kg K)], cp, Ts [K], patm [Pa]."""

    heat_capacity_ratio: Annotated[Number, Gt(1)]
    gas_constant: SpecificHeat
    specific_heat_cp: SpecificHeat
    supply_temperature: Temperature
    atmospheric_pressure: Annotated[Pressure, Gt(0)]
    critical_pressure_ratio: Annotated[Number, Gt(0), Lt(1)]


class SupplyParameters(_Model):
    """Supply [Pa absolute]; the tank fields are required only for ``model="tank"``."""

    model: Literal["ideal", "tank"]
    supply_pressure: Annotated[Pressure, Gt(0)]
    exhaust_pressure: Annotated[Pressure, Gt(0)]
    tank_volume: Annotated[Volume, Gt(0)] | None = None
    tank_initial_pressure: Annotated[Pressure, Gt(0)] | None = None
    tank_temperature: Temperature | None = None

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


class CylinderParameters(_Model):
    """Cylinder geometry [m, m², kg] (thesis App. B.1.1 lines 43–54)."""

    bore: Annotated[Length, Gt(0)]
    rod_diameter: Annotated[Length, Gt(0)]
    stroke: Annotated[Length, Gt(0)]
    cap_dead_length: Annotated[Length, Gt(0)]
    rod_dead_length: Annotated[Length, Gt(0)]
    slider_area: Annotated[Area, Ge(0)]
    piston_mass: Annotated[Mass, Ge(0)]

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


class SimpleValveParameters(_Model):
    """Linear-area valve [m², V] and its ISO 6358 form [m³/(s·Pa)]."""

    max_area: Annotated[Area, Gt(0)]
    leak_area: Annotated[Area, Ge(0)]
    full_scale_voltage: Annotated[Voltage, Gt(0)]
    cap_discharge_coefficient: Annotated[Number, Gt(0), Le(1)]
    rod_discharge_coefficient: Annotated[Number, Gt(0), Le(1)]
    sonic_conductance: Annotated[Conductance, Gt(0)]
    leak_conductance: Annotated[Conductance, Ge(0)]
    iso_critical_ratio: Annotated[Number, Ge(0), Lt(1)]


class ValvePortParameters(_Model):
    """Underlapped port: area polynomials [m², highest power first], cutoffs [V]."""

    area_positive: Polynomial
    area_negative: Polynomial
    high_pressure_cutoff: Voltage
    low_pressure_cutoff: Voltage

    @_model_validator(mode="after")
    def _cross(self) -> ValvePortParameters:
        if self.high_pressure_cutoff == self.low_pressure_cutoff:
            _fail(
                "low_pressure_cutoff",
                self.low_pressure_cutoff,
                "should differ from high_pressure_cutoff",
            )
        return self


class ValveParameters(_Model):
    """Proportional valve (MPYE-5): voltages [V], time constant [s], sub-tables."""

    model: Literal["underlapped", "simple"]
    flow_form: Literal["orifice", "iso6358"]
    area_curve: Literal["polynomial", "linear"] = "polynomial"
    input_pressure: Literal["tanh", "switched"] = "tanh"
    offset_voltage: Voltage
    min_voltage: Voltage
    max_voltage: Voltage
    spool_time_constant: Annotated[Time, Ge(0)]
    laminar_pressure_ratio: Annotated[Number, Gt(0.9), Lt(1)]
    cap_port: Literal[1, 2]
    simple: SimpleValveParameters
    port1: ValvePortParameters
    port2: ValvePortParameters

    @field_validator("cap_port", mode="before")
    @classmethod
    def _cap_port(cls, value: Any) -> Any:
        return _not_bool(value)

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


class FrictionParameters(_Model):
    """Friction models (thesis 4.2.2): forces [N], N·s/m, m/s, s/m, N/m."""

    model: Literal["stribeck_tanh", "viscous", "coulomb", "coulomb_viscous", "lugre"]
    static_force: Annotated[Force, Ge(0)]
    coulomb_force: Annotated[Force, Ge(0)]
    viscous_coefficient: Damping
    stribeck_velocity: Annotated[Velocity, Gt(0)]
    stribeck_exponent: Annotated[Number, Gt(0)]
    tanh_coefficient: Annotated[InverseVelocity, Gt(0)]
    damping_coefficient: Damping
    bristle_stiffness: Stiffness
    bristle_damping: Damping

    @_model_validator(mode="after")
    def _cross(self) -> FrictionParameters:
        if self.coulomb_force > self.static_force:
            _fail(
                "coulomb_force",
                self.coulomb_force,
                f"should not exceed static_force ({self.static_force:g} N)",
            )
        return self


class ThermodynamicsParameters(_Model):
    """Chamber thermodynamics: polytropic n, h [W/(m² K)], wall temperature [K]."""

    model: Literal["adiabatic", "polytropic", "heat_transfer"]
    polytropic_exponent: Annotated[Number, Ge(1)]
    heat_transfer_coefficient: HeatTransfer
    wall_temperature: Temperature


class ActuatorParameters(_Model):
    """One valve + cylinder actuator: every table except rig/controller/simulation."""

    meta: Meta
    gas: GasParameters
    supply: SupplyParameters
    cylinder: CylinderParameters
    valve: ValveParameters
    friction: FrictionParameters
    thermodynamics: ThermodynamicsParameters

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


class RigParameters(_Model):
    """Single-DoF test rig: load [kg], orientation, gravity, end stops, initial state."""

    load_mass: Annotated[Mass, Ge(0)]
    orientation: str
    gravity: Annotated[Acceleration, Ge(0)]
    spacer: StrictBool
    end_stop_stiffness: Stiffness
    end_stop_damping: Damping
    initial_position: Annotated[Length, Ge(0)]
    initial_cap_pressure: Annotated[Pressure, Gt(0)]
    initial_rod_pressure: Annotated[Pressure, Gt(0)]

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


class ControllerParameters(_Model):
    """PID position controller: gains [V/m, V/(m s), V s/m], filter [s], clamp [V]."""

    proportional_gain: Annotated[float, QuantityField("proportional_gain")]
    integral_gain: Annotated[float, QuantityField("integral_gain")]
    derivative_gain: Annotated[float, QuantityField("derivative_gain")]
    derivative_filter_time_constant: Annotated[Time, Ge(0)]
    integral_limit: Annotated[Voltage, Ge(0)]


class SimulationParameters(_Model):
    """Integration settings: control step [s], substeps, integrator, tolerances."""

    control_step: Annotated[Time, Gt(0)]
    substeps: Annotated[StrictInt, Ge(1)]
    integrator: Literal["fixed", "radau", "lsoda"]
    relative_tolerance: Annotated[Number, Gt(0)]
    absolute_tolerance: Annotated[Number, Gt(0)]


class RigSetup(_Model):
    """A complete single-DoF rig run: actuator, rig, controller and simulation."""

    actuator: ActuatorParameters
    rig: RigParameters
    controller: ControllerParameters
    simulation: SimulationParameters

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
