"""The display units of a report: one choice, SI or the thesis's US customary units, for
every figure, table and text of a whole report.

Everything inside pneumaquad is SI (recordings, summaries, parameters: m, Pa absolute,
N, s); a report converts only where it draws or prints, through one :class:`DisplayUnits`
made by :func:`display_units`. The two systems:

========================  ==================  =====================
quantity kind             ``"si"`` (default)  ``"us"`` (the thesis)
========================  ==================  =====================
length                    m                   in
small length              mm                  in
tiny length               µm                  0.001 in
pressure (absolute)       kPa abs             psia
pressure difference       kPa                 psi
gauge pressure            kPa gauge           psig
force                     N                   lbf
velocity                  m/s                 in/s
small velocity            mm/s                in/s
area                      mm²                 in²
small area (orifices)     mm²                 0.001 in²
========================  ==================  =====================

and the parameter units built from them (N s/m or lbf s/in, V/m or V/in, ...). Time (s),
angles (deg), voltages (V), masses (kg, as in the thesis) and air (normal litres, NL)
are the same in both. The factors come from the package's pint registry
(:func:`pneumaquad.params.units.unit_scale`), the registry the parameter files are read
with; a gauge pressure is the absolute one less :attr:`DisplayUnits.atmosphere` (a run's
report uses its parameter set's ``gas.atmospheric_pressure``).

A summary key or a recording column says its SI unit in brackets (``"max cap pressure
[Pa]"``); :meth:`DisplayUnits.key` gives the key and value to show (``"max cap pressure
[psia]"``, the value in psia).
"""

from __future__ import annotations

import functools
import re
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from pneumaquad.io.measured.mapping import STANDARD_ATMOSPHERE

__all__ = [
    "DEFAULT_SYSTEM",
    "KINDS",
    "SI",
    "UNIT_SYSTEMS",
    "DisplayUnit",
    "DisplayUnits",
    "display_units",
]

#: The unit systems a report can be shown in.
UNIT_SYSTEMS = ("si", "us")
DEFAULT_SYSTEM = "si"
#: How a report names each system.
_DESCRIPTIONS = {
    "si": "SI units (m, mm, kPa absolute unless marked gauge, N)",
    "us": "the thesis's US units (in, psia, psig, lbf)",
}


@dataclass(frozen=True)
class DisplayUnit:
    """One unit as a report shows it.

    Attributes
    ----------
    label : str
        As printed: ``"kPa abs"``, ``"psia"``, ``"0.001 in"``.
    pint : str
        The unit's name in the pint registry, for its SI factor (``"kPa"``, ``"psig"``,
        ``"thou"``); a gauge unit (``"psig"``, ``"kPag"``) subtracts the atmosphere.
    kind : str
        The kind of :data:`pneumaquad.params.units.KINDS` (or a pint dimension) the factor
        is taken for.
    """

    label: str
    pint: str
    kind: str


def _pair(kind: str, si: tuple[str, str], us: tuple[str, str]) -> dict[str, DisplayUnit]:
    return {"si": DisplayUnit(*si, kind), "us": DisplayUnit(*us, kind)}


