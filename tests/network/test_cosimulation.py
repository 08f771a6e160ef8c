"""Networked co-simulation: the split actuator / dynamics run equals the in-process run.

Measured: the lockstep co-simulation of the front-right gamma step (fixed thorax, 1 ms
control step) is bit-identical to :class:`RobotSimulation` run in process, in process
and over loopback UDP, also through a lossy, reordering proxy (the server recognises
retransmitted commands by their effect time and does not step twice). The actuator side
holds no MuJoCo data and starts from the dynamics' pistons (its first STATE). The piston
position travels as ``x`` and is turned back into a tendon length ``x + l2``; the kernel
computes ``(x + l2) - l2``, which could differ from ``x`` in the last bit, but did not
on this experiment; a 1e-12 rad bound is kept for that case.
"""

from __future__ import annotations

import dataclasses
import threading
from collections.abc import Iterator

import mujoco
import numpy as np
import pytest

from pneumaquad.network.actuator_side import ActuatorSide
from pneumaquad.network.client import ActuatorClient
from pneumaquad.network.dynamics_side import DynamicsSide
from pneumaquad.network.experiments import make_experiment
from pneumaquad.network.faults import FaultProxy, FaultRates
from pneumaquad.network.server import DynamicsServer
from pneumaquad.network.state import StateMessage
from pneumaquad.params import load_robot
from pneumaquad.robot.builder import build_robot
from pneumaquad.robot.simulation import RobotSimulation

POSE = np.tile(np.radians((0.0, -30.0, 60.0)), 4)
TOLERANCE = 1e-12  # [rad]; measured 0 (bit-identical)
STEPS = 300
SETTLE = 0.1  # [s]


def _robot(*overrides: str):
    return build_robot(load_robot("crr-quadruped", list(overrides)), "fixed")


@pytest.fixture(scope="module")
def reference() -> np.ndarray:
    """Joint angles [rad] after each step of the in-process gamma step, (STEPS, 12)."""
    simulation = RobotSimulation(_robot())
    simulation.set_pose(POSE)
    experiment = make_experiment("gamma-step", simulation.robot.joint_names, POSE,
                                 simulation.control_step, SETTLE)
    angles = []
    for step in range(STEPS):
        simulation.command_angles(experiment.references(step))
        simulation.step(1)
        angles.append(simulation.joint_angles())
    result = np.array(angles)
    assert np.degrees(np.ptp(result[:, 5])) > 10.0  # the step happened
    return result


def test_in_process_lockstep_equals_the_coupled_simulation(reference: np.ndarray) -> None:
    dynamics = DynamicsSide(_robot(), "force")
    dynamics.set_pose(POSE)
    actuators = ActuatorSide(_robot())
    # from the dynamics' own pistons, as ActuatorClient.connect does
    actuators.set_pose(POSE, piston_positions=dynamics.state().piston_positions)
    experiment = make_experiment("gamma-step", actuators.robot.joint_names, POSE,
                                 actuators.control_step, SETTLE)
    angles = []
    for step in range(STEPS):
        actuators.command_angles(experiment.references(step))
        dynamics.apply(actuators.forces(dynamics.state()))
        dynamics.step()
        angles.append(dynamics.state().joint_angles)
    difference = np.abs(np.array(angles) - reference).max()
    assert difference <= TOLERANCE, f"max angle difference {difference:.3g} rad"


def test_the_actuator_side_builds_no_mujoco(monkeypatch: pytest.MonkeyPatch) -> None:
    """From the joints alone (robot_joints): no MjSpec, no compiled MjModel, no MjData."""
    from pneumaquad.params import load_robot
    from pneumaquad.robot.builder import robot_joints

    def refuse(*_args: object, **_kwargs: object) -> None:
        raise AssertionError("the actuator side used MuJoCo")

    for name in ("MjData", "MjSpec", "MjModel"):
        monkeypatch.setattr(mujoco, name, refuse)
    robot = robot_joints(load_robot("crr-quadruped"), "quadruped")
    side = ActuatorSide(robot)
    side.set_pose(POSE)
    side.command_angles(POSE)
    pistons = side.joints.pistons_from_angles(np.clip(POSE, robot.lower_limits(),
                                                      robot.upper_limits()))
    state = StateMessage(
        simulation_time=0.0, joint_angles=POSE, joint_velocities=np.zeros(12),
        piston_positions=pistons, piston_velocities=np.zeros(12),
        thorax_position=np.zeros(3), thorax_quaternion=np.array([1.0, 0.0, 0.0, 0.0]))
    forces = side.forces(state)
    assert forces.shape == (12,) and np.all(np.isfinite(forces))
    assert side.bank.count == 12 and side.air_consumed() == 0.0


