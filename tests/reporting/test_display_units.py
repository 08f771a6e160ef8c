"""One display-unit choice per report: SI (default) or the thesis's US units, for every
figure, table and text; the conversions themselves are exact."""

from __future__ import annotations

import shutil
from pathlib import Path

import matplotlib
import numpy as np
import pytest
from matplotlib.figure import Figure

from pneumaquad.io.run_folder import RunFolderWriter, read_recording
from pneumaquad.params import load_rig
from pneumaquad.reporting import build_run_report
from pneumaquad.reporting.display_units import (
    KINDS,
    UNIT_SYSTEMS,
    DisplayUnits,
    display_units,
)

from .conftest import assert_only_units, figure_texts, page_text, write_measured_csv

matplotlib.use("Agg")

US, SI = display_units("us"), display_units("si")
PSI = 6894.757293168361  # Pa: 1 lbf / in², both exact by definition (1959)
LBF = 4.4482216152605  # N

# --- the conversions -------------------------------------------------------------------

def test_lengths_forces_and_pressures_convert_exactly() -> None:
    assert US.value(0.0254, "length") == pytest.approx(1.0, rel=1e-15)
    assert US.value(0.0254, "small length") == pytest.approx(1.0, rel=1e-15)
    assert US.value(2.54e-5, "tiny length") == pytest.approx(1.0, rel=1e-12)
    assert US.value(LBF, "force") == pytest.approx(1.0, rel=1e-15)
    assert US.value(PSI, "pressure difference") == pytest.approx(1.0, rel=1e-12)
    assert US.value(6894.757, "pressure difference") == pytest.approx(1.0, abs=1e-7)
    assert US.value(0.0254, "velocity") == pytest.approx(1.0)
    assert US.value(0.0254**2, "area") == pytest.approx(1.0)
    assert US.value(0.0254**2, "small area") == pytest.approx(1000.0)
    assert SI.value(0.0254, "length") == 0.0254
    assert SI.value(0.0254, "small length") == pytest.approx(25.4)
    assert SI.value(448_159.4, "pressure") == pytest.approx(448.1594)
    assert SI.value(1e-6, "area") == pytest.approx(1.0)  # mm²
    values = np.array([0.0, 0.01, 0.0445])
    np.testing.assert_allclose(US.value(values, "length"), values / 0.0254, rtol=1e-15)


def test_gauge_pressures_subtract_the_atmosphere() -> None:
    standard = US  # 101 325 Pa unless a run's parameters say otherwise
    assert standard.atmosphere == 101_325.0
    assert standard.value(101_325.0 + PSI, "gauge pressure") == pytest.approx(1.0, rel=1e-12)
    assert standard.value(101_325.0 + PSI, "pressure") == pytest.approx(1.0 + 101_325.0 / PSI)
    # the shipped parameter sets use 14.7 psia (App. B.1.1): 65 psia reads 50.3 psig
    atmosphere = load_rig("thesis-rig").actuator.gas.atmospheric_pressure
    assert atmosphere == pytest.approx(14.7 * PSI)
    thesis = US.with_atmosphere(atmosphere)
    assert thesis.value(65.0 * PSI, "gauge pressure") == pytest.approx(50.3, rel=1e-12)
    assert thesis.value(65.0 * PSI, "pressure") == pytest.approx(65.0, rel=1e-12)
    assert SI.with_atmosphere(atmosphere).value(atmosphere + 2e5, "gauge pressure") == (
        pytest.approx(200.0))


@pytest.mark.parametrize("system", UNIT_SYSTEMS)
@pytest.mark.parametrize("kind", sorted(KINDS))
def test_every_kind_converts_back(system: str, kind: str) -> None:
    units = display_units(system, atmosphere=98_000.0)
    si = np.array([-3.5, 0.02, 7.0e5])
    np.testing.assert_allclose(units.si(units.value(si, kind), kind), si, rtol=1e-12,
                               atol=1e-9)
    assert units.unit(kind)


