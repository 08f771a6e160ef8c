"""Simulated-versus-measured comparison: alignment, per-signal figures, Markdown table."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pneumaquad.analysis.compare import (
    SignalComparison,
    align_recordings,
    compare_recordings,
    comparison_rows,
    comparison_to_markdown,
)

ATMOSPHERE = 101325.0


def recording(time: np.ndarray, delay: float = 0.0, tau: float = 0.08) -> dict[str, np.ndarray]:
    """A smooth closed-loop-like run (step at 0.5 s + tracking sine), shifted by ``delay``."""
    t = time - delay
    elapsed = np.clip(t - 0.5, 0.0, None)
    position = 0.01 + 0.02 * (1 - np.exp(-elapsed / tau)) + 0.002 * np.sin(2 * np.pi * 1.1 * t)
    cap = 3.0e5 + 1.0e5 * (1 - np.exp(-elapsed / tau)) + 5e3 * np.sin(2 * np.pi * 0.8 * t)
    return {
        "time [s]": time,
        "command [V]": np.where(t >= 0.5, 7.0, 5.25),
        "position [m]": position,
        "cap pressure [Pa]": cap,
        "rod pressure [Pa]": 2.0e5 + 0.0 * time,
        "velocity [m/s]": np.gradient(position, time),
    }


TIME = np.arange(0.0, 3.0, 1e-3)


def test_a_run_compared_with_itself_has_no_error():
    run = recording(TIME)
    table, aligned = compare_recordings(run, run)
    assert [row.signal for row in table] == [
        "position [m]",
        "cap pressure [Pa]",
        "rod pressure [Pa]",
        "velocity [m/s]",
    ]
    for row in table:
        assert row.rmse == 0.0
        assert row.max_abs_error == 0.0
        assert row.simulated_range == row.measured_range
    position = table[0]
    assert position.lag == pytest.approx(0.0, abs=1e-9)
    assert position.rmse_percent == 0.0
    assert math.isnan(table[2].lag)  # a constant rod pressure has no lag
    np.testing.assert_allclose(aligned.time, TIME, atol=1e-12)


def test_a_delayed_copy_gives_that_delay():
    measured = recording(TIME)
    simulated = recording(TIME, delay=0.037)
    table, _ = compare_recordings(
        simulated, measured, signals=["position [m]", "cap pressure [Pa]"]
    )
    for row in table:
        assert row.lag == pytest.approx(0.037, abs=5e-4)
        assert row.rmse > 0
    reverse, _ = compare_recordings(measured, simulated, signals=["position [m]"])
    assert reverse[0].lag == pytest.approx(-0.037, abs=5e-4)


def test_estimated_time_offset_aligns_a_late_started_logger():
    simulated = recording(TIME)
    # The logger's clock reads 0.25 s less than the simulation's for the same event.
    measured_time = np.arange(-0.2, 2.5, 2e-3)
    measured = recording(measured_time + 0.25)
    measured["time [s]"] = measured_time
    aligned = align_recordings(simulated, measured, estimate_offset_from="position [m]")
    assert aligned.time_offset == pytest.approx(0.25, abs=1e-3)
    table, _ = compare_recordings(
        simulated, measured, estimate_offset_from="position [m]", signals=["position [m]"]
    )
    assert table[0].lag == pytest.approx(0.0, abs=1e-3)
    assert table[0].rmse < 1e-5
    given, _ = compare_recordings(simulated, measured, time_offset=0.25, signals=["position [m]"])
    assert given[0].rmse < 1e-5


def test_resampling_uses_only_the_overlap_and_the_coarser_grid():
    simulated = recording(TIME)
    measured_time = np.arange(1.0, 4.0, 2e-3)
    measured = recording(measured_time)
    aligned = align_recordings(simulated, measured)
    assert aligned.time[0] == pytest.approx(1.0)
    assert aligned.time[-1] <= TIME[-1]
    assert np.diff(aligned.time) == pytest.approx(2e-3)
    np.testing.assert_allclose(
        aligned.measured["position [m]"], recording(aligned.time)["position [m]"], atol=1e-12
    )
    with pytest.raises(ValueError, match="do not overlap"):
        align_recordings(simulated, recording(np.arange(5.0, 6.0, 1e-3)))


def test_step_time_constants_and_spans():
    simulated = recording(TIME, tau=0.10)
    measured = recording(TIME, tau=0.08)
    stroke = 1.75 * 0.0254
    for run in (simulated, measured):  # pure steps for the fit
        run["position [m]"] = run["position [m]"] - 0.002 * np.sin(2 * np.pi * 1.1 * TIME)
    table, _ = compare_recordings(
        simulated, measured, signals=["position [m]"], step_time=0.5, spans={"position [m]": stroke}
    )
    row = table[0]
    assert row.simulated_time_constant == pytest.approx(0.10, rel=1e-3)
    assert row.measured_time_constant == pytest.approx(0.08, rel=1e-3)
    assert row.rmse_percent == pytest.approx(100 * row.rmse / stroke)
    unfitted, _ = compare_recordings(simulated, measured, signals=["position [m]"])
    assert math.isnan(unfitted[0].simulated_time_constant)


def test_missing_signals_and_time_are_reported():
    run = recording(TIME)
    with pytest.raises(ValueError, match="'force \\[N\\]' \\(missing from the simulated"):
        compare_recordings(run, run, signals=["force [N]"])
    without_time = {k: v for k, v in run.items() if k != "time [s]"}
    with pytest.raises(ValueError, match="measured recording has no 'time"):
        compare_recordings(run, without_time)
    with pytest.raises(ValueError, match="no such column"):
        align_recordings(run, run, estimate_offset_from="force [N]")


def test_markdown_table():
    measured = recording(TIME)
    simulated = recording(TIME, delay=0.02)
    table, _ = compare_recordings(simulated, measured)
    text = comparison_to_markdown(table)
    lines = text.splitlines()
    assert lines[0].startswith("| signal | unit | RMSE |")
    assert "τ simulated [s]" in lines[0]
    assert lines[1] == "|---|---|---|---|---|---|---|---|"
    assert len(lines) == 2 + len(table)
    assert lines[2].startswith("| position | m | ")
    assert lines[3].startswith("| cap pressure | Pa | ")
    assert all(line.count("|") == 9 for line in lines)
    assert "–" in lines[2]  # no step time: no time constants
    assert f"{table[0].rmse:.4g}" in lines[2]
    row = table[0].as_row()
    assert row["RMSE [m]"] == table[0].rmse
    assert row["lag [s]"] == table[0].lag
    assert comparison_rows(table)[0]["signal"] == "position [m]"
    assert isinstance(table[0], SignalComparison)
