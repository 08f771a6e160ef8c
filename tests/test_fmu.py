"""The actuator FMU (docs/fmu.md): built, validated by FMPy, and simulated by FMPy in a
co-simulation loop against a mass on a spring, compared with the in-process kernel driving
the same load; its parameters' units; model parameters that change the behaviour; bad
parameters refused; reset; the ``pneumaquad export fmu`` command."""

from __future__ import annotations

import math
import re
import shutil
import sys
import zipfile
from collections.abc import Iterator, Mapping
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import Any

import fmpy
import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave
from fmpy.validation import validate_fmu
from typer.testing import CliRunner

from pneumaquad.cli.main import app, main
from pneumaquad.core.actuator import (
    initial_state,
    new_outputs,
    pack_parameter_array,
    supply_state,
)
from pneumaquad.core.kernel import step_actuators
from pneumaquad.core.layout import ACTUATOR_STATE_DTYPE
from pneumaquad.core.pneumatics import friction_of, state_outputs
from pneumaquad.interop.fmu_export import export_fmu
from pneumaquad.params import load_actuator

SET = "crr-gamma"
#: Load mass [kg]: the load integrates the FMU's force explicitly, so with the
#: Stribeck-tanh friction (slope k_tanh·Fs ≈ 3.2e4 N s/m near rest) a 1 ms exchange needs
#: m > h·slope/2 ≈ 16 kg.
MASS = 25.0
#: Spring stiffness [N/m] (3.9 Hz with the mass).
STIFFNESS = 15000.0
#: Exchange step [s] and length of the run (steps).
STEP = 1e-3
STEPS = 1500


def command(time: float) -> float:
    """Valve voltage [V] of the runs: a 2 V, 1.5 Hz sine about the 5.25 V offset."""
    return 5.25 + 2.0 * math.sin(2.0 * math.pi * 1.5 * time)


@pytest.fixture(scope="module")
def fmu_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return export_fmu(SET, tmp_path_factory.mktemp("fmu") / "gamma.fmu")


@pytest.fixture(scope="module")
def unpacked(fmu_file: Path, tmp_path_factory: pytest.TempPathFactory) -> tuple[Any, str]:
    """The FMU's model description and the folder it is extracted to."""
    folder = tmp_path_factory.mktemp("unpacked")
    return fmpy.read_model_description(str(fmu_file)), fmpy.extract(str(fmu_file), str(folder))


@contextmanager
def instance(unpacked: tuple[Any, str], name: str = "actuator") -> Iterator[FMU2Slave]:
    """An instantiated FMU, freed at the end (a pythonfmu FMU left allocated in a Python
    host crashes the interpreter at exit)."""
    description, folder = unpacked
    fmu = FMU2Slave(guid=description.guid, unzipDirectory=folder, instanceName=name,
                    modelIdentifier=description.coSimulation.modelIdentifier)
    fmu.instantiate()
    try:
        yield fmu
    finally:
        with suppress(FMICallException):  # an instance that failed its initialisation
            fmu.terminate()
        fmu.freeInstance()


def references(unpacked: tuple[Any, str]) -> dict[str, Any]:
    """Variable name -> model variable."""
    return {variable.name: variable for variable in unpacked[0].modelVariables}


def start(unpacked: tuple[Any, str], name: str) -> float:
    return float(references(unpacked)[name].start)


def initialise(fmu: FMU2Slave, refs: Mapping[str, Any], position: float,
               parameters: Mapping[str, float | str] | None = None) -> None:
    """Set up, set ``parameters`` and the inputs at rest at ``position`` [m], initialise."""
    fmu.setupExperiment(startTime=0.0)
    for name, value in (parameters or {}).items():
        reference = [refs[name].valueReference]
        if isinstance(value, str):
            fmu.setString(reference, [value])
        else:
            fmu.setReal(reference, [value])
    fmu.enterInitializationMode()
    fmu.setReal([refs[n].valueReference for n in ("valve_voltage", "piston_position",
                                                   "piston_velocity")],
                [command(0.0), position, 0.0])
    fmu.exitInitializationMode()


