"""Component cost table (thesis Table 3 analogue): cases, statistics and the page."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from pneumaquad.params import load_rig
from pneumaquad.reporting import measure_cost_table, write_cost_table_report
from pneumaquad.reporting.cost_report import cost_table_markdown
from pneumaquad.reporting.cost_table import THESIS_TABLE_3, cost_cases
from pneumaquad.reporting.curves import area_curves, input_pressure_curves


@pytest.fixture(scope="module")
def table():
    return measure_cost_table(duration=0.3, repeats=3)


def test_every_case_is_timed(table) -> None:
    names = [row.case for row in table.rows]
    assert names == list(THESIS_TABLE_3)
    complete = table.rows[0]
    assert complete.change_us == 0.0 and complete.change_percent == 0.0
    for row in table.rows:
        assert row.mean_us > 0 and row.std_us >= 0 and row.min_us <= row.mean_us
        assert math.isclose(row.change_percent, 100 * row.change_us / complete.mean_us)
        assert row.rms_error < 0.01  # every case still tracks the sine (m)
    assert table.repeats == 3 and table.steps == 300


def test_report_files(table, tmp_path: Path) -> None:
    page = write_cost_table_report(table, tmp_path)
    text = page.read_text(encoding="utf-8")
    assert "data:image/png;base64," in text and "simple valve: area part only" in text
    document = json.loads((tmp_path / "cost-table.json").read_text())
    assert len(document["rows"]) == 6
    assert cost_table_markdown(table).count("\n") == 8


def test_part_only_cases_replace_one_valve_part() -> None:
    base = load_rig("thesis-rig")
    cases = {case.name: case for case in cost_cases(base)}
    area = load_rig("thesis-rig", list(cases["simple valve: area part only"].overrides))
    pressure = load_rig("thesis-rig", list(cases["simple valve: pressure part only"].overrides))
    simple = base.actuator.valve.simple
    u = np.array([-3.0, -0.5, 0.5, 3.0])
    for curve in area_curves(area.actuator.valve, u):  # linear cd·A of the simple valve
        cd = (
            simple.cap_discharge_coefficient
            if curve.chamber == "cap"
            else simple.rod_discharge_coefficient
        )
        expected = cd * (
            simple.max_area * np.abs(curve.voltage) / simple.full_scale_voltage + simple.leak_area
        )
        np.testing.assert_allclose(curve.area, expected, rtol=1e-12)
    # tanh pressures untouched by the area case, switched at the offset by the pressure case
    for kept, base_curve in zip(
        input_pressure_curves(area.actuator, u),
        input_pressure_curves(base.actuator, u),
        strict=True,
    ):
        np.testing.assert_allclose(kept.pressure, base_curve.pressure)
    supply = base.actuator.supply
    cap, rod = input_pressure_curves(pressure.actuator, u)
    np.testing.assert_allclose(
        cap.pressure, np.where(u > 0, supply.supply_pressure, supply.exhaust_pressure), rtol=1e-9
    )
    np.testing.assert_allclose(
        rod.pressure, np.where(u > 0, supply.exhaust_pressure, supply.supply_pressure), rtol=1e-9
    )


def test_too_few_repeats() -> None:
    with pytest.raises(ValueError, match="repeats"):
        measure_cost_table(repeats=1)
