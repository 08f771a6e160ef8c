"""Robot experiments end to end: scenarios, run folders, summaries, CLI, Ctrl-C."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import mujoco
import numpy as np
import pytest
from typer.testing import CliRunner

from conftest import CLI, interrupt_when_recording
from pneumaquad.cli.main import app
from pneumaquad.io.run_folder import read_recording
from pneumaquad.params import load_robot
from pneumaquad.robot.builder import build_robot
from pneumaquad.robot.experiment import run_phases
from pneumaquad.robot.scenarios import (
    STANDING_ANGLES,
    foot_cycle_phases,
    leg_validation_phases,
    stand_up_phases,
)
from pneumaquad.robot.simulation import RobotSimulation, stance_swing_schedule


def _simulation(configuration: str = "fixed", *overrides: str) -> RobotSimulation:
    return RobotSimulation(build_robot(load_robot("crr-quadruped", list(overrides)),
                                       configuration))


def _alpha_step_overshoot(force_gain: float) -> float:
    """Overshoot [%] of a 25° front-right alpha step with PD gains that ring."""
    sim = _simulation()
    pose = np.tile(np.radians([0.0, -30.0, 60.0]), 4)
    sim.set_pose(pose)
    sim.command_angles(pose)
    sim.gains["proportional_gain"] = 150.0
    sim.gains["integral_gain"] = 0.0
    sim.gains["derivative_gain"] = 3.0
    sim.joint_control["force_feedback_gain"] = force_gain
    sim.step(1000)
    target = pose.copy()
    target[3] += np.radians(25.0)
    sim.command_angles(target)
    angles = []
    for _ in range(150):
        sim.step(10)
        angles.append(sim.joint_angles()[3])
    return float((max(angles) - target[3]) / (target[3] - pose[3]) * 100.0)


def test_force_feedback_damps_the_alpha_step() -> None:
    """Feeding back the net pneumatic force's deviation (pressure sensors) adds damping:
    measured 66 % overshoot without, 43 % with 0.01 V/N."""
    without = _alpha_step_overshoot(0.0)
    with_feedback = _alpha_step_overshoot(0.01)
    assert without > 40.0
    assert with_feedback < without - 10.0


def test_stance_swing_schedule_scales_the_gains_of_unloaded_legs() -> None:
    """On the fixed thorax no foot touches the ground, so every leg is in swing: a swing
    scale of 0 removes the controller and the tested joint no longer follows."""
    errors = {}
    for swing in (1.0, 0.0):
        sim = _simulation()
        sim.gain_schedule = stance_swing_schedule(stance_scale=1.0, swing_scale=swing)
        pose = np.tile(np.radians([0.0, -30.0, 60.0]), 4)
        sim.set_pose(pose)
        target = pose.copy()
        target[5] += np.radians(20.0)
        sim.command_angles(target)
        for _ in range(100):
            sim.step(10)
        np.testing.assert_array_equal(sim.gain_scale, swing)
        errors[swing] = abs(np.degrees(sim.joint_angles()[5] - target[5]))
    assert errors[1.0] < 2.0
    assert errors[0.0] > 10.0


def test_standing_quadruped_carries_its_weight_on_four_feet(tmp_path: Path) -> None:
    sim = _simulation("quadruped")
    phases = stand_up_phases(sim, hold=3.0, posture=False)
    run = run_phases(sim, phases, tmp_path, "stand")
    recording = run.recording
    weight = float(np.sum(sim.model.body_mass)) * 9.81
    late = recording["time [s]"] > recording["time [s]"][-1] - 0.5
    feet = sum(recording[f"{leg} foot normal force [N]"][late] for leg in sim.robot.legs)
    # the robot stands: thorax up at the standing height, the feet carry its weight
    assert np.mean(recording["thorax z [m]"][late]) > 0.3
    assert np.mean(feet) == pytest.approx(weight, rel=0.05)
    for name in sim.robot.joint_names:
        angle = recording[f"{name} angle [rad]"][late]
        target = STANDING_ANGLES[sim.robot.joint_types.index(name.rsplit("_", 1)[1]) % 3]
        # measured: gamma settles within 3° after 3 s (dry seal friction and a slow integral)
        assert abs(np.degrees(np.mean(angle) - target)) < 4.5, name
    phases_summary = run.summary["phases"]
    assert set(phases_summary) == {"rest", "stand up", "hold"}
    total = sum(p["air consumed [NL]"] for p in phases_summary.values())
    assert total == pytest.approx(run.summary["air consumed [NL]"], rel=1e-6)
    assert (tmp_path / "trajectory.npz").is_file() and (tmp_path / "model.xml").is_file()
    model = mujoco.MjModel.from_xml_path(str(tmp_path / "model.xml"))
    assert np.load(tmp_path / "trajectory.npz")["qpos"].shape[1] == model.nq


def test_leg_validation_moves_only_the_tested_joint_closed_loop() -> None:
    sim = _simulation()
    phases = leg_validation_phases(sim, "beta", "trapezoid", settle=0.5)
    closed = phases[1].closed_loop
    assert closed.sum() == 1 and sim.robot.joint_names[int(np.argmax(closed))] == (
        "front_right_beta"
    )
    voltages = phases[1].open_loop_voltage
    extended = [sim.robot.joint_names[i] for i in np.flatnonzero(np.isfinite(voltages))]
    assert extended == ["front_right_alpha", "front_right_gamma"]


def test_foot_cycle_references_follow_the_path_through_ik() -> None:
    """The IK references put the foot on the commanded path: the stride spans 12 cm along
    the body and the arc rises 6 cm."""
    from pneumaquad.robot.legs import leg_dh_table, thorax_frame_points

    sim = _simulation()
    phases = foot_cycle_phases(sim, ("slow",), cycles=1)
    times = np.linspace(1.0, 5.0, 400)
    table = phases[1].references(times)[:, 3:6]
    feet = thorax_frame_points(leg_dh_table(sim.robot, "front_right"), table)
    assert np.ptp(feet[:, 2]) == pytest.approx(0.12, abs=1e-3)  # along the body
    assert np.ptp(feet[:, 0]) == pytest.approx(0.06, abs=1e-3)  # upwards


runner = CliRunner()


def test_cli_robot_geometry_and_export(tmp_path: Path) -> None:
    result = runner.invoke(app, ["robot", "geometry"])
    assert result.exit_code == 0, result.output
    assert "0.1462" in result.output and "0.2870" in result.output
    path = tmp_path / "model.xml"
    result = runner.invoke(app, ["robot", "export", str(path), "--environment", "ramp"])
    assert result.exit_code == 0, result.output
    model = mujoco.MjModel.from_xml_path(str(path))
    assert mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "ramp") >= 0


@pytest.mark.parametrize(("arguments", "message"), [
    (["--transfer-gap", "0.3"], "leaves none"),  # duty 0.9: no window left for the sway
    (["--duty-factor", "0.76"], "transfer gap 0.04 must be in [0, 0.02]"),  # > 2·0.76 − 1.5
    (["--duty-factor", "0.75", "--transfer-gap", "0"], "four-legged phases"),
])
def test_cli_walk_refuses_gaits_that_cannot_be_planned(tmp_path: Path, arguments: list[str],
                                                      message: str) -> None:
    result = runner.invoke(app, ["robot", "walk", "--no-video", "-o", str(tmp_path / "w"),
                                 *arguments])
    assert result.exit_code == 2
    shown = " ".join(result.output.replace("│", " ").split())
    assert message in shown
    assert "--duty-factor, --lift-fraction, --transfer-gap or --margin" in shown
    assert "Traceback" not in result.output
    assert not (tmp_path / "w").exists()  # refused before a run folder is made


def test_cli_leg_validate_writes_a_run_folder(tmp_path: Path) -> None:
    out = tmp_path / "run"
    result = runner.invoke(
        app, ["leg", "validate", "--joint", "gamma", "--signal", "fast-sine", "--settle", "0.2",
              "-o", str(out)],
    )
    assert result.exit_code == 0, result.output
    summary = json.loads((out / "summary.json").read_text())
    assert summary["angle rmse [deg]"]["front_right_gamma"] < 10.0
    assert (out / "joints.png").stat().st_size > 10_000
    recording = read_recording(out / "recording.parquet")
    assert "front_right_gamma cap pressure [Pa]" in recording


def test_cli_leg_matrix_prints_every_run(tmp_path: Path) -> None:
    """Several runs (--signal all) end with one table of each run's angle RMSE."""
    out = tmp_path / "matrix"
    result = runner.invoke(
        app, ["leg", "validate", "--joint", "gamma", "--signal", "all", "--settle", "0.2",
              "-o", str(out)], terminal_width=200,
    )
    assert result.exit_code == 0, result.output
    table = result.output[result.output.index("leg validation: every run"):]
    for kind in ("steps", "trapezoid", "slow-sine", "fast-sine"):
        rmse = json.loads((out / f"gamma-{kind}" / "summary.json").read_text())[
            "angle rmse [deg]"]["front_right_gamma"]
        assert f"{rmse:.2f}" in table and f"gamma-{kind}" in table


