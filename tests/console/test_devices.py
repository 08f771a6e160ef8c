"""External input devices over UDP: messages, the device server, the console link."""

from __future__ import annotations

import socket
import struct
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
import typer
from typer.testing import CliRunner

pytest.importorskip("viser")

from pneumaquad.cli.console import console_command
from pneumaquad.console.app import ConsoleApp
from pneumaquad.console.devices import (
    BUTTON_ENGAGE,
    BUTTON_PLACE_FOOT,
    DeviceServer,
    decode_device_feedback,
    decode_device_input,
    encode_device_feedback,
    encode_device_input,
)
from pneumaquad.console.teleop import map_stylus
from pneumaquad.network.protocol import (
    HEADER_FORMAT,
    MAGIC,
    VERSION,
    MessageType,
    ProtocolError,
    encode,
    encode_ping,
)

CLIENT = Path(__file__).parents[2] / "docs" / "examples" / "stylus_client.py"
FRONT_RIGHT = 1  # leg index in robot.legs order


@pytest.fixture(scope="module")
def app() -> Iterator[ConsoleApp]:
    console = ConsoleApp(configuration="quadruped", environment="flat", port=0,
                         real_time=False, device_port=0)
    yield console
    console.close()



def _wait_for(server: DeviceServer, leg_index: int, sequence: int) -> None:
    deadline = time.monotonic() + 2.0
    while time.monotonic() < deadline:
        received = server.latest(leg_index)
        if received is not None and received.input.sequence == sequence:
            return
        time.sleep(0.005)
    raise AssertionError(f"input {sequence} of leg {leg_index} never arrived")


def _latest_feedback(sock: socket.socket) -> bytes:
    data, _ = sock.recvfrom(2048)  # at least one, within the timeout
    sock.settimeout(0.05)
    try:
        while True:
            data, _ = sock.recvfrom(2048)
    except TimeoutError:
        pass
    finally:
        sock.settimeout(2.0)
    return data


def test_device_messages_round_trip_with_their_layout() -> None:
    datagram = encode_device_input(7, 12.5, 1, np.array([0.01, -0.02, 0.03]), BUTTON_ENGAGE)
    assert len(datagram) == 24 + 5 * 8
    assert struct.unpack_from("<H", datagram, 6)[0] == MessageType.DEVICE_INPUT == 16
    assert struct.unpack_from("<5d", datagram, 24) == (1.0, 0.01, -0.02, 0.03, 1.0)
    message = decode_device_input(datagram)
    assert (message.leg_index, message.buttons, message.sequence) == (1, 1, 7)
    assert message.engaged and message.sender_time == 12.5
    np.testing.assert_array_equal(message.position, [0.01, -0.02, 0.03])
    datagram = encode_device_feedback(3, 1.25, 0, np.array([0.5, -1.0, 2.0]), 12.0, True)
    assert len(datagram) == 24 + 6 * 8
    assert struct.unpack_from("<H", datagram, 6)[0] == MessageType.DEVICE_FEEDBACK == 17
    feedback = decode_device_feedback(datagram)
    assert (feedback.leg_index, feedback.normal_force, feedback.clamped) == (0, 12.0, True)
    assert feedback.simulation_time == 1.25
    np.testing.assert_array_equal(feedback.force, [0.5, -1.0, 2.0])
    with pytest.raises(ProtocolError) as error:
        decode_device_input(encode(MessageType.DEVICE_INPUT, 0, 0.0, [1.5, 0, 0, 0, 1]))
    assert error.value.reason == "bad_count"


