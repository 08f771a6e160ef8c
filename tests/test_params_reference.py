"""The parameter reference generated from the schema (pneumaquad.params.reference,
docs/parameters.md): every field of every model, with unit, range, default, meaning and
thesis source."""

from __future__ import annotations

import inspect
import json
from pathlib import Path

import pytest
from pydantic import BaseModel

from pneumaquad.params import reference, robot_schema, schema
from pneumaquad.params.fields import PositiveLength, described
from pneumaquad.params.reference import (
    REFERENCE_MARKER,
    insert_reference,
    parameter_reference,
    reference_rows,
)

DOCS = Path(__file__).resolve().parents[1] / "docs"


def _schema_models() -> list[type[BaseModel]]:
    """Every parameter model the two schema modules define (their public classes)."""
    models = []
    for module in (schema, robot_schema):
        for name, value in inspect.getmembers(module, inspect.isclass):
            if (issubclass(value, BaseModel) and value.__module__ == module.__name__
                    and not name.startswith("_")):
                models.append(value)
    return models


def test_every_field_of_every_model_has_a_complete_row() -> None:
    rows = reference_rows()
    models = _schema_models()
    assert len(models) >= 25
    for model in models:
        # a base class of file tables (ControllerParameters) is covered by its subclasses
        shown = [m for m in rows if issubclass(m, model)]
        assert shown, f"{model.__name__} is not reachable from a parameter file"
        for shown_model in shown:
            names = [row.name for row in rows[shown_model]]
            assert names == list(shown_model.model_fields), shown_model.__name__
            assert set(model.model_fields) <= set(names), model.__name__
    for model, model_rows in rows.items():
        for row in model_rows:
            where = f"{model.__name__}.{row.name}"
            assert row.unit and row.allowed and row.default, where
            assert row.description and row.source, where


def test_the_markdown_has_one_row_per_field_under_its_model() -> None:
    markdown = parameter_reference()
    sections = markdown.split("{#model-")
    by_anchor = {part.split("}", 1)[0]: part for part in sections[1:]}
    for model, rows in reference_rows().items():
        section = by_anchor[model.__name__.lower()]
        for row in rows:
            assert f"| `{row.name}` |" in section, f"{model.__name__}.{row.name}"


def test_units_ranges_defaults_and_sources_read_from_the_models() -> None:
    rows = {(row.model.__name__, row.name): row
            for model_rows in reference_rows().values() for row in model_rows}
    bore = rows["CylinderParameters", "bore"]
    assert (bore.unit, bore.allowed, bore.default) == ("m", "(0, 10]", "required")
    assert "App. B.1.1 l.45" in bore.source
    supply = rows["SupplyParameters", "supply_pressure"]
    assert (supply.unit, supply.allowed) == ("Pa", "(0, 100 MPa]")
    assert rows["GasParameters", "specific_heat_cp"].unit == "J/(kg·K)"
    assert rows["GasParameters", "heat_capacity_ratio"].unit == "dimensionless"
    assert rows["SupplyParameters", "tank_volume"].default == "optional"
    iterations = rows["RobotSimulationParameters", "solver_iterations"]
    assert (iterations.unit, iterations.allowed, iterations.default) == (
        "integer", "[1, 10000]", "`50`")
    cone = rows["ContactParameters", "friction_cone"]
    assert cone.allowed == '`"elliptic"`, `"pyramidal"`' and cone.default == '`"elliptic"`'
    polynomial = rows["ValvePortParameters", "area_positive"]
    assert polynomial.unit == "list of 5, m²/Vⁿ (a plain number)"
    assert polynomial.allowed == "[-0.001, 0.001]"
    mounts = rows["RobotParameters", "mounts"]
    assert mounts.nested is robot_schema.Frame and "`front_left`" in mounts.allowed


def test_a_field_without_unit_description_or_source_is_refused() -> None:
    class NoUnit(BaseModel):
        length: float = described("A length.", "eq 1")

    class NoDescription(BaseModel):
        length: PositiveLength

    class NoSource(BaseModel):
        length: PositiveLength = described("A length.", " ")

    for model, message in ((NoUnit, "NoUnit.length: its unit cannot be told"),
                           (NoDescription, "NoDescription.length has no description"),
                           (NoSource, "NoSource.length has no thesis source")):
        with pytest.raises(ValueError, match=message):
            reference._row(model, "length", model.model_fields["length"])


def test_the_json_schema_has_meaning_range_and_source() -> None:
    properties = schema.CylinderParameters.model_json_schema()["properties"]
    assert properties["stroke"]["description"] == (
        "Piston stroke; finite, greater than 0 m and at most 10 m")
    assert properties["stroke"]["source"].startswith("App. B.1.1 l.46")
    json.dumps(robot_schema.RobotParameters.model_json_schema())


def test_the_parameters_page_gets_the_reference_at_its_marker() -> None:
    page = (DOCS / "parameters.md").read_text(encoding="utf-8")
    built = insert_reference(page)
    assert REFERENCE_MARKER not in built
    assert built.startswith(page.split(REFERENCE_MARKER)[0])
    assert "## Robot files" in built and "`[linkages.{alpha, beta, gamma}]`" in built
    with pytest.raises(ValueError, match="marker once"):
        insert_reference("# no marker here")
