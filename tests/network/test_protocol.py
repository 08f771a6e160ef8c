"""Wire protocol: round trips for every type, validation, malformed datagrams, fuzzing."""

from __future__ import annotations

import math
import pickle
import struct

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pneumaquad.network.protocol import (
    HEADER_FORMAT,
    HEADER_SIZE,
    MAGIC,
    MAX_DATAGRAM,
    MAX_VALUES,
    REASONS,
    VERSION,
    Message,
    MessageType,
    ProtocolError,
    StateMessage,
    StatusFlag,
    decode,
    decode_state,
    encode,
    encode_bye,
    encode_command,
    encode_hello,
    encode_ping,
    encode_pong,
    encode_state,
    expected_count,
    hello_parameters,
    next_sequence,
    pong_times,
    state_layout,
    state_value_count,
)

finite = st.floats(allow_nan=False, allow_infinity=False, width=64)
sequences = st.integers(0, 2**32 - 1)
joint_counts = st.sampled_from([6, 12])


def _raw(type_code=1, count=None, values=(), *, magic=MAGIC, version=VERSION, sequence=0,
         sender_time=0.0, extra=b"") -> bytes:
    """Hand-built datagram (bypasses the encoder's checks)."""
    count = len(values) if count is None else count
    header = struct.pack(HEADER_FORMAT, magic, version, type_code, sequence, sender_time,
                         count, 0)
    return header + struct.pack(f"<{len(values)}d", *values) + extra


def test_header_is_24_bytes_little_endian() -> None:
    datagram = encode(MessageType.TORQUE_COMMAND, 0x01020304, 1.5, [2.0], 1)
    assert HEADER_SIZE == 24 and len(datagram) == 32
    assert datagram[0:4] == b"PNQD"
    assert datagram[4:6] == b"\x01\x00"  # version 1
    assert datagram[6:8] == b"\x03\x00"  # TORQUE_COMMAND
    assert datagram[8:12] == b"\x04\x03\x02\x01"  # sequence, little-endian
    assert struct.unpack_from("<d", datagram, 12)[0] == 1.5
    assert datagram[20:22] == b"\x01\x00" and datagram[22:24] == b"\x00\x00"
    assert struct.unpack_from("<d", datagram, 24)[0] == 2.0


@settings(max_examples=60, deadline=None)
@given(st.sampled_from(sorted(MessageType)), sequences, finite, joint_counts, st.data())
def test_round_trip_every_type(message_type, sequence, sender_time, joints, data) -> None:
    count = expected_count(message_type, joints)
    values = data.draw(st.lists(finite, min_size=count, max_size=count))
    datagram = encode(message_type, sequence, sender_time, values, joints)
    assert len(datagram) == HEADER_SIZE + 8 * count
    message = decode(datagram, joints)
    assert message.type is message_type
    assert message.sequence == sequence
    assert message.sender_time == sender_time
    np.testing.assert_array_equal(message.values, np.asarray(values, dtype=float).reshape(-1))
    assert not message.values.flags.writeable


@settings(max_examples=40, deadline=None)
@given(joint_counts, sequences, finite, st.data())
def test_state_round_trip_named_fields(joints, sequence, now, data) -> None:
    arrays = {name: np.array(data.draw(st.lists(finite, min_size=size, max_size=size)))
              for name, size in (("joint_angles", joints), ("joint_velocities", joints),
                                 ("piston_positions", joints), ("piston_velocities", joints),
                                 ("thorax_position", 3), ("thorax_quaternion", 4))}
    state = StateMessage(
        simulation_time=data.draw(finite), **arrays,
        answered_sequence=data.draw(st.integers(-1, 2**32 - 1)),
        status=StatusFlag(data.draw(st.integers(0, 7))))
    datagram = encode_state(sequence, now, state)
    assert len(datagram) == HEADER_SIZE + 8 * (4 * joints + 10)
    decoded = decode_state(datagram, joints)
    assert decoded.simulation_time == state.simulation_time
    for name, values in arrays.items():
        np.testing.assert_array_equal(getattr(decoded, name), values)
    assert decoded.answered_sequence == state.answered_sequence
    assert decoded.status == state.status


