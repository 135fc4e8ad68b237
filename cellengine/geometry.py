"""The one module that owns SE(3) and SO(3) conversions. Transforms are 4x4 numpy arrays
named by their frames, e.g. ``T_cell_flange`` maps flange coordinates into the cell frame;
rotations are 3x3 arrays.

rpy follows URDF: R = Rz(yaw) @ Ry(pitch) @ Rx(roll). A rotation vector (axis times angle,
rad) is what :func:`log3` returns and :func:`exp3` takes.

A single pose goes through pinocchio (``pin.exp3``, ``pin.log3``, ``pin.skew``,
``pin.rpy``) where that gives the same numbers as before; many poses at once (``*_batch``,
:func:`slerp`, :func:`rotation_angles`) are vectorised numpy. A few single-pose functions
keep their own numpy formula because pinocchio's differs from it in the last bit and the
planners downstream (sampling-based) are sensitive to that: :func:`axis_angle_to_matrix`
(Rodrigues on the unit axis, where ``pin.exp3`` rescales the rotation vector),
:func:`inverse` (``R^T``, ``-R^T t`` as numpy sums it) and :func:`matrix_to_rpy` (yaw = 0
at the singularity, where pinocchio splits the angle otherwise).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from cellengine.arrays import Mat, Poses, Vec

# Rotation angle (rad) below which a rotation axis is meaningless.
TINY_ANGLE = 1e-12


# ----------------------------------------------------------------------------- vectors


def unit(v: ArrayLike) -> Vec:
    """``v`` scaled to unit length; a zero vector is an error."""
    a = np.asarray(v, dtype=float)
    n = float(np.linalg.norm(a))
    if n < 1e-12:
        raise ValueError("unit: zero vector")
    out: Vec = a / n
    return out


def cross(a: ArrayLike, b: ArrayLike) -> Vec:
    """``np.cross`` of two 3-vectors, to the bit, in a twentieth of its time (numpy's, made
    for arrays of vectors, costs ~17 us a call: 0.1 s of a cable plan's compile)."""
    a0, a1, a2 = np.asarray(a, dtype=float).reshape(3).tolist()
    b0, b1, b2 = np.asarray(b, dtype=float).reshape(3).tolist()
    return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])


def angle_between(a: ArrayLike, b: ArrayLike) -> float:
    """The angle (rad, in [0, pi]) between two vectors."""
    ua, ub = unit(a), unit(b)
    return math.atan2(float(np.linalg.norm(cross(ua, ub))), float(ua @ ub))


def signed_angle(a: ArrayLike, b: ArrayLike, axis: Vec) -> float:
    """Angle (rad, right-handed about ``axis``) from ``a`` to ``b``, both normal to it."""
    ua, ub = unit(a), unit(b)
    return math.atan2(float(cross(ua, ub) @ axis), float(ua @ ub))


