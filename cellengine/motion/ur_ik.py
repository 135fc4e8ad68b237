"""Closed-form inverse kinematics of the Universal Robots family (UR3e, UR5e, UR10e, UR5, ...).

Conventions are the controller's: standard DH, ``T_i = Rz(q_i) @ Tz(d_i) @ Tx(a_i) @ Rx(alpha_i)``,
from the controller base frame to the flange (``tool0``). Callers with a mounted base or a
tool transform their targets first: ``T_base_flange = inv(T_world_base) @ T_world_tcp @
inv(T_flange_tcp)``.

Eight branches per pose, indexed ``4 * shoulder + 2 * wrist + elbow`` (each bit 0 or 1):

- shoulder 0: ``q1 = psi + atan2(d4, +sqrt(r^2 - d4^2))``, 1: the ``-sqrt`` root, where
  ``r, psi`` are the polar coordinates of the wrist point ``p5`` in the base xy-plane;
- wrist 0: ``sin(q5) >= 0``, 1: ``sin(q5) <= 0``;
- elbow 0: ``sin(q3) >= 0``, 1: ``sin(q3) <= 0``.

Two code paths share these formulas: :meth:`URKinematics.solve` runs numpy over N poses at once
(per-call overhead amortised), and :meth:`URKinematics.ik` / :meth:`URKinematics.ik_all` run pure
Python ``math`` for one pose, because a numpy call costs about a microsecond and one pose would
need a few hundred of them.

Every angle comes from ``atan2`` of two well-conditioned quantities rather than ``acos``, so the
residual stays at rounding level even near ``q5 = 0`` (``acos`` near 1 loses half the digits).
Singular poses give a valid solution, never NaN: at the wrist singularity (``sin q5 = 0``) the
axes of joints 2, 3, 4 and 6 are parallel and the solutions form a one-parameter family; ``q6``
is taken from the seed and q2..q4 follow. At the shoulder singularity (``r = |d4|``) the two
shoulder roots coincide; with the elbow stretched (``q3 = 0``) the two elbows do.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from cellengine.arrays import BoolArray, FloatArray

TWO_PI = 2.0 * math.pi
INV_TWO_PI = 1.0 / TWO_PI
HALF_PI = 0.5 * math.pi

# Below this |sin q5| the wrist is treated as singular and q6 is taken from the seed. The
# orientation error this adds is at most 2 * |sin q5|, far under the 1e-9 residual goal.
WRIST_EPS = 1e-12
# Round-off slack: a wrist point this far (m^2) inside the d4 cylinder, or an elbow cosine this
# far beyond 1, is taken as on the boundary rather than unreachable.
SHOULDER_SLACK = 1e-12
ELBOW_SLACK = 1e-9
# A wrapped angle this close outside a joint limit is clamped onto it (round-off, not a violation).
LIMIT_SLACK = 1e-10
_SIGN2 = np.array([[1.0], [-1.0]])


@dataclass(frozen=True)
class DH:
    """A standard DH table: six d (m), a (m) and alpha (rad)."""

    d: tuple[float, float, float, float, float, float]
    a: tuple[float, float, float, float, float, float]
    alpha: tuple[float, float, float, float, float, float]


def _dh(d: Sequence[float], a: Sequence[float]) -> DH:
    alpha = (HALF_PI, 0.0, 0.0, HALF_PI, -HALF_PI, 0.0)
    return DH(tuple(float(x) for x in d), tuple(float(x) for x in a), alpha)  # type: ignore[arg-type]


# Published DH parameters (Universal Robots), controller base frame to flange.
UR_DH: dict[str, DH] = {
    "ur3e": _dh((0.15185, 0, 0, 0.13105, 0.08535, 0.0921), (0, -0.24355, -0.2132, 0, 0, 0)),
    "ur5e": _dh((0.1625, 0, 0, 0.1333, 0.0997, 0.0996), (0, -0.425, -0.3922, 0, 0, 0)),
    "ur10e": _dh((0.1807, 0, 0, 0.17415, 0.11985, 0.11655), (0, -0.6127, -0.57155, 0, 0, 0)),
    "ur5": _dh((0.089159, 0, 0, 0.10915, 0.09465, 0.0823), (0, -0.425, -0.39225, 0, 0, 0)),
}

# ur_description's position limits: +-2 pi, the elbow +-pi (beyond it the forearm meets the
# upper arm).
UR_UPPER = (TWO_PI, TWO_PI, math.pi, TWO_PI, TWO_PI, TWO_PI)
UR_LOWER = tuple(-x for x in UR_UPPER)


def _check_structure(d: Sequence[float], a: Sequence[float], alpha: Sequence[float]) -> None:
    """The closed form assumes the UR geometry: three parallel middle axes and a non-spherical
    wrist with offsets d4, d5, d6. Anything else must use the numerical solver."""
    if len(d) != 6 or len(a) != 6 or len(alpha) != 6:
        raise ValueError("a UR DH table has six rows")
    zero_d = (d[1], d[2])
    zero_a = (a[0], a[3], a[4], a[5])
    want_alpha = (HALF_PI, 0.0, 0.0, HALF_PI, -HALF_PI, 0.0)
    if any(abs(x) > 1e-12 for x in (*zero_d, *zero_a)):
        raise ValueError("not a UR geometry: d2, d3, a1, a4, a5, a6 must be 0")
    if any(abs(x - y) > 1e-9 for x, y in zip(alpha, want_alpha, strict=True)):
        raise ValueError("not a UR geometry: alpha must be (pi/2, 0, 0, pi/2, -pi/2, 0)")
    if abs(d[3]) < 1e-9 or abs(a[1]) < 1e-9 or abs(a[2]) < 1e-9:
        raise ValueError("not a UR geometry: d4, a2 and a3 must be non-zero")


def _limits(value: ArrayLike | None, default: float) -> list[float]:
    if value is None:
        return [default] * 6
    out = [float(x) for x in np.asarray(value, dtype=float).reshape(6)]
    return out


class URKinematics:
    """Forward and closed-form inverse kinematics of one UR arm from its DH table.

    ``lower``/``upper`` are the default joint limits (rad) for :meth:`ik` and :meth:`ik_batch`;
    UR arms allow +-2 pi on every joint, which is the default.
    """

    def __init__(
        self,
        d: Sequence[float],
        a: Sequence[float],
        alpha: Sequence[float],
        lower: ArrayLike | None = None,
        upper: ArrayLike | None = None,
    ) -> None:
        _check_structure(d, a, alpha)
        self.d = np.array(d, dtype=float)
        self.a = np.array(a, dtype=float)
        self.alpha = np.array(alpha, dtype=float)
        self.lower = np.array(_limits(lower, -TWO_PI))
        self.upper = np.array(_limits(upper, TWO_PI))
        self._lower = self.lower.tolist()
        self._upper = self.upper.tolist()
        d1, d4, d5, d6 = float(d[0]), float(d[3]), float(d[4]), float(d[5])
        a2, a3 = float(a[1]), float(a[2])
        self._d1, self._d4, self._d5, self._d6, self._a2, self._a3 = d1, d4, d5, d6, a2, a3
        self._elbow_k = a2 * a2 + a3 * a3
        self._elbow_den = 2.0 * a2 * a3

    @classmethod
    def from_dh(
        cls, dh: DH, lower: ArrayLike | None = None, upper: ArrayLike | None = None
    ) -> URKinematics:
        """From a :class:`DH` table (an ``Arm.dh``), e.g. with the arm's limits."""
        return cls(dh.d, dh.a, dh.alpha, lower, upper)

    @classmethod
    def from_name(
        cls, name: str, lower: ArrayLike | None = None, upper: ArrayLike | None = None
    ) -> URKinematics:
        """A built-in model by name: ``ur3e``, ``ur5e``, ``ur10e`` or ``ur5``, by default with
        the built-in URDFs' limits (ur_description's: +-2 pi, the elbow +-pi)."""
        dh = UR_DH[name]
        return cls(
            dh.d,
            dh.a,
            dh.alpha,
            UR_LOWER if lower is None else lower,
            UR_UPPER if upper is None else upper,
        )

    # ------------------------------------------------------------------ forward kinematics

    def fk(self, q: ArrayLike) -> FloatArray:
        """T_base_flange (4, 4) for one configuration (6,)."""
        T: FloatArray = self.fk_batch(np.asarray(q, dtype=float).reshape(1, 6))[0]
        return T

    def fk_batch(self, q: ArrayLike) -> FloatArray:
        """T_base_flange (N, 4, 4) for N configurations (N, 6)."""
        qa = np.asarray(q, dtype=float).reshape(-1, 6)
        n = qa.shape[0]
        T = np.broadcast_to(np.eye(4), (n, 4, 4)).copy()
        for i in range(6):
            T = T @ _dh_matrices(qa[:, i], self.d[i], self.a[i], self.alpha[i])
        return T

    # ------------------------------------------------------------------ batched (numpy)

    def solve(
        self, T_base_flange: ArrayLike, seed6: ArrayLike | None = None
    ) -> tuple[FloatArray, BoolArray]:
        """All eight branches for N poses: q (N, 8, 6) in [-pi, pi] and valid (N, 8).

        ``seed6`` (scalar or (N,)) is q6 at wrist singularities (default 0). Invalid branches
        (pose out of reach of that branch) hold finite garbage and ``valid`` False.
        """
        q, valid = self._solve_t(T_base_flange, seed6)
        return np.ascontiguousarray(q.transpose(2, 1, 0)), np.ascontiguousarray(valid.T)

    def _solve_t(
        self, T_base_flange: ArrayLike, seed6: ArrayLike | None
    ) -> tuple[FloatArray, BoolArray]:
        """:meth:`solve` in the layout the arithmetic wants: q (6, 8, N), valid (8, N). With the
        pose index last every operation runs over contiguous blocks of N, and sums over the
        six joints are six additions of whole blocks (numpy reduces a length-6 last axis
        slowly)."""
        Ts = np.asarray(T_base_flange, dtype=float).reshape(-1, 4, 4)
        n = Ts.shape[0]
        q6_sing = np.broadcast_to(np.asarray(0.0 if seed6 is None else seed6, float), (n,))
        d1, d4, d5, d6, a2, a3 = self._d1, self._d4, self._d5, self._d6, self._a2, self._a3
        M = np.ascontiguousarray(Ts[:, :3, :].transpose(2, 1, 0))  # (4 columns, 3 rows, N)
        x6, y6, z6, p = M[0], M[1], M[2], M[3]  # (3, N) each: flange axes and origin

        # Shoulder: the wrist point p5 lies on the plane p . z1 = d4, two roots for q1.
        # Axes from here on: (shoulder, wrist, elbow, N), each present once computed.
        p5 = p - d6 * z6
        r2 = p5[0] * p5[0] + p5[1] * p5[1]
        disc = r2 - d4 * d4
        ok1 = disc > -SHOULDER_SLACK
        sq = np.sqrt(np.maximum(disc, 0.0)) * _SIGN2  # (2, N)
        inv_r2 = 1.0 / np.where(r2 > 0.0, r2, 1.0)
        c1 = (p5[0] * sq - p5[1] * d4) * inv_r2
        s1 = (p5[1] * sq + p5[0] * d4) * inv_r2
        q1 = np.arctan2(s1, c1)

        # Wrist: z1 = (s1, -c1, 0) seen from the flange is (s5 c6, -s5 s6, c5).
        xz = x6[0] * s1 - x6[1] * c1
        yz = y6[0] * s1 - y6[1] * c1
        zz = z6[0] * s1 - z6[1] * c1
        s5abs = np.hypot(xz, yz)
        singular = s5abs < WRIST_EPS
        q5a = np.arctan2(s5abs, zz)
        q6a = np.where(singular, q6_sing, np.arctan2(-yz, xz))
        inv_s5 = 1.0 / np.where(singular, 1.0, s5abs)
        c6a = np.where(singular, np.cos(q6_sing), xz * inv_s5)
        s6a = np.where(singular, np.sin(q6_sing), -yz * inv_s5)
        # The flipped wrist is q5 -> -q5, q6 -> q6 + pi, so s5, c6, s6 change sign (q6 and its
        # cosine and sine stay when singular: any q6 is right there).
        flip = np.where(singular, 1.0, -1.0)
        q5 = np.stack([q5a, -q5a])  # (2 wrist, 2 shoulder, N) for now
        q6 = np.stack([q6a, np.where(singular, q6a, q6a + math.pi)])
        s5 = np.stack([s5abs, -s5abs])
        c6 = np.stack([c6a, c6a * flip])
        s6 = np.stack([s6a, s6a * flip])
        q5, q6, s5, c6, s6 = (a.swapaxes(0, 1) for a in (q5, q6, s5, c6, s6))  # (sh, wr, N)
        c5 = zz[:, None, :]
        c1w, s1w = c1[:, None, :], s1[:, None, :]

        # Frame 4 from the flange: z4 = -s6 x6 - c6 y6, x4 = c5 (c6 x6 - s6 y6) - s5 z6.
        z4 = [-s6 * x6[k] - c6 * y6[k] for k in range(3)]
        x4 = [c5 * (c6 * x6[k] - s6 * y6[k]) - s5 * z6[k] for k in range(3)]
        X = (p5[0] - d5 * z4[0]) * c1w + (p5[1] - d5 * z4[1]) * s1w
        Y = p5[2] - d5 * z4[2] - d1
        q234 = np.arctan2(x4[2], x4[0] * c1w + x4[1] * s1w)

        # Elbow: planar two-link (a2, a3) to (X, Y); q2 = atan2(Y, X) - atan2(a3 s3, A).
        c3 = (X * X + Y * Y - self._elbow_k) / self._elbow_den
        ok3 = np.abs(c3) <= 1.0 + ELBOW_SLACK
        np.clip(c3, -1.0, 1.0, out=c3)
        s3a = np.sqrt(1.0 - c3 * c3)
        q3a = np.arctan2(s3a, c3)
        A = a2 + a3 * c3
        s3 = np.stack([s3a, -s3a], axis=2)  # (sh, wr, elbow, N)
        q3 = np.stack([q3a, -q3a], axis=2)
        B = a3 * s3
        Xe, Ye, Ae = X[:, :, None], Y[:, :, None], A[:, :, None]
        q2 = np.arctan2(Ye * Ae - Xe * B, Xe * Ae + Ye * B)
        q4 = q234[:, :, None] - q2 - q3

        q = np.empty((6, 2, 2, 2, n))
        q[0] = q1[:, None, None, :]
        q[1] = q2
        q[2] = q3
        q[3] = q4
        q[4] = q5[:, :, None, :]
        q[5] = q6[:, :, None, :]
        q = _wrap(q.reshape(6, 8, n))
        valid = np.broadcast_to(ok1 & ok3[:, :, None, :], (2, 2, 2, n)).reshape(8, n)
        return q, valid

    def ik_batch(
        self,
        T_base_flange: ArrayLike,
        seed: ArrayLike,
        lower: ArrayLike | None = None,
        upper: ArrayLike | None = None,
    ) -> tuple[FloatArray, BoolArray]:
        """For each of N poses the solution nearest ``seed`` ((6,) or (N, 6)) within limits:
        q (N, 6) and ok (N,). Rows where ok is False are NaN."""
        Ts = np.asarray(T_base_flange, dtype=float).reshape(-1, 4, 4)
        n = Ts.shape[0]
        sd = np.broadcast_to(np.asarray(seed, dtype=float), (n, 6))
        lo = self.lower if lower is None else np.asarray(lower, dtype=float).reshape(6)
        hi = self.upper if upper is None else np.asarray(upper, dtype=float).reshape(6)
        q, valid = self._solve_t(Ts, sd[:, 5])
        sd_t = np.ascontiguousarray(sd.T)[:, None, :]  # (6, 1, N)
        q, within = _wrap_near(q, sd_t, lo[:, None, None], hi[:, None, None])
        valid &= within
        e = q - sd_t
        e *= e
        dist = e[0] + e[1] + e[2] + e[3] + e[4] + e[5]  # (8, N)
        dist[~valid] = np.inf
        best = np.argmin(dist, axis=0)
        cols = np.arange(n)
        out = np.ascontiguousarray(q[:, best, cols].T)
        ok = valid[best, cols]
        out[~ok] = np.nan
        return out, ok

    # ------------------------------------------------------------------ one pose (pure Python)

    def ik_all(self, T_base_flange: ArrayLike, seed6: float = 0.0) -> tuple[FloatArray, BoolArray]:
        """All eight branches for one pose: q (8, 6) in (-pi, pi] and valid (8,)."""
        branches = self._branches(_rows(T_base_flange), seed6)
        q = np.zeros((8, 6))
        valid = np.zeros(8, dtype=bool)
        for i, b in enumerate(branches):
            if b is not None:
                q[i] = [_wrap1(x) for x in b]
                valid[i] = True
        return q, valid

    def ik(
        self,
        T_base_flange: ArrayLike,
        seed: ArrayLike | None = None,
        lower: ArrayLike | None = None,
        upper: ArrayLike | None = None,
    ) -> FloatArray | None:
        """The solution nearest ``seed`` (Euclidean in joint space, each angle moved by a
        multiple of 2 pi to the representative nearest the seed within limits), or None when no
        branch reaches the pose within the limits."""
        sd = [0.0] * 6 if seed is None else _floats6(seed)
        lo = self._lower if lower is None else _floats6(lower)
        hi = self._upper if upper is None else _floats6(upper)
        best = self._nearest(self._branches(_rows(T_base_flange), sd[5]), sd, lo, hi)
        return None if best is None else np.array(best)

    def _nearest(
        self,
        branches: list[tuple[float, ...] | None],
        sd: list[float],
        lo: list[float],
        hi: list[float],
    ) -> list[float] | None:
        """The branch nearest the seed after wrapping, or None. Walks the branch tree (q1 is
        shared by a shoulder's four branches, q5 and q6 by a wrist's two) so that each shared
        angle is wrapped once and a subtree already farther than the best is skipped."""
        best: list[float] | None = None
        best_d = math.inf
        s0, s1, s2, s3, s4, s5 = sd
        for sh in (0, 4):
            first = branches[sh] or branches[sh + 2]
            if first is None:
                continue
            w1 = _near(first[0], s0, lo[0], hi[0])
            if w1 is None:
                continue
            d1 = (w1 - s0) * (w1 - s0)
            if d1 >= best_d:
                continue
            for k in (sh, sh + 2):
                b = branches[k]
                if b is None:
                    continue
                w5 = _near(b[4], s4, lo[4], hi[4])
                w6 = _near(b[5], s5, lo[5], hi[5])
                if w5 is None or w6 is None:
                    continue
                d56 = d1 + (w5 - s4) * (w5 - s4) + (w6 - s5) * (w6 - s5)
                if d56 >= best_d:
                    continue
                for e in (b, branches[k + 1]):
                    if e is None:
                        continue
                    w2 = _near(e[1], s1, lo[1], hi[1])
                    if w2 is None:
                        continue
                    d = d56 + (w2 - s1) * (w2 - s1)
                    if d >= best_d:
                        continue
                    w3 = _near(e[2], s2, lo[2], hi[2])
                    w4 = _near(e[3], s3, lo[3], hi[3])
                    if w3 is None or w4 is None:
                        continue
                    d += (w3 - s2) * (w3 - s2) + (w4 - s3) * (w4 - s3)
                    if d < best_d:
                        best, best_d = [w1, w2, w3, w4, w5, w6], d
        return best

    def _branches(self, m: list[list[float]], seed6: float) -> list[tuple[float, ...] | None]:
        """The eight branches of one pose in branch order, None where a branch cannot reach."""
        d1, d4, d5, d6, a2, a3 = self._d1, self._d4, self._d5, self._d6, self._a2, self._a3
        (nx, ox, ax, px), (ny, oy, ay, py), (nz, oz, az, pz) = m[0], m[1], m[2]
        p5x, p5y, p5z = px - d6 * ax, py - d6 * ay, pz - d6 * az
        r2 = p5x * p5x + p5y * p5y
        disc = r2 - d4 * d4
        if disc < -SHOULDER_SLACK or r2 == 0.0:
            return [None] * 8
        sq = math.sqrt(disc) if disc > 0.0 else 0.0
        out: list[tuple[float, ...] | None] = []
        atan2, hypot, sqrt = math.atan2, math.hypot, math.sqrt
        for sq1 in (sq, -sq):
            c1 = (p5x * sq1 - p5y * d4) / r2
            s1 = (p5y * sq1 + p5x * d4) / r2
            q1 = atan2(s1, c1)
            xz = nx * s1 - ny * c1
            yz = ox * s1 - oy * c1
            c5 = ax * s1 - ay * c1
            s5a = hypot(xz, yz)
            if s5a < WRIST_EPS:
                q6a = seed6
                c6a, s6a = math.cos(seed6), math.sin(seed6)
            else:
                q6a = atan2(-yz, xz)
                c6a, s6a = xz / s5a, -yz / s5a
            q5a = atan2(s5a, c5)
            for s5, c6, s6, q5, q6 in (
                (s5a, c6a, s6a, q5a, q6a),
                (-s5a, -c6a, -s6a, -q5a, q6a + math.pi),
            ):
                if s5a < WRIST_EPS:  # flipping q6 means nothing at the singularity
                    c6, s6, q6 = c6a, s6a, q6a
                z4x = -s6 * nx - c6 * ox
                z4y = -s6 * ny - c6 * oy
                z4z = -s6 * nz - c6 * oz
                c5c6, c5s6 = c5 * c6, c5 * s6
                x4x = c5c6 * nx - c5s6 * ox - s5 * ax
                x4y = c5c6 * ny - c5s6 * oy - s5 * ay
                x4z = c5c6 * nz - c5s6 * oz - s5 * az
                X = (p5x - d5 * z4x) * c1 + (p5y - d5 * z4y) * s1
                Y = p5z - d5 * z4z - d1
                q234 = atan2(x4z, x4x * c1 + x4y * s1)
                c3 = (X * X + Y * Y - self._elbow_k) / self._elbow_den
                if abs(c3) > 1.0 + ELBOW_SLACK:
                    out += (None, None)
                    continue
                s3a = sqrt(1.0 - c3 * c3) if abs(c3) < 1.0 else 0.0
                q3a = atan2(s3a, c3)
                A = a2 + a3 * c3
                XA, YA = X * A, Y * A
                for s3, q3 in ((s3a, q3a), (-s3a, -q3a)):
                    # q2 = atan2(Y, X) - atan2(a3 s3, A), as one atan2 of the rotated vector
                    B = a3 * s3
                    q2 = atan2(YA - X * B, XA + Y * B)
                    out.append((q1, q2, q3, q234 - q2 - q3, q5, q6))
        return out


