"""Datagram framing: header, message types, validation (``encode`` / ``decode``).

Every datagram is a 24-byte little-endian header followed by ``count`` float64 values;
``docs/protocol.md`` is the normative description. Import the public names from
:mod:`pneumaquad.network.protocol`, which re-exports this module and adds the
per-type helpers.

Header (struct ``"<4sHHIdHH"``): magic ``b"PNQD"``, version, message type, sequence
number, sender time [s], payload count, reserved (0).
"""

from __future__ import annotations

import math
import struct
from collections.abc import Sequence
from dataclasses import dataclass
from enum import IntEnum

import numpy as np

from pneumaquad.network.sequence import SEQUENCE_MODULUS

__all__ = [
    "COMMAND_TYPES", "HEADER", "HEADER_FORMAT", "HEADER_SIZE", "MAGIC", "MAX_DATAGRAM",
    "MAX_VALUES", "REASONS", "SEQUENCE_MODULUS", "VERSION", "Message", "MessageType",
    "ProtocolError", "decode", "encode", "expected_count",
]

MAGIC = b"PNQD"
VERSION = 1
HEADER_FORMAT = "<4sHHIdHH"
HEADER = struct.Struct(HEADER_FORMAT)
HEADER_SIZE = HEADER.size  # 24 bytes
MAX_DATAGRAM = 1400  # [B], below a 1500-byte Ethernet MTU after IP/UDP headers
MAX_VALUES = (MAX_DATAGRAM - HEADER_SIZE) // 8  # 172 float64 values
_VALUE_DTYPE = np.dtype("<f8")

#: Every ``ProtocolError.reason`` that :func:`decode` can give.
REASONS = ("truncated", "oversized", "bad_magic", "bad_version", "unknown_type",
           "bad_count", "non_finite")


class MessageType(IntEnum):
    """Message types; the payload of each is tabulated in ``docs/protocol.md``."""

    VALVE_COMMAND = 1  # client -> dynamics: N valve voltages [V]
    FORCE_COMMAND = 2  # actuator side -> dynamics: N cylinder forces [N]
    TORQUE_COMMAND = 3  # client -> dynamics: N joint torques [N m]
    STATE = 4  # dynamics -> peer: layout in pneumaquad.network.state
    PING = 5  # no payload; header sender time is the stamp
    PONG = 6  # echoed ping sender time [s], responder receive time [s]
    HELLO = 7  # joint count [-], control step [s]
    BYE = 8  # no payload
    DEVICE_INPUT = 16  # input device -> console: leg index, stylus x, y, z [m], buttons
    DEVICE_FEEDBACK = 17  # console -> device: leg, force x, y, z [N], normal force [N], clamped


#: Types whose payload is one value per joint.
COMMAND_TYPES = frozenset(
    {MessageType.VALVE_COMMAND, MessageType.FORCE_COMMAND, MessageType.TORQUE_COMMAND})
_FIXED_COUNTS = {MessageType.PING: 0, MessageType.PONG: 2, MessageType.HELLO: 2,
                 MessageType.BYE: 0, MessageType.DEVICE_INPUT: 5,
                 MessageType.DEVICE_FEEDBACK: 6}
_STATE_EXTRA = 10  # time, thorax position (3), quaternion (4), answered sequence, status


class ProtocolError(ValueError):
    """A datagram (or values to encode) that breaks the protocol.

    Parameters
    ----------
    reason
        One of :data:`REASONS`; receivers count drops by it.
    detail
        Human-readable explanation.
    """

    def __init__(self, reason: str, detail: str) -> None:
        if reason not in REASONS:
            raise ValueError(f"unknown protocol error reason {reason!r}")
        super().__init__(f"{reason}: {detail}")
        self.reason = reason
        self.detail = detail

    def __reduce__(self) -> tuple[type, tuple[str, str]]:
        return type(self), (self.reason, self.detail)


@dataclass(frozen=True, eq=False)
class Message:
    """A decoded datagram.

    Attributes
    ----------
    type
        Message type.
    sequence
        Sender's sequence number, 0 <= sequence < 2**32.
    sender_time
        Sender's clock at sending [s] (which clock depends on the type, see the document).
    values
        Read-only float64 payload, shape ``(count,)``.
    """

    type: MessageType
    sequence: int
    sender_time: float
    values: np.ndarray


def expected_count(message_type: MessageType | int, joint_count: int | None = None) -> int | None:
    """Payload count a message type requires.

    Parameters
    ----------
    message_type
        Message type.
    joint_count
        Number of joints N of the robot (12, or 6 on the test bed); needed by commands
        and ``STATE``.

    Returns
    -------
    int or None
        N for commands, ``4 N + 10`` for ``STATE``, the fixed count of the other types;
        ``None`` when the count depends on an unknown joint count.
    """
    message_type = MessageType(message_type)
    if message_type in _FIXED_COUNTS:
        return _FIXED_COUNTS[message_type]
    if joint_count is None:
        return None
    if message_type == MessageType.STATE:
        return 4 * joint_count + _STATE_EXTRA
    return joint_count


