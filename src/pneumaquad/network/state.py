"""Payload layout of the ``STATE`` message (dynamics -> peer).

For N joints the payload holds ``4 N + 10`` float64 values, in this order (value index,
byte offset in the datagram = 24 + 8 * index):

======================  ==============  ========  =====================================
field                   indices         unit      content
======================  ==============  ========  =====================================
simulation time         0               s         dynamics' simulation time
joint angles            1 .. N          rad       robot joint order
joint velocities        N+1 .. 2N       rad/s
piston positions        2N+1 .. 3N      m         cylinder piston displacement
piston velocities       3N+1 .. 4N      m/s
thorax position         4N+1 .. 4N+3    m         x, y, z in the world frame
thorax quaternion       4N+4 .. 4N+7    -         w, x, y, z (unit, world frame)
answered sequence       4N+8            -         sequence of the command answered, -1 none
status flags            4N+9            -         :class:`StatusFlag` bits as an integer
======================  ==============  ========  =====================================

The joint order is the robot model's: leg-major over front_left, front_right, rear_left,
rear_right (only the two front legs on the 6-joint test bed), alpha, beta, gamma within
a leg.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntFlag

import numpy as np

STATE_EXTRA_VALUES = 10  # values besides the 4 N per-joint ones
_SEQUENCE_LIMIT = 2**32
_STATUS_LIMIT = 2**16


class StatusFlag(IntFlag):
    """Bits of the ``STATE`` status value."""

    NONE = 0
    SAFE_STATE = 1  # bit 0: safe state engaged (valves centred / torques zeroed)
    COMMAND_TIMED_OUT = 2  # bit 1: no valid command within the timeout
    RESYNCHRONISED = 4  # bit 2: sequence tracking was reset (HELLO or long silence)
    CLAMPED = 8  # bit 3: the held command was clamped to what the actuators can deliver
    DIVERGED = 16  # bit 4: the simulation diverged; the last good state is held, run ends


def state_value_count(joint_count: int) -> int:
    """Number of payload values of a ``STATE`` for ``joint_count`` joints (``4 N + 10``)."""
    if joint_count < 1:
        raise ValueError("joint_count must be >= 1")
    return 4 * joint_count + STATE_EXTRA_VALUES


def state_layout(joint_count: int) -> dict[str, slice]:
    """Value-index slices of the ``STATE`` fields for ``joint_count`` joints.

    Parameters
    ----------
    joint_count
        Number of joints N.

    Returns
    -------
    dict
        Field name -> slice into the payload, in payload order. Byte offset of value
        ``i`` in the datagram: ``24 + 8 * i``.
    """
    n = joint_count
    state_value_count(n)
    return {
        "simulation_time": slice(0, 1),
        "joint_angles": slice(1, 1 + n),
        "joint_velocities": slice(1 + n, 1 + 2 * n),
        "piston_positions": slice(1 + 2 * n, 1 + 3 * n),
        "piston_velocities": slice(1 + 3 * n, 1 + 4 * n),
        "thorax_position": slice(1 + 4 * n, 4 + 4 * n),
        "thorax_quaternion": slice(4 + 4 * n, 8 + 4 * n),
        "answered_sequence": slice(8 + 4 * n, 9 + 4 * n),
        "status": slice(9 + 4 * n, 10 + 4 * n),
    }


@dataclass(frozen=True, eq=False)
class StateMessage:
    """Named fields of a ``STATE`` payload (SI units).

    Attributes
    ----------
    simulation_time
        Dynamics' simulation time [s].
    joint_angles, joint_velocities
        Shape (N,), [rad] and [rad/s].
    piston_positions, piston_velocities
        Shape (N,), [m] and [m/s].
    thorax_position
        Shape (3,), world frame [m].
    thorax_quaternion
        Shape (4,), w, x, y, z [-].
    answered_sequence
        Sequence number of the command this state answers (the newest accepted one);
        -1 when no command has been accepted yet.
    status
        :class:`StatusFlag` bits.
    """

    simulation_time: float
    joint_angles: np.ndarray
    joint_velocities: np.ndarray
    piston_positions: np.ndarray
    piston_velocities: np.ndarray
    thorax_position: np.ndarray
    thorax_quaternion: np.ndarray
    answered_sequence: int = -1
    status: StatusFlag = StatusFlag.NONE

    @property
    def joint_count(self) -> int:
        """Number of joints N."""
        return int(np.size(self.joint_angles))


def state_values(state: StateMessage) -> np.ndarray:
    """Flatten a :class:`StateMessage` into its ``4 N + 10`` payload values.

    Raises
    ------
    ValueError
        Per-joint arrays of unequal length, wrong thorax shapes, or an answered sequence
        / status outside ``-1 .. 2**32 - 1`` / ``0 .. 2**16 - 1``.
    """
    n = state.joint_count
    layout = state_layout(n)
    values = np.empty(state_value_count(n), dtype=np.float64)
    if not -1 <= state.answered_sequence < _SEQUENCE_LIMIT:
        raise ValueError(f"answered sequence {state.answered_sequence} out of range")
    if not 0 <= int(state.status) < _STATUS_LIMIT:
        raise ValueError(f"status {int(state.status)} out of range")
    for name, part in layout.items():
        field = np.asarray(getattr(state, name), dtype=np.float64).reshape(-1)
        if field.size != part.stop - part.start:
            raise ValueError(f"{name} has {field.size} values, expected {part.stop - part.start}")
        values[part] = field
    return values


def _integer(value: float, low: int, high: int, name: str) -> int:
    if not (low <= value < high and value == int(value)):
        raise ValueError(f"{name} {value} is not an integer in {low} .. {high - 1}")
    return int(value)


def state_from_values(values: np.ndarray, joint_count: int | None = None) -> StateMessage:
    """Build a :class:`StateMessage` from payload values (copies the arrays).

    Parameters
    ----------
    values
        ``4 N + 10`` float64 values.
    joint_count
        Expected N; inferred from the count when omitted.

    Returns
    -------
    StateMessage
        The named fields.

    Raises
    ------
    ValueError
        Count not of the form ``4 N + 10`` (or not matching ``joint_count``), or an
        answered sequence / status that is not an integer in range.
    """
    values = np.asarray(values, dtype=np.float64).reshape(-1)
    n, remainder = divmod(values.size - STATE_EXTRA_VALUES, 4)
    if remainder or n < 1 or (joint_count is not None and n != joint_count):
        raise ValueError(f"{values.size} values do not form a STATE for {joint_count} joints")
    layout = state_layout(n)
    fields = {name: values[part].copy() for name, part in layout.items()}
    return StateMessage(
        simulation_time=float(fields["simulation_time"][0]),
        joint_angles=fields["joint_angles"],
        joint_velocities=fields["joint_velocities"],
        piston_positions=fields["piston_positions"],
        piston_velocities=fields["piston_velocities"],
        thorax_position=fields["thorax_position"],
        thorax_quaternion=fields["thorax_quaternion"],
        answered_sequence=_integer(float(fields["answered_sequence"][0]), -1, _SEQUENCE_LIMIT,
                                   "answered sequence"),
        status=StatusFlag(_integer(float(fields["status"][0]), 0, _STATUS_LIMIT, "status")),
    )
