"""The stage clock that --profile reports: stages add up, shares and factors follow."""

from __future__ import annotations

import time

import pytest

from pneumaquad.io.stage_clock import StageClock


def test_stages_accumulate_and_report_shares_and_factors() -> None:
    clock = StageClock(started=time.perf_counter() - 10.0)  # a run that began 10 s ago
    clock.add("simulation", 2.0, calls=100)
    clock.add("simulation", 1.0, calls=50)
    clock.add("recording", 1.5)
    clock.add("simulation: MuJoCo (estimated)", 2.5)
    report = clock.report(simulated_time=60.0)
    stages = report["stages"]
    assert stages["simulation"]["seconds"] == pytest.approx(3.0)
    assert stages["simulation"]["calls"] == 150
    assert stages["simulation"]["real-time factor"] == pytest.approx(20.0)
    total = report["total [s]"]
    assert total == pytest.approx(10.0, abs=0.5)
    assert stages["recording"]["share"] == pytest.approx(1.5 / total)
    # a sub-stage ("name: part") is part of its stage, not extra time
    assert report["untimed [s]"] == pytest.approx(total - 4.5)
    assert report["real-time factor"] == pytest.approx(60.0 / total)


def test_a_stage_that_raises_is_still_timed() -> None:
    clock = StageClock()
    with pytest.raises(RuntimeError), clock.stage("plot"):
        time.sleep(0.01)
        raise RuntimeError("broken plot")
    assert clock.seconds["plot"] >= 0.01
