"""Inverse kinematics of one arm of the cell: TCP poses in the CELL frame -> joint positions.

One facade over the two solvers. An arm with a DH table (a built-in UR) uses the closed form
(:class:`~cellengine.motion.ur_ik.URKinematics`) on ``T_base_flange = inv(T_cell_base) @
T_cell_tcp @ inv(T_flange_tcp)``; any other arm uses the numerical solver
(:class:`~cellengine.motion.numeric_ik.NumericIK`) on the TCP frame of the arm's model
(whose universe is the cell frame), seeded with the arm's home when the caller gives no seed.
Both apply the arm's joint limits. q is in the arm model's layout (pinocchio's: a continuous
joint takes two entries, cos and sin).

Several solutions: the closed form has up to eight branches per pose (``4 * shoulder + 2 *
wrist + elbow``, see ur_ik); :meth:`ArmIK.solve_all` returns each that the limits allow. The
numerical solver finds one per seed, so it returns at most one.

An :class:`ArmIK` holds solver state (pinocchio data): one per thread. :func:`arm_ik` keeps
one per arm.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from cellengine import geometry as g
from cellengine.arrays import BoolArray, Vec
from cellengine.motion.numeric_ik import NumericIK
from cellengine.motion.robot import Arm
from cellengine.motion.ur_ik import URKinematics

TWO_PI = 2.0 * math.pi

# Two solutions closer than this (rad, per joint, after wrapping) are one (singular poses,
# where branches coincide).
SAME_SOLUTION = 1e-9

# by_branch's answers kept per arm (poses): skills ask again about the poses of paths they
# share (~4 times each on the cable-routing plans); 8 x 6 floats each, emptied when full.
BRANCH_CACHE = 4096


class ArmIK:
    """IK of ``arm``'s TCP in the cell frame. ``max_restarts`` applies to the numerical
    solver only (random restarts after the seeded attempt fails)."""

    def __init__(self, arm: Arm, *, max_restarts: int = 50) -> None:
        self.arm = arm
        self.lower = np.array(arm.limits.lower)
        self.upper = np.array(arm.limits.upper)
        self.home = _default_seed(arm)
        # inv(T_cell_base) and inv(T_flange_tcp), applied on both sides of every target
        self.T_base_cell = g.inverse(arm.T_cell_base)
        self.T_tcp_flange = g.inverse(arm.T_flange_tcp)
        self.closed_form: URKinematics | None = None
        self.numeric: NumericIK | None = None
        self._path_solver: NumericIK | None = None
        self._branches: dict[bytes, Vec] = {}  # by_branch's, by the pose's bytes
        if arm.dh is not None:
            self.closed_form = URKinematics.from_dh(arm.dh, self.lower, self.upper)
        else:
            self.numeric = NumericIK(
                arm.model, arm.tcp, nominal=self.home, max_restarts=max_restarts
            )

    @property
    def n(self) -> int:
        return self.arm.nq

    def path_solver(self) -> NumericIK:
        """Numerical only: the solver for following a path, warm-started at the previous
        waypoint and WITHOUT random restarts (a restart lands anywhere: a jump by
        construction). Built on first use."""
        if self.closed_form is not None:
            raise ValueError(f"arm '{self.arm.name}' follows paths in closed form")
        if self._path_solver is None:
            self._path_solver = NumericIK(self.arm.model, self.arm.tcp, max_restarts=0)
        return self._path_solver

    # ------------------------------------------------------------------ frames

    def base_flange(self, T_cell_tcp: ArrayLike) -> NDArray[np.float64]:
        """T_base_flange of TCP targets in the cell frame: (4, 4) or (N, 4, 4) as given."""
        T = np.asarray(T_cell_tcp, dtype=float)
        out: NDArray[np.float64] = self.T_base_cell @ T @ self.T_tcp_flange
        return out

    # ------------------------------------------------------------------ one pose

    def solve(self, T_cell_tcp: ArrayLike, seed: ArrayLike | None = None) -> Vec | None:
        """The solution nearest ``seed`` (default: the arm's home) within limits, or None.
        Closed form: nearest in joint space over all branches; numerical: the one its descent
        from the seed reaches (restarts if that fails)."""
        sd = self.home if seed is None else self._seed(seed)
        if self.closed_form is not None:
            return self.closed_form.ik(self.base_flange(T_cell_tcp), sd)
        assert self.numeric is not None
        return self.numeric.ik(np.asarray(T_cell_tcp, dtype=float), sd)

    def solve_all(self, T_cell_tcp: ArrayLike, seed: ArrayLike | None = None) -> Vec:
        """Every solution (k, n), k >= 0: closed form, each branch reaching the pose within
        limits (each angle the representative nearest ``seed``, default home), duplicates at
        singular poses dropped; numerical, the one solution from ``seed`` if found."""
        if self.closed_form is None:
            q = self.solve(T_cell_tcp, seed)
            return np.zeros((0, self.n)) if q is None else q[None, :]
        sd = self.home if seed is None else self._seed(seed)
        T_bf = self.base_flange(T_cell_tcp)
        q_all, valid = self.closed_form.ik_all(T_bf, float(sd[5]))
        found: list[Vec] = []
        for qb in q_all[valid]:
            w = wrap_near(qb, sd, self.lower, self.upper)
            if w is not None and not any(np.max(np.abs(w - f)) < SAME_SOLUTION for f in found):
                found.append(w)
        return np.array(found) if found else np.zeros((0, self.n))

    def by_branch(self, T_cell_tcp: ArrayLike) -> Vec | None:
        """Closed form: the solution of each of the eight branches (8, n), each angle the
        representative nearest home within limits, NaN rows where a branch does not reach
        the pose within limits: row k of two nearby poses is one continuous motion (away
        from singularities). None for an arm solved numerically (it has no branches)."""
        if self.closed_form is None:
            return None
        T = np.asarray(T_cell_tcp, dtype=float)
        key = T.tobytes()
        rows = self._branches.get(key)
        if rows is None:
            if len(self._branches) >= BRANCH_CACHE:
                self._branches.clear()
            q_all, valid = self.closed_form.ik_all(self.base_flange(T), float(self.home[5]))
            rows = self._branches[key] = wrap_rows_near(q_all, self.home, self.lower, self.upper)
            rows[~valid] = np.nan
        return rows.copy()  # the caller's to change

    # ------------------------------------------------------------------ many poses

    def solve_batch(
        self, T_cell_tcp: ArrayLike, seed: ArrayLike | None = None
    ) -> tuple[Vec, BoolArray]:
        """For N unrelated poses, each one's solution nearest ``seed`` ((n,) or (N, n);
        default home): q (N, n), NaN where ok (N,) is False. Closed form: one numpy pass;
        numerical: one solve per pose."""
        Ts = np.asarray(T_cell_tcp, dtype=float).reshape(-1, 4, 4)
        sd = np.broadcast_to(
            self.home if seed is None else np.asarray(seed, float), (len(Ts), self.n)
        )
        if self.closed_form is not None:
            return self.closed_form.ik_batch(self.base_flange(Ts), sd)
        q = np.full((len(Ts), self.n), np.nan)
        ok = np.zeros(len(Ts), dtype=bool)
        for i, T in enumerate(Ts):
            qi = self.solve(T, sd[i])
            if qi is not None:
                q[i], ok[i] = qi, True
        return q, ok

    def branches(
        self, T_cell_tcp: ArrayLike, seed6: ArrayLike | None = None
    ) -> tuple[Vec, BoolArray]:
        """Closed form only: all eight branches of N poses, q (N, 8, 6) wrapped to [-pi, pi],
        valid (N, 8) (reached, limits not applied). ``seed6``: q6 at wrist singularities."""
        kin = self._closed_form()
        return kin.solve(self.base_flange(np.asarray(T_cell_tcp, float).reshape(-1, 4, 4)), seed6)

    def branch(self, q: ArrayLike) -> int:
        """Closed form only: the branch index (``4 * shoulder + 2 * wrist + elbow``) of a
        configuration: the branch whose solution for q's own pose is q (up to 2 pi). At a
        singular configuration, where branches coincide, the lowest such index."""
        kin = self._closed_form()
        qa = self._seed(q)
        sols, valid = kin.ik_all(kin.fk(qa), float(qa[5]))
        d = np.abs(wrap(sols - qa)).max(axis=1)
        d[~valid] = np.inf
        return int(np.argmin(d))

    # ------------------------------------------------------------------ helpers

    def _closed_form(self) -> URKinematics:
        if self.closed_form is None:
            raise ValueError(f"arm '{self.arm.name}' has no closed-form IK (no DH table)")
        return self.closed_form

    def _seed(self, seed: ArrayLike) -> Vec:
        sd = np.asarray(seed, dtype=float)
        if sd.shape != (self.n,):
            raise ValueError(
                f"arm '{self.arm.name}': seed has shape {sd.shape}, expected ({self.n},)"
            )
        return sd


def arm_ik(arm: Arm) -> ArmIK:
    """The arm's :class:`ArmIK`, built once per arm and kept on it (building NumericIK costs a
    little), so it lives and goes with the arm's model."""
    ik = arm.solver
    if not isinstance(ik, ArmIK):
        ik = ArmIK(arm)
        object.__setattr__(arm, "solver", ik)
    return ik


