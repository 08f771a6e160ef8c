"""The operator console without a browser: scene, run controls, teleoperation, binding."""

from __future__ import annotations

import socket
import time
import urllib.request
from collections.abc import Iterator

import mujoco
import numpy as np
import pytest

pytest.importorskip("viser")

from pneumaquad.console.app import ConsoleApp
from pneumaquad.console.scene import capsule_mesh, geom_node_name
from pneumaquad.console.teleop import CLAMPED_COLOUR, REACHABLE_COLOUR, map_stylus
from pneumaquad.params import ParameterError


@pytest.fixture(scope="module")
def quadruped() -> Iterator[ConsoleApp]:
    app = ConsoleApp(configuration="quadruped", environment="block", port=0, real_time=False)
    yield app
    app.close()


@pytest.fixture(scope="module")
def fixed() -> Iterator[ConsoleApp]:
    app = ConsoleApp(configuration="fixed", environment="flat", port=0, real_time=False)
    yield app
    app.close()


def _press(button) -> None:
    """Press a GUI button as a browser would: its click handlers run."""
    button.value = True


def test_server_binds_loopback_and_serves_the_page(quadruped: ConsoleApp) -> None:
    assert quadruped.host == "127.0.0.1"
    assert quadruped.port > 0
    with urllib.request.urlopen(f"http://127.0.0.1:{quadruped.port}/", timeout=10) as reply:
        assert reply.status == 200
        assert b"<html" in reply.read().lower()
    addresses = {info[4][0] for info in socket.getaddrinfo(socket.gethostname(), None)}
    outside = [a for a in addresses if not a.startswith("127.") and a != "::1"]
    for address in outside[:1]:  # not reachable on a non-loopback interface
        with socket.socket(socket.AF_INET6 if ":" in address else socket.AF_INET) as probe:
            probe.settimeout(2.0)
            assert probe.connect_ex((address, quadruped.port)) != 0


def test_scene_has_a_node_per_geom_body_and_cylinder(quadruped: ConsoleApp) -> None:
    model = quadruped.simulation.model
    scene = quadruped.scene
    assert set(scene.geom_nodes) == set(range(model.ngeom))
    for geom, node in scene.geom_nodes.items():
        assert node.name == geom_node_name(model, geom)
    drawn_bodies = {int(model.geom_bodyid[g]) for g in scene.geom_nodes}
    assert drawn_bodies == set(range(model.nbody)) - {
        b for b in range(model.nbody) if not np.any(model.geom_bodyid == b)
    }
    assert "/world/block" in {node.name for node in scene.geom_nodes.values()}
    assert "/world/ground" in {node.name for node in scene.geom_nodes.values()}
    # cylinders: one segment per joint, as long as its tendon (two-site tendon)
    ends = np.asarray(scene.cylinders.points, dtype=float)
    assert ends.shape == (12, 2, 3)
    lengths = np.linalg.norm(ends[:, 1] - ends[:, 0], axis=1)
    data = quadruped.simulation.data
    np.testing.assert_allclose(lengths, data.ten_length[quadruped.simulation.robot.tendon_id],
                               atol=1e-5)


def test_geom_poses_follow_the_simulation(quadruped: ConsoleApp) -> None:
    quadruped.advance(200)
    data, model = quadruped.simulation.data, quadruped.simulation.model
    thorax_geom = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "thorax")
    node = quadruped.scene.geom_nodes[thorax_geom]
    np.testing.assert_allclose(node.position, data.geom_xpos[thorax_geom], atol=1e-6)
    quaternion = np.empty(4)
    mujoco.mju_mat2Quat(quaternion, data.geom_xmat[thorax_geom])
    assert abs(abs(np.dot(node.wxyz, quaternion)) - 1.0) < 1e-6


def test_contacts_are_drawn_with_force_arrows(quadruped: ConsoleApp) -> None:
    quadruped.advance(300)  # standing on the ground
    assert quadruped.scene.contact_count == quadruped.simulation.data.ncon > 0
    arrows = np.asarray(quadruped.scene.contact_forces.points, dtype=float)
    lengths = np.linalg.norm(arrows[:, 1] - arrows[:, 0], axis=1)
    assert lengths.sum() > 0.0


