"""Replay of a run folder in the console, and the static stability margin (no browser)."""

from __future__ import annotations

import time
from collections.abc import Iterator
from pathlib import Path

import mujoco
import numpy as np
import pytest
import typer
from typer.testing import CliRunner

pytest.importorskip("viser")

from pneumaquad.cli.console import console_command
from pneumaquad.console.app import ConsoleApp
from pneumaquad.console.replay import ReplayRun, Stability
from pneumaquad.console.scene import StabilityOverlay
from pneumaquad.gait.stability import stability_margin, support_polygon
from pneumaquad.io.run_folder import read_recording
from pneumaquad.params import load_robot
from pneumaquad.robot.builder import build_robot
from pneumaquad.robot.experiment import run_phases
from pneumaquad.robot.scenarios import stand_up_phases
from pneumaquad.robot.simulation import RobotSimulation


@pytest.fixture(scope="module")
def run_folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("replay-run")
    simulation = RobotSimulation(build_robot(load_robot("crr-quadruped"), "quadruped", "flat"))
    phases = stand_up_phases(simulation, hold=0.5, posture=False)
    run_phases(simulation, phases, folder, "test")
    return folder


@pytest.fixture(scope="module")
def app() -> Iterator[ConsoleApp]:
    console = ConsoleApp(configuration="quadruped", environment="flat", port=0,
                         real_time=False)
    yield console
    console.close()


def _press(button) -> None:
    button.value = True


def _thorax_geom(model: mujoco.MjModel) -> int:
    return mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "thorax")


