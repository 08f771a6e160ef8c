"""Unit parsing: quantity strings such as ``"50.3 psig"`` to SI floats.

One shared pint `UnitRegistry` (`ureg`) is used throughout. Pressures written with a
trailing ``g`` (``psig``, ``barg``, ``kPag``, ``Pag``, ``MPag``) are gauge and have the
atmospheric pressure added; every other pressure unit (``psi``, ``psia``, ``bar``,
``Pa``, ...) is absolute.
"""

from __future__ import annotations

import functools
import math
import re
from dataclasses import dataclass
from typing import Any

import pint

from .errors import ParameterError, Problem

__all__ = [
    "AMBIGUOUS_UNITS",
    "KINDS",
    "GaugeError",
    "Kind",
    "QuantityError",
    "convert_quantity",
    "parse_quantity",
    "unit_scale",
    "ureg",
]



def _registry() -> pint.UnitRegistry:
    """pint's default registry, its parsed definitions cached in the user's cache folder
    (pint's ``:auto:``: a fifth of the start-up time); built afresh where that folder
    cannot be used."""
    try:
        return pint.UnitRegistry(cache_folder=":auto:")
    except OSError:
        return pint.UnitRegistry()


ureg = _registry()
"""The package's single pint unit registry."""

if "psia" not in ureg:
    ureg.define("psia = psi")
if "bara" not in ureg:
    ureg.define("bara = bar")

_GAUGE_UNITS = {"psig": "psi", "barg": "bar", "kPag": "kPa", "Pag": "Pa", "MPag": "MPa"}
#: Pressure units used for both gauge and absolute readings in practice: refused alone,
#: so that every pressure says which it is (the thesis's lab readings were gauge).
AMBIGUOUS_UNITS = {"psi": ("psig", "psia"), "bar": ("barg", "bara")}

_NUMBER = re.compile(
    r"^\s*([+-]?(?:nan|inf(?:inity)?|(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?))\s*(.*?)\s*$",
    re.IGNORECASE,
)
_NON_FINITE = re.compile(r"\b(?:nan|inf|infinity)\b", re.IGNORECASE)


@dataclass(frozen=True)
class Kind:
    """A physical kind of quantity: its SI unit and how to describe it in messages.

    Parameters
    ----------
    si_unit : str
        Unit string of the SI value stored in the models (e.g. ``"Pa"``).
    what : str
        Description with article, e.g. ``"a pressure"``.
    example : str
        Example input, e.g. ``"50.3 psig"``.
    """

    si_unit: str
    what: str
    example: str

    @property
    def expectation(self) -> str:
        """Phrase ``'a pressure such as "50.3 psig"'`` used in messages."""
        return f'{self.what} such as "{self.example}"'


KINDS: dict[str, Kind] = {
    "pressure": Kind("Pa", "a pressure", "50.3 psig"),
    "length": Kind("m", "a length", "1.75 in"),
    "area": Kind("m^2", "an area", "1e-5 m^2"),
    "volume": Kind("m^3", "a volume", "2 L"),
    "mass": Kind("kg", "a mass", "0.2 kg"),
    "force": Kind("N", "a force", "4.5 lbf"),
    "time": Kind("s", "a time", "1 ms"),
    "frequency": Kind("Hz", "a frequency", "0.5 Hz"),
    "temperature": Kind("K", "a temperature", "298 K"),
    "voltage": Kind("V", "a voltage", "5.25 V"),
    "angle": Kind("rad", "an angle", "30 deg"),
    "specific_heat": Kind("J/(kg*K)", "a specific heat / gas constant", "287 J/(kg*K)"),
    "conductance": Kind("m^3/(s*Pa)", "a sonic conductance", "0.25 dm^3/(s*bar)"),
    "damping": Kind("N*s/m", "a damping coefficient", "70 N*s/m"),
    "stiffness": Kind("N/m", "a stiffness", "2e5 N/m"),
    "velocity": Kind("m/s", "a velocity", "0.1 in/s"),
    "inverse_velocity": Kind("s/m", "an inverse velocity", "40 s/in"),
    "acceleration": Kind("m/s^2", "an acceleration", "9.81 m/s^2"),
    "heat_transfer": Kind("W/(m^2*K)", "a heat transfer coefficient", "20 W/(m^2*K)"),
    "proportional_gain": Kind("V/m", "a proportional gain", "300 V/m"),
    "integral_gain": Kind("V/(m*s)", "an integral gain", "100 V/(m*s)"),
    "derivative_gain": Kind("V*s/m", "a derivative gain", "3 V*s/m"),
    "voltage_per_force": Kind("V/N", "a force feedback gain", "0.01 V/N"),
    "density": Kind("kg/m^3", "a density", "2700 kg/m^3"),
    "inertia": Kind("kg*m^2", "a moment of inertia", "0.01 kg*m^2"),
}


