"""Rigid transforms as 4×4 homogeneous matrices, in SrLib's conventions (App. C.2).

SrLib writes a frame as ``EulerZYX(Vec3(a, b, c), Vec3(x, y, z))``: the rotation
Rz(a)·Ry(b)·Rx(c) followed by the translation. A link is attached to a joint by the joint
frame expressed in the parent link and in the child link, so at joint angle 0 the child
link frame in the parent is ``parent_frame · inverse(child_frame)``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

__all__ = [
    "euler_zyx_matrix",
    "frame_matrix",
    "invert",
    "rotation_about",
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


def rotation_about(axis: Sequence[float], angle: float) -> np.ndarray:
    """Rotation matrix of ``angle`` [rad] about the unit ``axis`` (Rodrigues)."""
    x, y, z = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    skew = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    return np.eye(3) + np.sin(angle) * skew + (1.0 - np.cos(angle)) * (skew @ skew)


def rotation_to_quaternion(rotation: np.ndarray) -> np.ndarray:
    """Unit quaternion (w, x, y, z), w >= 0, of a rotation matrix (Shepperd's method)."""
    m = rotation
    trace = m[0, 0] + m[1, 1] + m[2, 2]
    candidates = np.array([trace, m[0, 0], m[1, 1], m[2, 2]])
    largest = int(np.argmax(candidates))
    if largest == 0:
        w = 0.5 * np.sqrt(1.0 + trace)
        q = [w, (m[2, 1] - m[1, 2]) / (4 * w), (m[0, 2] - m[2, 0]) / (4 * w),
             (m[1, 0] - m[0, 1]) / (4 * w)]
    elif largest == 1:
        x = 0.5 * np.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2])
        q = [(m[2, 1] - m[1, 2]) / (4 * x), x, (m[0, 1] + m[1, 0]) / (4 * x),
             (m[0, 2] + m[2, 0]) / (4 * x)]
    elif largest == 2:
        y = 0.5 * np.sqrt(1.0 - m[0, 0] + m[1, 1] - m[2, 2])
        q = [(m[0, 2] - m[2, 0]) / (4 * y), (m[0, 1] + m[1, 0]) / (4 * y), y,
             (m[1, 2] + m[2, 1]) / (4 * y)]
    else:
        z = 0.5 * np.sqrt(1.0 - m[0, 0] - m[1, 1] + m[2, 2])
        q = [(m[1, 0] - m[0, 1]) / (4 * z), (m[0, 2] + m[2, 0]) / (4 * z),
             (m[1, 2] + m[2, 1]) / (4 * z), z]
    quaternion = np.asarray(q)
    quaternion /= np.linalg.norm(quaternion)
    return quaternion if quaternion[0] >= 0.0 else -quaternion
