"""Versioned binary protocol over UDP of the networked co-simulation (issue #5).

This is the public module: it re-exports the framing (:mod:`~pneumaquad.network.wire`),
the ``STATE`` layout (:mod:`~pneumaquad.network.state`) and sequence tracking
(:mod:`~pneumaquad.network.sequence`), and adds one encoder / decoder per message type.
``docs/protocol.md`` is the normative description, written so that a client can be
built from it alone. The thesis ran the same exchange as header-less 21-double UDP
messages between Simulink and SrLib (Daepp 2011, ch. 5.1 and App. C.2.4); that layout
is :mod:`pneumaquad.network.thesis`.

Clocks in the header's sender time: commands carry the client's simulation time at
which they take effect; ``STATE``, ``PING``, ``PONG``, ``HELLO`` and ``BYE`` carry the
sender's monotonic clock (``time.monotonic()``) [s].
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from pneumaquad.network.sequence import (
    SequenceTracker,
    SequenceVerdict,
    Verdict,
    serial_difference,
)
from pneumaquad.network.state import (
    StateMessage,
    StatusFlag,
    state_from_values,
    state_layout,
    state_value_count,
    state_values,
)
from pneumaquad.network.wire import (
    COMMAND_TYPES,
    HEADER,
    HEADER_FORMAT,
    HEADER_SIZE,
    MAGIC,
    MAX_DATAGRAM,
    MAX_VALUES,
    REASONS,
    SEQUENCE_MODULUS,
    VERSION,
    Message,
    MessageType,
    ProtocolError,
    decode,
    encode,
    expected_count,
)

__all__ = [
    "COMMAND_TYPES", "HEADER", "HEADER_FORMAT", "HEADER_SIZE", "MAGIC", "MAX_DATAGRAM",
    "MAX_VALUES", "REASONS", "SEQUENCE_MODULUS", "STEP_TOLERANCE", "VERSION", "Message",
    "MessageType", "ProtocolError", "SequenceTracker", "SequenceVerdict", "StateMessage",
    "StatusFlag", "Verdict", "check_hello", "decode", "decode_state", "encode", "encode_bye",
    "encode_command", "encode_hello", "encode_ping", "encode_pong", "encode_state",
    "expected_count", "hello_parameters", "next_sequence", "pong_times", "serial_difference",
    "state_from_values", "state_layout", "state_value_count", "state_values",
]


def next_sequence(sequence: int) -> int:
    """Sequence number following ``sequence`` (wraps from 2**32 - 1 to 0)."""
    return (sequence + 1) % SEQUENCE_MODULUS


def encode_command(message_type: MessageType | int, sequence: int, simulation_time: float,
                   values: Sequence[float] | np.ndarray, joint_count: int | None = None) -> bytes:
    """Encode a ``VALVE_COMMAND`` [V], ``FORCE_COMMAND`` [N] or ``TORQUE_COMMAND`` [N m].

    Parameters
    ----------
    message_type
        One of :data:`COMMAND_TYPES`.
    sequence
        Sender's sequence number.
    simulation_time
        Client's simulation time at which the command takes effect [s] (header sender time).
    values
        One value per joint, in the robot's joint order (leg-major: front_left,
        front_right, rear_left, rear_right; alpha, beta, gamma within a leg).
    joint_count
        Optional check of ``len(values)``.

    Returns
    -------
    bytes
        The datagram.
    """
    if MessageType(message_type) not in COMMAND_TYPES:
        raise ValueError(f"{MessageType(message_type).name} is not a command type")
    return encode(message_type, sequence, simulation_time, values, joint_count)


def encode_ping(sequence: int, monotonic_time: float) -> bytes:
    """Encode a ``PING`` stamped with the sender's monotonic clock [s]."""
    return encode(MessageType.PING, sequence, monotonic_time)


def encode_pong(sequence: int, ping: Message, receive_time: float, send_time: float) -> bytes:
    """Answer a ``PING``.

    Parameters
    ----------
    sequence
        Responder's own sequence number.
    ping
        The ping being answered; its sender time is echoed bit for bit.
    receive_time
        Responder's monotonic clock when the ping arrived [s] (payload value 1).
    send_time
        Responder's monotonic clock now [s] (header sender time).

    Returns
    -------
    bytes
        The ``PONG`` datagram.
    """
    if ping.type != MessageType.PING:
        raise ValueError(f"can only answer a PING, got {ping.type.name}")
    return encode(MessageType.PONG, sequence, send_time, (ping.sender_time, receive_time))


def pong_times(pong: Message) -> tuple[float, float]:
    """Return ``(echoed ping sender time [s], responder receive time [s])`` of a ``PONG``."""
    if pong.type != MessageType.PONG:
        raise ValueError(f"expected a PONG, got {pong.type.name}")
    return float(pong.values[0]), float(pong.values[1])


