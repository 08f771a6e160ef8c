"""The dynamics server on loopback: real-time safe state, an independent client, filters."""

from __future__ import annotations

import socket
import struct
import threading
import time
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

from pneumaquad.network.dynamics_side import DynamicsSide
from pneumaquad.network.endpoint import UdpEndpoint
from pneumaquad.network.server import DynamicsServer
from pneumaquad.params import load_robot
from pneumaquad.robot.builder import build_robot

# --- an external client written from docs/protocol.md only (no package imports) -------
HEADER = struct.Struct("<4sHHIdHH")
VALVE_COMMAND, STATE, PING, PONG, BYE = 1, 4, 5, 6, 8
N = 12
SAFE_STATE, COMMAND_TIMED_OUT, RESYNCHRONISED = 1, 2, 4


def _datagram(kind: int, sequence: int, sender_time: float, values=()) -> bytes:
    return HEADER.pack(b"PNQD", 1, kind, sequence, sender_time, len(values), 0) + \
        struct.pack(f"<{len(values)}d", *values)


def _parse(data: bytes):
    if len(data) < HEADER.size:
        return None
    magic, version, kind, sequence, sender_time, count, _ = HEADER.unpack_from(data)
    if magic != b"PNQD" or version != 1 or len(data) != HEADER.size + 8 * count:
        return None
    return kind, sequence, sender_time, struct.unpack_from(f"<{count}d", data, HEADER.size)


def _await_state(sock: socket.socket, sequence: int) -> tuple[float, ...]:
    while True:  # socket timeout ends the test on silence
        parsed = _parse(sock.recv(2048))
        if parsed and parsed[0] == STATE and len(parsed[3]) == 4 * N + 10 \
                and int(parsed[3][4 * N + 8]) == sequence:
            return parsed[3]


# --- fixtures ------------------------------------------------------------------------------
def _side(kind: str) -> DynamicsSide:
    side = DynamicsSide(build_robot(load_robot("crr-quadruped"), "fixed"), kind)
    side.set_pose(np.tile(np.radians((0.0, -30.0, 60.0)), 4))
    return side


def _serve(server: DynamicsServer) -> threading.Thread:
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    return thread



def test_external_client_moves_the_robot_with_valve_commands(
        client_socket: socket.socket) -> None:
    server = DynamicsServer(_side("valve"), duration=20.0)
    thread = _serve(server)
    address = server.address
    client_socket.sendto(_datagram(PING, 0, 12.5), address)
    kind, _, _, values = _parse(client_socket.recv(2048))
    assert kind == PONG and values[0] == 12.5
    simulation_time, first = 0.0, None
    for sequence in range(1, 201):  # 0.2 s with every valve open towards extension
        client_socket.sendto(_datagram(VALVE_COMMAND, sequence, simulation_time,
                                       [7.25] * N), address)
        values = _await_state(client_socket, sequence)
        simulation_time = values[0]
        first = values[1:1 + N] if first is None else first
    moved = np.degrees(np.abs(np.array(values[1:1 + N]) - np.array(first)))
    assert moved.max() > 1.0, moved
    assert simulation_time == pytest.approx(0.2)
    client_socket.sendto(_datagram(BYE, 201, 0.0), address)
    thread.join(5.0)
    assert not thread.is_alive() and server.steps == 200


def test_realtime_timeout_engages_and_releases_the_safe_state(
        client_socket: socket.socket, tmp_path: Path) -> None:
    server = DynamicsServer(_side("valve"), mode="realtime", timeout=0.1, duration=20.0,
                            folder=tmp_path, plots=False)
    thread = _serve(server)
    client_socket.setblocking(False)
    flags: dict[str, list[int]] = {"before": [], "pause": [], "after": []}
    sequence = 0

    def phase(name: str, seconds: float, send: bool) -> None:
        nonlocal sequence
        end = time.perf_counter() + seconds
        while time.perf_counter() < end:
            if send:
                sequence += 1
                client_socket.sendto(_datagram(VALVE_COMMAND, sequence, 0.0, [5.5] * N),
                                     server.address)
            time.sleep(0.002)
            while True:
                try:
                    parsed = _parse(client_socket.recv(2048))
                except BlockingIOError:
                    break
                if parsed and parsed[0] == STATE:
                    flags[name].append(int(parsed[3][4 * N + 9]))

    phase("before", 0.3, True)
    phase("pause", 0.4, False)
    phase("after", 0.3, True)
    client_socket.sendto(_datagram(BYE, sequence + 1, 0.0), server.address)
    thread.join(5.0)
    assert not thread.is_alive()
    assert flags["before"][-1] == 0
    assert SAFE_STATE | COMMAND_TIMED_OUT in flags["pause"]
    assert any(flag & RESYNCHRONISED for flag in flags["after"])
    assert flags["after"][-1] == 0
    assert server.timeouts == 1
    status = pq.read_table(tmp_path / "recording.parquet")["network status [-]"].to_numpy()
    engaged = np.flatnonzero(status == SAFE_STATE | COMMAND_TIMED_OUT)
    assert engaged.size > 100 and status[-1] == 0 and np.any(status[engaged[-1]:] == 0)
    for name in ("packets.parquet", "timing.json", "recording.csv"):
        assert (tmp_path / name).is_file()


def test_peer_filter_drops_other_sources_and_garbage_never_crashes(
        client_socket: socket.socket) -> None:
    other = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    other.bind(("127.0.0.1", 0))
    other.settimeout(0.3)
    server = DynamicsServer(_side("torque"), peer=client_socket.getsockname(), duration=20.0)
    thread = _serve(server)
    try:
        other.sendto(_datagram(3, 1, 0.0, [0.0] * N), server.address)
        with pytest.raises(TimeoutError):
            other.recv(2048)
        garbage = [b"", b"PNQD", b"\x00" * 24, b"x" * 1500, _datagram(9, 1, 0.0),
                   _datagram(3, 1, float("nan"), [0.0] * N), _datagram(3, 1, 0.0, [0.0] * 5)]
        for datagram in garbage:
            client_socket.sendto(datagram, server.address)
        client_socket.sendto(_datagram(3, 1, 0.0, [0.1] * N), server.address)
        assert _await_state(client_socket, 1)[0] == pytest.approx(0.001)
    finally:
        client_socket.sendto(_datagram(BYE, 2, 0.0), server.address)
        thread.join(5.0)
        other.close()
    counters = server.endpoint.counters()
    assert counters["foreign [count]"] == 1
    assert counters["malformed [count]"] == len(garbage)  # the empty datagram too
    assert server.steps == 1


def test_binds_to_loopback_by_default() -> None:
    with UdpEndpoint() as endpoint:
        assert endpoint.address[0] == "127.0.0.1"
    server = DynamicsServer(_side("torque"))
    assert server.address[0] == "127.0.0.1"
    server.endpoint.close()
