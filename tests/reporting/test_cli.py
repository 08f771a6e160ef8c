"""``report RUN`` / ``report --cost-table``: exit 0 on good input, 2 with a message otherwise."""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from pneumaquad.cli.main import app
from pneumaquad.io.run_folder import read_recording

from .conftest import write_measured_csv

runner = CliRunner()


def test_report_run_writes_the_report(rig_run: Path, tmp_path: Path) -> None:
    out = tmp_path / "report"
    result = runner.invoke(app, ["report", str(rig_run), "-o", str(out)])
    assert result.exit_code == 0, result.output
    assert (out / "report.html").is_file()
    assert str(out / "report.html") in result.output.replace("\n", "")


def test_report_run_with_measured_data(rig_run: Path, tmp_path: Path) -> None:
    csv, mapping = write_measured_csv(read_recording(rig_run), tmp_path / "lab", shift=0.01)
    out = tmp_path / "report"
    result = runner.invoke(
        app,
        [
            "report",
            str(rig_run),
            "--measured",
            str(csv),
            "--mapping",
            str(mapping),
            "--time-offset",
            "-0.01",
            "-o",
            str(out),
        ],
    )
    assert result.exit_code == 0, result.output
    assert (out / "comparison.json").is_file()
    # the figures are printed too, in the report's units (SI: errors in mm and kPa)
    assert "simulated against measured" in result.output
    table = {line.split("│")[1].strip(): line.split("│")[2].strip()
             for line in result.output.splitlines() if line.count("│") > 3}
    assert table["position"] == "mm" and table["cap pressure"] == "kPa"
    assert "lag [s]" in result.output


def test_report_units_us_and_unknown_units(rig_run: Path, tmp_path: Path) -> None:
    csv, mapping = write_measured_csv(read_recording(rig_run), tmp_path / "lab", shift=0.01)
    out = tmp_path / "report"
    result = runner.invoke(app, ["report", str(rig_run), "--measured", str(csv), "--mapping",
                                 str(mapping), "--units", "us", "-o", str(out)])
    assert result.exit_code == 0, result.output
    table = {line.split("│")[1].strip(): line.split("│")[2].strip()
             for line in result.output.splitlines() if line.count("│") > 3}
    assert table["position"] == "in" and table["rod pressure"] == "psi"
    assert "psia" in (out / "report.html").read_text(encoding="utf-8")
    result = runner.invoke(app, ["report", str(rig_run), "--units", "furlongs"])
    assert result.exit_code == 2
    assert "'furlongs': expected one of si, us" in " ".join(result.output.split())


def test_missing_folder_exits_2_naming_it(tmp_path: Path) -> None:
    missing = tmp_path / "no-such-run"
    result = runner.invoke(app, ["report", str(missing)])
    assert result.exit_code == 2
    assert str(missing) in result.output.replace("\n", "")
    assert "Traceback" not in result.output


@pytest.mark.parametrize("problem", ["parameters", "mapping"])
def test_bad_files_exit_2(rig_run: Path, tmp_path: Path, problem: str) -> None:
    run = rig_run
    csv, mapping = write_measured_csv(read_recording(rig_run), tmp_path / "lab")
    if problem == "parameters":
        run = tmp_path / "run"
        run.mkdir()
        text = (rig_run / "parameters.toml").read_text()
        (run / "parameters.toml").write_text(text.replace('stroke = "', 'stroke = "-'))
        (run / "recording.csv").write_text((rig_run / "recording.csv").read_text())
        expected = "cylinder.stroke"
    else:
        mapping.write_text('[columns]\ntime = { source = "t_ms", unit = "furlong" }\n')
        expected = "furlong"
    result = runner.invoke(
        app,
        [
            "report",
            str(run),
            "--measured",
            str(csv),
            "--mapping",
            str(mapping),
            "-o",
            str(tmp_path / "r"),
        ],
    )
    assert result.exit_code == 2, result.output
    assert expected in result.output
    assert "Traceback" not in result.output


def test_measured_without_mapping_exits_2(rig_run: Path, tmp_path: Path) -> None:
    result = runner.invoke(app, ["report", str(rig_run), "--measured", "x.csv"])
    assert result.exit_code == 2
    assert "--mapping" in result.output


def test_cost_table_command(tmp_path: Path) -> None:
    out = tmp_path / "cost"
    result = runner.invoke(
        app,
        ["report", "--cost-table", "-o", str(out), "--repeats", "2", "--duration", "0.2"],
    )
    assert result.exit_code == 0, result.output
    assert "simple valve: pressure part only" in result.output
    for name in ("report.html", "cost-table.png", "cost-table.md", "cost-table.json"):
        assert (out / name).is_file()
