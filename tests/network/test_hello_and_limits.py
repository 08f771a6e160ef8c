"""HELLO checks and answers, and command limits of the dynamics side, on real loopback UDP."""

from __future__ import annotations

import socket
import struct
import threading
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

from pneumaquad.network.actuator_side import ActuatorSide
from pneumaquad.network.client import ActuatorClient, SessionMismatchError
from pneumaquad.network.dynamics_side import DynamicsSide
from pneumaquad.network.protocol import ProtocolError, StatusFlag, check_hello
from pneumaquad.network.server import DynamicsServer
from pneumaquad.network.wire import Message, MessageType
from pneumaquad.params import load_actuator, load_robot
from pneumaquad.robot.builder import build_robot
from pneumaquad.robot.linkage import moment_arm

# --- a client written from docs/protocol.md (struct and socket only) ----------------------
HEADER = struct.Struct("<4sHHIdHH")
FORCE_COMMAND, STATE, PING, PONG, HELLO, BYE = 2, 4, 5, 6, 7, 8
N = 12
CLAMPED, RESYNCHRONISED = 8, 4


def _datagram(kind: int, sequence: int, sender_time: float, values=()) -> bytes:
    return HEADER.pack(b"PNQD", 1, kind, sequence, sender_time, len(values), 0) + \
        struct.pack(f"<{len(values)}d", *values)


def _receive(sock: socket.socket) -> tuple[int, tuple[float, ...]]:
    data = sock.recv(2048)  # the socket's timeout bounds the wait
    _, _, kind, _, _, count, _ = HEADER.unpack_from(data)
    return kind, struct.unpack_from(f"<{count}d", data, HEADER.size)