def test_time_advances_only_while_running(quadruped: ConsoleApp) -> None:
    controls = quadruped.controls
    _press(controls.reset_button)
    assert quadruped.simulation.time == 0.0
    time.sleep(0.3)
    assert quadruped.simulation.time == 0.0  # paused after a reset
    _press(controls.step_button)
    assert quadruped.simulation.time == pytest.approx(quadruped.chunk)
    _press(controls.start_button)
    time.sleep(0.5)
    _press(controls.pause_button)
    time.sleep(0.2)  # let a chunk in flight finish
    paused_at = quadruped.simulation.time
    assert paused_at > 2 * quadruped.chunk
    time.sleep(0.3)
    assert quadruped.simulation.time == paused_at
    assert "paused" in controls.status.content


def test_supply_and_gain_sliders_change_the_simulation_live(quadruped: ConsoleApp) -> None:
    controls, simulation = quadruped.controls, quadruped.simulation
    controls.supply.value = 500.0
    assert simulation.supply_pressure() - simulation.atmospheric_pressure() == pytest.approx(5e5)
    controls.gains["beta"].value = 0.5
    betas = np.array([t == "beta" for t in simulation.robot.joint_types])
    ratio = simulation.gain_scale / quadruped.base_gain_scale
    np.testing.assert_allclose(ratio[betas], 0.5)
    np.testing.assert_allclose(ratio[~betas], 1.0)
    controls.gains["beta"].value = 1.0


def test_supply_change_keeps_parameters_and_records_in_sync(fixed: ConsoleApp) -> None:
    bank = fixed.simulation.bank
    before = fixed.supply_gauge_pressure()
    fixed.set_supply_pressure(420e3)
    for actuator, record in zip(bank.actuators, bank.params, strict=True):
        assert actuator.supply.supply_pressure == record["supply_pressure"]
        assert record["supply_pressure"] == record["atmospheric_pressure"] + 420e3
    assert fixed.supply_gauge_pressure() == pytest.approx(420e3)
    packed = bank.params.copy()
    with pytest.raises(ParameterError, match=r"supply\.supply_pressure") as refused:
        fixed.set_supply_pressure(2e8)  # above 100 MPa absolute
    assert "2" in str(refused.value) and "100 MPa" in str(refused.value)
    assert np.array_equal(bank.params, packed)  # nothing changed
    assert all(a.supply.supply_pressure == p for a, p in zip(
        bank.actuators, packed["supply_pressure"], strict=True))
    fixed.controls.supply.value = 200000.0  # the slider: refused, shown, unchanged
    assert "supply unchanged" in fixed.message and "supply.supply_pressure" in fixed.message
    assert np.array_equal(bank.params, packed)
    fixed.message = ""
    fixed.set_supply_pressure(before)


def test_stylus_drives_the_front_right_foot_through_ik(fixed: ConsoleApp) -> None:
    _press(fixed.controls.reset_button)
    simulation, teleop = fixed.simulation, fixed.teleop
    leg = teleop.legs["front_right"]
    before = simulation.reference_angles[leg.joints].copy()
    displacement = np.array([0.0, 0.05, 0.05])  # thorax frame [m]
    gizmo = leg.nodes["stylus"]
    gizmo.position = displacement  # what a drag in the browser sets ...
    result = teleop.apply("front_right")  # ... and the gizmo's update handler
    assert result is not None and result.reachable
    np.testing.assert_allclose(leg.target, leg.home + displacement)
    assert np.max(np.abs(simulation.reference_angles[leg.joints] - before)) > 0.05
    np.testing.assert_allclose(simulation.reference_angles[leg.joints], result.angles)
    assert tuple(leg.nodes["target"].color) == REACHABLE_COLOUR

    def foot_error() -> float:
        data = simulation.data
        thorax = simulation.robot.thorax_id
        rotation = data.xmat[thorax].reshape(3, 3)
        foot = simulation.foot_positions()[simulation.robot.legs.index("front_right")]
        return float(np.linalg.norm(rotation.T @ (foot - data.xpos[thorax]) - leg.target))

    start = foot_error()
    fixed.advance(1500)
    assert foot_error() < 0.3 * start
    assert foot_error() < 0.015