class QuantityError(ValueError):
    """A quantity could not be converted; the message follows the offending value."""


class GaugeError(QuantityError):
    """A gauge pressure could not be resolved: no valid atmospheric pressure."""


_SI_BASE = {
    "[length]": "m",
    "[mass]": "kg",
    "[time]": "s",
    "[temperature]": "K",
    "[current]": "A",
    "[substance]": "mol",
    "[luminosity]": "cd",
}


def _kind(expected_dimension: str) -> Kind:
    if expected_dimension in KINDS:
        return KINDS[expected_dimension]
    try:
        dims = ureg.get_dimensionality(expected_dimension)
        si = " * ".join(f"{_SI_BASE[d]}**{p}" for d, p in dims.items()) or "dimensionless"
    except Exception:
        raise ValueError(f"unknown expected dimension {expected_dimension!r}") from None
    return Kind(si, f"a quantity of dimension {expected_dimension}", f"1 {si}")


def _parse(text: str) -> pint.Quantity:
    match = _NUMBER.match(text)
    if match:
        number, unit = match.groups()
        try:
            return ureg.Quantity(float(number), unit)
        except Exception:
            pass
    return ureg.parse_expression(text)


def _what_it_is(quantity: pint.Quantity) -> str:
    """``'is a voltage'`` for a quantity of a known kind, else its dimension."""
    for kind in KINDS.values():
        if quantity.dimensionality == ureg.Quantity(1.0, kind.si_unit).dimensionality:
            return f"is {kind.what}"
    return f"has dimension {quantity.dimensionality}"


def convert_quantity(
    value: Any, kind: str | Kind, atmospheric_pressure: float | None = None
) -> float:
    """Convert a quantity string to an SI float; the error message omits the key.

    A string already converted with the same kind and atmospheric pressure is not parsed
    again (:data:`CONVERTED_CACHE_SIZE` conversions are remembered): loading many variants
    of one parameter set parses only the values that differ.

    Parameters
    ----------
    value : Any
        Input value; must be a string with a unit.
    kind : str or Kind
        Name in `KINDS` (or a pint dimension string), or a `Kind`.
    atmospheric_pressure : float, optional
        Atmospheric pressure in Pa, added for gauge pressure units.

    Returns
    -------
    float
        The value in the SI unit of `kind`.

    Raises
    ------
    QuantityError
        With a message to be read after the value, e.g.
        ``is a mass; expected a pressure such as "50.3 psig"``.
    """
    k = kind if isinstance(kind, Kind) else _kind(kind)
    expect = f"expected {k.expectation}"
    if isinstance(value, bool) or not isinstance(value, (str, int, float)):
        raise QuantityError(f"is not a quantity string; {expect}")
    if not isinstance(value, str):
        if not math.isfinite(value):
            raise QuantityError(f"is not finite; {expect}")
        raise QuantityError(f"has no unit; {expect}")
    return _convert_text(value, k, atmospheric_pressure)


#: Quantity strings whose conversion :func:`convert_quantity` remembers.
CONVERTED_CACHE_SIZE = 4096


