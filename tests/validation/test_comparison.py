"""The comparison page: its targets judge figures correctly, and the command writes it."""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from pneumaquad.cli.main import app
from pneumaquad.validation.comparison import SetFigures, targets_of
from pneumaquad.validation.leg_loop import FootCycleFigures, JointFigures
from pneumaquad.validation.rig_loop import RigLoopFigures


def _joint(name: str, lag: float, rise: float) -> JointFigures:
    return JointFigures(name, lag, 1.0, rise, 0.1, 5.0, 2.0)


def _walking(rmse: float, scale: float) -> list[FootCycleFigures]:
    return [FootCycleFigures("alpha", scale, rmse, 0.1, rmse, 1.0)]


def _figures(tau: float, lags: tuple[float, float, float], gamma_lag: float,
             beta_rise: float, reduced_rmse: float) -> SetFigures:
    return SetFigures(
        RigLoopFigures((tau, tau), (1.0, 3.0, 5.0), lags),
        {"gamma": _joint("gamma", gamma_lag, 0.2), "beta": _joint("beta", 0.16, beta_rise),
         "alpha": _joint("alpha", 0.1, 0.1)},
        {1.0: _walking(10.0, 1.0), 0.75: _walking(reduced_rmse, 0.75)},
        {})


def test_targets_pass_the_thesis_figures() -> None:
    rows = targets_of(_figures(0.082, (0.08, 0.05, 0.03), 0.16, 0.3, 7.3))
    assert [row.met for row in rows] == [True] * len(rows)


def test_targets_fail_each_miss() -> None:
    rows = targets_of(_figures(0.033, (0.06, 0.02, 0.01), 0.05, 0.1, 12.0))
    met = {row.claim: row.met for row in rows}
    assert not met["rig step time constant"]
    assert not met["rig sine lag at 1 rad/s"]
    assert not met["rig sine lag at 3 rad/s"]
    assert not met["rig sine lag at 5 rad/s"]
    assert not met["gamma sine lag"]
    assert met["beta fast-sine lag"]
    assert not met["beta step rise time / gamma's"]
    assert not met["walking motion: alpha RMSE, gain 1 -> 0.75"]


@pytest.mark.slow
def test_command_writes_the_page(tmp_path: Path) -> None:
    result = CliRunner().invoke(app, ["report", "--thesis-comparison", "--repeats", "3",
                                      "--output", str(tmp_path)])
    assert result.exit_code == 0, result.output
    page = (tmp_path / "thesis-comparison.md").read_text(encoding="utf-8")
    assert "| rig step time constant |" in page
    assert (tmp_path / "images" / "thesis-rig-loop.png").stat().st_size > 10_000
    assert (tmp_path / "images" / "thesis-alpha-walking.png").stat().st_size > 10_000
