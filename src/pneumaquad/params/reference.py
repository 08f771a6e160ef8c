"""The parameter reference: every key of the parameter files, rendered from the schema.

The pydantic models of :mod:`pneumaquad.params.schema` (actuator and rig files) and
:mod:`pneumaquad.params.robot_schema` (robot files) are the one statement of what a file
holds. Each field carries its meaning and its source in the thesis (``described`` in the
schema); its unit, range and default are read from its type. :func:`reference_rows` walks
the models and returns one :class:`ReferenceRow` per field, :func:`parameter_reference`
renders them as the Markdown tables of docs/parameters.md (the documentation site builds
that page with it). A field whose unit cannot be told from its type, or that has no
description or no source, is refused with its model and name, so the reference cannot
silently miss one.

Run ``python -m pneumaquad.params.reference`` to print the tables.
"""

from __future__ import annotations

import re
import types
import typing
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any, Literal

from pydantic import BaseModel
from pydantic.fields import FieldInfo
from pydantic_core import PydanticUndefined

from .fields import Bounds, NumberField, QuantityField
from .robot_schema import RobotParameters
from .schema import ActuatorParameters, RigSetup

__all__ = [
    "FILE_KINDS",
    "REFERENCE_MARKER",
    "FileKind",
    "ReferenceRow",
    "field_source",
    "insert_reference",
    "parameter_reference",
    "pretty_unit",
    "reference_rows",
]

#: The line of docs/parameters.md that the generated reference replaces.
REFERENCE_MARKER = (
    "<!-- parameter reference: generated here from the schema (pneumaquad.params.reference) -->"
)


@dataclass(frozen=True)
class FileKind:
    """One kind of parameter file: its root model and how its keys are written.

    Attributes
    ----------
    title : str
        Heading of its part of the reference (``"Actuator files"``).
    model : type of BaseModel
        The model a file of this kind validates into.
    flattened : tuple of str
        Fields of ``model`` whose tables sit at the top level of the file (a rig file's
        ``actuator``: its ``gas``, ``supply`` ... tables are written without a prefix).
    intro : str
        A sentence on which files these are.
    """

    title: str
    model: type[BaseModel]
    flattened: tuple[str, ...] = ()
    intro: str = ""


#: The parameter files, in the order the reference shows them.
FILE_KINDS: tuple[FileKind, ...] = (
    FileKind("Actuator files", ActuatorParameters, (),
             "One valve + cylinder actuator: the robot's joint files `crr-alpha`, "
             "`crr-beta`, `crr-gamma` (`load_actuator`), and the actuator tables of a rig "
             "file."),
    FileKind("Rig files", RigSetup, ("actuator",),
             "The single-DoF test rig, `thesis-rig` (`load_rig`): the actuator tables above "
             "at the top level of the file, and the rig's own tables."),
    FileKind("Robot files", RobotParameters, (),
             "The quadruped, `crr-quadruped` (`load_robot`); its actuators come from the "
             "actuator files named in `[actuators]`."),
)


@dataclass(frozen=True)
class ReferenceRow:
    """One field of a parameter model as the reference shows it.

    Attributes
    ----------
    model : type of BaseModel
        The model that declares the field.
    name : str
        The field's name, the key inside its table.
    unit : str
        SI unit of the stored value (``"Pa"``, ``"m²"``), or what else the value is
        (``"dimensionless"``, ``"integer"``, ``"choice"``, ``"true/false"``, ``"text"``,
        ``"table"``); ``"list of 3, m"`` for a list.
    allowed : str
        Its range (``"(0 m, 10 m]"``), its choices, or ``"—"``.
    default : str
        Its default as written in a file, ``"required"``, or ``"optional"`` (absent
        unless given).
    description : str
        What it is (the field's ``description``).
    source : str
        Where it comes from in the thesis, or why it is not there.
    nested : type of BaseModel or None
        For a table, the model of its keys.
    """

    model: type[BaseModel]
    name: str
    unit: str
    allowed: str
    default: str
    description: str
    source: str
    nested: type[BaseModel] | None = None