OUTPUT_NAMES = ("piston_force", "cap_pressure", "rod_pressure", "friction_force")


def fmu_run(fmu: FMU2Slave, refs: Mapping[str, Any], position: float, steps: int,
            exchange_step: float) -> dict[str, np.ndarray]:
    """The FMU against a mass on a spring (rest length: the start position), exchanging
    every ``exchange_step`` [s]: the load integrates the force of the last exchange
    (semi-implicit Euler) while the FMU steps with the load's position and velocity."""
    inputs = [refs[n].valueReference for n in ("valve_voltage", "piston_position",
                                               "piston_velocity")]
    outputs = [refs[n].valueReference for n in OUTPUT_NAMES]
    rest, velocity = position, 0.0
    force = fmu.getReal(outputs)[0]
    rows = []
    for n in range(steps):
        time = n * exchange_step
        fmu.setReal(inputs, [command(time), position, velocity])
        fmu.doStep(time, exchange_step)
        values = fmu.getReal(outputs)
        velocity += exchange_step * (force - STIFFNESS * (position - rest)) / MASS
        position += exchange_step * velocity
        force = values[0]
        rows.append([position, *values])
    return dict(zip(("position", *OUTPUT_NAMES), np.array(rows).T, strict=True))


def kernel_run(overrides: list[str], position: float, cap: float, rod: float, steps: int,
               exchange_step: float, kernel_steps: int, substeps: int) -> dict[str, np.ndarray]:
    """The same load driven by the in-process kernel: ``kernel_steps`` calls of
    ``step_actuators`` per exchange, the voltage and velocity held, the position moving on
    from the load's."""
    params = pack_parameter_array([load_actuator(SET, overrides)])
    state = np.zeros(1, ACTUATOR_STATE_DTYPE)
    initial_state(params[0], position, cap, rod, out=state[0])
    supply, outputs = supply_state(load_actuator(SET, overrides)), new_outputs(1)
    state_outputs(params[0], state[0], position, outputs[0])
    force = outputs[0]["pneumatic_force"] - friction_of(params[0], 0.0, 0.0)
    commands, positions, velocities = np.zeros(1), np.zeros(1), np.zeros(1)
    rest, velocity = position, 0.0
    rows = []
    for n in range(steps):
        commands[0] = command(n * exchange_step)
        velocities[0] = velocity
        positions[0] = position
        for _ in range(kernel_steps):
            step_actuators(params, state, commands, positions, velocities,
                           exchange_step / kernel_steps, substeps, supply, outputs)
            positions[0] = state[0]["position"]
        out = outputs[0]
        values = [out["pneumatic_force"] - out["friction_force"], state[0]["cap_pressure"],
                  state[0]["rod_pressure"], out["friction_force"]]
        velocity += exchange_step * (force - STIFFNESS * (position - rest)) / MASS
        position += exchange_step * velocity
        force = values[0]
        rows.append([position, *values])
    return dict(zip(("position", *OUTPUT_NAMES), np.array(rows).T, strict=True))


def assert_agree(fmu: Mapping[str, np.ndarray], kernel: Mapping[str, np.ndarray]) -> None:
    """Pressures within 0.1 % of the supply pressure, force within 0.5 % of its range;
    and the run moved the piston and swung the force (so the comparison means something)."""
    supply = load_actuator(SET).supply.supply_pressure
    force_range = np.ptp(kernel["piston_force"])
    assert force_range > 100.0
    assert np.ptp(kernel["position"]) > 0.005
    for name in ("cap_pressure", "rod_pressure"):
        assert np.max(np.abs(fmu[name] - kernel[name])) <= 1e-3 * supply, name
    assert np.max(np.abs(fmu["piston_force"] - kernel["piston_force"])) <= 5e-3 * force_range


def test_the_fmu_passes_fmpy_validation(fmu_file: Path) -> None:
    assert validate_fmu(str(fmu_file)) == []
    with zipfile.ZipFile(fmu_file) as archive:
        names = set(archive.namelist())
    assert {"modelDescription.xml", "resources/parameters.toml", "resources/fmu_settings.json",
            "binaries/linux64/pneumaquad_crr_gamma.so"} <= names


