"""Thesis-compatible datagrams: SrLib's header-less 21-value message (Daepp 2011, App. C.2.4).

The thesis's SrLib process sent and received one fixed struct per control step
(``SendNewData`` / ``ReceiveNewData`` in ``main.cpp``, App. C.2.4; in the thesis text
file lines 2329-2368 and 2374-2401). The struct's fields are named after legs (L1, R1,
L2, R2 = front_left, front_right, rear_left, rear_right) and an orientation matrix, but
are reused for other quantities. This module reads and writes that datagram so that a
peer speaking the thesis's layout can talk to our dynamics.

Assumptions (the listing does not show the struct declaration or the Simulink side):

- all 21 fields are float64 (the Simulink UDP blocks' default ``double``), packed
  without padding in the order of :data:`THESIS_LAYOUT`, little-endian (x86 hosts);
  168 bytes, no header, no magic, no sequence number;
- angles [rad], angular velocities [rad/s], torques [N m] and times [s] in SI, as SrLib
  works in SI (time step 0.001 s, gravity -9.8 m/s^2, App. C.2.4 ``User_Modeling``);
- ``SO3`` of SrLib's Lie-group library stores the rotation matrix column-major
  (``R(i, j) = _R[i + 3 j]``), so ``temp[0..5]`` (listing lines 21-26) are the first two
  *columns* R11, R21, R31, R12, R22, R32 despite the field names ori11..ori23; the third
  column is recovered as their cross product.
"""

from __future__ import annotations

import struct
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from pneumaquad.network.wire import ProtocolError

#: Field order of the SrLib message struct (App. C.2.4 listings).
THESIS_LAYOUT = (
    "L11", "L12", "L13", "R11", "R12", "R13", "L21", "L22", "L23", "R21", "R22", "R23",
    "ori11", "ori12", "ori13", "ori21", "ori22", "ori23", "ori31", "ori32", "ori33",
)
THESIS_FORMAT = "<21d"
THESIS_STRUCT = struct.Struct(THESIS_FORMAT)
THESIS_SIZE = THESIS_STRUCT.size  # 168 bytes
_INDEX = {name: index for index, name in enumerate(THESIS_LAYOUT)}


@dataclass(frozen=True, eq=False)
class ThesisState:
    """Contents of SrLib's outgoing message (``SendNewData``, listing lines 3-31).

    Attributes
    ----------
    joint_angles, joint_velocities
        Alpha, beta, gamma of leg R1 (front right) [rad], [rad/s].
    orientation
        Thorax rotation matrix, shape (3, 3) [-].
    time_packet
        Echo of the last received command's ``time_packet`` [s] (ori31, line 29).
    send_count
        SrLib's send counter ``udp_send_num`` (ori32, lines 3 and 30).
    simulation_time
        SrLib's simulation time ``m_Simulation_Time`` [s] (ori33, line 31).
    """

    joint_angles: np.ndarray
    joint_velocities: np.ndarray
    orientation: np.ndarray
    time_packet: float
    send_count: float
    simulation_time: float


@dataclass(frozen=True, eq=False)
class ThesisCommand:
    """Contents of the message SrLib receives (``ReceiveNewData``, listing lines 3-23).

    Attributes
    ----------
    torques
        Alpha, beta, gamma torque commands of leg R1 [N m] (L11, L12, L13; lines 5-7).
    front_right_angles
        R11, R12, R13 read into ``thetaR11..13`` (lines 10-12) [rad]; unused by the
        listed control loop, where leg R1 is torque-driven.
    rear_left_angles
        L21, L22, L23: position (haptic) commands of leg L2 [rad] (lines 13-15; control
        loop line 7).
    time_packet
        R21: the packet time stamp that SrLib echoes back in ori31 [s] (line 20).
    """

    torques: np.ndarray
    front_right_angles: np.ndarray
    rear_left_angles: np.ndarray
    time_packet: float


def _vector3(values: Sequence[float] | np.ndarray, name: str) -> np.ndarray:
    array = np.asarray(values, dtype=np.float64).reshape(-1)
    if array.size != 3:
        raise ValueError(f"{name} needs 3 values (alpha, beta, gamma), got {array.size}")
    return array


def _unpack(datagram: bytes | bytearray | memoryview) -> np.ndarray:
    data = bytes(datagram)
    if len(data) < THESIS_SIZE:
        raise ProtocolError("truncated", f"{len(data)} bytes, thesis layout needs {THESIS_SIZE}")
    if len(data) > THESIS_SIZE:
        raise ProtocolError("oversized", f"{len(data)} bytes, thesis layout needs {THESIS_SIZE}")
    values = np.array(THESIS_STRUCT.unpack(data), dtype=np.float64)
    if not np.isfinite(values).all():
        raise ProtocolError("non_finite", "thesis datagram holds NaN or inf")
    return values


