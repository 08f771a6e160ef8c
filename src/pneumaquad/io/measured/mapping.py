"""Column mappings for lab recordings: which source column is which quantity, in what unit.

A mapping is written as a small TOML file or given as a dict::

    atmospheric_pressure = 101325        # [Pa], or a string such as "14.6 psia"

    [columns]
    time = { source = "t", unit = "ms" }
    position = { source = "x", unit = "in" }
    cap_pressure = { source = "data", column = 7, unit = "psig" }

Quantity keys may use spaces or underscores. ``source`` names a CSV header or a MATLAB
variable (struct fields as ``"log.position"``); ``column`` picks a 1-based column of a
matrix variable, as MATLAB indexes it (the thesis' ``data(:,40)``, appendix A.2, script
line 12). Pressure units must say whether they are gauge or absolute: ``psig``/``psia``,
``barg``/``bara``; SI ``Pa``/``kPa``/``MPa`` are absolute and ``Pag``/``kPag``/``MPag``
gauge. The thesis' own scripts added 14.7 psi to its gauge readings (appendix A.2, script
line 9); here the atmospheric pressure added to gauge units is explicit (default 101325 Pa).
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any, NamedTuple

import numpy as np

from pneumaquad.params.units import QuantityError, convert_quantity, unit_scale

__all__ = [
    "QUANTITIES",
    "STANDARD_ATMOSPHERE",
    "ColumnMapping",
    "ColumnSpec",
    "MeasuredDataError",
    "Quantity",
    "load_mapping",
    "mapping_from_dict",
    "to_si",
]

#: Default atmospheric pressure added to gauge readings [Pa].
STANDARD_ATMOSPHERE = 101325.0



class MeasuredDataError(ValueError):
    """Unusable measured data or mapping; carries every problem found, not just the first.

    Parameters
    ----------
    problems : iterable of str
        One sentence per problem, naming the column and what is wrong.
    source : str, optional
        The file (or mapping origin) the problems are in, used in the message.
    """

    def __init__(self, problems: Iterable[str], source: str | None = None) -> None:
        self.problems: list[str] = list(problems)
        self.source = source
        super().__init__(str(self))

    def __str__(self) -> str:
        count = len(self.problems)
        where = f" in {self.source}" if self.source else ""
        head = f"{count} problem{'s' if count != 1 else ''} with measured data{where}:"
        return "\n".join([head, *(f"  {problem}" for problem in self.problems)])

    def __reduce__(self) -> tuple[Any, ...]:
        return (type(self), (self.problems, self.source))


class Quantity(NamedTuple):
    """A quantity a recording can hold: its output column name and physical kind."""

    column: str
    kind: str


#: Mapping keys and the project column (SI unit) each becomes.
QUANTITIES: dict[str, Quantity] = {
    "time": Quantity("time [s]", "time"),
    "position": Quantity("position [m]", "length"),
    "reference position": Quantity("reference position [m]", "length"),
    "cap pressure": Quantity("cap pressure [Pa]", "pressure"),
    "rod pressure": Quantity("rod pressure [Pa]", "pressure"),
    "supply pressure": Quantity("supply pressure [Pa]", "pressure"),
    "command": Quantity("command [V]", "voltage"),
}


@dataclass(frozen=True)
class ColumnSpec:
    """Where one quantity is found in the source file and in which unit.

    Attributes
    ----------
    source : str
        CSV header or MATLAB variable name (dotted for struct fields).
    unit : str
        The unit as written (any unit of the quantity's kind that the parameter files
        accept, e.g. ``"mm"``, ``"psig"``, ``"kPa"``).
    column : int or None
        1-based column of a matrix variable; None for a vector or CSV column.
    """

    source: str
    unit: str
    column: int | None = None

    def describe(self) -> str:
        """``'x'`` or ``'data' column 7``, for messages."""
        return f"{self.source!r}" + (f" column {self.column}" if self.column else "")


@dataclass(frozen=True)
class ColumnMapping:
    """Validated mapping from quantity names (keys of `QUANTITIES`) to `ColumnSpec`.

    Attributes
    ----------
    columns : Mapping of str to ColumnSpec
        Always contains ``"time"``.
    atmospheric_pressure : float
        Added to gauge pressures [Pa].
    origin : str or None
        Where the mapping came from (file path), for messages.
    """

    columns: Mapping[str, ColumnSpec]
    atmospheric_pressure: float = STANDARD_ATMOSPHERE
    origin: str | None = field(default=None, compare=False)


def load_mapping(path: str | Path) -> ColumnMapping:
    """Read and validate a TOML column mapping (format in the module docstring).

    Raises
    ------
    MeasuredDataError
        If the file cannot be read or parsed, or lists every problem of its content.
    """
    path = Path(path)
    try:
        with path.open("rb") as handle:
            data = tomllib.load(handle)
    except OSError as error:
        raise MeasuredDataError([f"cannot read the mapping file: {error}"], str(path)) from None
    except tomllib.TOMLDecodeError as error:
        raise MeasuredDataError([f"invalid TOML: {error}"], str(path)) from None
    return mapping_from_dict(data, origin=str(path))


def mapping_from_dict(data: Mapping[str, Any], origin: str | None = None) -> ColumnMapping:
    """Validate a mapping given as a dict.

    Parameters
    ----------
    data : mapping
        Either ``{"columns": {...}, "atmospheric_pressure": ...}`` as in the TOML form, or
        the ``columns`` table alone. Each column entry is a dict with ``source``, ``unit``
        and optionally ``column``, or a ``(source, unit)`` pair.
    origin : str, optional
        Where the mapping came from, for messages.

    Raises
    ------
    MeasuredDataError
        Listing every problem: unknown quantities or units, units of the wrong kind,
        ambiguous ``psi``/``bar``, a missing ``time`` entry, a bad ``column`` or
        atmospheric pressure.
    """
    if not isinstance(data, Mapping):
        raise MeasuredDataError([f"a mapping must be a table/dict, got {data!r}"], origin)
    problems: list[str] = []
    if "columns" in data:
        unexpected = sorted(set(data) - {"columns", "atmospheric_pressure"})
        if unexpected:
            problems.append(
                f"unknown mapping keys {unexpected}; expected 'columns' and "
                "optionally 'atmospheric_pressure'"
            )
        entries = data["columns"]
        atmospheric = data.get("atmospheric_pressure", STANDARD_ATMOSPHERE)
    else:
        entries, atmospheric = data, STANDARD_ATMOSPHERE
    if not isinstance(entries, Mapping):
        raise MeasuredDataError([f"'columns' must be a table/dict, got {entries!r}"], origin)
    columns: dict[str, ColumnSpec] = {}
    named: set[str] = set()
    for key, entry in entries.items():
        quantity = str(key).strip().replace("_", " ")
        if quantity not in QUANTITIES:
            problems.append(f"unknown quantity {key!r}; known: {sorted(QUANTITIES)}")
            continue
        if quantity in named:
            problems.append(f"{quantity}: given more than once (as {key!r} again)")
            continue
        named.add(quantity)
        spec = _column_spec(quantity, entry, problems)
        if spec is not None:
            columns[quantity] = spec
    if "time" not in named:
        problems.append("no 'time' entry: the mapping must name the time column")
    atmospheric_pressure = _atmospheric_pressure(atmospheric, problems)
    if problems:
        raise MeasuredDataError(problems, origin)
    return ColumnMapping(MappingProxyType(columns), atmospheric_pressure, origin)


def to_si(values: np.ndarray, unit: str, kind: str, atmospheric_pressure: float) -> np.ndarray:
    """Convert source values in ``unit`` (of physical ``kind``) to SI; gauge adds
    atmosphere. Units follow the parameter files' rules (:mod:`pneumaquad.params.units`)."""
    factor, gauge = unit_scale(unit, kind)
    converted = np.asarray(values, dtype=float) * factor
    return converted + atmospheric_pressure if gauge else converted


