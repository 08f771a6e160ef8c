"""Run reports: one self-contained HTML file with the parameters, metrics and figures."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from pneumaquad.io.run_folder import RunFolderError, detect_run_kind
from pneumaquad.reporting import build_run_report, load_run_folder
from pneumaquad.reporting.display_units import SI
from pneumaquad.reporting.html import format_value
from pneumaquad.reporting.parameters import flatten_summary
from pneumaquad.reporting.run_folder import ReportError

from .conftest import RIG_DESCRIPTION


def _images(text: str) -> list[str]:
    return re.findall(r"<img [^>]*src='([^']*)'", text)


def _metric_cells(summary: dict) -> list[str]:
    """The summary's numbers as an SI report shows them (pressures in kPa)."""
    return [
        format_value(value, 6)
        for _, value in SI.rows(flatten_summary(summary))
        if isinstance(value, (int, float)) and not isinstance(value, bool)
    ]


@pytest.fixture(scope="module")
def rig_report(rig_run: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    return build_run_report(rig_run, tmp_path_factory.mktemp("reports") / "rig")


@pytest.fixture(scope="module")
def robot_report(robot_run: Path) -> Path:
    return build_run_report(robot_run)  # default folder: RUN/report


def test_rig_report_is_one_self_contained_file(rig_report: Path) -> None:
    text = rig_report.read_text(encoding="utf-8")
    images = _images(text)
    assert len(images) >= 4  # time histories, friction, areas, input pressures
    assert all(src.startswith("data:image/png;base64,") for src in images)
    assert "<link" not in text and "<script" not in text
    for name in ("rig.png", "friction.png", "valve-area.png", "input-pressure.png"):
        assert (rig_report.parent / name).stat().st_size > 1000


def test_rig_report_holds_parameters_and_every_metric(rig_run: Path, rig_report: Path) -> None:
    text = rig_report.read_text(encoding="utf-8")
    summary = json.loads((rig_run / "summary.json").read_text())
    for cell in _metric_cells(summary):
        assert f">{cell}<" in text
    # SI by default (tests/reporting/test_display_units.py: both systems); supply App. B.1.1
    assert "<td>supply pressure, gauge</td><td class='num'>346.81</td>" in text
    assert "<td>stroke</td><td class='num'>0.04445</td><td>m</td>" in text
    assert "stribeck_tanh" in text and "underlapped" in text
    assert "Kp" in text


def test_rig_report_escapes_text(rig_report: Path) -> None:
    text = rig_report.read_text(encoding="utf-8")
    assert RIG_DESCRIPTION not in text
    assert "<b>bold</b>" not in text
    assert "step train &lt;b&gt;bold&lt;/b&gt; &amp; &quot;quoted&quot;" in text


def test_robot_report_plots_commanded_joints_and_masses(
    robot_run: Path, robot_report: Path
) -> None:
    assert robot_report == robot_run / "report" / "report.html"
    text = robot_report.read_text(encoding="utf-8")
    assert (robot_report.parent / "joints-front_right.png").is_file()
    assert not (robot_report.parent / "body.png").exists()  # fixed thorax: no body plot
    assert all(src.startswith("data:image/png;base64,") for src in _images(text))
    summary = json.loads((robot_run / "summary.json").read_text())
    for cell in _metric_cells(summary):
        assert f">{cell}<" in text
    assert "angle rmse [deg] / front_right_gamma" in text
    assert "mass (model.xml)" in text and "whole model" in text
    assert "crr-gamma" in text and "implicitfast" in text
    assert "Actuator of the" in text


def test_run_kind_comes_from_the_tables(rig_run: Path, robot_run: Path) -> None:
    assert load_run_folder(rig_run).kind == "rig"
    robot = load_run_folder(robot_run)
    assert robot.kind == "robot" and set(robot.actuators) == {"alpha", "beta", "gamma"}
    with pytest.raises(RunFolderError, match="neither"):
        detect_run_kind({"meta": {}})


def test_missing_and_broken_folders(tmp_path: Path, rig_run: Path) -> None:
    with pytest.raises(ReportError, match=re.escape(str(tmp_path / "nope"))):
        load_run_folder(tmp_path / "nope")
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(ReportError, match=r"no parameters\.toml"):
        load_run_folder(empty)
    partial = tmp_path / "partial"
    partial.mkdir()
    (partial / "parameters.toml").write_text((rig_run / "parameters.toml").read_text())
    with pytest.raises(ReportError, match="no recording"):
        load_run_folder(partial)
