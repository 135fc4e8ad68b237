"""The one module that owns SE(3) conversions. Transforms are 4x4 numpy arrays named by
their frames, e.g. ``T_cell_flange`` maps flange coordinates into the cell frame.

rpy follows URDF: R = Rz(yaw) @ Ry(pitch) @ Rx(roll).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

Mat = NDArray[np.float64]


def rot_x(a: float) -> Mat:
    c, s = np.cos(a), np.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(a: float) -> Mat:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_z(a: float) -> Mat:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def rpy_to_matrix(rpy: ArrayLike) -> Mat:
    r, p, y = np.asarray(rpy, dtype=float)
    return rot_z(y) @ rot_y(p) @ rot_x(r)


def matrix_to_rpy(R: Mat) -> Mat:
    """Inverse of :func:`rpy_to_matrix`; pitch in [-pi/2, pi/2], yaw = 0 at the singularity."""
    sp = -R[2, 0]
    if abs(sp) > 1.0 - 1e-12:
        pitch = np.copysign(np.pi / 2, sp)
        roll = np.arctan2(np.copysign(1.0, sp) * R[0, 1], R[1, 1])
        return np.array([roll, pitch, 0.0])
    return np.array([np.arctan2(R[2, 1], R[2, 2]), np.arcsin(sp), np.arctan2(R[1, 0], R[0, 0])])


def axis_angle_to_matrix(axis: Sequence[float], angle: float) -> Mat:
    """Rodrigues' formula. A zero axis means no rotation (FreeCAD writes '0 0 0 0')."""
    a = np.asarray(axis, dtype=float)
    n = float(np.linalg.norm(a))
    if n < 1e-12 or angle == 0.0:
        return np.eye(3)
    k = a / n
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    R: Mat = np.eye(3) + np.sin(angle) * K + (1.0 - np.cos(angle)) * (K @ K)
    return R


def transform(R: Mat | None = None, t: ArrayLike | None = None) -> Mat:
    T = np.eye(4)
    if R is not None:
        T[:3, :3] = R
    if t is not None:
        T[:3, 3] = t
    return T


def pose(xyz: ArrayLike = (0.0, 0.0, 0.0), rpy: ArrayLike = (0.0, 0.0, 0.0)) -> Mat:
    return transform(rpy_to_matrix(rpy), xyz)


def inverse(T: Mat) -> Mat:
    """Inverse of a rigid transform."""
    R, t = T[:3, :3], T[:3, 3]
    return transform(R.T, -R.T @ t)


def xyz_rpy(T: Mat) -> tuple[Mat, Mat]:
    return T[:3, 3].copy(), matrix_to_rpy(T[:3, :3])
