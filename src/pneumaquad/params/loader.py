"""Reading, overriding, validating and writing parameter files (docs/parameters.md)."""

from __future__ import annotations

import contextlib
import copy
import difflib
import functools
import os
import re
import tomllib
import typing
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any, TypeVar

import tomli_w
from pydantic import BaseModel, ValidationError

from .errors import MISSING, ParameterError, Problem
from .fields import CrossFieldError, QuantityField
from .robot_schema import RobotParameters
from .schema import ActuatorParameters, RigSetup
from .units import GaugeError, QuantityError, convert_quantity

__all__ = [
    "DATA_DIR",
    "apply_overrides",
    "list_parameter_sets",
    "load_actuator",
    "load_parameter_set",
    "load_rig",
    "load_robot",
    "resolved_parameters_toml",
    "validated_update",
]

DATA_DIR = Path(__file__).parent / "data"
"""Folder of the shipped parameter sets."""

_RIG_TABLES = ("rig", "controller", "simulation")


def list_parameter_sets() -> dict[str, str]:
    """Shipped parameter sets.

    Returns
    -------
    dict of str to str
        Set name (file stem, e.g. ``"thesis-rig"``) to its ``meta.description``.
    """
    sets = {}
    for path in sorted(DATA_DIR.glob("*.toml")):
        with path.open("rb") as f:
            sets[path.stem] = str(tomllib.load(f).get("meta", {}).get("description", ""))
    return sets


def _resolve(name_or_path: str | os.PathLike[str]) -> Path:
    if isinstance(name_or_path, str):
        is_name = not name_or_path.endswith(".toml") and not any(
            sep and sep in name_or_path for sep in ("/", os.sep, os.altsep)
        )
        if is_name:
            path = DATA_DIR / f"{name_or_path}.toml"
            if not path.is_file():
                names = ", ".join(list_parameter_sets())
                raise ParameterError(
                    [
                        Problem(
                            "<set>",
                            name_or_path,
                            f"is not a shipped parameter set (one of: {names}) nor a .toml path",
                        )
                    ]
                )
            return path
    return Path(name_or_path)


@functools.lru_cache(maxsize=64)
def _parsed(path: Path, modified_ns: int, size: int) -> dict[str, Any]:
    """A TOML file's tables, parsed once per version of the file (its modification time
    and size are part of the key): a study loads the same parameter file for every case.
    Shared between callers, who never modify it."""
    with path.open("rb") as f:
        return tomllib.load(f)


def _read(path: Path) -> dict[str, Any]:
    """The tables of a TOML file (shared: not to be modified)."""
    try:
        status = path.stat()
        return _parsed(path, status.st_mtime_ns, status.st_size)
    except FileNotFoundError:
        raise ParameterError([Problem("<file>", str(path), "does not exist")]) from None
    except OSError as exc:
        raise ParameterError(
            [Problem("<file>", str(path), f"could not be read ({exc.strerror})")]
        ) from None
    except tomllib.TOMLDecodeError as exc:
        raise ParameterError(
            [Problem("<file>", str(path), f"is not valid TOML: {exc}")], source=str(path)
        ) from None
    except UnicodeDecodeError as exc:
        raise ParameterError(
            [
                Problem(
                    "<file>",
                    str(path),
                    f"is not UTF-8 text (byte {exc.object[exc.start]:#04x} at offset "
                    f"{exc.start}); expected a TOML file encoded in UTF-8",
                )
            ],
            source=str(path),
        ) from None


def _parse_override_value(text: str) -> Any:
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text


#: Top-level key of a parameter file that names the set it changes (a shipped name, or a
#: path relative to the file): the file then holds only the keys that differ.
EXTENDS_KEY = "extends"


def _merged(base: dict[str, Any], changes: dict[str, Any]) -> dict[str, Any]:
    """``base`` with ``changes`` laid over it, table by table (a copy)."""
    merged = dict(base)
    for key, value in changes.items():
        if isinstance(value, dict) and isinstance(merged.get(key), dict):
            merged[key] = _merged(merged[key], value)
        else:
            merged[key] = value
    return merged