def test_cli_robot_profile_accounts_for_the_wall_time(tmp_path: Path) -> None:
    out = tmp_path / "run"
    result = runner.invoke(
        app, ["leg", "validate", "--joint", "gamma", "--signal", "fast-sine", "--settle", "0.2",
              "--no-video", "--profile", "-o", str(out)],
    )
    assert result.exit_code == 0, result.output
    assert "command real-time factor" in result.output
    profile = json.loads((out / "profile.json").read_text())
    stages = profile["stages"]
    for stage in ("model (parameters, MuJoCo model, actuator bank)", "simulation",
                  "recording", "plots"):
        assert stages[stage]["seconds"] > 0.0
    summary = json.loads((out / "summary.json").read_text())
    # the run's own stages lie within its wall time, and all of them within the total
    run_stages = sum(stages[name]["seconds"] for name in ("simulation", "recording"))
    assert run_stages <= summary["wall time [s]"]
    timed = sum(entry["seconds"] for name, entry in stages.items() if ":" not in name)
    assert timed + profile["untimed [s]"] == pytest.approx(profile["total [s]"])
    # the compiled steps' parts (each timed alone) and the rest make up the measured stage
    parts = [entry["seconds"] for name, entry in stages.items()
             if name.startswith("simulation: ")]
    assert len(parts) == 4 and min(parts) >= 0.0
    assert sum(parts) == pytest.approx(stages["simulation"]["seconds"])
    assert stages["simulation: MuJoCo (estimated)"]["seconds"] > (
        stages["simulation: actuators (estimated)"]["seconds"])