_SUPERSCRIPTS = {"^2": "²", "^3": "³", "^n": "ⁿ"}


def pretty_unit(unit: str) -> str:
    """A unit as printed in the reference: ``"J/(kg*K)"`` → ``"J/(kg·K)"``, ``"m^2"`` →
    ``"m²"``."""
    for plain, superscript in _SUPERSCRIPTS.items():
        unit = unit.replace(plain, superscript)
    return unit.replace("*", "·")


def field_source(field: FieldInfo) -> str | None:
    """The thesis source of a field (its ``json_schema_extra["source"]``), None without."""
    extra = field.json_schema_extra
    source = extra.get("source") if isinstance(extra, dict) else None
    return source if isinstance(source, str) and source.strip() else None


@dataclass
class _Type:
    unit: str
    allowed: str = "—"
    nested: type[BaseModel] | None = None
    keys: tuple[Any, ...] = ()


def _flatten(annotation: Any, metadata: Sequence[Any]) -> tuple[Any, list[Any]]:
    """The bare type under any ``Annotated`` layers, and every marker found on the way."""
    found = list(metadata)
    while typing.get_origin(annotation) is typing.Annotated:
        found.extend(annotation.__metadata__)
        annotation = typing.get_args(annotation)[0]
    return annotation, found


def _range(bounds: Bounds) -> str:
    """``(0, 10]``: the range in the field's unit (shown in its own column), an end
    written with another unit keeping it (``(0, 100 MPa]``)."""
    lower = "(" if not bounds.lower_inclusive or bounds.lower is None else "["
    upper = ")" if not bounds.upper_inclusive or bounds.upper is None else "]"
    ends = []
    for text, infinite in ((bounds.lower_text, "−∞"), (bounds.upper_text, "∞")):
        if text is None:
            ends.append(infinite)
        else:
            ends.append(text.removesuffix(f" {bounds.unit}") if bounds.unit else text)
    return pretty_unit(f"{lower}{ends[0]}, {ends[1]}{upper}")


def _literal_text(value: Any) -> str:
    return f'`"{value}"`' if isinstance(value, str) else f"`{value}`"


def _type_of(annotation: Any, metadata: Sequence[Any], where: str) -> _Type:
    bare, markers = _flatten(annotation, metadata)
    origin = typing.get_origin(bare)
    if origin in (typing.Union, types.UnionType):
        arms = [arm for arm in typing.get_args(bare) if arm is not type(None)]
        if len(arms) != 1:
            raise ValueError(f"{where}: cannot describe the union {bare!r}")
        return _type_of(arms[0], markers, where)
    if origin is tuple:
        items = typing.get_args(bare)
        inner = _type_of(items[0], markers, where)
        if any(_type_of(item, (), where) != _type_of(items[0], (), where)
               for item in items[1:]):
            raise ValueError(f"{where}: list items of different kinds")
        return _Type(f"list of {len(items)}, {inner.unit}", inner.allowed)
    if origin is dict:
        key_type, value_type = typing.get_args(bare)
        keys = typing.get_args(key_type) if typing.get_origin(key_type) is Literal else ()
        inner = _type_of(value_type, (), where)
        if inner.nested is None or not keys:
            raise ValueError(f"{where}: only tables keyed by fixed names are described")
        return _Type("table", "one per key: " + ", ".join(f"`{k}`" for k in keys),
                     inner.nested, keys)
    if origin is Literal:
        return _Type("choice", ", ".join(_literal_text(v) for v in typing.get_args(bare)))
    if isinstance(bare, type) and issubclass(bare, BaseModel):
        return _Type("table", nested=bare)
    bounds = next((m for m in markers if isinstance(m, Bounds)), None)
    allowed = _range(bounds) if bounds is not None else "—"
    if bare is bool:
        return _Type("true/false", "`true`, `false`")
    if bare is int:
        return _Type("integer", allowed)
    if bare is str:
        return _Type("text")
    if bare is float:
        quantity = next((m for m in markers if isinstance(m, QuantityField)), None)
        if quantity is not None:
            return _Type(pretty_unit(quantity.kind.si_unit), allowed)
        if any(isinstance(m, NumberField) for m in markers):
            if bounds is not None and bounds.unit:  # a plain number in a stated unit
                return _Type(f"{pretty_unit(bounds.unit)} (a plain number)", allowed)
            return _Type("dimensionless", allowed)
    raise ValueError(f"{where}: its unit cannot be told from its type {bare!r}; "
                     "use a quantity type (a unit) or Number (dimensionless)")


