"""Measured-versus-simulated comparison on data made from the run itself."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from pneumaquad.io.measured import load_mapping, read_measured
from pneumaquad.io.run_folder import read_recording
from pneumaquad.reporting import build_run_report, compare_with_measured
from pneumaquad.reporting.run_folder import ReportError

from .conftest import INCH, LEVELS, write_measured_csv

STROKE = 1.75 * INCH


def _by_signal(comparison) -> dict:
    return {c.signal: c for c in comparison.comparisons}


def test_same_run_gives_zero_error_in_the_report(rig_run: Path, tmp_path: Path) -> None:
    csv, mapping = write_measured_csv(read_recording(rig_run), tmp_path / "lab")
    report = build_run_report(rig_run, tmp_path / "report", csv, mapping)
    document = json.loads((report.parent / "comparison.json").read_text())
    rows = {row["signal"]: row for row in document["signals"]}
    assert set(rows) == {"position [m]", "cap pressure [Pa]", "rod pressure [Pa]"}
    assert rows["position [m]"]["rmse"] < 1e-9
    assert rows["cap pressure [Pa]"]["rmse"] < 1e-3  # CSV round-trip in psig
    assert rows["rod pressure [Pa]"]["max_abs_error"] < 1e-3
    assert all(abs(row["lag"]) < 1e-6 for row in rows.values())
    text = report.read_text(encoding="utf-8")
    assert "Measured vs simulated" in text and "Position figures per step" in text
    assert (report.parent / "measured-vs-simulated.png").is_file()
    assert (report.parent / "comparison.md").read_text().startswith("| signal |")
    # two steps in the step train, each measured and simulated alike
    assert len(document["steps simulated"]) == len(LEVELS) - 1
    for sim, meas in zip(document["steps simulated"], document["steps measured"], strict=True):
        assert sim["final level [m]"] == pytest.approx(meas["final level [m]"], abs=1e-9)


@pytest.mark.parametrize("shift", [0.04, -0.025])
def test_time_shift_is_reported_as_lag(rig_run: Path, tmp_path: Path, shift: float) -> None:
    simulated = read_recording(rig_run)
    csv, mapping = write_measured_csv(simulated, tmp_path, shift=shift)
    measured = read_measured(csv, load_mapping(mapping))
    comparison = compare_with_measured(simulated, measured, STROKE)
    rows = _by_signal(comparison)
    # measured(t) = simulated(t - shift): the simulation leads by `shift`
    assert rows["position [m]"].lag == pytest.approx(-shift, abs=1.5e-3)
    assert rows["position [m]"].rmse > 1e-4
    # undoing the shift brings the error back to zero
    aligned = compare_with_measured(simulated, measured, STROKE, time_offset=-shift)
    assert _by_signal(aligned)["position [m]"].rmse < 1e-6
    assert aligned.time_offset == -shift


def test_single_open_loop_step_gives_time_constants(tmp_path: Path) -> None:
    time = np.arange(1, 3001) * 1e-3
    command = np.where(time < 1.0, 0.0, 6.0)
    position = np.where(time < 1.0, 0.0, 0.04 * (1 - np.exp(-(time - 1.0) / 0.2)))
    recording = {
        "time [s]": time,
        "command [V]": command,
        "reference position [m]": np.full(time.size, np.nan),
        "position [m]": position,
    }
    comparison = compare_with_measured(recording, dict(recording), STROKE)
    assert comparison.step_time == pytest.approx(1.0)
    row = _by_signal(comparison)["position [m]"]
    assert row.simulated_time_constant == pytest.approx(0.2, rel=0.02)
    assert row.measured_time_constant == pytest.approx(row.simulated_time_constant)
    assert len(comparison.steps_simulated) == 1


def test_nothing_to_compare_and_robot_runs_are_user_errors(
    robot_run: Path, rig_run: Path, tmp_path: Path
) -> None:
    simulated = read_recording(rig_run)
    with pytest.raises(ReportError, match="none of the compared signals"):
        compare_with_measured(simulated, {"time [s]": simulated["time [s]"]}, STROKE)
    csv, mapping = write_measured_csv(simulated, tmp_path)
    with pytest.raises(ReportError, match="rig runs only"):
        build_run_report(robot_run, tmp_path / "r", csv, mapping)
    with pytest.raises(ReportError, match="go together"):
        build_run_report(rig_run, tmp_path / "r", csv, None)
    late = {**simulated, "time [s]": simulated["time [s]"] + 100.0}
    with pytest.raises(ReportError, match="overlap"):
        compare_with_measured(simulated, late, STROKE)