def wrap(x: Any) -> Any:
    """Angles moved by multiples of 2 pi into [-pi, pi)."""
    return x - TWO_PI * np.floor(np.asarray(x) / TWO_PI + 0.5)


def wrap_near(q: Vec, seed: Vec, lower: Vec, upper: Vec) -> Vec | None:
    """q with each angle moved by a multiple of 2 pi to the representative nearest ``seed``
    that lies within [lower, upper]; None if some joint has none."""
    w = seed + wrap(q - seed)
    w = np.where(w < lower, w + TWO_PI, w)
    w = np.where(w > upper, w - TWO_PI, w)
    if np.any(w < lower) or np.any(w > upper):
        return None
    out: Vec = w
    return out


def wrap_rows_near(q: Vec, seed: Vec, lower: Vec, upper: Vec) -> Vec:
    """wrap_near of each row of q (m, n): NaN rows where it gives None."""
    w = seed + wrap(q - seed)
    w = np.where(w < lower, w + TWO_PI, w)
    w = np.where(w > upper, w - TWO_PI, w)
    w[((w < lower) | (w > upper)).any(axis=1)] = np.nan
    out: Vec = w
    return out


def _default_seed(arm: Arm) -> Vec:
    """Where IK starts when no seed is given: the arm's home, or for an arm without one the
    middle of each bounded joint (what NumericIK would choose)."""
    if arm.home is not None and len(arm.home) == arm.nq:  # (a continuous joint takes 2)
        return np.array(arm.home, dtype=float)
    if arm.dh is not None:
        return np.zeros(arm.nq)
    return np.asarray(NumericIK(arm.model, arm.tcp).nominal, dtype=float)