# ---------------------------------------------------------------------- helpers


def _rows(T: Any) -> list[list[float]]:
    """A 4x4 pose as nested Python lists (indexing a numpy array costs ~100 ns per element)."""
    if isinstance(T, np.ndarray):
        rows: list[list[float]] = T.tolist()
        return rows
    return [[float(x) for x in r] for r in T]


def _floats6(v: Any) -> list[float]:
    if isinstance(v, np.ndarray):
        out: list[float] = v.tolist()
        return out
    return [float(x) for x in v]


def _wrap1(x: float) -> float:
    """x moved by a multiple of 2 pi into (-pi, pi]."""
    y = math.fmod(x + math.pi, TWO_PI)
    if y <= 0.0:
        y += TWO_PI
    return y - math.pi


def _near(v: float, s: float, lo: float, hi: float) -> float | None:
    """v moved by a multiple of 2 pi to the representative nearest s inside [lo, hi]."""
    w = s + ((v - s + math.pi) % TWO_PI - math.pi)  # Python's % is floored: one operation
    if lo <= w <= hi:
        return w
    w = w + TWO_PI if w < lo else w - TWO_PI
    if w < lo:
        return lo if w > lo - LIMIT_SLACK else None
    if w > hi:
        return hi if w < hi + LIMIT_SLACK else None
    return w


