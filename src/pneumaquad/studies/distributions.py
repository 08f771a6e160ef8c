"""Values a study varies: quantities with units, and the distributions they are drawn from.

A varied value is written like any parameter value: a quantity string (``"4.5 lbf"``,
``"50 psig"``) or a plain number for a dimensionless key. Within one varied key every
value is written in one unit, and the study samples the number in that unit (so a gauge
pressure stays gauge); the case's ``--set`` override carries the unit back, and the
parameter loader converts it to SI and checks it as it checks a file's value.

The distributions map a unit-interval sample ``u`` in (0, 1) to a value by their inverse
cumulative distribution function, so Latin hypercube and Sobol designs on the unit cube
keep their balance in every parameter.
"""

from __future__ import annotations

import itertools
import math
import re
from dataclasses import dataclass
from typing import Any

import numpy as np

from pneumaquad.params.errors import ParameterError, Problem

__all__ = [
    "DISTRIBUTIONS",
    "Distribution",
    "Quantity",
    "parse_distribution",
    "parse_study_quantity",
]

#: A number, then an optional unit (``"4.5 lbf"``, ``"-3e-2 m"``, ``"0.75"``).
_QUANTITY = re.compile(r"^\s*([+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?)\s*(.*?)\s*$")

#: Smallest distance of a unit-interval sample from 0 and 1 (keeps normal tails finite).
_UNIT_EDGE = 1e-12


@dataclass(frozen=True)
class Quantity:
    """A number and the unit it was written in (``""`` for a plain number)."""

    number: float
    unit: str

    def override_text(self) -> str:
        """The value as the TOML text of a ``--set`` override: ``"4.5 lbf"`` quoted, or
        the bare number."""
        return f'"{self.number!r} {self.unit}"' if self.unit else repr(self.number)


def parse_study_quantity(value: Any, key: str) -> Quantity:
    """A study value: a quantity string or a plain number.

    Raises
    ------
    ParameterError
        Naming ``key``, the value and what was expected.
    """
    if isinstance(value, bool) or not isinstance(value, (str, int, float)):
        raise ParameterError([Problem(key, value, 'should be a quantity such as "4.5 lbf" '
                                      "or a number")])
    if isinstance(value, (int, float)):
        if not math.isfinite(value):
            raise ParameterError([Problem(key, value, "should be finite")])
        return Quantity(float(value), "")
    match = _QUANTITY.match(value)
    if match is None:
        raise ParameterError([Problem(key, value, 'should be a number with a unit, such as '
                                      '"4.5 lbf"')])
    return Quantity(float(match.group(1)), match.group(2))


def _one_unit(key: str, values: list[Quantity], texts: list[Any]) -> str:
    """The unit shared by ``values``; every value of one key is written in one unit."""
    units = {value.unit for value in values}
    if len(units) > 1:
        raise ParameterError([Problem(key, texts, "should write every value in one unit "
                                      f"(found {sorted(units)})")])
    return units.pop()


@dataclass(frozen=True)
class Distribution:
    """A one-dimensional distribution of a varied value, in its unit.

    Parameters
    ----------
    kind : str
        One of :data:`DISTRIBUTIONS`.
    unit : str
        Unit of the numbers (``""``: dimensionless).
    numbers : tuple of float
        Its parameters in ``unit``: uniform (low, high); normal (mean, standard deviation,
        low, high) with ±inf for no truncation; log-normal (median, geometric standard
        deviation [-]); quartiles (minimum, lower quartile, median, upper quartile,
        maximum).
    """

    kind: str
    unit: str
    numbers: tuple[float, ...]

    def from_unit_interval(self, fractions: np.ndarray) -> np.ndarray:
        """Values [unit] at cumulative probabilities ``fractions`` in (0, 1) (inverse CDF).

        Quartiles are read like a box plot: the inverse CDF runs linearly through
        (0, minimum), (0.25, lower quartile), (0.5, median), (0.75, upper quartile) and
        (1, maximum).
        """
        from scipy import stats  # here: a study's worker processes never draw designs

        u = np.clip(np.asarray(fractions, dtype=float), _UNIT_EDGE, 1.0 - _UNIT_EDGE)
        if self.kind == "uniform":
            low, high = self.numbers
            return low + u * (high - low)
        if self.kind == "normal":
            mean, deviation, low, high = self.numbers
            a, b = (low - mean) / deviation, (high - mean) / deviation
            return stats.truncnorm.ppf(u, a, b, loc=mean, scale=deviation)
        if self.kind == "log-normal":
            median, spread = self.numbers
            return median * np.exp(math.log(spread) * stats.norm.ppf(u))
        return np.interp(u, (0.0, 0.25, 0.5, 0.75, 1.0), self.numbers)