def any_perpendicular(k: Vec) -> Vec:
    """A unit vector normal to the unit vector ``k`` (the cell's x made normal to it, or its
    y when ``k`` is near x)."""
    x = np.array([1.0, 0.0, 0.0]) if abs(k[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = x - k * float(x @ k)
    out: Vec = x / np.linalg.norm(x)
    return out


def skew(v: ArrayLike) -> Mat:
    """The cross-product matrix: ``skew(v) @ u == cross(v, u)``."""
    out: Mat = np.asarray(pin.skew(np.asarray(v, dtype=float).reshape(3)))
    return out


# ----------------------------------------------------------------------------- rotations


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
    """Rz(yaw) @ Ry(pitch) @ Rx(roll) (pinocchio's ``rpy.rpyToMatrix``)."""
    r, p, y = np.asarray(rpy, dtype=float).reshape(3)
    out: Mat = np.asarray(pin.rpy.rpyToMatrix(float(r), float(p), float(y)))
    return out


def matrix_to_rpy(R: Mat) -> Mat:
    """Inverse of :func:`rpy_to_matrix`; pitch in [-pi/2, pi/2], yaw = 0 at the singularity."""
    sp = -R[2, 0]
    if abs(sp) > 1.0 - 1e-12:
        pitch = np.copysign(np.pi / 2, sp)
        roll = np.arctan2(np.copysign(1.0, sp) * R[0, 1], R[1, 1])
        return np.array([roll, pitch, 0.0])
    return np.array([np.arctan2(R[2, 1], R[2, 2]), np.arcsin(sp), np.arctan2(R[1, 0], R[0, 0])])


def axis_angle_to_matrix(axis: Sequence[float] | ArrayLike, angle: float) -> Mat:
    """Rodrigues' formula. The axis need not be unit length; a zero axis means no rotation
    (FreeCAD writes '0 0 0 0')."""
    a = np.asarray(axis, dtype=float).reshape(3)
    n = float(np.linalg.norm(a))
    if n < 1e-12 or angle == 0.0:
        return np.eye(3)
    k = a / n
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    R: Mat = np.eye(3) + np.sin(angle) * K + (1.0 - np.cos(angle)) * (K @ K)
    return R


def exp3(w: ArrayLike) -> Mat:
    """The rotation of a rotation vector (``pin.exp3``)."""
    out: Mat = np.asarray(pin.exp3(np.asarray(w, dtype=float).reshape(3)))
    return out


def log3(R: ArrayLike) -> Vec:
    """The rotation vector (axis times the angle, rad in [0, pi]) of a rotation matrix
    (``pin.log3``)."""
    out: Vec = np.asarray(pin.log3(np.asarray(R, dtype=float)), dtype=float)
    return out


def exp3_batch(w: ArrayLike) -> Poses:
    """Rodrigues' formula over many rotation vectors (N, 3) -> (N, 3, 3)."""
    v = np.asarray(w, dtype=float).reshape(-1, 3)
    angle = np.linalg.norm(v, axis=1)
    k = v / np.where(angle > TINY_ANGLE, angle, 1.0)[:, None]
    K = np.zeros((len(v), 3, 3))
    K[:, 0, 1], K[:, 0, 2] = -k[:, 2], k[:, 1]
    K[:, 1, 0], K[:, 1, 2] = k[:, 2], -k[:, 0]
    K[:, 2, 0], K[:, 2, 1] = -k[:, 1], k[:, 0]
    s, c = np.sin(angle)[:, None, None], np.cos(angle)[:, None, None]
    R: Poses = np.eye(3) + s * K + (1.0 - c) * (K @ K)
    return R


def log3_batch(R: Poses) -> Vec:
    """log of many rotations (k, 3, 3) -> (k, 3): from the skew part for the small angles
    (angle from the chord, see :func:`rotation_angles`), ``pin.log3`` beyond 2 rad (near pi
    the skew part vanishes)."""
    chord = np.linalg.norm((R - np.eye(3)).reshape(-1, 9), axis=1)
    angle = 2.0 * np.arcsin(np.minimum(chord / (2.0 * math.sqrt(2.0)), 1.0))
    axis = np.stack([R[:, 2, 1] - R[:, 1, 2], R[:, 0, 2] - R[:, 2, 0], R[:, 1, 0] - R[:, 0, 1]], 1)
    small = angle < 1e-9  # angle / sin(angle) = 1 to round-off
    scale = np.where(small, 0.5, angle / np.where(small, 1.0, 2.0 * np.sin(angle)))
    out: Vec = axis * scale[:, None]
    for i in np.flatnonzero(angle > 2.0):
        out[i] = pin.log3(R[i])
    return out


def slerp(R0: Mat, R1: Mat, t: ArrayLike) -> Poses:
    """Rotations from R0 (t = 0) to R1 (t = 1) along the shortest arc, at constant angular
    speed: ``R0 @ exp(t * log(R0^T R1))``, (len(t), 3, 3)."""
    w = log3(np.asarray(R0).T @ np.asarray(R1))
    ts = np.atleast_1d(np.asarray(t, dtype=float))
    out: Poses = np.asarray(R0, dtype=float) @ exp3_batch(ts[:, None] * w)
    return out


def rotation_angle(A: Mat, B: Mat) -> float:
    """The angle (rad, in [0, pi]) of the rotation from A's orientation to B's (rotations or
    transforms)."""
    return float(np.linalg.norm(log3(A[:3, :3].T @ B[:3, :3])))


def rotation_angles(Ts: Poses) -> Vec:
    """Angle (rad) between consecutive orientations of (N, 4, 4) or (N, 3, 3) poses, (N-1,).
    From the chord: |R1 - R0|_F = 2 sqrt(2) sin(angle / 2), exact for small steps where
    arccos of the trace loses half the digits."""
    R = np.asarray(Ts)[:, :3, :3]
    chord = np.linalg.norm((R[1:] - R[:-1]).reshape(-1, 9), axis=1)
    out: Vec = 2.0 * np.arcsin(np.minimum(chord / (2.0 * math.sqrt(2.0)), 1.0))
    return out


def z_along(z: Vec) -> Mat:
    """A rotation whose z axis is the unit vector ``z`` (x: :func:`any_perpendicular`)."""
    x = any_perpendicular(z)
    return np.column_stack([x, cross(z, x), z])


def frame_yz(y: Vec, z: Vec) -> Mat:
    """The rotation with the orthonormal axes ``y`` and ``z``: columns y x z, y, z."""
    return np.column_stack([cross(y, z), y, z])


# ----------------------------------------------------------------------------- transforms


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


def rigid(T: Mat) -> Mat:
    """``T`` with its rotation replaced by the nearest rotation (polar decomposition).
    Products of rigid transforms leave SO(3) by round-off, and :func:`inverse` (a transpose)
    multiplies that: a pose composed with a grasp and its inverse again and again (a vial
    set down, picked up, set down...) must be brought back each time."""
    U, _, Vt = np.linalg.svd(np.asarray(T, dtype=float)[:3, :3])
    R = U @ Vt
    if np.linalg.det(R) < 0.0:  # a reflection is no nearer rotation than its negation
        R = U @ np.diag([1.0, 1.0, -1.0]) @ Vt
    return transform(R, np.asarray(T, dtype=float)[:3, 3])


def transform_points(T: Mat, points: ArrayLike) -> Vec:
    """Points (k, 3) given in T's child frame, in its parent frame: ``p @ R^T + t`` (any
    affine 4x4 ``T``)."""
    out: Vec = np.asarray(points) @ T[:3, :3].T + T[:3, 3]
    return out


def xyz_rpy(T: Mat) -> tuple[Mat, Mat]:
    return T[:3, 3].copy(), matrix_to_rpy(T[:3, :3])
