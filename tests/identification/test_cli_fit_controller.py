"""`pneumaquad fit controller` on run folders and lab files, and its refusals."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from typer.testing import CliRunner

from pneumaquad.cli.fit import fit_app
from pneumaquad.params import load_rig
from pneumaquad.rig import signals
from pneumaquad.rig.simulate import simulate_rig

from .test_controller_fit import GAIN_SETS, LEVELS, recording

MAPPING = """
[columns]
time = { source = "t", unit = "ms" }
position = { source = "x", unit = "mm" }
reference_position = { source = "r", unit = "mm" }
command = { source = "u", unit = "V" }
"""


def write_run_folder(folder: Path, columns: dict[str, np.ndarray]) -> Path:
    folder.mkdir(parents=True)
    pq.write_table(pa.table(columns), folder / "recording.parquet")
    return folder


def write_lab_csv(path: Path, columns: dict[str, np.ndarray], command: bool = True) -> Path:
    """Time in ms, positions in mm, the command in volts (optional)."""
    table = [columns["time [s]"] * 1e3, columns["position [m]"] * 1e3,
             columns["reference position [m]"] * 1e3]
    header = "t,x,r"
    if command:
        table.append(columns["command [V]"])
        header += ",u"
    np.savetxt(path, np.column_stack(table), delimiter=",", header=header, comments="",
               fmt="%.12g")
    return path


def invoke(*args: str):
    return CliRunner().invoke(fit_app, ["controller", *args])


def assert_gains(path: Path, gains: str, delay: float, tolerance: float) -> None:
    controller = load_rig(path).controller
    fitted = (controller.proportional_gain, controller.integral_gain,
              controller.derivative_gain)
    assert np.allclose(fitted, GAIN_SETS[gains], rtol=tolerance), fitted
    assert controller.measurement_delay == pytest.approx(delay, abs=1e-9)


def test_a_run_folder(tmp_path) -> None:
    run = write_run_folder(tmp_path / "run", recording("stiff", 10))
    output = tmp_path / "controller.toml"
    result = invoke(str(run), "--params", "thesis-rig", "-o", str(output))
    assert result.exit_code == 0, result.output
    assert "method: command" in result.output and "measurement delay: 10 ms" in result.output
    assert_gains(output, "stiff", 0.01, 1e-3)
    assert "fit 'PID from the valve command'" in output.read_text()


def test_a_lab_file_at_500_hz_through_a_mapping(tmp_path) -> None:
    csv = write_lab_csv(tmp_path / "lab.csv", recording("slow", 0, 2))
    mapping = tmp_path / "mapping.toml"
    mapping.write_text(MAPPING)
    output = tmp_path / "controller.toml"
    result = invoke(str(csv), "--mapping", str(mapping), "-o", str(output))
    assert result.exit_code == 0, result.output
    assert "differs from the controller period" in result.output
    assert_gains(output, "slow", 0.0, 0.01)


def test_a_lab_file_without_the_command_by_output_error(tmp_path) -> None:
    short = recording("slow", 0, 1, LEVELS[:3])
    csv = write_lab_csv(tmp_path / "lab.csv", short, command=False)
    mapping = tmp_path / "mapping.toml"
    mapping.write_text(MAPPING.replace('command = { source = "u", unit = "V" }\n', ""))
    output = tmp_path / "controller.toml"
    result = invoke(str(csv), "--mapping", str(mapping), "-o", str(output),
                    "--max-delay", "5 ms")
    assert result.exit_code == 0, result.output
    assert "method: output error" in result.output
    assert_gains(output, "slow", 0.0, 1e-3)


@pytest.mark.parametrize(("args", "message"), [
    (["--method", "guess"], "--method"),
    (["--delay", "1 s"], "--delay"),
    (["--max-delay", "5 kg"], "--max-delay"),
    (["--filter", "maybe"], "--filter"),
    (["--method", "command", "NO_COMMAND"], "needs the valve command"),
    (["CONSTANT"], "reference position is constant"),
    (["NO_REFERENCE"], "lacks the columns"),
    (["missing.csv"], "does not exist"),
])
def test_bad_input_ends_with_status_2_and_a_message(tmp_path, args, message) -> None:
    columns = dict(recording("slow", 0))
    runs = {
        "GOOD": columns,
        "NO_COMMAND": {k: v for k, v in columns.items() if k != "command [V]"},
        "CONSTANT": {**columns, "reference position [m]": np.full(columns["time [s]"].size,
                                                                   0.02)},
        "NO_REFERENCE": {k: v for k, v in columns.items() if k != "reference position [m]"},
    }
    named = [a for a in args if a in runs]
    paths = [str(write_run_folder(tmp_path / name, runs[name])) for name in named]
    options = [a for a in args if a not in runs]
    if not paths and "missing.csv" not in options:
        paths = [str(write_run_folder(tmp_path / "GOOD", runs["GOOD"]))]
    options = [str(tmp_path / a) if a == "missing.csv" else a for a in options]
    output = tmp_path / "controller.toml"
    result = invoke(*paths, *options, "-o", str(output))
    assert result.exit_code == 2, result.output
    assert message in result.output and "Traceback" not in result.output
    assert not output.exists()


def test_a_failed_fit_writes_nothing(tmp_path) -> None:
    # a PI controller: the fitted Kd is a small negative number
    kp, ki, _ = GAIN_SETS["slow"]
    pi = load_rig("thesis-rig", [f'controller.proportional_gain="{kp} V/m"',
                                 f'controller.integral_gain="{ki} V/(m*s)"',
                                 'controller.derivative_gain="0 V*s/m"'])
    reference = signals.step_train(LEVELS, 1.0, pi.simulation.control_step)
    run = write_run_folder(tmp_path / "pi",
                           simulate_rig(pi, reference, closed_loop=True).recording)
    output = tmp_path / "controller.toml"
    result = invoke(str(run), "-o", str(output))
    assert result.exit_code == 1, result.output
    assert "failed:" in result.output and "derivative_gain" in result.output
    assert "is negative" in result.output and "derivative filter" in result.output
    assert not output.exists()
    # --force cannot write a negative gain: the parameter file refuses it, naming the key
    forced = invoke(str(run), "-o", str(output), "--force")
    assert forced.exit_code == 2 and "controller.derivative_gain" in forced.output
    assert not output.exists()
