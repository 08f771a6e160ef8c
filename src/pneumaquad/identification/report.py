"""Fit results and parameter files written from them.

A `FitResult` holds fitted values keyed ``"name [unit]"`` (SI units, ``"-"`` for pure
numbers), their standard errors and goodness of fit. `write_parameter_file` starts from a
parameter set's raw TOML, sets the fitted values as unit strings, validates the result
with the simulator's own loader and writes it with a comment header naming the fits.
"""

from __future__ import annotations

import dataclasses
import math
import os
import re
import tomllib
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from datetime import datetime
from pathlib import Path
from typing import Any

import numpy as np
import tomli_w

from pneumaquad.params import DATA_DIR, ParameterError, Problem, apply_overrides, load_rig

__all__ = [
    "MAX_RELATIVE_STANDARD_ERROR",
    "FitResult",
    "check_standard_errors",
    "covariance_from_jacobian",
    "format_r_squared",
    "parameter_name_and_unit",
    "r_squared",
    "updates_from_fit",
    "write_parameter_file",
]

#: Largest standard error, as a share of the value, of a parameter `check_standard_errors`
#: accepts [-].
MAX_RELATIVE_STANDARD_ERROR = 0.25
_KEY_PATTERN = re.compile(r"^(?P<name>[^\[\]]+?)\s*\[(?P<unit>[^\[\]]+)\]$")
#: Units written as plain numbers (dimensionless parameters).
_DIMENSIONLESS = ("-", "1", "")


@dataclass(frozen=True)
class FitResult:
    """Outcome of one least-squares fit.

    Attributes
    ----------
    name : str
        What was fitted, e.g. ``"coulomb-viscous friction"``.
    parameters : Mapping of str to float
        Fitted values keyed ``"name [unit]"`` in SI, e.g. ``"coulomb_force [N]"``.
    standard_errors : Mapping of str to float
        One-sigma standard errors, same keys; ``inf`` where not identifiable. They assume
        independent residuals, so for time series they are lower bounds.
    r_squared : float
        Coefficient of determination 1 - SS_res/SS_tot [-].
    residual_rms : float
        Root-mean-square residual, in ``residual_unit``.
    n_points : int
        Number of residuals fitted.
    residual_unit : str
        Unit of the residuals (``"N"``, ``"Pa"``, ...).
    details : Mapping of str to Any
        Extra information (initial values, which parameters were held, ...).
    problems : tuple of str
        Why the fit is not to be trusted, one sentence each naming the parameter (a
        standard error that says the data do not determine it, a value at a bound, large
        residuals); empty for a fit that passed its checks.
    """

    name: str
    parameters: Mapping[str, float]
    standard_errors: Mapping[str, float]
    r_squared: float
    residual_rms: float
    n_points: int
    residual_unit: str = ""
    details: Mapping[str, Any] = field(default_factory=dict)
    problems: tuple[str, ...] = ()

    @property
    def failed(self) -> bool:
        """True when the fit's own checks say its values are not to be trusted."""
        return bool(self.problems)

    def value(self, name: str) -> float:
        """Fitted value of a parameter by its name without the unit (``"coulomb_force"``)."""
        for key, value in self.parameters.items():
            if parameter_name_and_unit(key)[0] == name:
                return value
        raise KeyError(f"{name!r} is not a parameter of the {self.name} fit")

    def rows(self) -> list[tuple[str, float, float]]:
        """(key, value, standard error) per parameter, for tables."""
        return [(key, value, self.standard_errors[key]) for key, value in self.parameters.items()]


def check_standard_errors(
    fit: FitResult, max_relative_error: float = MAX_RELATIVE_STANDARD_ERROR
) -> FitResult:
    """The fit with a problem added for each parameter the data do not determine.

    A parameter fails when its standard error is not finite or exceeds
    ``max_relative_error`` times its absolute value.

    Parameters
    ----------
    fit : FitResult
        Any fit.
    max_relative_error : float
        Largest acceptable standard error as a share of the value [-].

    Returns
    -------
    FitResult
        A copy with ``problems`` extended (the same object when nothing is added).
    """
    problems = []
    for key, value, error in fit.rows():
        if not (math.isfinite(error) and error <= max_relative_error * abs(value)):
            problems.append(
                f"{fit.name}: {key} = {value:.4g} has the standard error {error:.2g}, more "
                f"than {max_relative_error:.0%} of its value: the data do not determine it"
            )
    if not problems:
        return fit
    return dataclasses.replace(fit, problems=(*fit.problems, *problems))


def format_r_squared(value: float) -> str:
    """R² with four decimals, or ``"n/a"`` where it is not defined (NaN)."""
    return "n/a" if math.isnan(value) else f"{value:.4f}"


def parameter_name_and_unit(key: str) -> tuple[str, str]:
    """Split ``"coulomb_force [N]"`` into ``("coulomb_force", "N")``.

    Raises
    ------
    ValueError
        If the key has no ``[unit]`` suffix.
    """
    match = _KEY_PATTERN.match(key.strip())
    if match is None:
        raise ValueError(f"parameter key {key!r} should look like 'name [unit]'")
    return match["name"], match["unit"].strip()


