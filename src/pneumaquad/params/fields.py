"""The field types and checks the parameter schemas are built of (all SI).

:class:`QuantityField` parses a dimensional value from a quantity string (``"50.3 psig"``)
or, when a model is built in Python, takes a plain SI float; :class:`Bounds` checks a
finite value against its physically meaningful range and says which range it expected;
the ``Annotated`` aliases below pair them (``AbsolutePressure``, ``PositiveLength`` …).
:func:`described` gives a field its meaning and its source in the thesis, and
:class:`ParameterModel` is the base of every model of :mod:`pneumaquad.params.schema` and
:mod:`pneumaquad.params.robot_schema`.
"""

from __future__ import annotations

import math
from typing import Annotated, Any

from pydantic import BaseModel, ConfigDict, Field, StrictInt
from pydantic_core import PydanticUndefined, core_schema

from .units import KINDS, Kind, QuantityError, convert_quantity

__all__ = [
    "MAX_DAMPING",
    "MAX_FORCE",
    "MAX_GRAVITY",
    "MAX_LENGTH",
    "MAX_MASS",
    "MAX_PRESSURE",
    "MAX_STIFFNESS",
    "MAX_TEMPERATURE",
    "MAX_TIME_CONSTANT",
    "MAX_VOLTAGE",
    "AbsolutePressure",
    "Acceleration",
    "Area",
    "AreaCoefficient",
    "BoundedVoltage",
    "Bounds",
    "Conductance",
    "ControlStep",
    "CrossFieldError",
    "Damping",
    "Force",
    "HeatTransfer",
    "InverseVelocity",
    "Length",
    "Mass",
    "NonNegativeLength",
    "NonNegativeMass",
    "Number",
    "NumberField",
    "OpenFraction",
    "ParameterModel",
    "Polynomial",
    "PositiveLength",
    "Pressure",
    "QuantityField",
    "SpecificHeat",
    "StepCount",
    "Stiffness",
    "Temperature",
    "Time",
    "TimeConstant",
    "Velocity",
    "Voltage",
    "Volume",
    "described",
    "non_negative_bounds",
    "not_bool",
    "positive_bounds",
    "symmetric_bounds",
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


def not_bool(value: Any) -> Any:
    if isinstance(value, bool):
        raise QuantityError("is a boolean; expected 1 or 2")
    return value


class NumberField:
    def __get_pydantic_core_schema__(self, source: Any, handler: Any) -> Any:
        return core_schema.no_info_before_validator_function(_number, handler(source))


def _format_bound(value: float, unit: str) -> str:
    text = f"{value:.6g}"
    return f"{text} {unit}" if unit else text


class Bounds:
    """Annotation marker: a finite value within a physically meaningful range.

    The range is part of the field's JSON-schema description and of the error message,
    which reads after the value, e.g. ``'1e300 in' should be greater than 0 m and at most
    10 m``.

    Parameters
    ----------
    lower, upper : float or None
        Range ends in SI units (``None``: unbounded on that side).
    unit : str
        SI unit shown with the ends (``"m"``, ``"Pa"``); empty for plain numbers.
    lower_inclusive, upper_inclusive : bool
        Whether the ends themselves are allowed; by default the range is ``(lower,
        upper]``.
    lower_text, upper_text : str, optional
        How to show an end when its number is awkward (``"5/3"``, ``"100 MPa"``).
    """

    def __init__(
        self,
        lower: float | None,
        upper: float | None,
        unit: str = "",
        *,
        lower_inclusive: bool = False,
        upper_inclusive: bool = True,
        lower_text: str | None = None,
        upper_text: str | None = None,
    ) -> None:
        self.lower, self.upper, self.unit = lower, upper, unit
        self.lower_inclusive, self.upper_inclusive = lower_inclusive, upper_inclusive
        self.lower_text = lower_text or (
            None if lower is None else _format_bound(lower, unit)
        )
        self.upper_text = upper_text or (
            None if upper is None else _format_bound(upper, unit)
        )

    @property
    def expectation(self) -> str:
        """The range in words: ``"greater than 0 m and at most 10 m"``."""
        parts = []
        if self.lower_text is not None:
            lower_word = "at least" if self.lower_inclusive else "greater than"
            parts.append(f"{lower_word} {self.lower_text}")
        if self.upper_text is not None:
            upper_word = "at most" if self.upper_inclusive else "less than"
            parts.append(f"{upper_word} {self.upper_text}")
        return " and ".join(parts) if parts else "finite"

    def contains(self, value: float) -> bool:
        """Whether ``value`` is finite and within the range."""
        if not math.isfinite(value):
            return False
        if self.lower is not None and (
            value < self.lower or (value == self.lower and not self.lower_inclusive)
        ):
            return False
        return self.upper is None or not (
            value > self.upper or (value == self.upper and not self.upper_inclusive)
        )

    def _validate(self, value: Any) -> Any:
        number = isinstance(value, (int, float)) and not isinstance(value, bool)
        if number and not self.contains(float(value)):
            raise QuantityError(f"should be {self.expectation}")
        return value

    def __get_pydantic_core_schema__(self, source: Any, handler: Any) -> Any:
        return core_schema.no_info_after_validator_function(self._validate, handler(source))

    def __get_pydantic_json_schema__(self, schema: Any, handler: Any) -> Any:
        json_schema = handler(schema)
        json_schema["description"] = f"finite, {self.expectation}"
        return json_schema


# --- physically meaningful ranges (SI), shared by the actuator and robot schemas -------
#: Largest length of any part or placement [m].
MAX_LENGTH = 10.0
#: Largest absolute pressure [Pa] (100 MPa, far above any pneumatic component).
MAX_PRESSURE = 100e6
#: Highest temperature [K] (air at 2000 K is far outside any pneumatic use).
MAX_TEMPERATURE = 2000.0
#: Largest mass of a load, a link or a piston [kg].
MAX_MASS = 1000.0
#: Largest magnitude of a valve or controller voltage [V].
MAX_VOLTAGE = 100.0
#: Largest force of friction or of an end stop model [N].
MAX_FORCE = 1e5
#: Largest damping coefficient [N s/m].
MAX_DAMPING = 1e7
#: Largest stiffness [N/m].
MAX_STIFFNESS = 1e10
#: Largest time constant or other parameter time [s].
MAX_TIME_CONSTANT = 10.0
#: Largest gravity magnitude [m/s^2] (about ten times the Earth's).
MAX_GRAVITY = 100.0


def positive_bounds(upper: float, unit: str = "", **kwargs: Any) -> Bounds:
    """:class:`Bounds` (0, ``upper``]."""
    return Bounds(0.0, upper, unit, **kwargs)


def non_negative_bounds(upper: float, unit: str = "", **kwargs: Any) -> Bounds:
    """:class:`Bounds` [0, ``upper``]."""
    return Bounds(0.0, upper, unit, lower_inclusive=True, **kwargs)


def symmetric_bounds(limit: float, unit: str = "", **kwargs: Any) -> Bounds:
    """:class:`Bounds` [-``limit``, ``limit``]."""
    return Bounds(-limit, limit, unit, lower_inclusive=True, **kwargs)


Number = Annotated[float, NumberField()]
Pressure = Annotated[float, QuantityField("pressure")]
Length = Annotated[float, QuantityField("length")]
Area = Annotated[float, QuantityField("area")]
Volume = Annotated[float, QuantityField("volume")]
Mass = Annotated[float, QuantityField("mass")]
Force = Annotated[float, QuantityField("force")]
Time = Annotated[float, QuantityField("time")]
Voltage = Annotated[float, QuantityField("voltage")]
Conductance = Annotated[float, QuantityField("conductance")]
Velocity = Annotated[float, QuantityField("velocity")]
InverseVelocity = Annotated[float, QuantityField("inverse_velocity")]
Acceleration = Annotated[float, QuantityField("acceleration")]

#: Absolute pressure in (0, 100 MPa].
AbsolutePressure = Annotated[Pressure, positive_bounds(MAX_PRESSURE, "Pa", upper_text="100 MPa")]
#: Length in (0, 10 m].
PositiveLength = Annotated[Length, positive_bounds(MAX_LENGTH, "m")]
#: Length in [0, 10 m].
NonNegativeLength = Annotated[Length, non_negative_bounds(MAX_LENGTH, "m")]
#: Mass in [0, 1000 kg].
NonNegativeMass = Annotated[Mass, non_negative_bounds(MAX_MASS, "kg")]
#: Thermodynamic temperature in (0 K, 2000 K).
Temperature = Annotated[
    float,
    QuantityField("temperature"),
    Bounds(0.0, MAX_TEMPERATURE, "K", upper_inclusive=False),
]
#: Gas constant or specific heat in (0, 20000 J/(kg K)] (hydrogen's cp is 14300).
SpecificHeat = Annotated[
    float, QuantityField("specific_heat"), positive_bounds(20000.0, "J/(kg*K)")
]
#: Valve or controller voltage in [-100 V, 100 V].
BoundedVoltage = Annotated[Voltage, symmetric_bounds(MAX_VOLTAGE, "V")]
#: Damping coefficient in [0, 1e7 N s/m].
Damping = Annotated[float, QuantityField("damping"), non_negative_bounds(MAX_DAMPING, "N*s/m")]
#: Stiffness in (0, 1e10 N/m].
Stiffness = Annotated[float, QuantityField("stiffness"), positive_bounds(MAX_STIFFNESS, "N/m")]
#: Heat transfer coefficient in [0, 1e5 W/(m^2 K)].
HeatTransfer = Annotated[
    float, QuantityField("heat_transfer"), non_negative_bounds(1e5, "W/(m^2*K)")
]
#: Time constant in [0, 10 s].
TimeConstant = Annotated[Time, non_negative_bounds(MAX_TIME_CONSTANT, "s")]
#: Control step in [1 us, 1 s].
ControlStep = Annotated[Time, Bounds(1e-6, 1.0, "s", lower_inclusive=True)]
#: Area-polynomial coefficient in [-1e-3, 1e-3] m^2/V^n.
AreaCoefficient = Annotated[Number, symmetric_bounds(1e-3, "m^2/V^n")]
Polynomial = tuple[AreaCoefficient, AreaCoefficient, AreaCoefficient, AreaCoefficient,
                   AreaCoefficient]
#: Iteration and step counts in [1, 1000].
StepCount = Annotated[StrictInt, Bounds(1, 1000, lower_inclusive=True)]
#: A dimensionless ratio in (0, 1).
OpenFraction = Annotated[Number, Bounds(0.0, 1.0, upper_inclusive=False)]


def described(description: str, source: str, default: Any = PydanticUndefined) -> Any:
    """A field's meaning and its source in the thesis, for a model's field default.

    The parameter reference (:mod:`pneumaquad.params.reference`, docs/parameters.md)
    shows both beside the unit, range and default it reads from the field's type; the
    JSON schema has them as ``description`` (followed by the range) and ``source``.

    Parameters
    ----------
    description : str
        What the value is, with its symbol and equation where the thesis has one.
    source : str
        Where the thesis gives it (``"eq 4.1.8; App. B.1.1 l.11"``), or ``"not in
        thesis: ..."`` with what it is instead.
    default : Any
        The default value; without one the key is required.

    Returns
    -------
    pydantic.fields.FieldInfo
        To be assigned as the field's default.
    """
    return Field(default, description=description, json_schema_extra={"source": source})


def _range_in_description(schema: dict[str, Any], model: type[BaseModel]) -> None:
    """JSON schema: a bounded field's description ends with its range."""
    properties = schema.get("properties", {})
    for name, field in model.model_fields.items():
        bounds = next((m for m in field.metadata if isinstance(m, Bounds)), None)
        if bounds is not None and name in properties and field.description:
            properties[name]["description"] = (
                f"{field.description.rstrip('.')}; finite, {bounds.expectation}")


class ParameterModel(BaseModel):
    """Base of every parameter model: frozen, unknown keys rejected, a bounded field's
    range at the end of its JSON-schema description."""

    model_config = ConfigDict(frozen=True, extra="forbid",
                              json_schema_extra=_range_in_description)
