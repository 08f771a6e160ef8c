"""What the actuator FMU declares: its variables with their units, and its settings file.

The FMU of one actuator (:mod:`pneumaquad.interop.fmu_slave`, built by
:mod:`pneumaquad.interop.fmu_export`, docs/fmu.md) has three inputs (valve voltage, piston
position and velocity), the outputs of :data:`OUTPUTS`, and one parameter per value of the
actuator's parameter set: the set's dotted keys (``supply.supply_pressure``,
``friction.model``) with SI units, each polynomial coefficient of the valve's equivalent
areas as ``valve.port2.area_positive[1]`` … ``[5]`` (highest power first, as in the
parameter file), and four settings of the FMU itself (:data:`SETTING_VARIABLES`: initial
chamber pressures, kernel step and substeps). Their order here is the order of their value
references.

The FMU's ``resources`` folder holds the resolved parameter set (:data:`PARAMETERS_FILE`,
loadable with ``--params``) and :class:`FmuSettings` (:data:`SETTINGS_FILE`): the start
values of the parameters come from them, at export and again each time the FMU is
instantiated. Units are written in the SI notation of the parameter files (``"m^2"``,
``"J/(kg*K)"``) and declared in the model description in FMI notation (``"m2"``,
``"J/(kg.K)"``, :func:`fmi_unit`) with their SI base-unit exponents
(:func:`unit_definitions`).
"""

from __future__ import annotations

import json
import math
import typing
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import asdict, dataclass, fields
from pathlib import Path
from typing import Any, Literal
from xml.etree.ElementTree import Element, SubElement

from pydantic import BaseModel

from pneumaquad.core.layout import POLYNOMIAL_COEFFICIENTS
from pneumaquad.params import ActuatorParameters, ParameterError, Problem
from pneumaquad.params.fields import Bounds, QuantityField

__all__ = [
    "INPUTS",
    "OUTPUTS",
    "PARAMETERS_FILE",
    "SETTINGS_FILE",
    "SETTING_FIELDS",
    "SETTING_VARIABLES",
    "FmuSettings",
    "FmuVariable",
    "ParameterVariable",
    "complete_model_description",
    "fmi_unit",
    "parameter_changes",
    "parameter_variables",
    "unit_definitions",
]

#: The resolved actuator parameters in the FMU's resources folder.
PARAMETERS_FILE = "parameters.toml"
#: The FMU's own settings (:class:`FmuSettings`) in its resources folder.
SETTINGS_FILE = "fmu_settings.json"
#: Version of the settings file's layout.
SETTINGS_FORMAT = 1
#: Tables of the parameter set that are not FMU parameters (names and sources as text).
SKIPPED_TABLES = ("meta",)

VariableKind = Literal["real", "integer", "string"]


@dataclass(frozen=True)
class FmuVariable:
    """One variable of the FMU.

    Attributes
    ----------
    name : str
        FMI name (structured naming: dots between tables, ``[i]`` for a coefficient).
    kind : {"real", "integer", "string"}
        FMI type.
    unit : str or None
        SI unit in the parameter files' notation (``"Pa"``, ``"m^2/V^4"``); None for a
        dimensionless number, an integer or a string.
    description : str
        What it is, one line.
    """

    name: str
    kind: VariableKind
    unit: str | None
    description: str


@dataclass(frozen=True)
class ParameterVariable(FmuVariable):
    """An FMU parameter that holds one value of the actuator's parameter set.

    Attributes
    ----------
    key : str
        Dotted key of the value in the parameter set (``"valve.port2.area_positive"``).
    index : int or None
        Position in a coefficient tuple (0 = highest power), None for a single value.
    """

    key: str = ""
    index: int | None = None


INPUTS = (
    FmuVariable("valve_voltage", "real", "V",
                "Valve command, held over each communication step; saturated to "
                "[valve.min_voltage, valve.max_voltage]"),
    FmuVariable("piston_position", "real", "m",
                "Piston extension at the start of the step (0: fully retracted), from the "
                "load side; clipped to [0, cylinder.stroke]"),
    FmuVariable("piston_velocity", "real", "m/s",
                "Piston velocity at the start of the step, held over it; positive extends"),
)

