"""Numerical IK on pinocchio: a 7-DOF arm with a continuous joint, a cartesian robot with three
prismatic axes and a rotation, and the built-in UR5e. Success, accuracy, limits, determinism."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from cellengine.motion.numeric_ik import IKResult, NumericIK

DATA = Path(__file__).resolve().parents[1] / "data" / "ik"
BUILTIN = Path(__file__).resolve().parents[2] / "cellengine" / "motion" / "urdf"
UR_HOME = np.array([0.0, -math.pi / 2, math.pi / 2, -math.pi / 2, -math.pi / 2, 0.0])
TOL = 1e-5


def load(name: str) -> pin.Model:
    path = BUILTIN / "ur5e.urdf" if name == "ur5e" else DATA / f"{name}.urdf"
    return pin.buildModelFromUrdf(str(path))


def solver(name: str, **kw: object) -> NumericIK:
    if name == "ur5e":
        return NumericIK(load(name), "tool0", nominal=UR_HOME, **kw)  # type: ignore[arg-type]
    return NumericIK(load(name), "tcp", **kw)  # type: ignore[arg-type]


def targets(ik: NumericIK, n: int, seed: int) -> tuple[list[np.ndarray], list[pin.SE3]]:
    """FK of random configurations within the limits: reachable by construction."""
    rng = np.random.default_rng(seed)
    data = ik.model.createData()
    qs, Ts = [], []
    for _ in range(n):
        q = ik._chain.sample(rng, pin.neutral(ik.model))
        pin.framesForwardKinematics(ik.model, data, q)
        qs.append(q)
        Ts.append(pin.SE3(data.oMf[ik.frame_id]))
    return qs, Ts


def true_error(ik: NumericIK, q: np.ndarray, T: pin.SE3) -> tuple[float, float]:
    data = ik.model.createData()
    pin.framesForwardKinematics(ik.model, data, q)
    M = data.oMf[ik.frame_id]
    dp = float(np.linalg.norm(M.translation - T.translation))
    dr = float(np.linalg.norm(pin.log3(M.rotation.T @ T.rotation)))
    return dp, dr


def within_limits(ik: NumericIK, q: np.ndarray) -> bool:
    b = ik._chain.bounded
    return bool(np.all(q[b] >= ik.lower[b] - 1e-9) and np.all(q[b] <= ik.upper[b] + 1e-9))


# ---------------------------------------------------------------------- success and accuracy


@pytest.mark.parametrize(("name", "n"), [("arm7", 300), ("cartesian4", 200), ("ur5e", 300)])
def test_random_reachable_poses_from_the_nominal_seed(name: str, n: int) -> None:
    ik = solver(name)
    _, Ts = targets(ik, n, seed=11)
    results = [ik.solve(T) for T in Ts]
    assert sum(r.success for r in results) / n >= 0.995
    for r, T in zip(results, Ts, strict=True):
        if not r.success:
            continue
        dp, dr = true_error(ik, r.q, T)
        assert dp <= TOL and dr <= TOL
        assert r.pos_err == pytest.approx(dp, abs=1e-9)
        assert r.rot_err == pytest.approx(dr, abs=1e-9)
        assert within_limits(ik, r.q)


def test_continuous_joint_stays_normalised() -> None:
    """Joint 7 of arm7 is continuous: pinocchio's (cos, sin) pair stays on the unit circle."""
    ik = solver("arm7")
    _, Ts = targets(ik, 50, seed=12)
    for T in Ts:
        r = ik.solve(T)
        assert r.success
        c, s = r.q[6], r.q[7]
        assert c * c + s * s == pytest.approx(1.0, abs=1e-9)


def test_tighter_tolerance() -> None:
    ik = solver("ur5e", tol_pos=1e-10, tol_rot=1e-10)
    _, Ts = targets(ik, 50, seed=13)
    for T in Ts:
        r = ik.solve(T)
        assert r.success and r.pos_err <= 1e-10 and r.rot_err <= 1e-10


def test_warm_seed_converges_in_a_few_iterations() -> None:
    ik = solver("arm7")
    qs, Ts = targets(ik, 50, seed=14)
    rng = np.random.default_rng(0)
    for q, T in zip(qs, Ts, strict=True):
        seed = pin.integrate(ik.model, q, rng.normal(0.0, 0.01, ik.model.nv))
        r = ik.solve(T, seed)
        assert r.success and r.attempts == 1 and r.iterations <= 3


def test_seed_on_the_target_needs_no_iteration() -> None:
    ik = solver("cartesian4")
    qs, Ts = targets(ik, 5, seed=15)
    for q, T in zip(qs, Ts, strict=True):
        r = ik.solve(T, q)
        assert r.success and r.iterations == 0 and np.array_equal(r.q, q)


def test_accepts_a_4x4_matrix() -> None:
    ik = solver("ur5e")
    _, Ts = targets(ik, 3, seed=16)
    for T in Ts:
        a = ik.ik(T.homogeneous)
        b = ik.ik(T)
        assert a is not None and b is not None and np.array_equal(a, b)


# ---------------------------------------------------------------------- limits


def test_prismatic_limits_are_respected() -> None:
    """A target beyond the x travel (1.2 m) is reported unreachable; the best attempt found
    stays within the limits, pressed against the x limit."""
    ik = solver("cartesian4", max_restarts=5)
    data = ik.model.createData()
    q = np.array([1.0, 0.4, 0.2, 0.5])
    pin.framesForwardKinematics(ik.model, data, q)
    T = pin.SE3(data.oMf[ik.frame_id])
    T.translation = T.translation + np.array([0.5, 0.0, 0.0])
    r = ik.solve(T)
    assert not r.success and ik.ik(T) is None
    assert within_limits(ik, r.q)
    assert r.q[0] == pytest.approx(1.2)
    assert r.pos_err == pytest.approx(0.3, abs=1e-4)


