"""`pneumaquad rig spacer` with several held voltages feeds `pneumaquad fit valve --spacer`."""

from __future__ import annotations

import json
import subprocess

import pytest
from typer.testing import CliRunner

from conftest import CLI
from pneumaquad.cli.main import app
from pneumaquad.io.run_folder import read_recording
from pneumaquad.params import ParameterError, load_rig

#: The README's sweep: centered -1.25 ... +0.75 V, at least two points in each port's
#: transition (eq 4.2.7-4.2.11 with thesis-rig's cutoffs).
SWEEP = "4 V,4.5 V,4.85 V,5.25 V,5.55 V,6 V"


def test_a_spacer_sweep_run_is_enough_for_fit_valve(tmp_path) -> None:
    folder = tmp_path / "sweep"
    result = CliRunner().invoke(app, ["rig", "spacer", SWEEP, "-o", str(folder)])
    assert result.exit_code == 0, result.output
    summary = json.loads((folder / "summary.json").read_text())
    assert summary["held voltages [V]"] == pytest.approx([4.0, 4.5, 4.85, 5.25, 5.55, 6.0])
    assert summary["time per voltage [s]"] == pytest.approx(5.0)
    recording = read_recording(folder)
    assert recording["time [s]"][-1] == pytest.approx(30.0)
    output = tmp_path / "fitted.toml"
    fitted = CliRunner().invoke(app, ["fit", "valve", "--spacer", str(folder), "-o", str(output)])
    assert fitted.exit_code == 0, fitted.output
    valve = load_rig(output).actuator.valve
    assert valve.port1.high_pressure_cutoff == pytest.approx(-1.25, abs=0.01)
    assert valve.port1.low_pressure_cutoff == pytest.approx(0.75, abs=0.01)
    assert valve.port2.high_pressure_cutoff == pytest.approx(1.25, abs=0.01)
    assert valve.port2.low_pressure_cutoff == pytest.approx(-0.75, abs=0.01)


@pytest.mark.parametrize(
    ("arguments", "fragment"),
    [
        (["4 V,,5 V"], "VOLTAGES"),
        (["4 V,12 V"], "12 V"),
        (["4 V,5 s"], "5 s"),
        (["5 V", "--duration", "0 s"], "--duration"),
    ],
)
def test_bad_sweeps_are_refused_naming_the_value(tmp_path, arguments, fragment) -> None:
    result = CliRunner().invoke(app, ["rig", "spacer", *arguments, "-o", str(tmp_path / "r")])
    assert isinstance(result.exception, ParameterError)
    assert fragment in str(result.exception)
    assert not (tmp_path / "r").exists()


def test_bad_sweep_exits_2_without_traceback(tmp_path) -> None:
    result = subprocess.run(
        [*CLI, "rig", "spacer", "4 V,11 V", "-o", str(tmp_path / "r")],
        capture_output=True,
        text=True,
        check=False,
    )
    assert result.returncode == 2
    assert "VOLTAGES" in result.stderr and "11 V" in result.stderr
    assert "Traceback" not in result.stderr + result.stdout
