"""`pneumaquad fit` commands (typer app `fit_app`) on small generated files."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from typer.testing import CliRunner

from pneumaquad.cli.fit import fit_app
from pneumaquad.params import load_rig

from .conftest import (
    SPACER_VOLTAGES,
    TRUE_COULOMB,
    TRUE_CUTOFFS,
    TRUE_STATIC,
    TRUE_VISCOUS,
    spacer_recording,
    step_recording,
)

PSI = 6894.757293168361  # Pa per psi
ATMOSPHERE = 101325.0  # the mapping's default, Pa
MAPPING = """
[columns]
time = { source = "t", unit = "s" }
position = { source = "x", unit = "mm" }
cap_pressure = { source = "pc", unit = "kPa" }
rod_pressure = { source = "pr", unit = "psig" }
command = { source = "u", unit = "V" }
"""


def write_lab_csv(path: Path, recording: dict[str, np.ndarray]) -> Path:
    """The recording as a lab file would hold it: mm, kPa absolute, psig."""
    table = np.column_stack(
        [
            recording["time [s]"],
            recording["position [m]"] * 1e3,
            recording["cap pressure [Pa]"] / 1e3,
            (recording["rod pressure [Pa]"] - ATMOSPHERE) / PSI,
            recording["command [V]"],
        ]
    )
    np.savetxt(path, table, delimiter=",", header="t,x,pc,pr,u", comments="", fmt="%.9g")
    return path


def write_run_folder(folder: Path, recording: dict[str, np.ndarray]) -> Path:
    folder.mkdir(parents=True)
    pq.write_table(pa.table(recording), folder / "recording.parquet")
    return folder


@pytest.fixture(scope="module")
def lab_files(tmp_path_factory, friction_rig) -> list[Path]:
    folder = tmp_path_factory.mktemp("lab")
    return [
        write_lab_csv(folder / f"step-{voltage}.csv", step_recording(friction_rig, voltage, 50 + i))
        for i, voltage in enumerate((4.8, 5.75, 6.0, 3.0, 4.0, 7.0, 7.5))
    ]


def test_friction_command_writes_a_loadable_file(tmp_path, lab_files) -> None:
    mapping = tmp_path / "mapping.toml"
    mapping.write_text(MAPPING)
    output = tmp_path / "fitted.toml"
    args = ["friction", *map(str, lab_files), "--mapping", str(mapping), "-o", str(output)]
    result = CliRunner().invoke(fit_app, args)
    assert result.exit_code == 0, result.output
    assert "coulomb-viscous friction" in result.output and "stiction peaks" in result.output
    friction = load_rig(output).actuator.friction
    assert friction.static_force == pytest.approx(TRUE_STATIC, rel=0.10)
    assert friction.coulomb_force == pytest.approx(TRUE_COULOMB, rel=0.10)
    assert friction.viscous_coefficient == pytest.approx(TRUE_VISCOUS, rel=0.25)


@pytest.mark.parametrize(
    ("mapping_text", "fragment"),
    [
        (MAPPING.replace("position =", "positon ="), "positon"),
        (MAPPING.replace('unit = "psig"', 'unit = "psi"'), "rod pressure"),
        (MAPPING.replace('source = "pc"', 'source = "p_cap"'), "p_cap"),
    ],
)
def test_bad_mapping_exits_2_naming_the_key(tmp_path, lab_files, mapping_text, fragment) -> None:
    mapping = tmp_path / "mapping.toml"
    mapping.write_text(mapping_text)
    output = tmp_path / "fitted.toml"
    args = ["friction", str(lab_files[0]), "--mapping", str(mapping), "-o", str(output)]
    result = CliRunner().invoke(fit_app, args)
    assert result.exit_code == 2
    assert fragment in result.output
    assert "Traceback" not in result.output
    assert not output.exists()


def test_valve_command_fits_cutoffs_from_a_run_folder(tmp_path, spacer_rig, area_rig) -> None:
    spacer = write_run_folder(
        tmp_path / "spacer", spacer_recording(spacer_rig, SPACER_VOLTAGES, 6.0, seed=60)
    )
    steps = write_run_folder(tmp_path / "step", step_recording(area_rig, 6.0, 61, duration=1.2))
    output = tmp_path / "valve.toml"
    args = ["valve", "--spacer", str(spacer), "--steps", str(steps), "-o", str(output)]
    result = CliRunner().invoke(fit_app, args)
    assert result.exit_code == 0, result.output
    assert "area polynomials not updated" in result.output  # one step is too few
    valve = load_rig(output).actuator.valve
    for port, (high, low) in TRUE_CUTOFFS.items():
        assert getattr(valve, f"port{port}").high_pressure_cutoff == pytest.approx(high, abs=0.02)
        assert getattr(valve, f"port{port}").low_pressure_cutoff == pytest.approx(low, abs=0.02)


def test_valve_command_without_inputs_exits_2(tmp_path) -> None:
    result = CliRunner().invoke(fit_app, ["valve", "-o", str(tmp_path / "x.toml")])
    assert result.exit_code == 2
    assert "--spacer" in result.output and "Traceback" not in result.output
    missing = CliRunner().invoke(
        fit_app, ["friction", str(tmp_path / "nope.csv"), "-o", str(tmp_path / "x.toml")]
    )
    assert missing.exit_code == 2 and "nope.csv" in missing.output


#: Held voltages that leave both ports on their plateaus: no cutoff is determined.
PLATEAU_VOLTAGES = (-2.25, -1.25, 1.75, 2.75)


@pytest.fixture(scope="module")
def plateau_spacer(tmp_path_factory, spacer_rig) -> Path:
    folder = tmp_path_factory.mktemp("plateaus") / "spacer"
    return write_run_folder(folder, spacer_recording(spacer_rig, PLATEAU_VOLTAGES, 3.0, seed=62))


def test_failed_fit_exits_1_names_the_port_and_writes_nothing(tmp_path, plateau_spacer) -> None:
    output = tmp_path / "valve.toml"
    arguments = ["valve", "--spacer", str(plateau_spacer), "-o", str(output)]
    result = CliRunner().invoke(fit_app, arguments)
    assert result.exit_code == 1, result.output
    assert not output.exists()
    text = " ".join(result.output.split())
    for port in (1, 2):
        assert f"input-pressure curve, port {port}" in text
        assert f"port {port} high_pressure_cutoff" in text or f"port {port}: the two" in text
    assert "No parameter file written" in text and "--force" in text
    assert "Traceback" not in result.output


def test_force_writes_a_failed_fit_and_marks_it(tmp_path, plateau_spacer) -> None:
    output = tmp_path / "valve.toml"
    arguments = ["valve", "--spacer", str(plateau_spacer), "-o", str(output), "--force"]
    result = CliRunner().invoke(fit_app, arguments)
    assert result.exit_code == 0, result.output
    assert "--force" in result.output
    header = output.read_text().split("\n\n")[0]
    assert "FAILED CHECK" in header and "port 2" in header
    load_rig(output)


@pytest.mark.parametrize(
    ("option", "value", "fragment"),
    [
        ("--start-temperature", "warm", "--start-temperature"),
        ("--start-temperature", "20 m", "--start-temperature"),
        ("--mode", "both", "--mode"),
        ("--duration", "0 s", "--duration"),
    ],
)
def test_bad_valve_options_exit_2(tmp_path, option: str, value: str, fragment: str) -> None:
    step = write_run_folder(tmp_path / "step", {"time [s]": np.arange(3.0)})
    output = tmp_path / "x.toml"
    result = CliRunner().invoke(
        fit_app, ["valve", "--steps", str(step), option, value, "-o", str(output)]
    )
    assert result.exit_code == 2, result.output
    assert fragment in result.output and "Traceback" not in result.output
    assert not output.exists()


def test_glob_patterns_are_expanded_and_must_match(tmp_path, area_rig) -> None:
    for index, voltage in enumerate((6.0, 4.0)):
        write_lab_csv(tmp_path / f"step-{index}.csv", step_recording(area_rig, voltage, 63 + index))
    mapping = tmp_path / "mapping.toml"
    mapping.write_text(MAPPING)
    output = tmp_path / "valve.toml"
    base = ["valve", "--mapping", str(mapping), "-o", str(output)]
    missing = CliRunner().invoke(fit_app, [*base, "--steps", str(tmp_path / "nothing-*.csv")])
    assert missing.exit_code == 2 and "matches no file" in missing.output
    result = CliRunner().invoke(
        fit_app, [*base, "--steps", str(tmp_path / "step-*.csv"), "--start-temperature", "hold"]
    )
    assert result.output.count("(hold)") == 2  # one table row per step: both files read
    # two steps are too few for the area polynomials, and nothing else was asked for
    assert result.exit_code == 2 and "nothing was fitted" in result.output