def test_the_joints_alone_equal_the_built_robots() -> None:
    from pneumaquad.params import load_robot
    from pneumaquad.robot.builder import RobotJoints, build_robot, robot_joints

    parameters = load_robot("crr-quadruped")
    built = build_robot(parameters, "quadruped")
    alone = robot_joints(parameters, "quadruped")
    for field in dataclasses.fields(RobotJoints):
        assert getattr(built, field.name) == getattr(alone, field.name), field.name


def test_geometric_pistons_stay_within_the_tolerance(reference: np.ndarray) -> None:
    """Without the STATE's pistons the actuator side places them by the linkage's closed
    form, a few 1e-17 m from MuJoCo's tendon lengths (measured 2.5e-14 rad at the end)."""
    dynamics = DynamicsSide(_robot(), "force")
    dynamics.set_pose(POSE)
    actuators = ActuatorSide(_robot())
    actuators.set_pose(POSE)
    experiment = make_experiment("gamma-step", actuators.robot.joint_names, POSE,
                                 actuators.control_step, SETTLE)
    for step in range(STEPS):
        actuators.command_angles(experiment.references(step))
        dynamics.apply(actuators.forces(dynamics.state()))
        dynamics.step()
    assert np.abs(dynamics.state().joint_angles - reference[-1]).max() <= TOLERANCE


def test_force_mode_refuses_actuator_seal_friction() -> None:
    robot = _robot('simulation.seal_friction="actuator"')
    with pytest.raises(ValueError, match="seal_friction"):
        DynamicsSide(robot, "force")
    with pytest.raises(ValueError, match="seal_friction"):
        ActuatorSide(robot)
    with pytest.raises(ValueError, match="command kind"):
        DynamicsSide(_robot(), "pressure")


@pytest.fixture
def server() -> Iterator[DynamicsServer]:
    dynamics = DynamicsSide(_robot(), "force")
    dynamics.set_pose(POSE)
    server = DynamicsServer(dynamics, duration=30.0)
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    yield server
    server.stop()
    thread.join(5.0)
    assert not thread.is_alive()


def _networked_run(address, reply_timeout: float = 0.05) -> ActuatorClient:
    client = ActuatorClient(ActuatorSide(_robot()), address, reply_timeout=reply_timeout,
                            max_retries=200)
    initial = client.connect()
    assert np.array_equal(initial.joint_angles, np.clip(
        POSE, client.side.robot.lower_limits(), client.side.robot.upper_limits()))
    experiment = make_experiment("gamma-step", client.side.robot.joint_names,
                                 initial.joint_angles, client.side.control_step, SETTLE)
    client.run(experiment, STEPS, initial)
    return client


def test_networked_lockstep_equals_the_coupled_simulation(
        server: DynamicsServer, reference: np.ndarray) -> None:
    client = _networked_run(server.address)
    client.bye()
    client.close()
    angles = np.array([state.joint_angles for state in client.states])
    difference = np.abs(angles - reference).max()
    assert difference <= TOLERANCE, f"max angle difference {difference:.3g} rad"
    assert client.summary["resends [count]"] == 0
    times = np.array([state.simulation_time for state in client.states])
    assert np.allclose(np.diff(times), client.side.control_step)


def test_faulty_link_keeps_both_sides_running_and_counts_match(
        server: DynamicsServer, reference: np.ndarray) -> None:
    proxy = FaultProxy(server.address, FaultRates(), seed=5).start()
    try:
        client = _networked_run(proxy.address, reply_timeout=0.02)
        client.bye()
    finally:
        proxy.stop()
    client.close()
    server.stop()
    angles = np.array([state.joint_angles for state in client.states])
    assert np.abs(angles - reference).max() <= TOLERANCE  # lost packets delay, not change
    to_server, to_client = proxy.counts["to_server"], proxy.counts["to_client"]
    assert min(to_server.dropped, to_server.garbage, to_server.duplicated, to_client.dropped,
               to_server.delayed + to_server.reordered) > 0, proxy.counts
    counters = server.endpoint.counters()
    assert counters["malformed [count]"] == to_server.garbage
    assert counters["duplicates [count]"] == to_server.duplicated
    assert to_server.reordered <= counters["reordered [count]"]
    assert counters["reordered [count]"] <= to_server.reordered + to_server.delayed
    client_counters = client.endpoint.counters()
    assert client_counters["malformed [count]"] == to_client.garbage
    assert client_counters["duplicates [count]"] == to_client.duplicated
    assert client.summary["resends [count]"] >= to_server.dropped
    # a dropped STATE made the client resend a command the server had applied already
    assert server.retransmissions > 0