def test_state_layout_offsets_for_twelve_joints() -> None:
    layout = state_layout(12)
    assert state_value_count(12) == 58 and state_value_count(6) == 34
    expected = {"simulation_time": (0, 1), "joint_angles": (1, 13),
                "joint_velocities": (13, 25), "piston_positions": (25, 37),
                "piston_velocities": (37, 49), "thorax_position": (49, 52),
                "thorax_quaternion": (52, 56), "answered_sequence": (56, 57),
                "status": (57, 58)}
    assert {name: (s.start, s.stop) for name, s in layout.items()} == expected
    state = StateMessage(2.5, np.full(12, 0.1), np.full(12, 0.2), np.full(12, 0.3),
                         np.full(12, 0.4), np.array([1.0, 2.0, 3.0]),
                         np.array([0.5, 0.5, 0.5, 0.5]), 41,
                         StatusFlag.SAFE_STATE | StatusFlag.RESYNCHRONISED)
    datagram = encode_state(9, 100.0, state)
    assert len(datagram) == 488
    read = lambda index: struct.unpack_from("<d", datagram, 24 + 8 * index)[0]  # noqa: E731
    assert read(0) == 2.5 and read(1) == 0.1 and read(13) == 0.2 and read(48) == 0.4
    assert (read(49), read(51), read(52)) == (1.0, 3.0, 0.5)
    assert read(56) == 41.0 and read(57) == 5.0


def test_state_rejects_bad_fields() -> None:
    good = dict(simulation_time=0.0, joint_angles=np.zeros(6), joint_velocities=np.zeros(6),
                piston_positions=np.zeros(6), piston_velocities=np.zeros(6),
                thorax_position=np.zeros(3), thorax_quaternion=np.array([1.0, 0, 0, 0]))
    with pytest.raises(ValueError, match="joint_velocities"):
        encode_state(0, 0.0, StateMessage(**good | {"joint_velocities": np.zeros(5)}))
    with pytest.raises(ValueError, match="answered sequence"):
        encode_state(0, 0.0, StateMessage(**good, answered_sequence=2**32))
    values = np.zeros(34)
    values[-2] = 1.5  # non-integer answered sequence
    with pytest.raises(ValueError, match="answered sequence"):
        decode_state(encode(MessageType.STATE, 0, 0.0, values))
    with pytest.raises(ValueError, match="expected a STATE"):
        decode_state(encode_ping(0, 0.0))


def test_helpers_round_trip() -> None:
    ping = decode(encode_ping(7, 123.25))
    assert ping.type is MessageType.PING and ping.values.size == 0
    pong = decode(encode_pong(3, ping, receive_time=5.0, send_time=5.5))
    assert pong.type is MessageType.PONG and pong.sender_time == 5.5
    assert pong_times(pong) == (123.25, 5.0)
    hello = decode(encode_hello(0, 1.0, 12, 0.001))
    assert hello_parameters(hello) == (12, 0.001)
    assert decode(encode_bye(9, 2.0)).type is MessageType.BYE
    valve = decode(encode_command(MessageType.VALVE_COMMAND, 4, 0.25, np.full(6, 5.0), 6), 6)
    assert valve.sender_time == 0.25 and valve.values.tolist() == [5.0] * 6
    with pytest.raises(ValueError, match="not a command"):
        encode_command(MessageType.STATE, 0, 0.0, [1.0])
    with pytest.raises(ValueError):
        encode_pong(0, hello, 0.0, 0.0)
    with pytest.raises(ProtocolError) as info:
        hello_parameters(Message(MessageType.HELLO, 0, 0.0, np.array([2.5, 0.001])))
    assert info.value.reason == "bad_count"
    assert next_sequence(2**32 - 1) == 0 and next_sequence(5) == 6