def _check_count(message_type: MessageType, count: int, joint_count: int | None) -> None:
    required = expected_count(message_type, joint_count)
    if required is not None:
        if count != required:
            raise ProtocolError("bad_count", f"{message_type.name} with {joint_count} joints "
                                f"needs {required} values, got {count}")
        return
    # Joint count unknown: only the structure can be checked.
    if message_type == MessageType.STATE:
        if count <= _STATE_EXTRA or (count - _STATE_EXTRA) % 4:
            raise ProtocolError("bad_count", f"STATE needs 4 N + 10 values (N >= 1), got {count}")
    elif count < 1:
        raise ProtocolError("bad_count", f"{message_type.name} needs at least one value")


def _check_values(message_type: MessageType, sender_time: float, values: np.ndarray,
                  joint_count: int | None) -> None:
    _check_count(message_type, values.size, joint_count)
    if not math.isfinite(sender_time):
        raise ProtocolError("non_finite", f"sender time is {sender_time}")
    if not np.isfinite(values).all():
        raise ProtocolError("non_finite", f"{message_type.name} payload holds NaN or inf")


def encode(message_type: MessageType | int, sequence: int, sender_time: float,
           values: Sequence[float] | np.ndarray = (), joint_count: int | None = None) -> bytes:
    """Build one datagram.

    Parameters
    ----------
    message_type
        Message type.
    sequence
        Sender's sequence number, 0 <= sequence < 2**32 (use ``(previous + 1) % 2**32``).
    sender_time
        Sender's clock [s], finite.
    values
        Payload; converted to float64.
    joint_count
        When given, the payload count is checked against it like :func:`decode` does.

    Returns
    -------
    bytes
        The datagram, ``24 + 8 * len(values)`` bytes; :func:`decode` accepts it.

    Raises
    ------
    ProtocolError
        Values that :func:`decode` would reject (``"oversized"``, ``"bad_count"``,
        ``"non_finite"``).
    ValueError
        Unknown message type or sequence number out of range.
    """
    message_type = MessageType(message_type)
    if not 0 <= sequence < SEQUENCE_MODULUS:
        raise ValueError(f"sequence number {sequence} outside 0 .. 2**32 - 1")
    payload = np.ascontiguousarray(values, dtype=_VALUE_DTYPE).reshape(-1)
    if payload.size > MAX_VALUES:
        raise ProtocolError("oversized", f"{payload.size} values exceed {MAX_VALUES}")
    _check_values(message_type, float(sender_time), payload, joint_count)
    header = HEADER.pack(MAGIC, VERSION, int(message_type), int(sequence), float(sender_time),
                         payload.size, 0)
    return header + payload.tobytes()


def decode(datagram: bytes | bytearray | memoryview, joint_count: int | None = None) -> Message:
    """Parse and validate one datagram.

    Parameters
    ----------
    datagram
        Bytes as received.
    joint_count
        Number of joints N the receiver expects; when given, commands and ``STATE``
        must carry exactly the matching count.

    Returns
    -------
    Message
        The message; ``values`` is a read-only float64 array.

    Raises
    ------
    ProtocolError
        With ``reason`` one of :data:`REASONS`; no other exception escapes for any input
        of type bytes.
    """
    data = bytes(datagram)
    size = len(data)
    if size < HEADER_SIZE:
        raise ProtocolError("truncated", f"{size} bytes, header needs {HEADER_SIZE}")
    if size > MAX_DATAGRAM:
        raise ProtocolError("oversized", f"{size} bytes exceed {MAX_DATAGRAM}")
    magic, version, type_code, sequence, sender_time, count, _reserved = HEADER.unpack_from(data)
    if magic != MAGIC:
        raise ProtocolError("bad_magic", f"magic {magic!r}, expected {MAGIC!r}")
    if version != VERSION:
        raise ProtocolError("bad_version", f"version {version}, expected {VERSION}")
    try:
        message_type = MessageType(type_code)
    except ValueError:
        raise ProtocolError("unknown_type", f"message type {type_code}") from None
    declared = HEADER_SIZE + 8 * count
    if size < declared:
        raise ProtocolError("truncated", f"{size} bytes, {count} values need {declared}")
    if size > declared:
        raise ProtocolError("oversized", f"{size} bytes, {count} values need {declared}")
    values = np.frombuffer(data, dtype=_VALUE_DTYPE, count=count, offset=HEADER_SIZE)
    _check_values(message_type, sender_time, values, joint_count)
    return Message(message_type, sequence, sender_time, values)