def _side(kind: str, configuration: str = "fixed", overrides: tuple[str, ...] = ()):
    robot = build_robot(load_robot("crr-quadruped", list(overrides)), configuration)
    side = DynamicsSide(robot, kind) if kind else ActuatorSide(robot)
    side.set_pose(np.tile(np.radians((0.0, -30.0, 60.0)), robot.joint_count // 3))
    return side


@pytest.fixture(scope="module")
def force_side() -> DynamicsSide:
    return _side("force")



def _serve(server: DynamicsServer) -> threading.Thread:
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    return thread


# --- HELLO -------------------------------------------------------------------------------
def _hello(joints: float, step: float) -> Message:
    return Message(MessageType.HELLO, 0, 0.0, np.array([joints, step]))


@pytest.mark.parametrize(("joints", "step", "fragment"), [
    (-1.0, 0.001, "joint count -1 is not an integer in 1 .. 172"),
    (12.5, 0.001, "joint count 12.5 is not an integer"),
    (12.0, 0.0, "control step 0 s is not positive"),
    (6.0, 0.001, "announces 6 joints; this receiver has 12"),
    (12.0, 0.002, "announces a 0.002 s control step; this receiver steps 0.001 s"),
])
def test_check_hello_refuses_other_dimensions(joints: float, step: float,
                                              fragment: str) -> None:
    with pytest.raises(ProtocolError) as info:
        check_hello(_hello(joints, step), 12, 0.001)
    assert info.value.reason == "bad_count" and fragment in str(info.value)


def test_check_hello_returns_the_announced_dimensions() -> None:
    assert check_hello(_hello(12.0, 0.001), 12, 0.001) == (12, 0.001)
    assert check_hello(_hello(6.0, 0.002)) == (6, 0.002)  # no dimensions of its own


def test_server_refuses_bad_hellos_answers_with_its_own_and_counts_them(
        force_side: DynamicsSide, client_socket: socket.socket, tmp_path: Path) -> None:
    server = DynamicsServer(force_side, duration=20.0, folder=tmp_path, plots=False)
    thread = _serve(server)
    bad = [(-1.0, 0.001), (6.0, 0.001), (12.5, 0.001), (12.0, 0.0), (12.0, 0.002)]
    for sequence, (joints, step) in enumerate(bad):
        client_socket.sendto(_datagram(HELLO, sequence, 1.0, (joints, step)), server.address)
        assert _receive(client_socket) == (HELLO, (12.0, 0.001))  # the server's dimensions
        client_socket.sendto(_datagram(PING, 100 + sequence, 2.5), server.address)
        kind, values = _receive(client_socket)
        assert kind == PONG and values[0] == 2.5  # no STATE came before it: not accepted
    client_socket.sendto(_datagram(HELLO, 0, 3.0, (12.0, 0.001)), server.address)
    assert _receive(client_socket) == (HELLO, (12.0, 0.001))
    kind, values = _receive(client_socket)
    assert kind == STATE and len(values) == 4 * N + 10
    assert int(values[4 * N + 9]) & RESYNCHRONISED
    client_socket.sendto(_datagram(BYE, 1, 0.0), server.address)
    thread.join(5.0)
    assert not thread.is_alive()
    assert server.summary["refused hellos [count]"] == 5
    assert server.summary["malformed bad_count [count]"] == 5


def test_client_reads_the_server_dimensions(force_side: DynamicsSide) -> None:
    server = DynamicsServer(force_side, duration=20.0)
    thread = _serve(server)
    client = ActuatorClient(_side(""), server.address, reply_timeout=0.5, max_retries=4)
    try:
        state = client.connect()
        assert (client.server_joint_count, client.server_control_step) == (12, 0.001)
        assert state.joint_count == 12
        client.bye()
    finally:
        client.close()
    thread.join(5.0)
    assert not thread.is_alive() and server.refused_hellos == 0


@pytest.mark.parametrize(("configuration", "overrides", "fragment"), [
    ("testbed", (), "this actuator side has 6 joints and a 0.001 s step"),
    ("fixed", ('simulation.control_step="2 ms"',), "has 12 joints and a 0.002 s step"),
])
def test_client_stops_on_a_server_with_other_dimensions(
        force_side: DynamicsSide, configuration: str, overrides: tuple[str, ...],
        fragment: str) -> None:
    server = DynamicsServer(force_side, duration=20.0)
    thread = _serve(server)
    client = ActuatorClient(_side("", configuration, overrides), server.address,
                            reply_timeout=0.5, max_retries=4)
    try:
        with pytest.raises(SessionMismatchError) as info:
            client.connect()
        message = str(info.value)
        assert "simulates 12 joints with a 0.001 s control step" in message
        assert fragment in message
        assert (client.server_joint_count, client.server_control_step) == (12, 0.001)
    finally:
        client.bye()
        client.close()
    thread.join(5.0)
    assert not thread.is_alive() and server.refused_hellos == 1


# --- command limits ------------------------------------------------------------------------
def test_force_limits_follow_supply_exhaust_and_areas(force_side: DynamicsSide) -> None:
    gamma = load_actuator("crr-gamma")
    supply, exhaust = gamma.supply.supply_pressure, gamma.supply.exhaust_pressure
    atmosphere, cylinder = gamma.gas.atmospheric_pressure, gamma.cylinder
    extending = (supply * cylinder.cap_area - exhaust * cylinder.rod_area
                 - atmosphere * cylinder.rod_cross_section)
    retracting = (exhaust * cylinder.cap_area - supply * cylinder.rod_area
                  - atmosphere * cylinder.rod_cross_section)
    index = force_side.robot.joint_names.index("front_right_gamma")
    assert force_side.force_limits[index] == pytest.approx([retracting, extending], rel=1e-12)
    assert 150.0 < extending < 170.0 and -140.0 < retracting < -120.0  # 50 psig, 1 1/16 in bore
    assert force_side.command_limits is force_side.force_limits
    np.testing.assert_array_equal(force_side.voltage_limits, np.tile([0.0, 10.0], (N, 1)))


def test_torque_limit_is_the_force_through_the_largest_moment_arm() -> None:
    side = _side("torque")
    robot = side.robot
    for index, kind in enumerate(robot.joint_types):
        link = robot.linkages[kind]
        force = np.abs(side.force_limits[index]).max()
        joint = getattr(robot.parameters.leg, kind)
        arms = np.abs(moment_arm(link, np.linspace(joint.lower_limit, joint.upper_limit, 7)))
        limit = side.torque_limits[index, 1]
        assert side.torque_limits[index, 0] == -limit
        # no smaller than the torque at any sampled angle, no larger than the shorter arm
        assert force * arms.max() <= limit * (1 + 1e-9)
        assert limit <= force * min(link.child_pivot_radius, link.parent_pivot_radius)


def test_apply_clamps_counts_and_refuses_non_finite() -> None:
    force_side = _side("force")
    low, high = force_side.force_limits[:, 0], force_side.force_limits[:, 1]
    inside = np.full(N, 10.0)
    force_side.apply(inside)
    assert not force_side.command_clamped and force_side.clamped_commands == 0
    wild = inside.copy()
    wild[0], wild[5] = 1e6, -1e9
    force_side.apply(wild)
    assert force_side.command_clamped
    assert force_side.command[0] == high[0] and force_side.command[5] == low[5]
    np.testing.assert_array_equal(force_side.command[1:5], 10.0)
    assert (force_side.clamped_commands, force_side.clamped_values) == (1, 2)
    held = force_side.command.copy()
    with pytest.raises(ValueError, match="non-finite force command for front_left_alpha"):
        force_side.apply(np.r_[np.nan, inside[1:]])
    np.testing.assert_array_equal(force_side.command, held)
    force_side.apply(inside)
    assert not force_side.command_clamped and force_side.clamped_commands == 1


def test_valve_voltages_are_clamped_to_the_valve_range() -> None:
    side = _side("valve")
    side.apply(np.r_[np.full(6, 12.0), np.full(6, -3.0)])
    np.testing.assert_array_equal(side.command, np.r_[np.full(6, 10.0), np.zeros(6)])
    np.testing.assert_array_equal(side.simulation.open_loop_voltage, side.command)
    assert side.clamped_values == 12


def test_clamped_command_is_flagged_in_state_and_recording(client_socket: socket.socket,
                                                           tmp_path: Path) -> None:
    side = _side("force")
    server = DynamicsServer(side, duration=20.0, folder=tmp_path, plots=False)
    thread = _serve(server)
    flags = []
    for sequence, force in enumerate((1e6, 0.0)):
        client_socket.sendto(_datagram(FORCE_COMMAND, sequence, sequence * 0.001,
                                       [force] * N), server.address)
        kind, values = _receive(client_socket)
        assert kind == STATE and int(values[4 * N + 8]) == sequence
        flags.append(int(values[4 * N + 9]))
    client_socket.sendto(_datagram(BYE, 2, 0.0), server.address)
    thread.join(5.0)
    assert flags[0] & CLAMPED and not flags[1] & CLAMPED
    assert StatusFlag.CLAMPED == CLAMPED
    assert server.summary["clamped commands [count]"] == 1
    status = pq.read_table(tmp_path / "recording.parquet").column("network status [-]")
    assert status.to_pylist()[1:] == [float(CLAMPED), 0.0]
    forces = pq.read_table(tmp_path / "recording.parquet").column(
        "front_left_alpha force command [N]").to_pylist()
    assert forces[1] == pytest.approx(side.force_limits[0, 1])
