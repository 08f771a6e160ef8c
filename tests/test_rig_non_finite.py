"""A rig run that goes non-finite stops, names the quantity and the time, keeps what ran."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from pneumaquad.io.run_folder import read_recording
from pneumaquad.params import load_rig
from pneumaquad.reporting.rig_experiment import run_rig_experiment
from pneumaquad.rig import signals
from pneumaquad.rig.simulate import RIG_COLUMNS, RigDivergedError, first_non_finite, simulate_rig


def _with_gravity(integrator: str, gravity: float):
    """A rig whose gravity bypasses validation (the schema refuses more than 100 m/s^2)."""
    setup = load_rig("thesis-rig", [f'simulation.integrator="{integrator}"'])
    return setup.model_copy(update={"rig": setup.rig.model_copy(update={"gravity": gravity})})


def test_a_nan_command_stops_the_run_and_keeps_the_rows_before_it(tmp_path: Path) -> None:
    signal = signals.constant(6.0, 1000)
    signal[700] = math.nan  # row 700: the step from 0.700 s to 0.701 s
    with pytest.raises(RigDivergedError) as info:
        run_rig_experiment(load_rig("thesis-rig"), tmp_path, signal, False, "nan command")
    error = info.value
    assert error.quantity == "command [V]"
    assert error.time == pytest.approx(0.701)
    assert "command [V] became non-finite at t = 0.701 s" in str(error)
    assert "the recording up to t = 0.7 s is kept" in str(error)
    kept = error.result.recording
    assert kept["time [s]"].size == 700 and kept["time [s]"][-1] == pytest.approx(0.7)
    for name in ("recording.csv", "recording.parquet"):
        recording = read_recording(tmp_path / name)
        assert recording["time [s]"].size == 700
        assert np.isfinite(recording["cap pressure [Pa]"]).all()
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["steps"] == 700 and "command [V] became non-finite" in summary["error"]


def test_gravity_beyond_the_validated_range_names_the_first_bad_quantity() -> None:
    with pytest.raises(RigDivergedError) as info:
        simulate_rig(_with_gravity("fixed", 1e300), signals.constant(6.0, 100), False)
    assert info.value.quantity == "position [m]"
    assert info.value.time == pytest.approx(0.001)
    assert info.value.result.recording["time [s]"].size == 0
    assert "nothing before it was recorded" in str(info.value)


@pytest.mark.filterwarnings("ignore::RuntimeWarning")
def test_the_adaptive_reference_stops_on_non_finite_values_too() -> None:
    signal = signals.constant(6.0, 30)
    signal[20] = math.nan
    setup = load_rig("thesis-rig", ['simulation.integrator="radau"'])
    with pytest.raises(RigDivergedError) as info:
        simulate_rig(setup, signal, False)
    assert info.value.quantity == "command [V]" and info.value.time == pytest.approx(0.02)
    assert info.value.result.recording["time [s]"].size == 20
    with pytest.raises(RigDivergedError) as info:
        simulate_rig(_with_gravity("radau", 1e300), signal, False)
    assert "solver" in info.value.quantity and info.value.time == 0.0


def test_columns_that_are_nan_by_design_are_not_reported() -> None:
    rows = np.ones((3, len(RIG_COLUMNS)))
    reference = RIG_COLUMNS.index("reference position [m]")
    tank = RIG_COLUMNS.index("tank pressure [Pa]")
    rows[:, [reference, tank]] = math.nan
    assert first_non_finite(rows, [reference, tank]) is None
    rows[2, RIG_COLUMNS.index("rod pressure [Pa]")] = math.inf
    rows[2, RIG_COLUMNS.index("velocity [m/s]")] = math.nan
    assert first_non_finite(rows, [reference, tank]) == (2, RIG_COLUMNS.index("velocity [m/s]"))
    assert first_non_finite(rows, [tank]) == (0, reference)


def test_a_normal_run_is_untouched() -> None:
    result = simulate_rig(load_rig("thesis-rig"), signals.constant(6.0, 200), False)
    assert result.recording["time [s]"].size == 200
    assert np.isnan(result.recording["tank pressure [Pa]"]).all()  # ideal supply: no tank