def _read_layered(path: Path, chain: tuple[Path, ...] = ()) -> dict[str, Any]:
    """The raw tables of a parameter file, laid over the set it ``extends`` (recursively);
    not to be modified (a file that extends nothing gives its cached tables themselves).

    Raises
    ------
    ParameterError
        For an ``extends`` that is not a string, names no set or file, or loops back.
    """
    raw = _read(path)
    base = raw.get(EXTENDS_KEY)
    if base is None:
        return raw
    raw = {key: value for key, value in raw.items() if key != EXTENDS_KEY}
    if not isinstance(base, str):
        raise ParameterError([Problem(EXTENDS_KEY, base, "should be a parameter set name or "
                                      "a path to a TOML file")], source=str(path))
    try:
        base_path = _resolve(base)
    except ParameterError:
        raise ParameterError([Problem(EXTENDS_KEY, base, "is not a shipped parameter set "
                                      f"(one of: {', '.join(list_parameter_sets())}) nor a "
                                      ".toml path")], source=str(path)) from None
    if not base_path.is_absolute():  # a path beside the file (a shipped name is absolute)
        base_path = path.parent / base_path
    resolved = base_path.resolve()
    if resolved in chain or resolved == path.resolve():
        raise ParameterError([Problem(EXTENDS_KEY, base, "extends a file that extends this "
                                      "one (a loop)")], source=str(path))
    return _merged(_read_layered(base_path, (*chain, path.resolve())), raw)


def apply_overrides(raw: dict[str, Any], overrides: Iterable[str] = ()) -> dict[str, Any]:
    """Apply ``section.key=value`` overrides to a raw (unvalidated) parameter dict.

    Parameters
    ----------
    raw : dict
        Parsed TOML content; not modified.
    overrides : iterable of str
        Items ``"dotted.key=value"``. The value is read as a TOML value if it parses
        (``3``, ``true``, ``"30 psig"``, ``[1, 2]``), otherwise as a plain string, so
        ``supply.supply_pressure=30 psig`` works without quotes. Unknown keys are
        accepted here and rejected by validation.

    Returns
    -------
    dict
        A deep copy of `raw` with the overrides applied (missing tables are created).

    Raises
    ------
    ParameterError
        Listing every malformed override (no ``=``, an empty key part, or a key that
        descends into a non-table value).
    """
    out = copy.deepcopy(raw)
    problems = []
    for item in overrides:
        key, sep, text = str(item).partition("=")
        parts = [p.strip() for p in key.split(".")]
        if not sep or not all(parts):
            problems.append(Problem("<override>", item, 'should look like "section.key=value"'))
            continue
        node = out
        for part in parts[:-1]:
            node = node.setdefault(part, {})
            if not isinstance(node, dict):
                problems.append(Problem(key.strip(), item, f"cannot set inside non-table {part!r}"))
                break
        else:
            node[parts[-1]] = _parse_override_value(text.strip())
    if problems:
        raise ParameterError(problems, source="overrides")
    return out


def _dotted(loc: Sequence[Any]) -> str:
    return "".join(f"[{p}]" if isinstance(p, int) else f".{p}" for p in loc).lstrip(".")


def _lookup(raw: Any, loc: Sequence[Any], default: Any) -> Any:
    node = raw
    for part in loc:
        in_dict = isinstance(node, dict) and part in node
        in_list = isinstance(node, list) and isinstance(part, int) and part < len(node)
        if in_dict or in_list:
            node = node[part]
        else:
            return default
    return node


def _model_at(model: type[BaseModel], loc: Sequence[Any]) -> type[BaseModel] | None:
    for part in loc:
        field = model.model_fields.get(part) if isinstance(part, str) else None
        ann = field.annotation if field else None
        if not (isinstance(ann, type) and issubclass(ann, BaseModel)):
            return None
        model = ann
    return model