def test_fmu_and_kernel_agree_on_a_mass_spring_load(unpacked: tuple[Any, str]) -> None:
    refs = references(unpacked)
    position = start(unpacked, "piston_position")
    with instance(unpacked) as fmu:
        initialise(fmu, refs, position)
        through_fmu = fmu_run(fmu, refs, position, STEPS, STEP)
    in_process = kernel_run([], position, start(unpacked, "initial.cap_pressure"),
                            start(unpacked, "initial.rod_pressure"), STEPS, STEP, 1,
                            int(refs["simulation.substeps"].start))
    assert_agree(through_fmu, in_process)


@pytest.mark.parametrize(("exchange_step", "kernel_steps"), [(5e-3, 5), (2.5e-3, 3)])
def test_a_long_communication_step_takes_kernel_steps_with_the_inputs_held(
        unpacked: tuple[Any, str], exchange_step: float, kernel_steps: int) -> None:
    """5 ms: five 1 ms kernel steps; 2.5 ms: three equal ones of 0.83 ms (viscous friction:
    the explicit exchange with the Stribeck-tanh law would need a far heavier load)."""
    refs = references(unpacked)
    position = start(unpacked, "piston_position")
    steps = round(STEPS * STEP / exchange_step)
    with instance(unpacked) as fmu:
        initialise(fmu, refs, position, {"friction.model": "viscous"})
        through_fmu = fmu_run(fmu, refs, position, steps, exchange_step)
    in_process = kernel_run(['friction.model="viscous"'], position,
                            start(unpacked, "initial.cap_pressure"),
                            start(unpacked, "initial.rod_pressure"), steps, exchange_step,
                            kernel_steps, int(refs["simulation.substeps"].start))
    assert_agree(through_fmu, in_process)


@pytest.mark.parametrize("exchange_step", [1e-3, 2.5e-3])
def test_the_outputs_agree_with_each_other(unpacked: tuple[Any, str],
                                           exchange_step: float) -> None:
    """Force balance, mean flows that add up to the air consumed (also over a step of three
    kernel steps), the supply pressure of an ideal supply; the piston held still."""
    refs = references(unpacked)
    names = [v.name for v in unpacked[0].modelVariables if v.causality == "output"]
    actuator = load_actuator(SET)
    cylinder, gas = actuator.cylinder, actuator.gas
    rows = []
    with instance(unpacked, "outputs") as fmu:
        initialise(fmu, refs, start(unpacked, "piston_position"))
        for n in range(round(0.3 / exchange_step)):
            fmu.setReal([refs["valve_voltage"].valueReference], [command(n * exchange_step)])
            fmu.doStep(n * exchange_step, exchange_step)
            rows.append(dict(zip(names, fmu.getReal([refs[name].valueReference for name in names]),
                                 strict=True)))
    last = rows[-1]
    assert last["piston_force"] == last["pneumatic_force"] - last["friction_force"]
    assert last["pneumatic_force"] == pytest.approx(
        last["cap_pressure"] * cylinder.cap_area - last["rod_pressure"] * cylinder.rod_area
        - gas.atmospheric_pressure * cylinder.rod_cross_section, rel=1e-12)
    drawn = sum(row["supply_mass_flow"] for row in rows) * exchange_step
    assert last["air_consumed"] > 0.0
    assert drawn == pytest.approx(last["air_consumed"], rel=1e-9)
    assert all(row["available_supply_pressure"] == actuator.supply.supply_pressure
               for row in rows)
    assert all(200.0 < row[name] < 400.0 for row in rows
               for name in ("cap_temperature", "rod_temperature"))


#: Real parameters of the set that are plain numbers (no unit).
DIMENSIONLESS = {
    "gas.heat_capacity_ratio", "gas.critical_pressure_ratio", "valve.laminar_pressure_ratio",
    "valve.area_scale",
    "valve.simple.cap_discharge_coefficient", "valve.simple.rod_discharge_coefficient",
    "valve.simple.iso_critical_ratio", "friction.stribeck_exponent",
    "thermodynamics.polytropic_exponent",
}


