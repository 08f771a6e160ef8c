"""Rigid transforms as 4×4 homogeneous matrices, in SrLib's conventions (App. C.2).

SrLib writes a frame as ``EulerZYX(Vec3(a, b, c), Vec3(x, y, z))``: the rotation
Rz(a)·Ry(b)·Rx(c) followed by the translation. A link is attached to a joint by the joint
frame expressed in the parent link and in the child link, so at joint angle 0 the child
link frame in the parent is ``parent_frame · inverse(child_frame)``.
"""

from __future__ import annotations

from collections.abc import Sequence

import mujoco
import numpy as np

__all__ = [
    "euler_zyx_matrix",
    "frame_matrix",
    "invert",
    "rotation_to_quaternion",
]


def _rotation_x(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _rotation_y(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def _rotation_z(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def euler_zyx_matrix(angles: Sequence[float]) -> np.ndarray:
    """Rotation matrix Rz(a)·Ry(b)·Rx(c) for ``angles`` = (a, b, c) [rad]."""
    a, b, c = angles
    return _rotation_z(a) @ _rotation_y(b) @ _rotation_x(c)


def frame_matrix(rotation_zyx: Sequence[float], position: Sequence[float]) -> np.ndarray:
    """Homogeneous transform of an SrLib ``EulerZYX`` frame (angles [rad], position [m])."""
    transform = np.eye(4)
    transform[:3, :3] = euler_zyx_matrix(rotation_zyx)
    transform[:3, 3] = position
    return transform


def invert(transform: np.ndarray) -> np.ndarray:
    """Inverse of a rigid homogeneous transform."""
    rotation = transform[:3, :3]
    inverse = np.eye(4)
    inverse[:3, :3] = rotation.T
    inverse[:3, 3] = -rotation.T @ transform[:3, 3]
    return inverse


def rotation_to_quaternion(rotation: np.ndarray) -> np.ndarray:
    """Unit quaternion (w, x, y, z), w >= 0, of a rotation matrix (MuJoCo's ``mju_mat2Quat``)."""
    quaternion = np.zeros(4)
    mujoco.mju_mat2Quat(quaternion, np.ascontiguousarray(rotation, dtype=float).reshape(9))
    return quaternion if quaternion[0] >= 0.0 else -quaternion
