"""A real UDP exchange over 127.0.0.1: command -> state, ping -> pong, a malformed datagram."""

from __future__ import annotations

import socket
import time
from collections.abc import Iterator

import numpy as np
import pytest

from pneumaquad.network.protocol import (
    MessageType,
    SequenceTracker,
    StateMessage,
    decode,
    decode_state,
    encode_command,
    encode_hello,
    encode_ping,
    encode_pong,
    encode_state,
    hello_parameters,
    pong_times,
)
from pneumaquad.network.timing import PacketLog, accept_datagram, round_trip_times

JOINTS = 6


@pytest.fixture
def sockets() -> Iterator[tuple[socket.socket, socket.socket]]:
    server = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    client = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    server.bind(("127.0.0.1", 0))
    client.bind(("127.0.0.1", 0))
    server.settimeout(2.0)
    client.settimeout(2.0)
    try:
        yield server, client
    finally:
        server.close()
        client.close()


def _state(time_s: float, answered: int) -> StateMessage:
    zeros = np.zeros(JOINTS)
    return StateMessage(time_s, zeros + 0.1, zeros, zeros, zeros, np.zeros(3),
                        np.array([1.0, 0.0, 0.0, 0.0]), answered)


def test_loopback_exchange(sockets: tuple[socket.socket, socket.socket]) -> None:
    server, client = sockets
    server_address = server.getsockname()
    client_log, server_log = PacketLog(capacity=2), PacketLog()
    client_tracker, server_tracker = SequenceTracker(), SequenceTracker()
    sequence = 0

    def client_send(datagram: bytes) -> None:
        client_log.record_sent(datagram, time.monotonic())
        client.sendto(datagram, server_address)

    client_send(encode_hello(sequence, time.monotonic(), JOINTS, 0.001))
    data, peer = server.recvfrom(2048)
    hello = accept_datagram(data, time.monotonic(), server_log, server_tracker, None)
    assert hello is not None and hello_parameters(hello) == (JOINTS, 0.001)

    for step in range(5):
        sequence += 1
        client_send(encode_command(MessageType.VALVE_COMMAND, sequence, step * 0.001,
                                   np.full(JOINTS, 0.5 * step), JOINTS))
        data, peer = server.recvfrom(2048)
        command = accept_datagram(data, time.monotonic(), server_log, server_tracker, JOINTS)
        assert command is not None and command.values[0] == 0.5 * step
        reply = encode_state(step, time.monotonic(), _state(step * 0.001, command.sequence))
        server_log.record_sent(reply)
        server.sendto(reply, peer)
        data = client.recv(2048)
        message = accept_datagram(data, time.monotonic(), client_log, client_tracker, JOINTS)
        assert message is not None and decode_state(message).answered_sequence == sequence

    sequence += 1
    client_send(encode_ping(sequence, time.monotonic()))
    data, peer = server.recvfrom(2048)
    ping = decode(data)
    server.sendto(encode_pong(5, ping, time.monotonic(), time.monotonic()), peer)
    pong_data = client.recv(2048)
    pong = accept_datagram(pong_data, time.monotonic(), client_log, client_tracker)
    assert pong is not None and pong_times(pong)[0] == ping.sender_time

    client.sendto(b"garbage", server_address)
    data, _ = server.recvfrom(2048)
    assert accept_datagram(data, time.monotonic(), server_log, server_tracker) is None

    rtts = round_trip_times(client_log)
    assert rtts.size == 6 and np.all((rtts > 0) & (rtts < 1.0))
    assert len(client_log) == 13  # 7 sent + 6 received, grown from capacity 2
    assert server_log.classification[-1] == 10  # truncated