def _problems(exc: ValidationError, raw: dict[str, Any], root: type[BaseModel]) -> list[Problem]:
    problems: list[Problem] = []
    errors = exc.errors()
    bad_atmosphere = [("gas",), ("gas", "atmospheric_pressure")]
    atmosphere_bad = any(
        e["loc"][-2:] in bad_atmosphere or e["loc"] == ("actuator", "gas") for e in errors
    )
    for err in errors:
        loc = list(err["loc"])
        file_loc = loc[1:] if root is RigSetup and loc[:1] == ["actuator"] else loc
        error = err.get("ctx", {}).get("error")
        if isinstance(error, GaugeError) and atmosphere_bad and file_loc[:1] != ["gas"]:
            continue  # follows from the atmospheric pressure problem reported already
        if err["type"] == "missing" and isinstance(loc[-1], int):
            key = _dotted(file_loc[:-1])
            if not any(p.key == key for p in problems):
                value = _lookup(raw, file_loc[:-1], MISSING)
                problems.append(Problem(key, value, "should be a list of 5 numbers"))
            continue
        if isinstance(error, CrossFieldError):
            for sub, value, message in error.items:
                key_loc = file_loc + sub.split(".")
                problems.append(Problem(_dotted(key_loc), _lookup(raw, key_loc, value), message))
            continue
        if err["type"] == "missing":
            problems.append(Problem(_dotted(file_loc), MISSING, "this key is required"))
            continue
        value = _lookup(raw, file_loc, err.get("input"))
        if err["type"] == "extra_forbidden":
            model = _model_at(root, loc[:-1])
            known = list(model.model_fields) if model else []
            close = difflib.get_close_matches(str(loc[-1]), known, n=1, cutoff=0.75)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            problems.append(Problem(_dotted(file_loc), value, f"is not a known key{hint}"))
            continue
        message = err["msg"].removeprefix("Value error, ").replace("Input should", "should")
        message = re.sub(r"a valid dictionary or instance of \w+", "a table", message)
        problems.append(Problem(_dotted(file_loc), value, message))
    return problems


def _raw_atmosphere(raw: dict[str, Any]) -> float | None:
    """The absolute ``gas.atmospheric_pressure`` [Pa] of a raw parameter table, if valid."""
    gas = raw.get("gas")
    if isinstance(gas, dict):
        with contextlib.suppress(QuantityError):  # reported by validation itself
            return convert_quantity(gas.get("atmospheric_pressure"), "pressure")
    return None


def _mounted_atmosphere(raw: dict[str, Any]) -> float | None:
    """The atmospheric pressure [Pa] of a robot file's actuator sets (the gamma set's, as
    the three share one supply): what its gauge pressures refer to."""
    mounting = raw.get("actuators")
    if not isinstance(mounting, dict) or not isinstance(mounting.get("gamma"), str):
        return None
    try:
        return _raw_atmosphere(_read_layered(_resolve(mounting["gamma"])))
    except (OSError, ParameterError, ValueError):
        return None


def _validate(root: type[BaseModel], data: dict[str, Any], raw: dict[str, Any], source: str,
              atmospheric: float | None = None) -> Any:
    if atmospheric is None:
        atmospheric = _raw_atmosphere(raw)
    context = {"from_file": True, "atmospheric_pressure": atmospheric}
    try:
        return root.model_validate(data, context=context)
    except ValidationError as exc:
        raise ParameterError(_problems(exc, raw, root), source=source) from None


_Model = TypeVar("_Model", bound=BaseModel)