def _wrap(q: FloatArray) -> FloatArray:
    """q moved by multiples of 2 pi into [-pi, pi]."""
    out: FloatArray = q - TWO_PI * np.floor(q * INV_TWO_PI + 0.5)
    return out


def _wrap_near(
    q: FloatArray, seed: FloatArray, lo: FloatArray, hi: FloatArray
) -> tuple[FloatArray, BoolArray]:
    """Vectorised :func:`_near` on (6, 8, N) angles with seed (6, 1, N) and limits (6, 1, 1):
    (moved q, all six within limits (8, N)). The limit fix-ups run only when some angle needs
    one (with UR limits of +-2 pi, rarely)."""
    # floor(x + 0.5), not np.round or np.mod: several times faster here (no SIMD rint/fmod)
    k = seed - q
    k *= INV_TWO_PI
    k += 0.5
    np.floor(k, out=k)
    k *= TWO_PI
    w = q + k
    below, above = w < lo, w > hi
    if below.any() or above.any():
        w += TWO_PI * below
        w -= TWO_PI * above
        # within round-off of a limit: onto the limit
        w = np.where((w < lo) & (w > lo - LIMIT_SLACK), lo, w)
        w = np.where((w > hi) & (w < hi + LIMIT_SLACK), hi, w)
        below, above = w < lo, w > hi
    out = below | above
    within = ~(out[0] | out[1] | out[2] | out[3] | out[4] | out[5])
    return w, within


def _dh_matrices(theta: FloatArray, d: float, a: float, alpha: float) -> FloatArray:
    """Rz(theta) Tz(d) Tx(a) Rx(alpha) for each theta: (N, 4, 4)."""
    ct, st = np.cos(theta), np.sin(theta)
    ca, sa = math.cos(alpha), math.sin(alpha)
    T = np.zeros((theta.shape[0], 4, 4))
    T[:, 0, 0], T[:, 0, 1], T[:, 0, 2], T[:, 0, 3] = ct, -st * ca, st * sa, a * ct
    T[:, 1, 0], T[:, 1, 1], T[:, 1, 2], T[:, 1, 3] = st, ct * ca, -ct * sa, a * st
    T[:, 2, 1], T[:, 2, 2], T[:, 2, 3] = sa, ca, d
    T[:, 3, 3] = 1.0
    return T