OUTPUTS = (
    FmuVariable("piston_force", "real", "N",
                "Force on the load at the end of the step, positive extending: "
                "pneumatic_force - friction_force"),
    FmuVariable("pneumatic_force", "real", "N",
                "Pressure force on the piston (eq 4.1.11 without friction), positive extending"),
    FmuVariable("friction_force", "real", "N",
                "Seal friction of friction.model at piston_velocity (sliding branch of the "
                "Coulomb models), positive when it opposes extension"),
    FmuVariable("cap_pressure", "real", "Pa", "Cap chamber pressure, absolute"),
    FmuVariable("rod_pressure", "real", "Pa", "Rod chamber pressure, absolute"),
    FmuVariable("cap_temperature", "real", "K", "Cap chamber gas temperature"),
    FmuVariable("rod_temperature", "real", "K", "Rod chamber gas temperature"),
    FmuVariable("cap_mass_flow", "real", "kg/s",
                "Mean net mass flow into the cap chamber over the last communication step"),
    FmuVariable("rod_mass_flow", "real", "kg/s",
                "Mean net mass flow into the rod chamber over the last communication step"),
    FmuVariable("supply_mass_flow", "real", "kg/s",
                "Mean mass flow drawn from the supply over the last communication step"),
    FmuVariable("air_consumed", "real", "kg", "Air drawn from the supply since the start"),
    FmuVariable("available_supply_pressure", "real", "Pa",
                "Supply pressure the valve sees, absolute: supply.supply_pressure, or a "
                "tank's pressure once it has fallen below it"),
)

#: The FMU's own parameters, beside the parameter set's: name -> FmuSettings field.
SETTING_FIELDS = {
    "initial.cap_pressure": "initial_cap_pressure",
    "initial.rod_pressure": "initial_rod_pressure",
    "simulation.control_step": "control_step",
    "simulation.substeps": "substeps",
}

SETTING_VARIABLES = (
    FmuVariable("initial.cap_pressure", "real", "Pa",
                "Cap chamber pressure at initialisation, absolute (gas at "
                "gas.supply_temperature, piston at rest at the piston_position input)"),
    FmuVariable("initial.rod_pressure", "real", "Pa",
                "Rod chamber pressure at initialisation, absolute"),
    FmuVariable("simulation.control_step", "real", "s",
                "Kernel step: a communication step is split into equal kernel steps of at "
                "most this length, the inputs held; range: at least 1e-06 s and at most 1 s"),
    FmuVariable("simulation.substeps", "integer", None,
                "Heun substeps of the chamber equations per kernel step; range: 1 to 1000"),
)


@dataclass(frozen=True)
class FmuSettings:
    """The settings an FMU is exported with (its :data:`SETTINGS_FILE`), SI.

    Attributes
    ----------
    model_name : str
        The FMU's model name and identifier (a C identifier).
    parameter_set : str
        The parameter set it was exported from (name or path, for people).
    pneumaquad_version : str
        The version of pneumaquad that exported it.
    control_step : float
        Default kernel step [s].
    substeps : int
        Default Heun substeps per kernel step.
    initial_position : float
        Start value of the ``piston_position`` input [m].
    initial_cap_pressure, initial_rod_pressure : float
        Default chamber pressures at initialisation [Pa, absolute].
    """

    model_name: str
    parameter_set: str
    pneumaquad_version: str
    control_step: float
    substeps: int
    initial_position: float
    initial_cap_pressure: float
    initial_rod_pressure: float

    def write(self, path: Path) -> None:
        """Write the settings as JSON to ``path``."""
        path.write_text(json.dumps({"format": SETTINGS_FORMAT, **asdict(self)}, indent=2) + "\n",
                        encoding="utf-8")

    @classmethod
    def read(cls, path: Path) -> FmuSettings:
        """Settings from a JSON file written by :meth:`write`.

        Raises
        ------
        ParameterError
            A file of another format version, or without one of the settings.
        """
        data = json.loads(path.read_text(encoding="utf-8"))
        if data.get("format") != SETTINGS_FORMAT:
            raise ParameterError([Problem("format", data.get("format"),
                                          f"should be {SETTINGS_FORMAT}: an FMU exported by "
                                          "another version of pneumaquad; export it again")],
                                 source=str(path))
        names = [field.name for field in fields(cls)]
        missing = [name for name in names if name not in data]
        if missing:
            raise ParameterError([Problem(name, data.get(name), "is missing") for name in missing],
                                 source=str(path))
        return cls(**{name: data[name] for name in names})