def covariance_from_jacobian(jacobian: np.ndarray, residuals: np.ndarray) -> np.ndarray:
    """Parameter covariance s²·(JᵀJ)⁻¹ of a least-squares fit, via the SVD.

    Parameters
    ----------
    jacobian : numpy.ndarray
        d(residual)/d(parameter) at the solution, shape (n_residuals, n_parameters).
    residuals : numpy.ndarray
        Residuals at the solution; s² = SS_res / (n_residuals - n_parameters).

    Returns
    -------
    numpy.ndarray
        Covariance (n_parameters, n_parameters); all ``inf`` if J is rank deficient.
    """
    jacobian = np.atleast_2d(np.asarray(jacobian, dtype=float))
    count, unknowns = jacobian.shape
    residual_variance = float(residuals @ residuals) / max(count - unknowns, 1)
    _, singular, vt = np.linalg.svd(jacobian, full_matrices=False)
    threshold = np.finfo(float).eps * max(jacobian.shape) * (singular[0] if singular.size else 0)
    if singular.size < unknowns or np.any(singular <= threshold):
        return np.full((unknowns, unknowns), np.inf)
    return (vt.T / singular**2) @ vt * residual_variance


def r_squared(residuals: np.ndarray, observed: np.ndarray) -> float:
    """1 - SS_res/SS_tot [-] (NaN when the observations are constant)."""
    total = float(np.sum((observed - np.mean(observed)) ** 2))
    if total == 0.0:
        return math.nan
    return 1.0 - float(residuals @ residuals) / total


def updates_from_fit(
    fit: FitResult, section: str, names: Iterable[str] | None = None
) -> dict[str, Any]:
    """Parameter-file updates ``{"section.name": "value unit"}`` from a fit.

    Parameters
    ----------
    fit : FitResult
        Its keys must be parameter-file key names with units (``"coulomb_force [N]"``).
    section : str
        Dotted table of the parameter file, e.g. ``"friction"`` or ``"valve.port2"``.
    names : iterable of str, optional
        Only these parameter names; all by default.

    Returns
    -------
    dict
        Dotted key to a unit string (``"13.3 N"``) or, for ``[-]``, a plain float.
    """
    wanted = None if names is None else set(names)
    updates: dict[str, Any] = {}
    for key, value in fit.parameters.items():
        name, unit = parameter_name_and_unit(key)
        if wanted is not None and name not in wanted:
            continue
        updates[f"{section}.{name}"] = (
            float(value) if unit in _DIMENSIONLESS else f"{float(value)!r} {unit}"
        )
    return updates


def _base_path(base_set: str | os.PathLike[str]) -> Path:
    if isinstance(base_set, str) and not base_set.endswith(".toml") and "/" not in base_set:
        path = DATA_DIR / f"{base_set}.toml"
        if not path.is_file():
            raise ParameterError([Problem("<set>", base_set, "is not a shipped parameter set")])
        return path
    return Path(base_set)


def _set_dotted(raw: dict[str, Any], key: str, value: Any) -> None:
    parts = key.split(".")
    node = raw
    for part in parts[:-1]:
        node = node.setdefault(part, {})
        if not isinstance(node, dict):
            raise ParameterError([Problem(key, value, f"cannot be set: {part!r} is not a table")])
    node[parts[-1]] = value


def _header(
    base_set: str | os.PathLike[str], updates: Mapping[str, Any], fits: Sequence[FitResult]
) -> str:
    lines = [
        f"# Identified by pneumaquad.identification on {datetime.now():%Y-%m-%d %H:%M:%S}",
        f"# base parameter set: {base_set}",
    ]
    for fit in fits:
        lines.append(
            f"# fit '{fit.name}': n = {fit.n_points}, R^2 = {format_r_squared(fit.r_squared)}, "
            f"residual RMS = {fit.residual_rms:.4g} {fit.residual_unit}".rstrip()
        )
        for key, value, error in fit.rows():
            lines.append(f"#   {key} = {value:.6g} +/- {error:.2g}")
        for problem in fit.problems:
            lines.append(f"#   FAILED CHECK (written with --force): {problem}")
    lines.append("# keys set from the fits: " + ", ".join(updates))
    lines.append("# (comments of the base file are not carried over)")
    return "\n".join(lines) + "\n\n"


def write_parameter_file(
    base_set: str | os.PathLike[str],
    updates: Mapping[str, Any],
    path: str | os.PathLike[str],
    fits: Sequence[FitResult] = (),
    overrides: Iterable[str] = (),
) -> Path:
    """Write a rig parameter file: a base set with fitted values applied.

    Parameters
    ----------
    base_set : str or path-like
        Shipped set name (``"thesis-rig"``) or TOML path (e.g. a run's
        ``parameters.toml``).
    updates : mapping
        Dotted key to TOML value: unit strings such as ``"20.1 N"``, numbers, or lists
        (area polynomials), e.g. from `updates_from_fit`.
    path : str or path-like
        Output TOML file; its folder is created.
    fits : sequence of FitResult
        Listed in the comment header with their statistics.
    overrides : iterable of str
        ``"section.key=value"`` items applied to the base before the updates.

    Returns
    -------
    Path
        The written file; ``pneumaquad.params.load_rig(path)`` loads it.

    Raises
    ------
    ParameterError
        If the base set cannot be read, or the updated set is not valid (nothing is
        written then).
    """
    source = _base_path(base_set)
    try:
        with source.open("rb") as handle:
            raw = tomllib.load(handle)
    except (OSError, tomllib.TOMLDecodeError) as error:
        raise ParameterError([Problem("<file>", str(source), f"cannot be read: {error}")]) from None
    raw = apply_overrides(raw, overrides)
    for key, value in updates.items():
        _set_dotted(raw, key, value)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    scratch = path.with_name(f".{path.stem}.checking.toml")
    scratch.write_text(_header(base_set, updates, fits) + tomli_w.dumps(raw), encoding="utf-8")
    try:
        load_rig(scratch)
    except ParameterError as error:
        scratch.unlink(missing_ok=True)
        raise ParameterError(error.problems, source=f"fitted parameters for {path}") from None
    scratch.replace(path)
    return path
