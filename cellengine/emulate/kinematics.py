"""The TCP pose the controller reports: forward kinematics from the published DH parameters
of the e-Series arms (controller base frame to the flange), then the TCP offset. Plain
Python: the emulator stays free of numpy and pinocchio."""

from __future__ import annotations

import math
from collections.abc import Sequence

# model name the dashboard reports -> (d, a) in m; alpha is (pi/2, 0, 0, pi/2, -pi/2, 0)
DH = {
    "UR3": ((0.15185, 0, 0, 0.13105, 0.08535, 0.0921), (0, -0.24355, -0.2132, 0, 0, 0)),
    "UR5": ((0.1625, 0, 0, 0.1333, 0.0997, 0.0996), (0, -0.425, -0.3922, 0, 0, 0)),
    "UR10": ((0.1807, 0, 0, 0.17415, 0.11985, 0.11655), (0, -0.6127, -0.57155, 0, 0, 0)),
    "UR16": ((0.1807, 0, 0, 0.17415, 0.11985, 0.11655), (0, -0.4784, -0.36, 0, 0, 0)),
}
ALPHA = (math.pi / 2, 0.0, 0.0, math.pi / 2, -math.pi / 2, 0.0)

Matrix = list[list[float]]  # 3 x 4: rotation and translation


def _mul(A: Matrix, B: Matrix) -> Matrix:
    return [
        [
            A[i][0] * B[0][j] + A[i][1] * B[1][j] + A[i][2] * B[2][j] + (A[i][3] if j == 3 else 0)
            for j in range(4)
        ]
        for i in range(3)
    ]


def _dh(theta: float, d: float, a: float, alpha: float) -> Matrix:
    ct, st, ca, sa = math.cos(theta), math.sin(theta), math.cos(alpha), math.sin(alpha)
    return [[ct, -st * ca, st * sa, a * ct], [st, ct * ca, -ct * sa, a * st], [0.0, sa, ca, d]]


def _from_pose(p: Sequence[float]) -> Matrix:
    """A pose [x, y, z, rx, ry, rz] (rotation vector) as a matrix (Rodrigues)."""
    x, y, z, rx, ry, rz = p
    angle = math.sqrt(rx * rx + ry * ry + rz * rz)
    if angle < 1e-12:
        return [[1.0, 0.0, 0.0, x], [0.0, 1.0, 0.0, y], [0.0, 0.0, 1.0, z]]
    kx, ky, kz = rx / angle, ry / angle, rz / angle
    c, s = math.cos(angle), math.sin(angle)
    v = 1 - c
    return [
        [c + kx * kx * v, kx * ky * v - kz * s, kx * kz * v + ky * s, x],
        [ky * kx * v + kz * s, c + ky * ky * v, ky * kz * v - kx * s, y],
        [kz * kx * v - ky * s, kz * ky * v + kx * s, c + kz * kz * v, z],
    ]


def _to_pose(T: Matrix) -> tuple[float, ...]:
    """The rotation vector of a matrix's rotation, as the controller reports it."""
    (r00, r01, r02, x), (r10, r11, r12, y), (r20, r21, r22, z) = T
    cos = max(-1.0, min(1.0, (r00 + r11 + r22 - 1) / 2))
    angle = math.acos(cos)
    if angle < 1e-9:
        return (x, y, z, 0.0, 0.0, 0.0)
    if math.pi - angle < 1e-6:  # near pi: the axis from the diagonal
        kx = math.sqrt(max(0.0, (r00 + 1) / 2))
        ky = math.copysign(math.sqrt(max(0.0, (r11 + 1) / 2)), r01 if kx else 1.0)
        kz = math.copysign(math.sqrt(max(0.0, (r22 + 1) / 2)), r02 if kx else r12)
        return (x, y, z, kx * angle, ky * angle, kz * angle)
    f = angle / (2 * math.sin(angle))
    return (x, y, z, (r21 - r12) * f, (r02 - r20) * f, (r10 - r01) * f)


def tcp_pose(model: str, q: Sequence[float], tcp: Sequence[float]) -> tuple[float, ...]:
    """The TCP pose in the base frame for joint angles ``q`` and TCP offset ``tcp``."""
    ds, as_ = DH.get(model.upper(), DH["UR5"])
    T: Matrix = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]]
    for theta, d, a, alpha in zip(q, ds, as_, ALPHA, strict=True):
        T = _mul(T, _dh(theta, d, a, alpha))
    return _to_pose(_mul(T, _from_pose(tcp)))
