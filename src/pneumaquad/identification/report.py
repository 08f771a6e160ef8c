"""Parameter files written from fit results.

The fits return the package's one result type, `pneumaquad.analysis.fits.FitResult`
(fitted values keyed ``"name [unit]"`` in SI units, ``"-"`` for pure numbers, their
standard errors and goodness of fit). `write_parameter_file` starts from a
parameter set's raw TOML, sets the fitted values as unit strings, validates the result
with the simulator's own loader and writes it with a comment header naming the fits.
"""

from __future__ import annotations

import os
import tomllib
from collections.abc import Iterable, Mapping, Sequence
from datetime import datetime
from pathlib import Path
from typing import Any

import tomli_w

from pneumaquad.analysis.fits import FitResult, format_r_squared, parameter_name_and_unit
from pneumaquad.params import DATA_DIR, ParameterError, Problem, apply_overrides, load_rig

__all__ = ["updates_from_fit", "write_parameter_file"]

#: Units written as plain numbers (dimensionless parameters).
_DIMENSIONLESS = ("-", "1", "")


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