def validated_update(model: _Model, changes: Mapping[str, Any],
                     source: str = "update") -> _Model:
    """A copy of a validated parameter model with some keys changed, validated again.

    Unlike pydantic's ``model_copy(update=...)``, every range and cross-field check of
    the model runs on the result, so a setter cannot store a value a parameter file could
    not hold.

    Parameters
    ----------
    model : pydantic model
        A validated parameter model (``ActuatorParameters``, ``ControllerParameters``...).
    changes : mapping
        Dotted key (``"supply.supply_pressure"``) → new value, SI (plain floats are SI
        values; quantity strings such as ``"50 psig"`` are accepted too).
    source : str
        Where the change comes from, for the error message.

    Returns
    -------
    The same model type, new (the input is frozen and unchanged).

    Raises
    ------
    ParameterError
        Naming each key, its value and what was expected (``supply.supply_pressure:
        2e+08 should be greater than 0 Pa and at most 100 MPa``).
    """
    data = model.model_dump()
    for key, value in changes.items():
        node = data
        *parents, name = key.split(".")
        for part in parents:
            child = node.get(part)
            if not isinstance(child, dict):
                raise ParameterError([Problem(key, value, "is not a known key")], source)
            node = child
        node[name] = value
    root = type(model)
    try:
        return root.model_validate(data, context={"atmospheric_pressure": _atmosphere(model)})
    except ValidationError as exc:
        raise ParameterError(_problems(exc, data, root), source=source) from None


def _atmosphere(model: BaseModel) -> float | None:
    """The atmospheric pressure [Pa] gauge values of an update refer to, if the model has
    one (its gas table)."""
    gas = getattr(model, "gas", None)
    return getattr(gas, "atmospheric_pressure", None)


def _load_raw(
    name_or_path: str | os.PathLike[str], overrides: Iterable[str]
) -> tuple[dict[str, Any], str]:
    path = _resolve(name_or_path)
    raw = apply_overrides(_read_layered(path), overrides)
    return raw, str(path)


def load_actuator(
    name_or_path: str | os.PathLike[str], overrides: Iterable[str] = ()
) -> ActuatorParameters:
    """Load and validate the actuator tables of a parameter file.

    Parameters
    ----------
    name_or_path : str or path-like
        A shipped set name (``"crr-beta"``: no ``.toml`` suffix, no path separator) or
        a path to a TOML file. The ``rig``/``controller``/``simulation`` tables of a
        rig file are ignored.
    overrides : iterable of str
        ``"section.key=value"`` items, see `apply_overrides`.

    Returns
    -------
    ActuatorParameters
        Validated parameters, all SI.

    Raises
    ------
    ParameterError
        Listing every problem found (missing file, TOML syntax, unknown or missing
        keys, wrong units, out-of-range values, failed cross-field checks).
    """
    raw, source = _load_raw(name_or_path, overrides)
    data = {k: v for k, v in raw.items() if k not in _RIG_TABLES}
    return _validate(ActuatorParameters, data, raw, source)


def load_rig(name_or_path: str | os.PathLike[str], overrides: Iterable[str] = ()) -> RigSetup:
    """Load and validate a complete rig parameter file (actuator + rig tables).

    Parameters
    ----------
    name_or_path : str or path-like
        A shipped set name (``"thesis-rig"``) or a path to a TOML file.
    overrides : iterable of str
        ``"section.key=value"`` items, see `apply_overrides`.

    Returns
    -------
    RigSetup
        Validated parameters, all SI.

    Raises
    ------
    ParameterError
        Listing every problem found.
    """
    raw, source = _load_raw(name_or_path, overrides)
    data: dict[str, Any] = {"actuator": {k: v for k, v in raw.items() if k not in _RIG_TABLES}}
    data.update({k: raw[k] for k in _RIG_TABLES if k in raw})
    return _validate(RigSetup, data, raw, source)


def load_robot(
    name_or_path: str | os.PathLike[str], overrides: Iterable[str] = ()
) -> RobotParameters:
    """Load and validate a robot parameter file (``crr-quadruped`` or a path).

    Parameters
    ----------
    name_or_path : str or path-like
        A shipped set name or a path to a TOML file.
    overrides : iterable of str
        ``"section.key=value"`` items, e.g. ``"controller.alpha.gain_scale=0.75"``.

    Returns
    -------
    RobotParameters
        Validated parameters, SI (angles in rad). The actuator sets it names are loaded
        with :func:`load_actuator`.

    Raises
    ------
    ParameterError
        Listing every problem found.
    """
    raw, source = _load_raw(name_or_path, overrides)
    return _validate(RobotParameters, raw, raw, source, _mounted_atmosphere(raw))