def test_parameters_carry_their_units(unpacked: tuple[Any, str]) -> None:
    description = unpacked[0]
    units = {unit.name: unit for unit in description.unitDefinitions}
    parameters = [v for v in description.modelVariables if v.causality == "parameter"]
    reals = [v for v in parameters if v.type == "Real"]
    assert {v.name for v in reals if v.unit is None} == DIMENSIONLESS
    assert all(v.unit in units for v in description.modelVariables if v.unit is not None)
    named = {v.name: v for v in parameters}
    actuator = load_actuator(SET)
    supply = named["supply.supply_pressure"]
    assert supply.unit == "Pa" and float(supply.start) == actuator.supply.supply_pressure
    assert named["friction.viscous_coefficient"].unit == "N.s/m"
    assert named["valve.simple.sonic_conductance"].unit == "m3/(s.Pa)"
    assert [named[f"valve.port2.area_positive[{i}]"].unit for i in range(1, 6)] == [
        "m2/V4", "m2/V3", "m2/V2", "m2/V", "m2"]
    assert float(named["valve.port2.area_positive[1]"].start) == \
        actuator.valve.port2.area_positive[0]
    assert named["friction.model"].type == "String"
    assert named["friction.model"].start == actuator.friction.model
    assert named["valve.cap_port"].type == "Integer"
    pascal = units["Pa"].baseUnit
    assert (pascal.kg, pascal.m, pascal.s) == (1, -1, -2)
    volt = units["V"].baseUnit
    assert (volt.kg, volt.m, volt.s, volt.A) == (1, 2, -3, -1)
    by_name = references(unpacked)
    assert [by_name[n].unit for n in ("valve_voltage", "piston_position", "piston_velocity",
                                      "piston_force", "cap_temperature", "cap_mass_flow",
                                      "air_consumed")] == ["V", "m", "m/s", "N", "K", "kg/s",
                                                           "kg"]


def short_run(unpacked: tuple[Any, str], parameters: Mapping[str, float | str],
              steps: int = 200) -> dict[str, np.ndarray]:
    refs = references(unpacked)
    position = start(unpacked, "piston_position")
    with instance(unpacked, f"run {sorted(parameters.items())}") as fmu:
        initialise(fmu, refs, position, parameters)
        return fmu_run(fmu, refs, position, steps, STEP)


def test_model_parameters_change_the_behaviour(unpacked: tuple[Any, str]) -> None:
    thesis = short_run(unpacked, {})
    viscous = short_run(unpacked, {"friction.model": "viscous"})
    simple_valve = short_run(unpacked, {"valve.model": "simple"})
    assert np.max(np.abs(viscous["friction_force"] - thesis["friction_force"])) > 1.0
    assert np.max(np.abs(simple_valve["cap_pressure"] - thesis["cap_pressure"])) > 1e4
    refs = references(unpacked)
    with instance(unpacked, "viscous friction") as fmu:
        initialise(fmu, refs, start(unpacked, "piston_position"),
                   {"friction.model": "viscous", "friction.damping_coefficient": 50.0})
        fmu.setReal([refs["piston_velocity"].valueReference], [0.02])
        fmu.doStep(0.0, STEP)
        friction = fmu.getReal([refs["friction_force"].valueReference])[0]
    assert friction == pytest.approx(50.0 * 0.02, rel=1e-12)


@pytest.mark.parametrize("parameters", [
    {"friction.model": "dry"},
    {"supply.supply_pressure": -1.0},
    {"supply.exhaust_pressure": 1e6},  # above the supply pressure
    {"simulation.control_step": 0.0},
])
def test_bad_parameters_fail_the_initialisation(unpacked: tuple[Any, str],
                                                parameters: dict[str, Any]) -> None:
    refs = references(unpacked)
    with instance(unpacked, "bad") as fmu, pytest.raises(FMICallException):
        initialise(fmu, refs, start(unpacked, "piston_position"), parameters)


def test_parameters_are_fixed_after_initialisation(unpacked: tuple[Any, str]) -> None:
    refs = references(unpacked)
    with instance(unpacked, "fixed") as fmu:
        initialise(fmu, refs, start(unpacked, "piston_position"))
        with pytest.raises(FMICallException):
            fmu.setReal([refs["supply.supply_pressure"].valueReference], [4e5])