def test_revolute_limits_narrowed_by_the_caller() -> None:
    """Limits passed in override the URDF's: a pose reachable only with joint 1 at 0.8 fails
    when joint 1 is limited to [-0.5, 0.5] (the other joints cannot make up a base rotation)."""
    model = load("cartesian4")
    lower = model.lowerPositionLimit.copy()
    upper = model.upperPositionLimit.copy()
    lower[3], upper[3] = -0.5, 0.5
    ik = NumericIK(model, "tcp", lower, upper, max_restarts=5)
    data = model.createData()
    pin.framesForwardKinematics(model, data, np.array([0.6, 0.4, 0.2, 0.8]))
    T = pin.SE3(data.oMf[ik.frame_id])
    r = ik.solve(T)
    assert not r.success and within_limits(ik, r.q)
    assert r.q[3] == pytest.approx(0.5)
    pin.framesForwardKinematics(model, data, np.array([0.6, 0.4, 0.2, 0.3]))
    assert ik.ik(pin.SE3(data.oMf[ik.frame_id])) is not None


def test_results_within_limits_on_the_7dof_arm() -> None:
    """arm7's joints 2, 4, 6 are limited to +-2 rad: every answer respects them."""
    ik = solver("arm7")
    _, Ts = targets(ik, 100, seed=17)
    for T in Ts:
        r = ik.solve(T)
        assert r.success and within_limits(ik, r.q)


def test_seed_outside_the_limits_is_clamped() -> None:
    ik = solver("arm7")
    _, Ts = targets(ik, 5, seed=18)
    seed = np.array([3.5, 2.5, -3.5, 2.5, 0.0, -2.5, 1.0, 0.0])
    for T in Ts:
        r = ik.solve(T, seed)
        assert r.success and within_limits(ik, r.q)


# ---------------------------------------------------------------------- determinism


def test_same_inputs_same_output() -> None:
    """Restarts come from a generator seeded per call: the answer does not depend on what was
    solved before, nor on the solver instance."""
    a, b = solver("arm7"), solver("arm7")
    _, Ts = targets(a, 60, seed=19)
    first = [a.solve(T) for T in Ts]
    second = [b.solve(T) for T in reversed(Ts)][::-1]
    again = [a.solve(T) for T in Ts]
    assert any(r.attempts > 1 for r in first), "no case needing a restart: test is too easy"
    for r1, r2, r3 in zip(first, second, again, strict=True):
        assert np.array_equal(r1.q, r2.q) and np.array_equal(r1.q, r3.q)
        assert r1.iterations == r2.iterations == r3.iterations


def test_rng_seed_changes_restarts_only() -> None:
    a, b = solver("cartesian4", max_restarts=3), solver("cartesian4", max_restarts=3, rng_seed=7)
    data = a.model.createData()
    pin.framesForwardKinematics(a.model, data, np.array([1.0, 0.4, 0.2, 0.5]))
    T = pin.SE3(data.oMf[a.frame_id])
    assert np.array_equal(a.solve(T).q, b.solve(T).q)  # first attempt succeeds: same answer


# ---------------------------------------------------------------------- larger models


def test_only_the_chain_moves_in_a_two_arm_model() -> None:
    """In a model holding two arms (a cell), solving for one arm's frame leaves the other
    arm's coordinates at the seed's values."""
    arm = load("arm7")
    text = (DATA / "arm7.urdf").read_text()
    second = pin.buildModelFromXML(text.replace('name="', 'name="b_').replace('link="', 'link="b_'))
    placement = pin.SE3(np.eye(3), np.array([1.0, 0.0, 0.0]))
    both = pin.appendModel(arm, second, 0, placement)
    assert both.nq == 16
    tcp2 = both.getFrameId("b_tcp")
    ik = NumericIK(both, tcp2)
    assert ik._chain.n == 7
    rng = np.random.default_rng(20)
    data = both.createData()
    for _ in range(20):
        q = ik._chain.sample(rng, pin.neutral(both))
        pin.framesForwardKinematics(both, data, q)
        T = pin.SE3(data.oMf[tcp2])
        seed = pin.neutral(both)
        seed[:8] = q[:8] + 0.1 * (np.arange(8) % 3 - 1)
        seed[6:8] = [1.0, 0.0]
        r = ik.solve(T, seed)
        assert r.success
        assert np.array_equal(r.q[:8], seed[:8])


# ---------------------------------------------------------------------- interface


def test_frame_by_name_or_id() -> None:
    model = load("ur5e")
    fid = model.getFrameId("tool0")
    assert NumericIK(model, "tool0").frame_id == NumericIK(model, fid).frame_id == fid
    with pytest.raises(ValueError, match="no frame"):
        NumericIK(model, "flange_of_nothing")
    with pytest.raises(ValueError, match="no frame"):
        NumericIK(model, 10_000)


def test_wrong_sizes_are_refused() -> None:
    model = load("ur5e")
    with pytest.raises(ValueError, match="nq"):
        NumericIK(model, "tool0", np.zeros(5), np.ones(5))
    ik = NumericIK(model, "tool0")
    with pytest.raises(ValueError, match="nq"):
        ik.solve(pin.SE3.Identity(), np.zeros(7))


def test_result_type() -> None:
    ik = solver("ur5e")
    _, Ts = targets(ik, 1, seed=21)
    r = ik.solve(Ts[0])
    assert isinstance(r, IKResult) and r.q.shape == (6,) and r.attempts >= 1