#: Distribution kinds and the fields each needs.
DISTRIBUTIONS: dict[str, tuple[str, ...]] = {
    "uniform": ("low", "high"),
    "normal": ("mean", "std"),
    "log-normal": ("median", "geometric_std"),
    "quartiles": ("quartiles",),
}
_OPTIONAL = {"normal": ("low", "high")}


def parse_distribution(key: str, table: dict[str, Any]) -> Distribution:
    """A distribution from its spec table (``[vary."friction.static_force"]``).

    Parameters
    ----------
    key : str
        The table's dotted spec path, for messages (``vary."friction.static_force"``).
    table : dict
        ``distribution`` and its fields (:data:`DISTRIBUTIONS`): quantity strings or
        numbers, ``quartiles`` a list of five, ``geometric_std`` a plain number > 1.

    Raises
    ------
    ParameterError
        Naming the field, its value and what was expected.
    """
    kind = table.get("distribution")
    if kind not in DISTRIBUTIONS:
        raise ParameterError([Problem(f"{key}.distribution", kind,
                                      f"should be one of {', '.join(DISTRIBUTIONS)}")])
    allowed = {"distribution", *DISTRIBUTIONS[kind], *_OPTIONAL.get(kind, ())}
    unknown = sorted(set(table) - allowed)
    if unknown:
        raise ParameterError([Problem(f"{key}.{unknown[0]}", table[unknown[0]],
                                      f"is not a field of a {kind} distribution (fields: "
                                      f"{', '.join(sorted(allowed))})")])
    missing = [name for name in DISTRIBUTIONS[kind] if name not in table]
    if missing:
        raise ParameterError([Problem(f"{key}.{missing[0]}", table.get(missing[0]),
                                      f"is required by a {kind} distribution")])
    if kind == "quartiles":
        return _quartiles(key, table["quartiles"])
    if kind == "log-normal":
        median = parse_study_quantity(table["median"], f"{key}.median")
        spread = table["geometric_std"]
        if isinstance(spread, bool) or not isinstance(spread, (int, float)) or not spread > 1:
            raise ParameterError([Problem(f"{key}.geometric_std", spread,
                                          "should be a plain number greater than 1")])
        if not median.number > 0:
            raise ParameterError([Problem(f"{key}.median", table["median"],
                                          "should be positive for a log-normal")])
        return Distribution(kind, median.unit, (median.number, float(spread)))
    names = [name for name in (*DISTRIBUTIONS[kind], *_OPTIONAL.get(kind, ())) if name in table]
    values = [parse_study_quantity(table[name], f"{key}.{name}") for name in names]
    unit = _one_unit(key, values, [table[name] for name in names])
    given = dict(zip(names, (value.number for value in values), strict=True))
    if kind == "uniform":
        if not given["low"] < given["high"]:
            raise ParameterError([Problem(f"{key}.high", table["high"],
                                          f"should be greater than low ({table['low']})")])
        return Distribution(kind, unit, (given["low"], given["high"]))
    if not given["std"] > 0:
        raise ParameterError([Problem(f"{key}.std", table["std"], "should be positive")])
    low, high = given.get("low", -math.inf), given.get("high", math.inf)
    if not low < given["mean"] < high:
        raise ParameterError([Problem(f"{key}.mean", table["mean"],
                                      "should lie between low and high")])
    return Distribution(kind, unit, (given["mean"], given["std"], low, high))


def _quartiles(key: str, texts: Any) -> Distribution:
    if not isinstance(texts, list) or len(texts) != 5:
        raise ParameterError([Problem(f"{key}.quartiles", texts, "should be a list of five "
                                      "values: minimum, lower quartile, median, upper "
                                      "quartile, maximum")])
    values = [parse_study_quantity(text, f"{key}.quartiles") for text in texts]
    unit = _one_unit(f"{key}.quartiles", values, texts)
    numbers = tuple(value.number for value in values)
    if any(b < a for a, b in itertools.pairwise(numbers)) or numbers[0] == numbers[-1]:
        raise ParameterError([Problem(f"{key}.quartiles", texts,
                                      "should not decrease and should span a range")])
    return Distribution("quartiles", unit, numbers)