def test_reset_returns_to_the_start(unpacked: tuple[Any, str]) -> None:
    refs = references(unpacked)
    position = start(unpacked, "piston_position")
    with instance(unpacked, "reset") as fmu:
        initialise(fmu, refs, position, {"supply.supply_pressure": 5e5})
        first = fmu_run(fmu, refs, position, 300, STEP)
        fmu.reset()
        supply = fmu.getReal([refs["supply.supply_pressure"].valueReference])[0]
        assert supply == start(unpacked, "supply.supply_pressure")  # back to the start value
        initialise(fmu, refs, position, {"supply.supply_pressure": 5e5})
        again = fmu_run(fmu, refs, position, 300, STEP)
    for name in first:
        np.testing.assert_array_equal(again[name], first[name])


def test_export_command(tmp_path: Path) -> None:
    runner = CliRunner()
    target = tmp_path / "gamma.fmu"
    made = runner.invoke(app, ["export", "fmu", "--params", SET, "-o", str(target)])
    assert made.exit_code == 0, made.output
    assert zipfile.is_zipfile(target)
    occupied = runner.invoke(app, ["export", "fmu", "--params", SET, "-o", str(target)])
    assert occupied.exit_code == 2
    assert "--overwrite" in occupied.output
    replaced = runner.invoke(app, ["export", "fmu", "--params", "thesis-rig", "-o", str(target),
                                   "--overwrite"])
    assert replaced.exit_code == 0, replaced.output
    description = fmpy.read_model_description(str(target))
    assert description.coSimulation.modelIdentifier == "pneumaquad_thesis_rig"
    starts = {v.name: v.start for v in description.modelVariables}
    assert float(starts["piston_position"]) == pytest.approx(1.75 * 0.0254)  # the rig's start


@pytest.mark.parametrize(("arguments", "expected"), [
    (["--params", "no-such-set"], "is not a shipped parameter set"),
    (["--params", "crr-quadruped"], "is a robot file"),
    (["--params", SET, "--set", 'friction.model="dry"'], "friction.model"),
    (["--params", SET, "-o", "gamma.zip"], "ending in .fmu"),
])
def test_export_command_refuses_bad_input(arguments: list[str], expected: str, tmp_path: Path,
                                          monkeypatch: pytest.MonkeyPatch,
                                          capsys: pytest.CaptureFixture[str]) -> None:
    """A message and exit status 2, no traceback, nothing written (the command line's
    ``main`` turns a parameter error into that)."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "argv", ["pneumaquad", "export", "fmu", *arguments])
    with pytest.raises(SystemExit) as ended:
        main()
    message = " ".join(capsys.readouterr().err.replace("│", " ").split())
    assert ended.value.code == 2, message
    assert expected in message
    assert "Traceback" not in message
    assert not list(tmp_path.iterdir())


def test_export_command_without_pythonfmu_says_what_to_install(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.chdir(tmp_path)
    monkeypatch.setitem(sys.modules, "pythonfmu", None)  # as if not installed
    monkeypatch.setattr(sys, "argv", ["pneumaquad", "export", "fmu", "--params", SET])
    with pytest.raises(SystemExit) as ended:
        main()
    message = capsys.readouterr().err
    assert ended.value.code == 2
    assert "pip install 'pneumaquad[fmu]'" in message
    assert not list(tmp_path.iterdir())


def test_the_documented_example_runs(fmu_file: Path, tmp_path: Path,
                                     monkeypatch: pytest.MonkeyPatch) -> None:
    """docs/fmu.md's FMPy loop, run on a copy of the exported FMU."""
    page = Path(__file__).resolve().parents[1] / "docs" / "fmu.md"
    blocks = re.findall(r"```python\n(.*?)```", page.read_text(encoding="utf-8"), re.S)
    assert blocks
    shutil.copy(fmu_file, tmp_path / "gamma.fmu")
    monkeypatch.chdir(tmp_path)
    for index, block in enumerate(blocks):
        exec(compile(block, f"docs/fmu.md python block {index}", "exec"), {})