def test_slider_shows_the_trajectory_sample_and_the_recording_row(
        app: ConsoleApp, run_folder: Path) -> None:
    controls = app.controls
    controls.run_folder.value = str(run_folder)
    _press(controls.open_button)
    assert app.replaying and not app.running
    assert not controls.replay_slider.disabled
    trajectory = np.load(run_folder / "trajectory.npz")
    times, qpos = trajectory["time"], trajectory["qpos"]
    assert controls.replay_slider.max == pytest.approx(times[-1])
    recording = read_recording(run_folder)
    # the live robot is hidden, the replayed one drawn under /replay
    assert not any(node.visible for node in app.scene.geom_nodes.values())
    model = app.replay.model
    node = app.replay_scene.geom_nodes[_thorax_geom(model)]
    assert node.name == "/replay/robot/geoms/thorax"
    for index in (len(times) // 3, len(times) - 1):
        controls.replay_slider.value = float(times[index]) + 0.3 * (times[1] - times[0])
        # the scene's thorax pose is the sample's (independent forward kinematics)
        data = mujoco.MjData(model)
        data.qpos[:] = qpos[index]
        mujoco.mj_forward(model, data)
        geom = _thorax_geom(model)
        np.testing.assert_allclose(node.position, data.geom_xpos[geom], atol=1e-6)
        quaternion = np.empty(4)
        mujoco.mju_mat2Quat(quaternion, data.geom_xmat[geom])
        assert abs(abs(np.dot(node.wxyz, quaternion)) - 1.0) < 1e-6
        np.testing.assert_allclose(app.replay.data.qpos[:3], qpos[index, :3])
        # readouts and plots follow the recording row nearest in time
        row = int(np.argmin(np.abs(recording["time [s]"] - times[index])))
        assert f"t = {times[index]:.2f} s" in controls.status.content
        supply = recording["supply pressure [Pa]"][row] / 1000.0
        assert f"Supply {supply:.0f} kPa" in controls.readout.content
        assert f"{recording['air consumed [NL]'][row]:.2f} NL" in controls.readout.content
        angles = controls.angle_plot.data
        assert angles[0][-1] == pytest.approx(recording["time [s]"][row])
        assert angles[1][-1] == pytest.approx(
            np.degrees(recording["front_right_alpha reference [rad]"][row]))
        assert angles[2][-1] == pytest.approx(
            np.degrees(recording["front_right_alpha angle [rad]"][row]))
        assert controls.pressure_plot.data[1][-1] == pytest.approx(
            recording["front_right_alpha cap pressure [Pa]"][row] / 1000.0)
    # at the end the robot stands: the recorded margin is shown, the marker is green
    margin = recording["stability margin [m]"][-1]
    assert app.stability.margin == pytest.approx(margin)
    assert f"Stability margin {1000.0 * margin:.0f} mm" in controls.stability.content
    assert len(app.stability.polygon) == 4
    assert tuple(app.overlay.com.color) == StabilityOverlay.colour(margin)
    # Back to live: the live robot again, paused where it was
    live_time = app.simulation.time
    _press(controls.live_button)
    assert not app.replaying and app.replay_scene is None
    assert all(node.visible for node in app.scene.geom_nodes.values())
    assert controls.replay_slider.disabled
    assert app.simulation.time == live_time
    app.advance(20)
    assert app.simulation.time > live_time
    assert "live" in controls.stability.content


def test_playback_advances_the_replay_time(app: ConsoleApp, run_folder: Path) -> None:
    assert app.open_run(run_folder)
    _press(app.controls.play_button)
    deadline = 50
    while app.replay_time < 0.2 and deadline:
        time.sleep(0.05)
        deadline -= 1
    _press(app.controls.replay_pause_button)
    assert app.replay_time >= 0.2
    assert app.controls.replay_slider.value == pytest.approx(app.replay_time)
    _press(app.controls.start_button)  # Start leaves the replay for the live simulation
    _press(app.controls.pause_button)
    assert not app.replaying


def test_bad_folder_shows_an_error_and_keeps_the_app_running(
        app: ConsoleApp, tmp_path: Path) -> None:
    (tmp_path / "model.xml").write_text("<mujoco/>", encoding="utf-8")
    for folder, why in ((tmp_path, "no trajectory.npz"), (tmp_path / "missing", "not a folder")):
        app.controls.run_folder.value = str(folder)
        _press(app.controls.open_button)
        assert not app.replaying
        assert why in app.message
        assert f"⚠ {app.message}" in app.controls.replay_status.content
        assert "⚠" in app.controls.status.content
    before = app.simulation.time
    app.advance(10)
    assert app.simulation.time > before
    with pytest.raises(ValueError, match="not a run folder"):
        ReplayRun(tmp_path)


def test_live_margin_matches_an_independent_computation(app: ConsoleApp) -> None:
    _press(app.controls.reset_button)
    app.advance(400)  # standing on four feet
    simulation = app.simulation
    forces = simulation.foot_normal_forces()
    assert np.all(forces > 1.0)
    polygon = support_polygon(simulation.foot_positions()[forces > 1.0, :2])
    expected = float(stability_margin(simulation.data.subtree_com[0, :2], polygon))
    assert app.stability.margin == pytest.approx(expected)
    assert 0.25 < expected < 0.4  # the walking stance: feet 0.356 m either side
    assert f"Stability margin {1000.0 * expected:.0f} mm" in app.controls.stability.content
    segments = np.asarray(app.overlay.polygon.points, dtype=float)
    assert segments.shape == (4, 2, 3) and app.overlay.polygon.visible
    np.testing.assert_allclose(np.sort(segments[:, 0, :2], axis=0), np.sort(polygon, axis=0),
                               atol=1e-5)
    np.testing.assert_allclose(app.overlay.com.position[:2],
                               simulation.data.subtree_com[0, :2], atol=1e-6)
    assert tuple(app.overlay.com.color) == StabilityOverlay.colour(1.0)


def test_com_marker_is_red_outside_the_support_polygon(app: ConsoleApp) -> None:
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    com = np.array([1.5, 0.5])
    margin = float(stability_margin(com, square))
    assert margin < 0.0
    app.overlay.update(Stability(square, com, margin))
    assert tuple(app.overlay.com.color) == (230, 30, 30)
    assert StabilityOverlay.colour(0.1) != StabilityOverlay.colour(-0.1)
    app.refresh()


def test_console_command_opens_a_run_with_replay(run_folder: Path) -> None:
    cli = typer.Typer()
    cli.command("console")(console_command)
    cli.command("other")(lambda: None)
    result = CliRunner().invoke(
        cli, ["console", "--port", "0", "--duration", "0.5", "--replay", str(run_folder)])
    assert result.exit_code == 0, result.output
    assert f"Replaying {run_folder}" in result.output
    assert "Console stopped." in result.output