#: Quantity kind → its unit in each system (label, pint name).
KINDS: dict[str, dict[str, DisplayUnit]] = {
    "length": _pair("length", ("m", "m"), ("in", "in")),
    "small length": _pair("length", ("mm", "mm"), ("in", "in")),
    "tiny length": _pair("length", ("µm", "micrometer"), ("0.001 in", "thou")),
    "pressure": _pair("pressure", ("kPa abs", "kPa"), ("psia", "psia")),
    "pressure difference": _pair("pressure", ("kPa", "kPa"), ("psi", "psia")),
    "gauge pressure": _pair("pressure", ("kPa gauge", "kPag"), ("psig", "psig")),
    "force": _pair("force", ("N", "N"), ("lbf", "lbf")),
    "velocity": _pair("velocity", ("m/s", "m/s"), ("in/s", "in/s")),
    "small velocity": _pair("velocity", ("mm/s", "mm/s"), ("in/s", "in/s")),
    "area": _pair("area", ("mm²", "mm**2"), ("in²", "in**2")),
    "small area": _pair("area", ("mm²", "mm**2"), ("0.001 in²", "thou*in")),
    "damping": _pair("damping", ("N s/m", "N*s/m"), ("lbf s/in", "lbf*s/in")),
    "stiffness": _pair("stiffness", ("N/m", "N/m"), ("lbf/in", "lbf/in")),
    "inverse velocity": _pair("inverse_velocity", ("s/m", "s/m"), ("s/in", "s/in")),
    "proportional gain": _pair("proportional_gain", ("V/m", "V/m"), ("V/in", "V/in")),
    "integral gain": _pair("integral_gain", ("V/(m s)", "V/(m*s)"), ("V/(in s)", "V/(in*s)")),
    "derivative gain": _pair("derivative_gain", ("V s/m", "V*s/m"), ("V s/in", "V*s/in")),
    "force feedback gain": _pair("voltage_per_force", ("V/N", "V/N"), ("V/lbf", "V/lbf")),
    "air per length": _pair("1/[length]", ("NL/m", "1/m"), ("NL/in", "1/in")),
}

#: The SI unit texts of keys and tables (``"[Pa]"``) → the kind they are shown as.
_SI_UNITS = {
    "m": "length", "mm": "small length", "µm": "tiny length", "Pa": "pressure",
    "Pa gauge": "gauge pressure", "N": "force", "m/s": "velocity", "mm/s": "small velocity",
    "m²": "area", "m^2": "area", "mm²": "area", "N s/m": "damping", "N/m": "stiffness",
    "s/m": "inverse velocity", "V/m": "proportional gain", "V/(m s)": "integral gain",
    "V s/m": "derivative gain", "V/N": "force feedback gain", "NL/m": "air per length",
}
#: SI factor of the units of :data:`_SI_UNITS` that are not the kind's base unit.
_SI_PREFIX = {"mm": 1e-3, "µm": 1e-6, "mm/s": 1e-3, "mm²": 1e-6}
#: A pressure key naming one of these words is a difference (an error), not absolute.
_DIFFERENCE_WORDS = ("rmse", "error", "difference", "drop")
#: SI unit of a signal → the kind its errors are shown as (a position error of a rig is
#: a fraction of its 44 mm stroke: millimetres, not metres).
_ERROR_KINDS = {"m": "small length", "Pa": "pressure difference", "N": "force"}
#: ``quantity [unit]`` at the end of a key.
_KEY = re.compile(r"^(?P<name>.*?)\s*\[(?P<unit>[^\[\]]+)\]$")


@functools.cache
def _factor(unit: DisplayUnit) -> tuple[float, bool]:
    """SI value of one ``unit`` and whether it is a gauge pressure (pint, cached)."""
    from pneumaquad.params.units import unit_scale

    return unit_scale(unit.pint, unit.kind)