def load_parameter_set(
    name_or_path: str | os.PathLike[str], overrides: Iterable[str] = ()
) -> RigSetup | ActuatorParameters | RobotParameters:
    """Load a parameter file of any kind, told by its tables: a robot file (``[leg]`` and
    ``[actuators]``: :func:`load_robot`), a rig file (``[rig]``: :func:`load_rig`) or an
    actuator file (:func:`load_actuator`).

    Raises
    ------
    ParameterError
        Listing every problem found, against the kind of file it is.
    """
    raw, _ = _load_raw(name_or_path, ())
    if "leg" in raw and "actuators" in raw:
        return load_robot(name_or_path, overrides)
    if "rig" in raw:
        return load_rig(name_or_path, overrides)
    return load_actuator(name_or_path, overrides)


def _quantity(annotation: Any, metadata: Iterable[Any] = ()) -> QuantityField | None:
    for item in metadata:
        if isinstance(item, QuantityField):
            return item
    if typing.get_origin(annotation) is typing.Annotated:
        found = _quantity(None, annotation.__metadata__)
        return found or _quantity(typing.get_args(annotation)[0])
    for arg in typing.get_args(annotation):
        found = _quantity(arg)
        if found:
            return found
    return None


def _number(value: Any, digits: int | None) -> Any:
    """``value`` as written: exact (repr) without ``digits``, else a float rounded to that
    many significant digits (conversion noise such as 0.0020000000000000005 removed)."""
    if digits is None or isinstance(value, bool) or not isinstance(value, float):
        return value
    return float(f"{value:.{digits}g}")


def _to_toml_value(value: Any, annotation: Any, metadata: Iterable[Any] = (),
                   digits: int | None = None) -> Any:
    if isinstance(value, BaseModel):
        return _to_toml_dict(value, digits)
    if isinstance(value, dict):
        item_annotation = typing.get_args(annotation)[-1] if typing.get_args(annotation) else None
        return {str(k): _to_toml_value(v, item_annotation, (), digits)
                for k, v in value.items()}
    if isinstance(value, tuple):
        args = [a for a in typing.get_args(annotation) if a is not type(None)]
        if len(args) == 1 and typing.get_origin(args[0]) is tuple:
            args = list(typing.get_args(args[0]))
        items = args if len(args) == len(value) else [None] * len(value)
        return [_to_toml_value(v, a, (), digits) for v, a in zip(value, items, strict=True)]
    if (q := _quantity(annotation, metadata)) is not None:
        return f"{_number(float(value), digits)!r} {q.kind.si_unit}"
    return _number(value, digits)


def _to_toml_dict(model: BaseModel, digits: int | None = None) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for name, field in type(model).model_fields.items():
        value = getattr(model, name)
        if value is None:
            continue
        out[name] = _to_toml_value(value, field.annotation, field.metadata, digits)
    return out


def resolved_parameters_toml(params: RigSetup | ActuatorParameters | RobotParameters,
                             digits: int | None = None) -> str:
    """Write validated parameters back as TOML with explicit SI units.

    Parameters
    ----------
    params : RigSetup or ActuatorParameters
        Validated parameters.
    digits : int, optional
        Round every number to this many significant digits (for reading: unit
        conversions leave noise such as ``0.0020000000000000005 m^3``); by default each
        is written exactly.

    Returns
    -------
    str
        TOML text in the file layout (actuator tables at top level), every dimensional
        value as an SI string such as ``supply_pressure = "448159.22405594354 Pa"``
        (pressures absolute). Without ``digits``, loading it with `load_rig` /
        `load_actuator` gives an equal object.
    """
    data = _to_toml_dict(params, digits)
    if isinstance(params, RigSetup):
        data = {**data.pop("actuator"), **data}
    header = "# Resolved parameters, SI units (pressures absolute); generated by pneumaquad\n"
    if digits is not None:
        header += f"# numbers rounded to {digits} significant digits\n"
    return header + tomli_w.dumps(data)
