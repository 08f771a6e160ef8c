"""Thesis-compatible layout: SrLib's 21-double message (Daepp 2011, App. C.2.4)."""

from __future__ import annotations

import math
import struct

import numpy as np
import pytest

from pneumaquad.network.protocol import ProtocolError
from pneumaquad.network.thesis import (
    THESIS_LAYOUT,
    THESIS_SIZE,
    decode_thesis_command,
    decode_thesis_state,
    encode_thesis_command,
    encode_thesis_state,
)


def _fields(datagram: bytes) -> dict[str, float]:
    return dict(zip(THESIS_LAYOUT, struct.unpack("<21d", datagram), strict=True))


def _rotation(angle: float) -> np.ndarray:
    """Rotation about z then x: a matrix whose transpose differs from itself."""
    c, s = math.cos(angle), math.sin(angle)
    rz = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    rx = np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
    return rz @ rx


def test_layout_is_21_doubles_in_listing_order() -> None:
    assert THESIS_SIZE == 168
    assert THESIS_LAYOUT == (
        "L11", "L12", "L13", "R11", "R12", "R13", "L21", "L22", "L23", "R21", "R22", "R23",
        "ori11", "ori12", "ori13", "ori21", "ori22", "ori23", "ori31", "ori32", "ori33")


def test_state_fields_follow_send_new_data() -> None:
    rotation = _rotation(0.3)
    datagram = encode_thesis_state(joint_angles=[0.1, 0.2, 0.3],  # alpha, beta, gamma
                                   joint_velocities=[1.1, 1.2, 1.3], orientation=rotation,
                                   time_packet=4.5, send_count=17, simulation_time=0.017)
    assert len(datagram) == 168
    fields = _fields(datagram)
    # SendNewData lines 6-11: gamma pos/vel, beta pos/vel, alpha pos/vel.
    assert [fields[n] for n in ("L11", "L12", "L13", "R11", "R12", "R13")] == [
        0.3, 1.3, 0.2, 1.2, 0.1, 1.1]
    # Lines 12-17: zeros.
    assert all(fields[n] == 0.0 for n in ("L21", "L22", "L23", "R21", "R22", "R23"))
    # Lines 21-26: SO3 storage elements 0..5, column-major = first two columns.
    sent = [fields[n] for n in ("ori11", "ori12", "ori13", "ori21", "ori22", "ori23")]
    np.testing.assert_array_equal(sent, [rotation[0, 0], rotation[1, 0], rotation[2, 0],
                                         rotation[0, 1], rotation[1, 1], rotation[2, 1]])
    # Lines 29-31: debugging data.
    assert (fields["ori31"], fields["ori32"], fields["ori33"]) == (4.5, 17.0, 0.017)
    state = decode_thesis_state(datagram)
    np.testing.assert_allclose(state.orientation, rotation, atol=1e-15)
    np.testing.assert_array_equal(state.joint_angles, [0.1, 0.2, 0.3])
    np.testing.assert_array_equal(state.joint_velocities, [1.1, 1.2, 1.3])
    assert (state.time_packet, state.send_count, state.simulation_time) == (4.5, 17, 0.017)


def test_command_fields_follow_receive_new_data() -> None:
    values = {name: float(index + 1) for index, name in enumerate(THESIS_LAYOUT)}
    datagram = struct.pack("<21d", *values.values())
    command = decode_thesis_command(datagram)
    np.testing.assert_array_equal(command.torques, [1.0, 2.0, 3.0])  # lines 5-7
    np.testing.assert_array_equal(command.front_right_angles, [4.0, 5.0, 6.0])  # 10-12
    np.testing.assert_array_equal(command.rear_left_angles, [7.0, 8.0, 9.0])  # 13-15
    assert command.time_packet == 10.0  # line 20: R21
    encoded = _fields(encode_thesis_command([1.0, 2.0, 3.0], [4.0, 5.0, 6.0],
                                            [7.0, 8.0, 9.0], time_packet=10.0))
    assert [encoded[n] for n in THESIS_LAYOUT[:10]] == [float(k) for k in range(1, 11)]
    assert all(encoded[n] == 0.0 for n in THESIS_LAYOUT[10:])


@pytest.mark.parametrize(("datagram", "reason"), [
    (b"\x00" * 167, "truncated"), (b"", "truncated"), (b"\x00" * 169, "oversized"),
    (struct.pack("<21d", *([0.0] * 20 + [math.nan])), "non_finite"),
])
def test_bad_thesis_datagrams(datagram: bytes, reason: str) -> None:
    for decoder in (decode_thesis_command, decode_thesis_state):
        with pytest.raises(ProtocolError) as info:
            decoder(datagram)
        assert info.value.reason == reason


def test_argument_shapes_are_checked() -> None:
    with pytest.raises(ValueError, match="torques"):
        encode_thesis_command([1.0, 2.0])
    with pytest.raises(ValueError, match="orientation"):
        encode_thesis_state([0, 0, 0], [0, 0, 0], np.eye(4), 0.0, 1, 0.0)