def _markers(field_annotation: Any, metadata: Iterable[Any]) -> list[Any]:
    """The annotation markers of a field (``QuantityField``, ``Bounds``...), including
    those inside an optional (``X | None``) annotation."""
    found = list(metadata)
    for argument in (field_annotation, *typing.get_args(field_annotation)):
        found.extend(getattr(argument, "__metadata__", ()))
    return found


def _one_line(text: str | None) -> str:
    """A description as one line of plain text (no Markdown backticks)."""
    return " ".join((text or "").replace("`", "").split())


def _joined(*parts: str) -> str:
    """Sentences joined, each ending with a full stop."""
    return " ".join(f"{part.rstrip('.')}." for part in parts if part)


def parameter_variables(actuator: ActuatorParameters) -> list[ParameterVariable]:
    """One FMU parameter per value of an actuator's parameter set, in the set's order.

    Numbers are Real parameters with the SI unit of their field (none for dimensionless
    ones), model choices (``friction.model``, ``valve.model``...) String parameters, the
    valve's ``cap_port`` an Integer; the five coefficients of each equivalent-area
    polynomial are ``key[1]`` … ``key[5]`` [m^2/V^4 … m^2]. The ``meta`` table and optional
    values the set leaves out (a tank's, with an ideal supply that has none) are not
    parameters.

    Parameters
    ----------
    actuator : ActuatorParameters
        The validated parameter set.

    Returns
    -------
    list of ParameterVariable
    """
    variables: list[ParameterVariable] = []
    _collect(actuator, "", variables)
    return variables


def _collect(model: BaseModel, prefix: str, variables: list[ParameterVariable]) -> None:
    """Append the parameters of ``model``'s fields (recursing into its tables)."""
    for name, field in type(model).model_fields.items():
        value = getattr(model, name)
        if (not prefix and name in SKIPPED_TABLES) or value is None:
            continue
        key = f"{prefix}{name}"
        if isinstance(value, BaseModel):
            _collect(value, f"{key}.", variables)
            continue
        markers = _markers(field.annotation, field.metadata)
        meaning = _one_line(field.description)
        if isinstance(value, str):
            choices = ", ".join(str(c) for c in typing.get_args(field.annotation))
            variables.append(ParameterVariable(key, "string", None,
                                               _joined(meaning, f"One of: {choices}"), key))
        elif isinstance(value, bool):
            raise TypeError(f"{key}: a boolean parameter has no FMU variable kind here")
        elif isinstance(value, int):
            choices = ", ".join(str(c) for c in typing.get_args(field.annotation))
            variables.append(ParameterVariable(key, "integer", None,
                                               _joined(meaning, f"One of: {choices}"), key))
        elif isinstance(value, tuple):
            if len(value) != POLYNOMIAL_COEFFICIENTS:
                raise TypeError(f"{key}: {len(value)} values where the FMU expects the "
                                f"{POLYNOMIAL_COEFFICIENTS} coefficients of a polynomial")
            for index in range(POLYNOMIAL_COEFFICIENTS):
                power = POLYNOMIAL_COEFFICIENTS - 1 - index
                unit = "m^2" if power == 0 else ("m^2/V" if power == 1 else f"m^2/V^{power}")
                coefficient = f"Coefficient of u^{power} (u: centered valve voltage in V)"
                variables.append(ParameterVariable(f"{key}[{index + 1}]", "real", unit,
                                                   _joined(meaning, coefficient), key, index))
        else:
            quantity = next((m for m in markers if isinstance(m, QuantityField)), None)
            bounds = next((m for m in markers if isinstance(m, Bounds)), None)
            unit = quantity.kind.si_unit if quantity is not None else None
            if unit == "Pa":
                meaning = _joined(meaning, "Absolute pressure")
            limits = f"Range: {bounds.expectation}" if bounds is not None else ""
            variables.append(ParameterVariable(key, "real", unit, _joined(meaning, limits), key))


def parameter_changes(variables: Sequence[ParameterVariable],
                      values: Mapping[str, Any]) -> dict[str, Any]:
    """The FMU parameters' values as changes of the parameter set: dotted key -> value, the
    coefficients of each polynomial gathered into a tuple (for
    :func:`pneumaquad.params.loader.validated_update`).

    Parameters
    ----------
    variables : sequence of ParameterVariable
        From :func:`parameter_variables`.
    values : mapping
        FMU parameter name -> its present value (SI).
    """
    changes: dict[str, Any] = {}
    coefficients: dict[str, list[Any]] = {}
    for variable in variables:
        value = values[variable.name]
        if variable.index is None:
            changes[variable.key] = value
        else:
            coefficients.setdefault(variable.key, [None] * POLYNOMIAL_COEFFICIENTS)
            coefficients[variable.key][variable.index] = value
    changes.update({key: tuple(values) for key, values in coefficients.items()})
    return changes