def test_encoder_refuses_what_decoder_rejects() -> None:
    with pytest.raises(ValueError):
        encode(MessageType.PING, 2**32, 0.0)
    with pytest.raises(ValueError):
        encode(99, 0, 0.0)
    with pytest.raises(ProtocolError) as info:
        encode(MessageType.VALVE_COMMAND, 0, 0.0, np.zeros(MAX_VALUES + 1))
    assert info.value.reason == "oversized"
    with pytest.raises(ProtocolError) as info:
        encode(MessageType.VALVE_COMMAND, 0, 0.0, [1.0, math.nan])
    assert info.value.reason == "non_finite"
    with pytest.raises(ProtocolError) as info:
        encode(MessageType.VALVE_COMMAND, 0, 0.0, np.zeros(6), joint_count=12)
    assert info.value.reason == "bad_count"


MALFORMED = {
    "truncated": [b"", b"PNQD\x01\x00", _raw(1, count=2, values=(1.0,))],
    "oversized": [_raw(1, values=(1.0,), extra=b"\x00"), _raw(1, values=(0.0,) * 200),
                  b"\x00" * (MAX_DATAGRAM + 1)],
    "bad_magic": [_raw(1, values=(1.0,), magic=b"PNQX"), b"\x00" * 24],
    "bad_version": [_raw(1, values=(1.0,), version=2), _raw(1, values=(1.0,), version=0)],
    "unknown_type": [_raw(0, values=(1.0,)), _raw(9, values=(1.0,)), _raw(65535)],
    "bad_count": [_raw(1, values=()), _raw(4, values=(0.0,) * 11), _raw(5, values=(1.0,)),
                  _raw(6, values=(1.0,)), _raw(7, values=(12.0,)), _raw(8, values=(1.0,))],
    "non_finite": [_raw(1, values=(1.0, math.nan)), _raw(3, values=(math.inf,)),
                   _raw(2, values=(1.0,), sender_time=math.nan),
                   _raw(4, values=(math.nan,) + (0.0,) * 13)],
}


@pytest.mark.parametrize(("reason", "datagram"),
                         [(r, d) for r, ds in MALFORMED.items() for d in ds])
def test_malformed_datagrams_give_their_reason(reason: str, datagram: bytes) -> None:
    with pytest.raises(ProtocolError) as info:
        decode(datagram)
    assert info.value.reason == reason
    assert isinstance(info.value, ValueError)


@pytest.mark.parametrize(("message_type", "count", "joints"),
                         [(1, 6, 12), (2, 13, 12), (3, 12, 6), (4, 58, 6), (4, 34, 12)])
def test_count_must_match_joint_count(message_type: int, count: int, joints: int) -> None:
    datagram = _raw(message_type, values=(0.0,) * count)
    decode(datagram)  # structurally fine without a joint count
    with pytest.raises(ProtocolError) as info:
        decode(datagram, joint_count=joints)
    assert info.value.reason == "bad_count"


def test_reason_set_is_fixed() -> None:
    assert set(REASONS) == set(MALFORMED)
    with pytest.raises(ValueError):
        ProtocolError("something_else", "")
    copy = pickle.loads(pickle.dumps(ProtocolError("truncated", "3 bytes")))
    assert copy.reason == "truncated" and str(copy) == "truncated: 3 bytes"


@settings(max_examples=400, deadline=None)
@given(st.binary(max_size=1500))
def test_fuzz_random_bytes(datagram: bytes) -> None:
    _decode_or_protocol_error(datagram)


@settings(max_examples=400, deadline=None)
@given(st.sampled_from(sorted(MessageType)), st.integers(0, 40), st.binary(max_size=400),
       st.integers(0, 2), joint_counts)
def test_fuzz_valid_header_random_payload(message_type, count, payload, version, joints):
    datagram = struct.pack(HEADER_FORMAT, MAGIC, version, message_type, 1, 0.0, count, 0)
    _decode_or_protocol_error(datagram + payload, joints)


def _decode_or_protocol_error(datagram: bytes, joints: int | None = None) -> None:
    try:
        message = decode(datagram, joints)
    except ProtocolError as error:
        assert error.reason in REASONS
    else:
        assert isinstance(message, Message)
        assert len(datagram) == HEADER_SIZE + 8 * message.values.size