def _column_spec(quantity: str, entry: Any, problems: list[str]) -> ColumnSpec | None:
    kind = QUANTITIES[quantity].kind
    if isinstance(entry, list | tuple) and len(entry) == 2:
        entry = {"source": entry[0], "unit": entry[1]}
    if not isinstance(entry, Mapping):
        problems.append(f"{quantity}: expected a table with 'source' and 'unit', got {entry!r}")
        return None
    found = len(problems)
    unexpected = sorted(set(entry) - {"source", "unit", "column"})
    if unexpected:
        problems.append(f"{quantity}: unknown keys {unexpected}; expected source, unit, column")
    source = entry.get("source")
    if not isinstance(source, str) or not source.strip():
        problems.append(f"{quantity}: 'source' must name a column or variable, got {source!r}")
    column = entry.get("column")
    if column is not None and (
        isinstance(column, bool) or not isinstance(column, int) or column < 1
    ):
        problems.append(f"{quantity}: 'column' must be a 1-based integer index, got {column!r}")
    unit = _check_unit(quantity, kind, entry.get("unit"), problems)
    if len(problems) > found:
        return None
    return ColumnSpec(source.strip(), unit, column)


def _check_unit(quantity: str, kind: str, unit: Any, problems: list[str]) -> str:
    """The unit name to convert ``quantity`` with: as written when the parameter files'
    parser takes it for a ``kind``, else its usual spelling if it is one lab files write
    in capitals (``"PSIG"``, ``"MS"``); problems are appended, naming the quantity."""
    if not isinstance(unit, str) or not unit.strip():
        problems.append(f"{quantity}: 'unit' must be a unit name such as "
                        f"{_EXAMPLE_UNITS[kind]!r}; got {unit!r}")
        return ""
    name = unit.strip()
    try:
        unit_scale(name, kind)
        return name
    except QuantityError as error:
        spelled = _CASE_FREE_UNITS.get(name.lower())
        if spelled is None or spelled == name:
            problems.append(f"{quantity}: unit {unit!r} {error}")
            return ""
    try:
        unit_scale(spelled, kind)
    except QuantityError as error:
        problems.append(f"{quantity}: unit {unit!r} ({spelled!r}) {error}")
        return ""
    return spelled