def fmi_unit(unit: str) -> str:
    """A unit in FMI's (and Modelica's) notation: ``"m^2"`` -> ``"m2"``, ``"J/(kg*K)"`` ->
    ``"J/(kg.K)"``, ``"N*s/m"`` -> ``"N.s/m"``."""
    return unit.replace("^", "").replace("*", ".")


#: FMI BaseUnit attribute of each SI base dimension (pint's names).
_BASE_UNIT_ATTRIBUTES = {
    "[mass]": "kg",
    "[length]": "m",
    "[time]": "s",
    "[current]": "A",
    "[temperature]": "K",
    "[substance]": "mol",
    "[luminosity]": "cd",
}


def unit_definitions(units: Iterable[str]) -> Element:
    """The ``<UnitDefinitions>`` element of a model description.

    Parameters
    ----------
    units : iterable of str
        SI units in the parameter files' notation (``"Pa"``, ``"m^3/(s*Pa)"``).

    Returns
    -------
    xml.etree.ElementTree.Element
        One ``<Unit name=...>`` per distinct unit (named in FMI notation, :func:`fmi_unit`)
        with its ``<BaseUnit>``: the exponents of kg, m, s, A, K, mol and cd.

    Raises
    ------
    ValueError
        A unit that is not a coherent SI unit (a factor other than 1 to the base units).
    """
    from pneumaquad.params.units import ureg

    element = Element("UnitDefinitions")
    for unit in sorted(set(units), key=fmi_unit):
        base = ureg.Quantity(1.0, unit).to_base_units()
        if not math.isclose(base.magnitude, 1.0, rel_tol=1e-12):
            raise ValueError(f"{unit} is not a coherent SI unit (1 {unit} = {base})")
        exponents = {_BASE_UNIT_ATTRIBUTES[dimension]: f"{exponent:g}"
                     for dimension, exponent in base.dimensionality.items()}
        definition = SubElement(element, "Unit", name=fmi_unit(unit))
        SubElement(definition, "BaseUnit", exponents)
    return element


def complete_model_description(root: Element, variables: Sequence[FmuVariable],
                               real_starts: Mapping[str, float]) -> Element:
    """Add to a model description what pythonfmu does not write.

    * ``<UnitDefinitions>`` of every unit the variables use, and the ``unit`` of each Real;
    * the start values of Real parameters to the last bit (``repr``: 17 digits where
      pythonfmu writes 16);
    * ``<InitialUnknowns>`` listing the outputs (computed in initialisation mode), and
      ``dependencies=""`` on the outputs: they are the state at the end of the last step,
      so none depends on an input directly (no algebraic loop through the FMU).

    Parameters
    ----------
    root : xml.etree.ElementTree.Element
        ``<fmiModelDescription>`` as pythonfmu builds it (modified in place).
    variables : sequence of FmuVariable
        The FMU's variables, in the order of ``<ModelVariables>``.
    real_starts : mapping
        Name -> exact start value of the Real parameters.

    Returns
    -------
    xml.etree.ElementTree.Element
        ``root``.
    """
    by_name = {variable.name: variable for variable in variables}
    units = [variable.unit for variable in variables if variable.unit is not None]
    position = list(root).index(root.find("CoSimulation")) + 1
    root.insert(position, unit_definitions(units))
    for scalar in root.find("ModelVariables"):
        variable = by_name[scalar.get("name")]
        real = scalar.find("Real")
        if real is None:
            continue
        if variable.unit is not None:
            real.set("unit", fmi_unit(variable.unit))
        if variable.name in real_starts:
            real.set("start", repr(float(real_starts[variable.name])))
    structure = root.find("ModelStructure")
    outputs = structure.find("Outputs")
    if outputs is not None:
        initial = SubElement(structure, "InitialUnknowns")
        for unknown in outputs:
            unknown.set("dependencies", "")
            SubElement(initial, "Unknown", index=unknown.get("index"))
    return root
