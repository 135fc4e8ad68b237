"""Numerical inverse kinematics for any serial chain of a pinocchio model.

Levenberg-Marquardt on the frame's SE(3) error, as in pinocchio's IK example: the error is
``log6(oMf^-1 * oMdes)`` (in the frame), its Jacobian ``-Jlog6(iMd^-1) @ J_frame``. Revolute and
prismatic joints are clamped to their limits after every step (the step is projected, so a
joint pressed against a limit stops there while the others keep converging); continuous joints
(pinocchio stores them as cos/sin) have none. The first attempt starts from the caller's seed
(or a fixed nominal configuration), then random restarts from a generator seeded per call, so
the same inputs always give the same answer.

Only the joints supporting the frame move; other joints of a larger model (the second arm of a
cell) keep the seed's values.

The inner loop is where the time goes (a few microseconds per pinocchio or numpy call from
Python), so it is kept flat: one kinematics pass per iteration (``computeJointJacobians`` does the
forward kinematics and the Jacobians together), the damped system solved at the smaller of its
two sizes (6x6 for redundant arms, n x n for fewer than six joints) with an Eigen Cholesky.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import eigenpy  # type: ignore[import-untyped]
import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from cellengine.arrays import FloatArray

# Limits beyond these are "none" for sampling restarts (URDF joints without a limit tag get
# +-max float in pinocchio).
UNBOUNDED_ANGLE = 4.0 * math.pi
UNBOUNDED_LENGTH = 10.0
# A restart is sampled from this range for unbounded revolute / prismatic coordinates.
SAMPLE_ANGLE = math.pi
SAMPLE_LENGTH = 1.0
# Squared error (m^2 + rad^2) under which the linearisation is trusted as is: no Jlog6 and no
# step cap (1 mm / 1 mrad).
NEAR = 1e-6
# Squared error under which slow progress is not a local minimum but ill-conditioning (near a
# singularity convergence is linear): the descent goes on rather than restarting.
STALL_FLOOR = 1e-8


class IKResult(NamedTuple):
    """The outcome of one solve. ``q`` is the best configuration found (the solution when
    ``success``), in pinocchio's layout (nq). A NamedTuple: a third of a frozen dataclass's
    construction time, which shows in a 30 us warm solve."""

    q: FloatArray
    success: bool
    pos_err: float  # m, |p_frame - p_target|
    rot_err: float  # rad, angle of R_frame^T R_target
    iterations: int  # summed over attempts
    attempts: int  # 1 + restarts used


class NumericIK:
    """Damped least squares IK of one frame of ``model``.

    ``lower``/``upper`` (nq) override the model's position limits. ``nominal`` is the seed when
    the caller gives none (default: the middle of each bounded joint's range, 0 for others).
    Tolerances are on the true residual: position (m) and rotation angle (rad).

    An instance holds pinocchio data and work arrays: one per thread.
    """

    def __init__(
        self,
        model: pin.Model,
        frame: int | str,
        lower: ArrayLike | None = None,
        upper: ArrayLike | None = None,
        *,
        nominal: ArrayLike | None = None,
        tol_pos: float = 1e-5,
        tol_rot: float = 1e-5,
        max_iter: int = 40,
        max_restarts: int = 50,
        rng_seed: int = 0,
        damping: float = 1e-6,
        damping_err: float = 1e-2,
        max_step: float = 1.0,
        stall_ratio: float = 0.5,
        stall_iters: int = 4,
    ) -> None:
        self.model = model
        self.data = model.createData()
        self.frame_id = _frame_id(model, frame)
        self.tol_pos = tol_pos
        self.tol_rot = tol_rot
        self.max_iter = max_iter
        self.max_restarts = max_restarts
        self.rng_seed = rng_seed
        # lambda = damping + damping_err * |e|^2 (Sugihara's choice): nearly Gauss-Newton close
        # to the solution (quadratic convergence), heavily damped far from it or at a singularity.
        self.damping = damping
        self.damping_err = damping_err
        # A step's largest joint motion (rad or m) is capped: linearisation far from the target
        # otherwise throws the arm across its workspace.
        self.max_step = max_step
        self.stall_ratio = stall_ratio
        self.stall_iters = stall_iters
        self._chain = _Chain(model, self.frame_id, lower, upper)
        # One Cholesky object reused: constructing one per iteration costs as much as solving.
        self._llt = eigenpy.LLT(self._chain.eye)
        self.lower = self._chain.lower
        self.upper = self._chain.upper
        self.nominal = (
            self._chain.middle()
            if nominal is None
            else np.array(np.asarray(nominal, dtype=float).reshape(model.nq))
        )

    # ------------------------------------------------------------------ public

    def ik(self, target: pin.SE3 | ArrayLike, seed: ArrayLike | None = None) -> FloatArray | None:
        """The configuration (nq) placing the frame at ``target``, or None."""
        r = self.solve(target, seed)
        return r.q if r.success else None

    def solve(self, target: pin.SE3 | ArrayLike, seed: ArrayLike | None = None) -> IKResult:
        """Solve from ``seed`` (default: the nominal configuration), then restarts."""
        oMdes = target if isinstance(target, pin.SE3) else pin.SE3(np.asarray(target, float))
        q0 = self.nominal if seed is None else np.asarray(seed, dtype=float).reshape(-1)
        q = self._chain.clamp(np.asarray(q0, dtype=float))  # a new array: q0 is never written
        best = self._attempt(q, oMdes)
        iterations, attempts = best[3], 1
        rng: np.random.Generator | None = None
        while not best[0] and attempts <= self.max_restarts:
            if rng is None:  # created only when needed: default_rng costs tens of microseconds
                rng = np.random.default_rng(self.rng_seed)
            r = self._attempt(self._chain.sample(rng, q), oMdes)
            iterations += r[3]
            attempts += 1
            if r[0] or r[1] + r[2] < best[1] + best[2]:
                best = r
        ok, ep, er, _, qb = best
        return IKResult(qb, ok, ep, er, iterations, attempts)

    # ------------------------------------------------------------------ the loop

    def _attempt(self, q: FloatArray, oMdes: pin.SE3) -> tuple[bool, float, float, int, FloatArray]:
        """One LM descent from q: (success, pos err, rot err, iterations, q)."""
        model, data, fid = self.model, self.data, self.frame_id
        chain = self._chain
        tol_p2, tol_r2 = self.tol_pos**2, self.tol_rot**2
        lam0, lam_e, max_step = self.damping, self.damping_err, self.max_step
        eye, cols, step, llt = chain.eye, chain.cols, chain.step, self._llt
        stall_ratio, stall_iters = self.stall_ratio, self.stall_iters
        small = chain.n <= 6  # solve (J^T J + lambda I) v = J^T e, else J^T (J J^T + lambda I)^-1 e
        ep2 = er2 = math.inf
        history: list[float] = []
        for it in range(self.max_iter + 1):
            pin.computeJointJacobians(model, data, q)
            iMd = pin.updateFramePlacement(model, data, fid).actInv(oMdes)
            err = pin.log6(iMd).vector
            # |iMd.translation| = |p_frame - p_target| exactly (a rotation keeps lengths);
            # the angular part of log6 is the rotation angle. Python floats beat numpy here.
            tx, ty, tz = iMd.translation.tolist()
            _, _, _, wx, wy, wz = err.tolist()
            ep2 = tx * tx + ty * ty + tz * tz
            er2 = wx * wx + wy * wy + wz * wz
            if ep2 <= tol_p2 and er2 <= tol_r2:
                return True, math.sqrt(ep2), math.sqrt(er2), it, q
            if it == self.max_iter:
                break
            # A local minimum (elbow stretched against the target, pressed into a limit) is
            # left for a restart rather than ground on: a converging descent at least halves
            # the error every few steps. Close to the target slow progress is ill-conditioning
            # near a singularity, not a local minimum, and goes on.
            e2 = ep2 + er2
            if e2 > STALL_FLOOR and it >= stall_iters and e2 > stall_ratio * history[-stall_iters]:
                break
            history.append(e2)
            far = e2 > NEAR
            J = pin.getFrameJacobian(model, data, fid, pin.LOCAL)
            J = np.reshape(J, (6, -1))  # 1-D for a one-joint arm
            if cols is not None:
                J = J[:, cols]
            if far:  # d err / dq = -Jlog6(iMd^-1) J; near the target Jlog6 = I + O(|err|),
                # which keeps Newton's quadratic convergence, so the product is skipped there
                J = pin.Jlog6(iMd.inverse()).dot(J)
            lam = lam0 + lam_e * e2
            if small:
                llt.compute(J.T.dot(J) + lam * eye)
                v = llt.solve(J.T.dot(err))
            else:
                llt.compute(J.dot(J.T) + lam * eye)
                v = J.T.dot(llt.solve(err))
            if far:
                vmax = max(v.max(), -v.min())
                if vmax > max_step:
                    v *= max_step / vmax
            q = step(q, v)
        return False, math.sqrt(ep2), math.sqrt(er2), it, q


class _Chain:
    """Which coordinates the frame's chain moves, and their limits."""

    def __init__(
        self, model: pin.Model, frame_id: int, lower: ArrayLike | None, upper: ArrayLike | None
    ) -> None:
        self.model = model
        lo = np.array(model.lowerPositionLimit if lower is None else lower, dtype=float)
        hi = np.array(model.upperPositionLimit if upper is None else upper, dtype=float)
        if lo.shape != (model.nq,) or hi.shape != (model.nq,):
            raise ValueError(f"limits must have nq = {model.nq} entries")
        joint = model.frames[frame_id].parentJoint
        support = [j for j in model.supports[joint].tolist() if j > 0]
        cols: list[int] = []
        self.bounded: list[int] = []  # q indices clamped to limits
        self.continuous: list[int] = []  # q index of the cos of each cos/sin pair
        self.prismatic: set[int] = set()
        for j in support:
            jm = model.joints[j]
            iq, iv, nq, nv = jm.idx_q, jm.idx_v, jm.nq, jm.nv
            cols.extend(range(iv, iv + nv))
            if nq == 1 and nv == 1:
                self.bounded.append(iq)
                if jm.shortname().startswith("JointModelP"):  # PX, PY, PZ, PrismaticUnaligned
                    self.prismatic.add(iq)
            elif nq == 2 and nv == 1:
                self.continuous.append(iq)
                lo[iq : iq + 2], hi[iq : iq + 2] = -np.inf, np.inf
            else:
                raise ValueError(f"joint {model.names[j]!r}: {jm.shortname()} is not supported")
        self.n = len(cols)
        # Slicing the Jacobian costs a microsecond; skip it when the chain is the whole model.
        self.cols: list[int] | None = None if cols == list(range(model.nv)) else cols
        self.eye = np.eye(self.n if self.n <= 6 else 6)
        self.lower, self.upper = lo, hi
        self._v = np.zeros(model.nv)
        # Clamp only where limits exist: np.minimum/maximum with +-inf elsewhere.
        self._lo = np.where(np.isin(np.arange(model.nq), self.bounded), lo, -np.inf)
        self._hi = np.where(np.isin(np.arange(model.nq), self.bounded), hi, np.inf)

    def step(self, q: FloatArray, v_chain: FloatArray) -> FloatArray:
        """q moved by v along the chain, then clamped to the limits."""
        if self.cols is None:
            v = v_chain
        else:
            v = self._v
            v[self.cols] = v_chain
        q2: FloatArray = np.minimum(np.maximum(pin.integrate(self.model, q, v), self._lo), self._hi)
        return q2

    def clamp(self, q: FloatArray) -> FloatArray:
        if q.shape != (self.model.nq,):
            raise ValueError(f"a configuration has nq = {self.model.nq} entries, got {q.shape}")
        out: FloatArray = np.minimum(np.maximum(q, self._lo), self._hi)
        return out

    def middle(self) -> FloatArray:
        """The middle of each bounded coordinate's range; 0 (angle) for the others."""
        q: FloatArray = pin.neutral(self.model)
        for i in self.bounded:
            lo, hi = self.lower[i], self.upper[i]
            q[i] = 0.5 * (lo + hi) if np.isfinite(lo + hi) and hi - lo < 1e300 else 0.0
        return self.clamp(q)

    def sample(self, rng: np.random.Generator, q: FloatArray) -> FloatArray:
        """q with the chain's coordinates drawn uniformly within their limits (a bounded range
        for coordinates without useful limits)."""
        out = q.copy()
        for i in self.bounded:
            span = SAMPLE_LENGTH if i in self.prismatic else SAMPLE_ANGLE
            wide = UNBOUNDED_LENGTH if i in self.prismatic else UNBOUNDED_ANGLE
            lo = max(self.lower[i], -wide) if self.lower[i] > -wide else -span
            hi = min(self.upper[i], wide) if self.upper[i] < wide else span
            out[i] = rng.uniform(lo, hi)
        for i in self.continuous:
            a = rng.uniform(-math.pi, math.pi)
            out[i], out[i + 1] = math.cos(a), math.sin(a)
        return out


def _frame_id(model: pin.Model, frame: Any) -> int:
    if isinstance(frame, str):
        if not model.existFrame(frame):
            raise ValueError(f"no frame {frame!r} in the model")
        return int(model.getFrameId(frame))
    fid = int(frame)
    if not 0 <= fid < model.nframes:
        raise ValueError(f"no frame {fid} in the model")
    return fid
