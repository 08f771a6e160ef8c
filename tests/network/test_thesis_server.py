"""The thesis-compatible server: a client that only knows App. C.2.4's 21 doubles."""

from __future__ import annotations

import socket
import struct
import threading
from pathlib import Path

import numpy as np
import pytest

from pneumaquad.io.run_folder import read_recording
from pneumaquad.network.dynamics_side import DynamicsSide
from pneumaquad.network.thesis_server import ThesisServer
from pneumaquad.params import load_robot
from pneumaquad.robot.builder import build_robot

LAYOUT = struct.Struct("<21d")  # L11..L13 R11..R13 L21..L23 R21..R23 ori11..ori33
POSTURE = np.tile(np.radians([0.0, -30.0, 60.0]), 4)


def _server(tmp_path: Path, **options) -> tuple[ThesisServer, threading.Thread]:
    robot = build_robot(load_robot("crr-quadruped"), "fixed")
    side = DynamicsSide(robot, "torque")
    side.set_pose(POSTURE)
    server = ThesisServer(side, duration=30.0, folder=tmp_path, **options)
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    return server, thread


def _exchange(client: socket.socket, address, torques, time_packet: float) -> tuple:
    values = [0.0] * 21
    values[0:3] = torques  # L11, L12, L13: alpha, beta, gamma torques of R1
    values[9] = time_packet  # R21
    client.sendto(LAYOUT.pack(*values), address)
    reply, _ = client.recvfrom(4096)
    assert len(reply) == LAYOUT.size == 168
    return LAYOUT.unpack(reply)


def test_a_simulink_style_client_drives_the_front_right_leg(tmp_path: Path) -> None:
    server, thread = _server(tmp_path)
    client = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    client.settimeout(5.0)
    try:
        first = _exchange(client, server.address, (0.0, 0.0, 0.0), 0.5)
        gamma_start = first[0]  # L11: gamma angle (SendNewData line 6)
        for step in range(300):  # 0.3 s of a positive gamma torque
            reply = _exchange(client, server.address, (0.0, 0.0, 2.0), 1.0 + step)
        client.sendto(b"\x00" * 10, server.address)  # garbage: dropped, counted
        last = _exchange(client, server.address, (0.0, 0.0, 0.0), 7.0)
    finally:
        server.stop()
        thread.join(5.0)
        client.close()
    assert reply[0] > gamma_start + np.radians(5.0)  # gamma turned with the torque
    assert reply[18] == 1.0 + 299  # ori31 echoes time_packet (R21)
    assert last[19] == 302.0  # ori32: SrLib's send counter
    assert last[20] == pytest.approx(0.302)  # ori33: simulation time, 1 ms per datagram
    first_column = np.array(last[12:15])  # ori11..ori13: first orientation column
    assert np.linalg.norm(first_column) == pytest.approx(1.0)
    assert server.dropped["truncated"] == 1
    recording = read_recording(tmp_path / "recording.parquet")
    assert recording["time [s]"].size == 302


def test_the_thesis_server_binds_to_loopback_and_filters_peers(tmp_path: Path) -> None:
    other = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    other.bind(("127.0.0.1", 0))
    server, thread = _server(tmp_path, peer=("127.0.0.1", 9))  # nobody sends from port 9
    try:
        assert server.address[0] == "127.0.0.1"
        other.settimeout(0.3)
        other.sendto(LAYOUT.pack(*([0.0] * 21)), server.address)
        with pytest.raises(socket.timeout):
            other.recvfrom(4096)
    finally:
        server.stop()
        thread.join(5.0)
        other.close()
    assert server.steps == 0
