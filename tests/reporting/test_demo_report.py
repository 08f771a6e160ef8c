"""The demo report is written by the one HTML page builder (reporting.html.HtmlPage), in SI
units: its sections give SI key figures and draw in the report's units."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

from pneumaquad.demo.run import DemoReport, _reference_solver, _spacer, _tank
from pneumaquad.reporting.display_units import display_units

from .conftest import assert_only_units, figure_texts, page_text


def test_demo_report_sections_escape_and_embed(tmp_path: Path) -> None:
    figure, axes = plt.subplots()
    axes.plot([0.0, 1.0])
    figure.savefig(tmp_path / "plot.png")
    plt.close(figure)
    report = DemoReport(tmp_path)
    report.add("Step <6 V>", "pressures & position", tmp_path / "plot.png",
               {"rise time [s]": 0.123456, "runs": 3})
    page = report.write().read_text(encoding="utf-8")
    assert "<h2>Step &lt;6 V&gt;</h2>" in page and "pressures &amp; position" in page
    assert "0.1235" in page and "data:image/png;base64," in page
    markdown = (tmp_path / "report.md").read_text(encoding="utf-8")
    assert "| rise time [s] | 0.1235 |" in markdown and "![Step <6 V>](plot.png)" in markdown


def test_demo_report_shows_si_key_figures_in_its_units(tmp_path: Path) -> None:
    figures = {"settled [Pa]": 448_159.4, "RMSE [mm]": 0.5, "position RMSE [µm]": 25.4,
               "cap pressure RMSE [Pa]": 6894.757293168361, "lag [s]": 0.02}
    shown = {}
    for system in ("si", "us"):
        folder = tmp_path / system
        folder.mkdir()
        figure = plt.figure()
        figure.savefig(folder / "plot.png")
        plt.close(figure)
        report = DemoReport(folder, display_units(system))
        report.add("Section", "text", folder / "plot.png", figures)
        report.write()
        shown[system] = (folder / "report.md").read_text(encoding="utf-8")
    for row in ("| settled [kPa abs] | 448.2 |", "| RMSE [mm] | 0.5 |",
                "| position RMSE [µm] | 25.4 |", "| cap pressure RMSE [kPa] | 6.895 |",
                "| lag [s] | 0.02 |"):
        assert row in shown["si"]
    for row in ("| settled [psia] | 65 |", "| RMSE [in] | 0.01969 |",
                "| position RMSE [0.001 in] | 1 |", "| cap pressure RMSE [psi] | 1 |"):
        assert row in shown["us"]


def test_demo_rig_sections_draw_and_tell_in_si(tmp_path: Path, drawn: list) -> None:
    report = DemoReport(tmp_path)  # the demo's units: SI
    for section in (_spacer, _reference_solver, _tank):
        section(tmp_path, report)
    page = report.write()
    assert len(drawn) >= 3
    assert_only_units("si", [t for f in drawn for t in figure_texts(f)], "the figures")
    assert_only_units("si", [page_text(page)], "the page")