#: Units lab files often write in capitals, matched without regard to case when the name
#: as written is not a unit of the quantity's kind ("MS" is megasiemens to pint).
_CASE_FREE_UNITS = {name.lower(): name for name in (
    "s", "ms", "m", "cm", "mm", "in", "Pa", "kPa", "MPa", "bara", "psia", "Pag", "kPag",
    "MPag", "barg", "psig", "psi", "bar", "V", "mV")}


#: A unit of each kind, for messages.
_EXAMPLE_UNITS = {"time": "ms", "length": "mm", "pressure": "psig", "voltage": "V"}


def _atmospheric_pressure(value: Any, problems: list[str]) -> float:
    """Atmospheric pressure [Pa] from a number in Pa or a string such as ``"14.7 psia"``."""
    expected = (
        "must be a positive number [Pa] or an absolute pressure string such as "
        '"14.7 psia" or "101.3 kPa"'
    )
    if isinstance(value, str):
        try:  # the parameter files' parser; a gauge unit has no atmosphere to add here
            value = convert_quantity(value, "pressure", atmospheric_pressure=None)
        except QuantityError:
            problems.append(f"atmospheric_pressure: {value!r} {expected}")
            return math.nan
    if (
        isinstance(value, bool)
        or not isinstance(value, int | float)
        or not (math.isfinite(value) and value > 0)
    ):
        problems.append(f"atmospheric_pressure: {value!r} {expected}")
        return math.nan
    return float(value)