def test_keys_say_their_unit_in_the_system() -> None:
    assert US.key("max cap pressure [Pa]", 65.0 * PSI) == ("max cap pressure [psia]",
                                                            pytest.approx(65.0))
    assert US.key("cap pressure RMSE [Pa]", PSI) == ("cap pressure RMSE [psi]",
                                                      pytest.approx(1.0))
    assert US.key("rmse [m]", 0.0254) == ("rmse [in]", pytest.approx(1.0))
    assert US.key("RMSE [mm]", 25.4) == ("RMSE [in]", pytest.approx(1.0))
    assert US.key("air per metre [NL/m]", 1.0) == ("air per metre [NL/in]",
                                                    pytest.approx(0.0254))
    assert SI.key("final cap pressure [Pa]", 2e5) == ("final cap pressure [kPa abs]", 200.0)
    assert SI.key("rmse [m]", 1e-4) == ("rmse [m]", 1e-4)
    for key in ("angle rmse [deg]", "air consumed [NL]", "lag [s]", "cases", "x [m] y"):
        assert US.key(key, 1.5) == (key, 1.5)
    assert US.key("stroke [m]", "text") == ("stroke [in]", "text")  # no number: unit only
    assert US.error(0.001, "m") == (pytest.approx(0.001 / 0.0254), "in")
    assert SI.error(0.001, "m") == (pytest.approx(1.0), "mm")
    assert SI.error(500.0, "Pa") == (pytest.approx(0.5), "kPa")
    assert SI.error(0.1, "V") == (0.1, "V")


def test_unknown_systems_and_kinds_are_refused() -> None:
    with pytest.raises(ValueError, match="si, us"):
        display_units("imperial")
    with pytest.raises(KeyError, match="unknown quantity kind 'furlongs'"):
        SI.value(1.0, "furlongs")
    assert display_units(US) is US and display_units(None) == SI
    assert isinstance(display_units("US"), DisplayUnits)


# --- whole reports ---------------------------------------------------------------------

@pytest.mark.parametrize("system", UNIT_SYSTEMS)
def test_a_rig_report_against_measured_data_shows_one_system(
    system: str, rig_run: Path, tmp_path: Path, drawn: list[Figure]
) -> None:
    csv, mapping = write_measured_csv(read_recording(rig_run), tmp_path / "lab", shift=0.01)
    report = build_run_report(rig_run, tmp_path / system, csv, mapping, -0.01, units=system)
    assert len(drawn) >= 6  # rig, friction, areas, input pressures, overlay, error
    assert_only_units(system, [t for f in drawn for t in figure_texts(f)], "the figures")
    assert_only_units(system, [page_text(report)], "the page")
    # the numbers are converted, not only the labels
    position = read_recording(rig_run)["position [m]"]
    axis = next(a for f in drawn for a in f.axes if a.get_ylabel().startswith("Position (")
                and a.get_lines() and len(a.get_lines()[0].get_ydata()) == position.size)
    scale = 1 / 0.0254 if system == "us" else 1000.0
    np.testing.assert_allclose(axis.get_lines()[0].get_ydata(), position * scale, rtol=1e-12)
    page = report.read_text(encoding="utf-8")
    rows = {"us": ("<td>supply pressure</td><td class='num'>65</td><td>psia</td>",
                   "<td>supply pressure, gauge</td><td class='num'>50.3</td><td>psig</td>",
                   "<td>stroke</td><td class='num'>1.75</td><td>in</td>"),
            "si": ("<td>supply pressure</td><td class='num'>448.16</td><td>kPa abs</td>",
                   "<td>supply pressure, gauge</td><td class='num'>346.81</td>"
                   "<td>kPa gauge</td>",
                   "<td>stroke</td><td class='num'>0.04445</td><td>m</td>")}
    for row in rows[system]:
        assert row in page


@pytest.fixture
def walk_like_run(robot_run: Path, tmp_path: Path) -> Path:
    """The robot run with a walk's judgement and walking.png beside it (a real walk takes
    longer than this test should)."""
    folder = tmp_path / "walk"
    shutil.copytree(robot_run, folder, ignore=shutil.ignore_patterns("report"))
    RunFolderWriter(folder).update_summary({"walking": {
        "success": True, "reasons": ["reached the distance"],
        "distance travelled [m]": 0.3048, "smallest tip-over margin [m]": 0.0254,
        "air per metre [NL/m]": 6.0, "stance": {"verified": True}}})
    Figure().savefig(folder / "walking.png")
    return folder


@pytest.mark.parametrize("system", UNIT_SYSTEMS)
def test_a_robot_report_shows_one_system(
    system: str, walk_like_run: Path, tmp_path: Path, drawn: list[Figure]
) -> None:
    report = build_run_report(walk_like_run, tmp_path / system, units=system)
    walking = [f for f in drawn if any(a.get_ylabel().startswith("Static margin")
                                       for a in f.axes)]
    # SI: the run's own walking.png (drawn in SI); US: drawn again in inches
    assert len(walking) == (1 if system == "us" else 0)
    assert_only_units(system, [t for f in drawn for t in figure_texts(f)], "the figures")
    assert_only_units(system, [page_text(report)], "the page")
    page = report.read_text(encoding="utf-8")
    travelled = {"us": "<td>distance travelled [in]</td><td class='num'>12</td>",
                 "si": "<td>distance travelled [m]</td><td class='num'>0.3048</td>"}
    assert travelled[system] in page