def _default_text(field: FieldInfo, kind: _Type) -> str:
    default = field.default
    if default is PydanticUndefined:
        return "required"
    if default is None:
        return "optional"
    if isinstance(default, bool):
        return f"`{str(default).lower()}`"
    if isinstance(default, str):
        return f'`"{default}"`'
    if isinstance(default, tuple):
        return "`[" + ", ".join(f"{v:g}" for v in default) + "]`"
    if isinstance(default, float) and kind.unit not in ("dimensionless", "integer"):
        return f"{default:g} {kind.unit}"
    return f"{default:g}" if isinstance(default, float) else f"`{default}`"


def _row(model: type[BaseModel], name: str, field: FieldInfo) -> ReferenceRow:
    where = f"{model.__name__}.{name}"
    kind = _type_of(field.annotation, field.metadata, where)
    description = (field.description or "").strip()
    source = field_source(field)
    if not description:
        raise ValueError(f"{where} has no description")
    if source is None:
        raise ValueError(f"{where} has no thesis source (json_schema_extra['source'])")
    return ReferenceRow(model, name, kind.unit, kind.allowed, _default_text(field, kind),
                        description, source, kind.nested)


def _walk(model: type[BaseModel], path: tuple[str, ...], flattened: tuple[str, ...],
          ) -> Iterator[tuple[type[BaseModel], tuple[str, ...]]]:
    """Every model under ``model`` (itself first) with the file path of its table."""
    yield model, path
    for name, field in model.model_fields.items():
        kind = _type_of(field.annotation, field.metadata, f"{model.__name__}.{name}")
        if kind.nested is None:
            continue
        if not path and name in flattened:
            yield from _walk(kind.nested, (), ())
            continue
        steps = (name, "{" + ", ".join(map(str, kind.keys)) + "}") if kind.keys else (name,)
        yield from _walk(kind.nested, (*path, *steps), ())


def _merge_paths(paths: list[tuple[str, ...]]) -> list[tuple[str, ...]]:
    """Paths that differ in one place written once: ``leg.{alpha, beta}.child_frame``."""
    merged = list(dict.fromkeys(paths))
    changed = True
    while changed:
        changed = False
        for position in range(max((len(p) for p in merged), default=0)):
            groups: dict[tuple[Any, ...], list[tuple[str, ...]]] = {}
            for path in merged:
                if len(path) > position:
                    groups.setdefault((len(path), path[:position], path[position + 1:]),
                                      []).append(path)
            for group in groups.values():
                if len(group) > 1:
                    parts = []
                    for p in group:
                        part = p[position]
                        parts.extend(part[1:-1].split(", ") if part.startswith("{")
                                     else [part])
                    joined = "{" + ", ".join(dict.fromkeys(parts)) + "}"
                    first = merged.index(group[0])
                    merged = [p for p in merged if p not in group]
                    merged.insert(first, (*group[0][:position], joined,
                                          *group[0][position + 1:]))
                    changed = True
                    break
            if changed:
                break
    return merged


def reference_rows() -> dict[type[BaseModel], list[ReferenceRow]]:
    """One row per field of every model the parameter files are made of.

    Returns
    -------
    dict of model to list of ReferenceRow
        Each model met under :data:`FILE_KINDS` once, in the order first met, with its
        fields in declaration order.

    Raises
    ------
    ValueError
        For a field whose unit cannot be told from its type or that lacks a description
        or a source, naming the model and the field.
    """
    rows: dict[type[BaseModel], list[ReferenceRow]] = {}
    for kind in FILE_KINDS:
        for model, _ in _walk(kind.model, (), kind.flattened):
            if model not in rows:
                rows[model] = [_row(model, name, field)
                               for name, field in model.model_fields.items()]
    return rows