def test_malformed_datagrams_are_counted_and_ignored(client_socket: socket.socket) -> None:
    server = DeviceServer()
    try:
        assert server.host == "127.0.0.1" and server.port > 0
        address = ("127.0.0.1", server.port)
        valid = encode_device_input(5, 0.0, FRONT_RIGHT, np.array([0.0, 0.0, 0.02]), 1)
        bad = [
            b"junk",  # truncated
            b"XXXX" + valid[4:],  # bad_magic
            struct.pack(HEADER_FORMAT, MAGIC, VERSION, 16, 1, 0.0, 4, 0) + bytes(32),  # count
            encode(MessageType.DEVICE_INPUT, 2, 0.0, [9, 0.0, 0.0, 0.0, 1]),  # leg index
            encode(MessageType.DEVICE_INPUT, 3, 0.0, [1, 0.0, 0.0, 0.0, 0.5]),  # buttons
            valid[:-8] + struct.pack("<d", float("nan")),  # non_finite
            struct.pack(HEADER_FORMAT, MAGIC, VERSION, 99, 4, 0.0, 0, 0),  # unknown_type
        ]
        for datagram in [*bad, encode_ping(4, 0.0), valid, valid]:  # + a duplicate
            client_socket.sendto(datagram, address)
        _wait_for(server, FRONT_RIGHT, 5)
        time.sleep(0.05)  # the duplicate
        assert server.malformed == {"truncated": 1, "bad_magic": 1, "bad_count": 3,
                                    "non_finite": 1, "unknown_type": 1}
        assert server.ignored == 1 and server.dropped_old == 1
        received = server.latest(FRONT_RIGHT)
        assert received is not None and received.sender == client_socket.getsockname()
        np.testing.assert_array_equal(received.input.position, [0.0, 0.0, 0.02])
        assert server.latest(0) is None
    finally:
        server.close()


def test_stale_input_is_ignored(client_socket: socket.socket) -> None:
    server = DeviceServer(stale_timeout=0.5)
    try:
        client_socket.sendto(encode_device_input(0, 0.0, FRONT_RIGHT, np.zeros(3), 1),
                      ("127.0.0.1", server.port))
        _wait_for(server, FRONT_RIGHT, 0)
        arrival = server.latest(FRONT_RIGHT).arrival
        assert server.latest(FRONT_RIGHT, now=arrival + 0.6) is None
        assert server.take_fresh(now=arrival + 0.6) == {}
        assert not server.send_feedback(FRONT_RIGHT, np.zeros(3), 0.0, False, 0.0,
                                        now=arrival + 0.6)
        assert set(server.take_fresh(now=arrival + 0.1)) == {FRONT_RIGHT}
        assert server.take_fresh(now=arrival + 0.1) == {}  # taken once
    finally:
        server.close()


def test_engaged_device_drives_the_foot_and_gets_feedback(app: ConsoleApp,
                                                          client_socket: socket.socket) -> None:
    app.reset()
    app.advance(500)  # standing
    leg = app.teleop.legs["front_right"]
    simulation = app.simulation

    before = simulation.reference_angles[leg.joints].copy()
    position = np.array([-0.01, 0.0, 0.0])  # press the foot 1 cm down (thorax x is up)
    client_socket.sendto(encode_device_input(10, time.monotonic(), FRONT_RIGHT, position,
                                      BUTTON_ENGAGE), ("127.0.0.1", app.devices.server.port))
    _wait_for(app.devices.server, FRONT_RIGHT, 10)
    app.advance(20)
    expected = map_stylus(position, leg.home + app.teleop.shift, app.teleop.scale)
    np.testing.assert_allclose(leg.target, expected)
    np.testing.assert_allclose(simulation.reference_angles[leg.joints], leg.result.angles)
    assert np.max(np.abs(simulation.reference_angles[leg.joints] - before)) > 1e-3
    load = simulation.foot_normal_forces()[FRONT_RIGHT]
    app.advance(1000)  # the load moves to the pressed diagonal within about 0.75 s
    pressed = []
    for _ in range(10):  # the loads rock between the feet: compare a 250 ms mean
        app.advance(25)
        pressed.append(simulation.foot_normal_forces()[FRONT_RIGHT])
    # the foot stands on the ground: pressed down, it takes more of the robot's weight
    assert np.mean(pressed) > load + 1.0  # measured +6.2 N (12.7 N before)
    feedback = decode_device_feedback(_latest_feedback(client_socket))
    assert feedback.leg_index == FRONT_RIGHT and not feedback.clamped
    assert feedback.simulation_time == pytest.approx(simulation.time)
    assert np.all(np.isfinite(feedback.force)) and 0.0 < np.linalg.norm(feedback.force) <= 3.3
    up = simulation.data.xmat[simulation.robot.thorax_id].reshape(3, 3).T @ [0.0, 0.0, 1.0]
    assert feedback.force @ up > 0.9 * np.linalg.norm(feedback.force)  # contact dominates
    assert feedback.normal_force == pytest.approx(simulation.foot_normal_forces()[1])
    assert "front_right feedback" in app.controls.feedback_readout.content
    arrows = np.asarray(app.feedback_arrows.segments.points)
    assert arrows.shape == (2, 2, 3) and app.feedback_arrows.segments.visible