def encode_hello(sequence: int, monotonic_time: float, joint_count: int,
                 control_step: float) -> bytes:
    """Encode a ``HELLO``: announce a peer or ask for resynchronisation.

    Parameters
    ----------
    sequence
        Sender's sequence number (a new session usually starts at 0).
    monotonic_time
        Sender's monotonic clock [s].
    joint_count
        Number of joints N the sender will command or report (>= 1).
    control_step
        Sender's control (exchange) period [s], > 0.

    Returns
    -------
    bytes
        The datagram.
    """
    if not 1 <= joint_count <= MAX_VALUES or not 0.0 < control_step < math.inf:
        raise ValueError(f"HELLO needs a joint count in 1 .. {MAX_VALUES} and a positive, "
                         f"finite control step; got {joint_count}, {control_step} s")
    return encode(MessageType.HELLO, sequence, monotonic_time, (joint_count, control_step))


#: Relative tolerance of the control-step comparison of :func:`check_hello`.
STEP_TOLERANCE = 1e-9


def hello_parameters(hello: Message) -> tuple[int, float]:
    """Return ``(joint count [-], control step [s])`` of a ``HELLO``.

    Raises
    ------
    ProtocolError
        ``"bad_count"`` when the joint count is not an integer in 1 .. 172
        (:data:`MAX_VALUES`) or the control step is not positive and finite.
    """
    if hello.type != MessageType.HELLO:
        raise ValueError(f"expected a HELLO, got {hello.type.name}")
    joints, step = float(hello.values[0]), float(hello.values[1])
    if not (1 <= joints <= MAX_VALUES and joints == int(joints)):
        raise ProtocolError("bad_count", f"HELLO joint count {joints:g} is not an integer "
                            f"in 1 .. {MAX_VALUES}")
    if not (0.0 < step < math.inf):
        raise ProtocolError("bad_count", f"HELLO control step {step:g} s is not positive")
    return int(joints), step


def check_hello(hello: Message, joint_count: int | None = None,
                control_step: float | None = None) -> tuple[int, float]:
    """Read a ``HELLO`` and check it against the receiver's own dimensions.

    Parameters
    ----------
    hello
        The message.
    joint_count
        The receiver's joint count N; ``None``: any valid count.
    control_step
        The receiver's control step [s]; ``None``: any valid step. Steps equal within a
        relative :data:`STEP_TOLERANCE` (1e-9) match.

    Returns
    -------
    tuple
        ``(joint count [-], control step [s])`` announced by the sender.

    Raises
    ------
    ProtocolError
        ``"bad_count"``: invalid parameters (:func:`hello_parameters`), or a joint count
        or control step other than the receiver's.
    """
    joints, step = hello_parameters(hello)
    if joint_count is not None and joints != joint_count:
        raise ProtocolError("bad_count", f"HELLO announces {joints} joints; this receiver "
                            f"has {joint_count}")
    if control_step is not None and not math.isclose(step, control_step,
                                                     rel_tol=STEP_TOLERANCE, abs_tol=0.0):
        raise ProtocolError("bad_count", f"HELLO announces a {step:g} s control step; this "
                            f"receiver steps {control_step:g} s")
    return joints, step


def encode_bye(sequence: int, monotonic_time: float) -> bytes:
    """Encode a ``BYE`` (the peer leaves; the receiver may release its session)."""
    return encode(MessageType.BYE, sequence, monotonic_time)


def encode_state(sequence: int, monotonic_time: float, state: StateMessage) -> bytes:
    """Encode a ``STATE``.

    Parameters
    ----------
    sequence
        Dynamics' sequence number.
    monotonic_time
        Dynamics' monotonic clock at sending [s] (header sender time); the simulation
        time travels in the payload.
    state
        Named fields, see :mod:`pneumaquad.network.state`.

    Returns
    -------
    bytes
        The datagram, ``24 + 8 (4 N + 10)`` bytes (488 B for 12 joints).
    """
    return encode(MessageType.STATE, sequence, monotonic_time, state_values(state),
                  state.joint_count)


def decode_state(message: Message | bytes, joint_count: int | None = None) -> StateMessage:
    """Named fields of a ``STATE`` message (or datagram).

    Parameters
    ----------
    message
        A decoded message or the raw datagram.
    joint_count
        Expected N; inferred from the payload count when omitted.

    Returns
    -------
    StateMessage
        The fields.

    Raises
    ------
    ProtocolError
        Raw datagram rejected by :func:`decode`.
    ValueError
        Not a ``STATE``, or an answered sequence / status that is not an integer in range.
    """
    if not isinstance(message, Message):
        message = decode(message, joint_count)
    if message.type != MessageType.STATE:
        raise ValueError(f"expected a STATE, got {message.type.name}")
    return state_from_values(np.asarray(message.values), joint_count)