def encode_thesis_state(joint_angles: Sequence[float] | np.ndarray,
                        joint_velocities: Sequence[float] | np.ndarray,
                        orientation: np.ndarray, time_packet: float, send_count: int,
                        simulation_time: float) -> bytes:
    """Encode a state datagram the way SrLib's ``SendNewData`` fills it.

    Parameters
    ----------
    joint_angles
        Alpha, beta, gamma angles of the reported leg [rad].
    joint_velocities
        Alpha, beta, gamma angular velocities [rad/s].
    orientation
        Thorax rotation matrix (3, 3) [-]; its first two columns are sent.
    time_packet
        ``time_packet`` of the last command received [s] (echoed for round trips).
    send_count
        Number of datagrams sent so far, this one included.
    simulation_time
        Simulation time [s].

    Returns
    -------
    bytes
        168 bytes: L11 gamma angle, L12 gamma velocity, L13 beta angle, R11 beta
        velocity, R12 alpha angle, R13 alpha velocity, L21..R23 zero, ori11..ori23 the
        first two matrix columns, ori31 ``time_packet``, ori32 ``send_count``, ori33
        ``simulation_time``.
    """
    angles = _vector3(joint_angles, "joint_angles")
    velocities = _vector3(joint_velocities, "joint_velocities")
    rotation = np.asarray(orientation, dtype=np.float64)
    if rotation.shape != (3, 3):
        raise ValueError(f"orientation must be 3 x 3, got {rotation.shape}")
    values = np.zeros(len(THESIS_LAYOUT))
    values[0:6] = (angles[2], velocities[2], angles[1], velocities[1], angles[0], velocities[0])
    values[_INDEX["ori11"]:_INDEX["ori31"]] = rotation[:, :2].T.reshape(-1)  # column-major
    values[_INDEX["ori31"]:] = (time_packet, send_count, simulation_time)
    return THESIS_STRUCT.pack(*values)


def decode_thesis_state(datagram: bytes | bytearray | memoryview) -> ThesisState:
    """Decode a ``SendNewData``-style datagram (the inverse of :func:`encode_thesis_state`).

    Raises
    ------
    ProtocolError
        ``"truncated"``/``"oversized"`` (not 168 bytes) or ``"non_finite"``.
    """
    values = _unpack(datagram)
    first, second = values[12:15], values[15:18]
    orientation = np.column_stack((first, second, np.cross(first, second)))
    return ThesisState(
        joint_angles=values[[4, 2, 0]], joint_velocities=values[[5, 3, 1]],
        orientation=orientation, time_packet=float(values[18]),
        send_count=float(values[19]), simulation_time=float(values[20]))


def encode_thesis_command(torques: Sequence[float] | np.ndarray,
                          front_right_angles: Sequence[float] | np.ndarray = (0.0, 0.0, 0.0),
                          rear_left_angles: Sequence[float] | np.ndarray = (0.0, 0.0, 0.0),
                          time_packet: float = 0.0) -> bytes:
    """Encode a command datagram as the thesis's Simulink model sent it to SrLib.

    Parameters
    ----------
    torques
        Alpha, beta, gamma torques [N m] -> L11, L12, L13.
    front_right_angles
        -> R11, R12, R13 [rad].
    rear_left_angles
        -> L21, L22, L23 [rad].
    time_packet
        -> R21 [s]; SrLib echoes it in ori31.

    Returns
    -------
    bytes
        168 bytes; fields SrLib does not read (R22, R23, ori11..ori33) are zero.
    """
    values = np.zeros(len(THESIS_LAYOUT))
    values[0:3] = _vector3(torques, "torques")
    values[3:6] = _vector3(front_right_angles, "front_right_angles")
    values[6:9] = _vector3(rear_left_angles, "rear_left_angles")
    values[_INDEX["R21"]] = time_packet
    return THESIS_STRUCT.pack(*values)


def decode_thesis_command(datagram: bytes | bytearray | memoryview) -> ThesisCommand:
    """Decode a command datagram the way SrLib's ``ReceiveNewData`` reads it.

    Parameters
    ----------
    datagram
        168 bytes in :data:`THESIS_LAYOUT` order.

    Returns
    -------
    ThesisCommand
        Torques from L11..L13, angles from R11..R13 and L21..L23, ``time_packet`` from
        R21; R22, R23 and ori11..ori33 are ignored as in the listing.

    Raises
    ------
    ProtocolError
        ``"truncated"``/``"oversized"`` (not 168 bytes) or ``"non_finite"``.
    """
    values = _unpack(datagram)
    return ThesisCommand(torques=values[0:3], front_right_angles=values[3:6],
                         rear_left_angles=values[6:9], time_packet=float(values[9]))