def _anchor(model: type[BaseModel]) -> str:
    return f"model-{model.__name__.lower()}"


def _cell(text: str) -> str:
    return " ".join(text.split()).replace("|", "\\|")


def _table(rows: list[ReferenceRow]) -> list[str]:
    lines = ["| key | unit | range | default | meaning | thesis source |",
             "|---|---|---|---|---|---|"]
    for row in rows:
        unit = row.unit
        if row.nested is not None:
            unit = f"[table](#{_anchor(row.nested)})"
        lines.append(f"| `{row.name}` | {unit} | {_cell(row.allowed)} | {row.default} | "
                     f"{_cell(row.description)} | {_cell(row.source)} |")
    return lines


_ROLE = re.compile(r":\w+:`(?P<tilde>~?)(?P<name>[^`<]+?)(?:\s*<[^`>]*>)?`")


def _role_text(match: re.Match[str]) -> str:
    name = match["name"].strip()
    return f"`{name.rsplit('.', 1)[-1] if match['tilde'] else name}`"


def _doc_summary(model: type[BaseModel]) -> str:
    """The first paragraph of a model's docstring, Sphinx roles shown as code."""
    doc = (model.__doc__ or "").strip().split("\n\n")[0]
    return _ROLE.sub(_role_text, " ".join(doc.split()))


def parameter_reference(heading_level: int = 2) -> str:
    """The parameter reference as Markdown: per file kind, one table per model.

    Parameters
    ----------
    heading_level : int
        Level of the file kinds' headings (the tables' are one deeper).

    Returns
    -------
    str
        Markdown: for each of :data:`FILE_KINDS` a heading, a sentence and its tables
        (the file's top-level keys first), each row a key with its unit, range, default,
        meaning and thesis source; a table's heading names where it sits in the file and
        carries the anchor ``model-<class name>``.

    Raises
    ------
    ValueError
        As :func:`reference_rows`.
    """
    rows = reference_rows()
    paths: dict[type[BaseModel], list[tuple[str, ...]]] = {}
    for kind in FILE_KINDS:
        for model, path in _walk(kind.model, (), kind.flattened):
            paths.setdefault(model, []).append(path)
    top, sub = "#" * heading_level, "#" * (heading_level + 1)
    lines: list[str] = []
    rendered: set[type[BaseModel]] = set()
    for kind in FILE_KINDS:
        lines += [f"{top} {kind.title}", "", kind.intro, ""]
        for model, path in _walk(kind.model, (), kind.flattened):
            if model in rendered:
                continue
            rendered.add(model)
            where = [p for p in _merge_paths(paths[model]) if p]
            if not path:
                title = "Top-level tables"
            else:
                title = ", ".join(f"`[{'.'.join(p)}]`" for p in where)
            lines += [f"{sub} {title} {{#{_anchor(model)}}}", "",
                      f"{_doc_summary(model)} (`{model.__module__}.{model.__name__}`)", ""]
            lines += _table(rows[model])
            lines.append("")
    return "\n".join(lines)


def insert_reference(markdown: str) -> str:
    """A page with its :data:`REFERENCE_MARKER` line replaced by the reference.

    Parameters
    ----------
    markdown : str
        The page's Markdown (docs/parameters.md), holding the marker line once.

    Returns
    -------
    str
        The page with :func:`parameter_reference` in place of the marker.

    Raises
    ------
    ValueError
        When the page does not hold the marker exactly once.
    """
    count = markdown.count(REFERENCE_MARKER)
    if count != 1:
        raise ValueError(f"the page should hold the parameter reference marker once, "
                         f"not {count} times: {REFERENCE_MARKER}")
    return markdown.replace(REFERENCE_MARKER, parameter_reference())


if __name__ == "__main__":  # pragma: no cover - prints the reference
    print(parameter_reference())