@functools.lru_cache(maxsize=CONVERTED_CACHE_SIZE)
def _convert_text(value: str, k: Kind, atmospheric_pressure: float | None) -> float:
    """:func:`convert_quantity` of a string (errors are raised afresh, never remembered)."""
    expect = f"expected {k.expectation}"
    if _NON_FINITE.search(value):
        raise QuantityError(f"is not finite; {expect}")
    text, gauge = value, False
    match = _NUMBER.match(value)
    if match and match.group(2) in AMBIGUOUS_UNITS:
        gauge_name, absolute_name = AMBIGUOUS_UNITS[match.group(2)]
        raise QuantityError(
            f"does not say gauge or absolute; write {gauge_name!r} for a gauge pressure "
            f"or {absolute_name!r} for an absolute one")
    if match and match.group(2) in _GAUGE_UNITS:
        text, gauge = f"{match.group(1)} {_GAUGE_UNITS[match.group(2)]}", True
    try:
        q = _parse(text)
    except Exception as exc:
        raise QuantityError(f"could not be parsed ({exc}); {expect}") from None
    if not isinstance(q, pint.Quantity) or q.unitless:
        raise QuantityError(f"has no unit; {expect}")
    try:
        si = q.to(k.si_unit).magnitude
    except pint.DimensionalityError:
        raise QuantityError(f"{_what_it_is(q)}; {expect}") from None
    except Exception as exc:
        raise QuantityError(f"could not be converted ({exc}); {expect}") from None
    si = float(si)
    if gauge:
        if k.si_unit != "Pa":
            raise QuantityError(f"uses a gauge unit for a non-pressure; {expect}")
        if atmospheric_pressure is None:
            raise GaugeError(
                "is a gauge pressure but no valid absolute gas.atmospheric_pressure is "
                'available to add; use an absolute unit such as "65 psia"'
            )
        si += atmospheric_pressure
    if not math.isfinite(si):
        raise QuantityError(f"is not finite; {expect}")
    return si


def parse_quantity(
    text: Any,
    expected_dimension: str,
    key: str,
    atmospheric_pressure: float | None = None,
) -> float:
    """Parse a quantity string such as ``"50.3 psig"`` and return its SI value.

    Parameters
    ----------
    text : Any
        The input, normally a string with a number and a unit. Plain numbers,
        non-finite numbers and other types are rejected.
    expected_dimension : str
        A kind name from `KINDS` (``"pressure"``, ``"length"``, ``"force"``, ...) or a
        pint dimension string such as ``"[length] / [time]"``.
    key : str
        Dotted key used in the error message.
    atmospheric_pressure : float, optional
        Atmospheric pressure in Pa, added for gauge units (``psig``, ``barg``, ...).
        Gauge units are rejected when it is not given.

    Returns
    -------
    float
        The SI value (Pa, m, N, ...).

    Raises
    ------
    ParameterError
        Naming `key`, the value and the expectation, e.g.
        ``supply.supply_pressure: '50 kg' is a mass; expected a pressure
        such as "50.3 psig"``.

    Examples
    --------
    >>> round(parse_quantity("50.3 psig", "pressure", "p", 101352.9), 1)
    448159.2
    """
    try:
        return convert_quantity(text, expected_dimension, atmospheric_pressure)
    except QuantityError as exc:
        raise ParameterError([Problem(key, text, str(exc))]) from None


def unit_scale(unit: str, kind: str | Kind) -> tuple[float, bool]:
    """SI factor of a unit name and whether it is a gauge pressure.

    The same registry and gauge/absolute rule as the parameter files, for callers that
    convert whole columns (lab recordings): ``value_SI = value·factor (+ atmosphere if
    gauge)``.

    Raises
    ------
    QuantityError
        Unknown unit, a unit of another kind, or ``psi``/``bar`` without ``g``/``a``.
    """
    name = unit.strip()
    return convert_quantity(f"1 {name}", kind, atmospheric_pressure=0.0), name in _GAUGE_UNITS