@dataclass(frozen=True)
class DisplayUnits:
    """The units one report is shown in; every conversion of a report goes through it.

    Attributes
    ----------
    system : str
        ``"si"`` or ``"us"`` (:data:`UNIT_SYSTEMS`).
    atmosphere : float
        Atmospheric pressure [Pa] subtracted for gauge pressures.
    """

    system: str = DEFAULT_SYSTEM
    atmosphere: float = STANDARD_ATMOSPHERE

    def __post_init__(self) -> None:
        if self.system not in UNIT_SYSTEMS:
            raise ValueError(f"unknown unit system {self.system!r}: expected one of "
                             f"{', '.join(UNIT_SYSTEMS)}")

    @property
    def description(self) -> str:
        """How a report names the system: ``"the thesis's US units (in, psia, ...)"``."""
        return _DESCRIPTIONS[self.system]

    def with_atmosphere(self, atmosphere: float) -> DisplayUnits:
        """The same units with another atmospheric pressure [Pa] for gauge values."""
        return replace(self, atmosphere=float(atmosphere))

    def _unit(self, kind: str) -> DisplayUnit:
        try:
            return KINDS[kind][self.system]
        except KeyError:
            raise KeyError(f"unknown quantity kind {kind!r}: expected one of "
                           f"{', '.join(KINDS)}") from None

    def unit(self, kind: str) -> str:
        """The label of ``kind``'s unit (``"psia"``, ``"kPa abs"``)."""
        return self._unit(kind).label

    def value(self, si: Any, kind: str) -> Any:
        """``si`` (a number or an array, in the kind's SI unit) in the display unit."""
        factor, gauge = _factor(self._unit(kind))
        values = np.asarray(si, dtype=float)
        shown = ((values - self.atmosphere) if gauge else values) / factor
        return float(shown) if shown.ndim == 0 else shown

    def si(self, shown: Any, kind: str) -> Any:
        """The inverse of :meth:`value`: a displayed number or array back in SI."""
        factor, gauge = _factor(self._unit(kind))
        values = np.asarray(shown, dtype=float) * factor
        values = values + self.atmosphere if gauge else values
        return float(values) if values.ndim == 0 else values

    def axis(self, name: str, kind: str) -> str:
        """An axis label: ``"Pressure (psia)"`` (a name ending in a line break puts the
        unit on the next line)."""
        space = "" if name.endswith("\n") else " "
        return f"{name}{space}({self.unit(kind)})"

    def text(self, si: float, kind: str, digits: int = 4) -> str:
        """A value with its unit for prose: ``"1.75 in"``."""
        return f"{self.value(si, kind):.{digits}g} {self.unit(kind)}"

    def cell(self, value: Any, si_unit: str, name: str = "") -> tuple[Any, str]:
        """A table's (value, unit) from an SI (value, unit): numbers in a unit of
        :data:`_SI_UNITS` are converted, anything else is passed through unchanged.
        ``name`` tells a pressure difference (an RMSE, an error) from an absolute one."""
        kind = _SI_UNITS.get(si_unit)
        if kind is None:
            return value, si_unit
        if kind == "pressure" and any(word in name.lower() for word in _DIFFERENCE_WORDS):
            kind = "pressure difference"
        if isinstance(value, (int, float, np.ndarray)) and not isinstance(value, bool):
            value = self.value(np.asarray(value, dtype=float) * _SI_PREFIX.get(si_unit, 1.0),
                               kind)
        return value, self.unit(kind)

    def error(self, value: Any, si_unit: str) -> tuple[Any, str]:
        """(value, unit) of an error (an RMSE, a difference) of a signal in ``si_unit``:
        lengths as small lengths (mm or in), pressures as differences (kPa or psi); other
        units pass through."""
        kind = _ERROR_KINDS.get(si_unit)
        if kind is None:
            return value, si_unit
        return self.value(value, kind), self.unit(kind)

    def key(self, key: str, value: Any = None) -> tuple[str, Any]:
        """A ``"quantity [SI unit]"`` key and its value as shown: ``("max cap pressure
        [psia]", 64.9...)`` for ``("max cap pressure [Pa]", 448000.0)``. Keys without a
        convertible unit come back unchanged; a pressure named an RMSE, error, difference
        or drop is a difference, any other absolute."""
        match = _KEY.match(key)
        if match is None or match["unit"] not in _SI_UNITS:
            return key, value
        value, unit = self.cell(value, match["unit"], match["name"])
        return f"{match['name']} [{unit}]", value

    def rows(self, rows: list[tuple[str, Any]]) -> list[tuple[str, Any]]:
        """:meth:`key` of every (key, value) row."""
        return [self.key(key, value) for key, value in rows]


#: The default units (SI, standard atmosphere).
SI = DisplayUnits()


def display_units(system: str | DisplayUnits | None = None,
                  atmosphere: float | None = None) -> DisplayUnits:
    """The display units named ``system`` (``"si"``, ``"us"``; None: SI), or ``system``
    itself, with ``atmosphere`` [Pa] for gauge pressures when given.

    Raises
    ------
    ValueError
        For a name not in :data:`UNIT_SYSTEMS`.
    """
    units = system if isinstance(system, DisplayUnits) else DisplayUnits(
        (system or DEFAULT_SYSTEM).lower())
    return units if atmosphere is None else units.with_atmosphere(atmosphere)