def test_scale_and_offset_map_the_stylus(fixed: ConsoleApp) -> None:
    np.testing.assert_allclose(map_stylus([0.1, 0.0, -0.2], [1.0, 2.0, 3.0], 0.5),
                               [1.05, 2.0, 2.9])
    _press(fixed.controls.reset_button)
    leg = fixed.teleop.legs["front_right"]
    fixed.controls.scale.value = 0.5
    fixed.controls.shift.value = (0.0, 0.01, 0.0)
    fixed.teleop.set_stylus("front_right", np.array([0.04, 0.0, 0.0]))
    np.testing.assert_allclose(leg.target, leg.home + np.array([0.02, 0.01, 0.0]))
    fixed.controls.scale.value = 1.0
    fixed.controls.shift.value = (0.0, 0.0, 0.0)


def test_unreachable_target_is_clamped_and_flagged(fixed: ConsoleApp) -> None:
    _press(fixed.controls.reset_button)
    leg = fixed.teleop.legs["front_right"]
    result = fixed.teleop.set_stylus("front_right", np.array([0.8, 0.0, 0.0]))
    assert result is not None and not result.reachable
    assert leg.clamped
    assert tuple(leg.nodes["target"].color) == CLAMPED_COLOUR
    assert result.error > 0.1
    lower = fixed.simulation.robot.lower_limits()[leg.joints]
    upper = fixed.simulation.robot.upper_limits()[leg.joints]
    assert np.all(result.angles >= lower - 1e-9) and np.all(result.angles <= upper + 1e-9)
    fixed.controls.update()
    assert "clamped" in fixed.controls.teleop_status.content
    _press(fixed.controls.reset_button)
    assert not leg.clamped


def test_plots_hold_reference_angle_and_pressures(fixed: ConsoleApp) -> None:
    _press(fixed.controls.reset_button)
    for _ in range(5):
        _press(fixed.controls.step_button)
    angles = fixed.controls.angle_plot.data
    pressures = fixed.controls.pressure_plot.data
    assert len(angles) == 7 and len(pressures) == 7
    assert len(angles[0]) == 6  # the reset sample and five steps
    assert np.all(pressures[1][1:] > 100.0)  # absolute kPa


def test_rebuild_switches_configuration_and_environment() -> None:
    app = ConsoleApp(configuration="fixed", port=0, real_time=False)
    try:
        app.controls.supply.value = 400.0
        app.controls.environment.value = "ramp"
        assert app.environment == "ramp"
        app.controls.configuration.value = "testbed"
        assert app.simulation.robot.configuration == "testbed"
        assert app.simulation.robot.legs == ("front_left", "front_right")
        assert set(app.scene.geom_nodes) == set(range(app.simulation.model.ngeom))
        assert app.supply_gauge_pressure() == pytest.approx(4e5)
        app.advance(100)
    finally:
        app.close()


def test_capsule_mesh_is_closed_and_sized() -> None:
    vertices, faces = capsule_mesh(0.1, 0.3, segments=16)
    assert vertices[:, 2].max() == pytest.approx(0.4)
    assert vertices[:, 2].min() == pytest.approx(-0.4)
    assert np.max(np.linalg.norm(vertices[:, :2], axis=1)) == pytest.approx(0.1, abs=1e-6)
    assert faces.max() < len(vertices)


def test_the_free_robot_starts_standing_on_its_feet(quadruped: ConsoleApp) -> None:
    """The console's reset pose has settled: every foot carries load, together the
    robot's weight, at t = 0."""
    _press(quadruped.controls.reset_button)
    simulation = quadruped.simulation
    assert simulation.time == 0.0
    normal = simulation.foot_normal_forces()
    weight = simulation.model.body_mass.sum() * 9.81
    assert np.all(normal > 0.15 * weight)
    assert normal.sum() == pytest.approx(weight, rel=0.05)