def test_released_button_leaves_the_target(app: ConsoleApp, client_socket: socket.socket) -> None:
    app.reset()
    leg = app.teleop.legs["front_right"]
    client_socket.sendto(encode_device_input(20, time.monotonic(), FRONT_RIGHT,
                                      np.array([0.0, 0.0, 0.03]), 0),
                  ("127.0.0.1", app.devices.server.port))
    _wait_for(app.devices.server, FRONT_RIGHT, 20)
    app.advance(20)
    np.testing.assert_array_equal(leg.target, leg.home)
    np.testing.assert_array_equal(app.teleop.stylus("front_right"), 0.0)


def test_stale_input_does_not_move_the_console_foot(app: ConsoleApp,
                                                    client_socket: socket.socket) -> None:
    app.reset()
    leg = app.teleop.legs["front_right"]
    server = app.devices.server
    client_socket.sendto(encode_device_input(30, time.monotonic(), FRONT_RIGHT,
                                      np.array([0.0, 0.0, 0.03]), BUTTON_ENGAGE),
                  ("127.0.0.1", server.port))
    _wait_for(server, FRONT_RIGHT, 30)
    server.stale_timeout = 0.05  # the input is older than that after the sleep
    try:
        time.sleep(0.15)
        app.advance(20)
    finally:
        server.stale_timeout = 0.5
    np.testing.assert_array_equal(leg.target, leg.home)


def test_example_client_prints_feedback() -> None:
    console = ConsoleApp(configuration="fixed", environment="flat", port=0, real_time=True,
                         device_port=0)
    try:
        console.start()
        result = subprocess.run(
            [sys.executable, str(CLIENT), "--port", str(console.devices.server.port),
             "--duration", "1"], capture_output=True, text=True, timeout=30, check=True)
        moved = console.teleop.legs["front_right"].target - console.teleop.legs[
            "front_right"].home
    finally:
        console.close()
    lines = [line for line in result.stdout.splitlines() if line.startswith("feedback")]
    assert len(lines) > 10, result.stdout + result.stderr
    assert "leg=front_right" in lines[-1] and "N normal=" in lines[-1]
    assert np.linalg.norm(moved) > 0.001  # the circle moved the target


def test_console_command_has_a_device_port() -> None:
    command = typer.Typer()
    command.command("console")(console_command)
    command.command("other")(lambda: None)
    result = CliRunner().invoke(command, ["console", "--port", "0", "--duration", "0.5",
                                          "--configuration", "fixed", "--device-port", "0"])
    assert result.exit_code == 0, result.output
    assert "Input devices: UDP 127.0.0.1:" in result.output


def test_place_foot_button_chooses_the_front_foothold_in_shared_walking(
        app: ConsoleApp, client_socket: socket.socket) -> None:
    front_left = 0  # leg index
    address = ("127.0.0.1", app.devices.server.port)
    app.reset()
    for _ in range(25):
        app.advance()
    app.set_walking("shared")
    crawl = app.walking.crawl
    # placed 6 cm forward (thorax z) with the button
    forward = np.array([0.0, 0.0, 0.06])
    client_socket.sendto(encode_device_input(30, time.monotonic(), front_left, forward,
                                             BUTTON_ENGAGE | BUTTON_PLACE_FOOT), address)
    _wait_for(app.devices.server, front_left, 30)
    app.advance()
    placed = crawl.operator_footholds["front_left"].copy()
    assert "front_left" in app.devices.placed
    # moved back 4 cm with engage alone: the placed foothold stays
    client_socket.sendto(encode_device_input(31, time.monotonic(), front_left,
                                             np.array([0.0, 0.0, -0.04]), BUTTON_ENGAGE),
                         address)
    _wait_for(app.devices.server, front_left, 31)
    leg = list(app.simulation.robot.legs).index("front_left")
    start = crawl.footholds[leg].copy()
    for _ in range(250):
        app.advance()
        if crawl.footholds[leg][0] > start[0] + 0.01:
            break
    np.testing.assert_array_equal(crawl.operator_footholds["front_left"], placed)
    assert crawl.footholds[leg] == pytest.approx(placed, abs=0.01)  # it stepped there
    stylus = app.teleop.legs["front_left"]
    assert stylus.target[2] < stylus.home[2]  # the stylus itself moved back
    app.set_walking("off")
    app.reset()
    assert not app.devices.placed