def test_cli_rejects_bad_robot_values(tmp_path: Path) -> None:
    result = subprocess.run(
        [*CLI, "leg", "validate", "--set", 'leg.gamma.upper_limit="95 kg"', "-o",
         str(tmp_path / "x")], capture_output=True, text=True, timeout=120,
    )
    assert result.returncode == 2
    assert "leg.gamma.upper_limit" in result.stderr and "Traceback" not in result.stderr
    result = runner.invoke(app, ["leg", "validate", "--joint", "delta"])
    assert result.exit_code == 2 and "delta" in result.output


def test_ctrl_c_keeps_the_robot_recording(tmp_path: Path) -> None:
    out = tmp_path / "long"
    csv = out / "recording.csv"
    returncode, stderr = interrupt_when_recording(
        ["robot", "stand", "--hold", "3000", "--no-video", "-o", str(out)], csv, 200_000, 120.0,
        cwd=tmp_path,
    )
    assert returncode == 130, stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["interrupted"] is True
    recording = read_recording(out / "recording.parquet")
    assert recording["time [s]"].size == read_recording(csv)["time [s]"].size > 10
    assert np.all(np.isfinite(recording["thorax z [m]"]))
    assert np.load(out / "trajectory.npz")["time"].size == recording["time [s]"].size


def test_a_diverging_run_stops_with_a_clear_error_and_keeps_its_recording(
    tmp_path: Path,
) -> None:
    """30 ms steps, explicit Euler and massless pistons blow up: MuJoCo would silently reset
    the state; we stop, name the time window and keep what was recorded before."""
    from pneumaquad.robot.simulation import SimulationDivergedError

    overrides = [
        'simulation.control_step="30 ms"',
        'simulation.integrator="euler"',
        *(f'linkages.{joint}.moving_mass="0 kg"' for joint in ("alpha", "beta", "gamma")),
    ]
    sim = _simulation("fixed", *overrides)
    phases = leg_validation_phases(sim, "gamma", "fast-sine", settle=0.5)
    with pytest.raises(SimulationDivergedError, match="diverged between t ="):
        run_phases(sim, phases, tmp_path, "diverging")
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert "diverged" in summary["error"]
    assert summary["diverged"] is True and summary["divergences [count]"] == 1
    times = read_recording(tmp_path / "recording.csv")["time [s]"]
    assert times.size >= 1
    assert np.all(np.diff(times) > 0.0)  # no silent reset: time never jumps back
    assert summary["diverged at [s]"] >= times[-1]
    assert sim.time == pytest.approx(summary["diverged at [s]"])  # stopped, not reset


def test_tank_supply_runs_down_by_the_air_the_cylinders_draw() -> None:
    """With ``supply="tank"`` all 12 cylinders draw from the actuator files' 2 L tank: its
    pressure falls by R·T·m/V (isothermal) for the m they drew, and the endurance
    estimate is the usable mass over the mean flow."""
    from pneumaquad.robot.experiment import tank_endurance

    sim = RobotSimulation(build_robot(load_robot("crr-quadruped"), "fixed"), supply="tank")
    tank = sim.robot.actuators["alpha"].supply
    start = sim.supply_pressure()
    assert start == pytest.approx(tank.tank_initial_pressure)
    pose = np.tile(np.radians([0.0, -30.0, 60.0]), 4)
    sim.set_pose(pose)
    target = pose.copy()
    target[3:6] += np.radians([20.0, -15.0, 20.0])
    sim.command_angles(target)
    sim.step(1000)
    drawn = sim.air_consumed()
    assert drawn > 0.0
    gas_constant = sim.robot.actuators["alpha"].gas.gas_constant
    gas = gas_constant * tank.tank_temperature / tank.tank_volume
    assert start - sim.supply_pressure() == pytest.approx(gas * drawn, rel=1e-9)
    usable = tank.tank_volume * (start - tank.supply_pressure) / (
        gas_constant * tank.tank_temperature
    )
    assert tank_endurance(sim, 1e-4) == pytest.approx(usable / 1e-4, rel=1e-9)
