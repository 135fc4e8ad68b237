"""Closed-form UR IK: round trips, the eight branches, nearest-seed choice, limits, singular
poses, and the batched path against the single-pose path."""

from __future__ import annotations

import math
import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from cellengine.motion.ur_ik import UR_DH, UR_LOWER, UR_UPPER, URKinematics

MODELS = sorted(UR_DH)
BUILTIN = Path(__file__).resolve().parents[2] / "cellengine" / "motion" / "urdf"
FIXTURE = Path(__file__).resolve().parents[1] / "data" / "ik" / "ur5e_dh.urdf"
RESIDUAL = 1e-9


def residual(k: URKinematics, q: np.ndarray, T: np.ndarray) -> float:
    """Largest position (m) or rotation (rad) error of FK(q) against T, for one or many q."""
    Tq = k.fk_batch(np.atleast_2d(q))
    dp = np.linalg.norm(Tq[:, :3, 3] - T[:3, 3], axis=1)
    R = np.einsum("nji,jk->nik", Tq[:, :3, :3], T[:3, :3])
    cos = np.clip((np.trace(R, axis1=1, axis2=2) - 1.0) / 2.0, -1.0, 1.0)
    # arccos loses precision near 0: use the skew part for small angles
    skew = np.stack([R[:, 2, 1] - R[:, 1, 2], R[:, 0, 2] - R[:, 2, 0], R[:, 1, 0] - R[:, 0, 1]])
    ang = np.arctan2(np.linalg.norm(skew, axis=0) / 2.0, cos)
    return float(max(dp.max(), ang.max()))


def random_q(rng: np.random.Generator, n: int) -> np.ndarray:
    return rng.uniform(UR_LOWER, UR_UPPER, (n, 6))


def angle_diff(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    d: np.ndarray = np.abs((a - b + math.pi) % (2 * math.pi) - math.pi)
    return d


@pytest.fixture(params=MODELS)
def kin(request: pytest.FixtureRequest) -> URKinematics:
    return URKinematics.from_name(request.param)


# ---------------------------------------------------------------------- forward kinematics


@pytest.mark.parametrize("name", MODELS)
def test_fk_equals_builtin_urdf(name: str) -> None:
    """Our DH FK and pinocchio on the built-in URDF agree, base to tool0."""
    k = URKinematics.from_name(name)
    model = pin.buildModelFromUrdf(str(BUILTIN / f"{name}.urdf"))
    data = model.createData()
    fid = model.getFrameId("tool0")
    for q in random_q(np.random.default_rng(1), 50):
        pin.framesForwardKinematics(model, data, q)
        assert np.abs(data.oMf[fid].homogeneous - k.fk(q)).max() < 1e-9


def test_fk_equals_fixture_urdf() -> None:
    k = URKinematics.from_name("ur5e")
    model = pin.buildModelFromUrdf(str(FIXTURE))
    data = model.createData()
    fid = model.getFrameId("tool0")
    for q in random_q(np.random.default_rng(2), 20):
        pin.framesForwardKinematics(model, data, q)
        assert np.abs(data.oMf[fid].homogeneous - k.fk(q)).max() < 1e-9


def test_fk_of_zero_is_the_published_home() -> None:
    """At q = 0 a UR lies stretched along -x: x = a2 + a3, y = -(d4 + d6), z = d1 - d5."""
    k = URKinematics.from_name("ur5e")
    T = k.fk(np.zeros(6))
    assert np.allclose(T[:3, 3], [-0.425 - 0.3922, -(0.1333 + 0.0996), 0.1625 - 0.0997])


# ---------------------------------------------------------------------- round trips


def test_round_trip_batch(kin: URKinematics) -> None:
    """Every reachable pose is solved (100 %), to 1e-9, and the seed's own branch comes back."""
    q = random_q(np.random.default_rng(3), 2000)
    T = kin.fk_batch(q)
    qs, ok = kin.ik_batch(T, q)
    assert ok.all()
    assert max(residual(kin, qs[i], T[i]) for i in range(len(q))) <= RESIDUAL
    assert np.abs(qs - q).max() < 1e-8


def test_round_trip_single(kin: URKinematics) -> None:
    rng = np.random.default_rng(4)
    for q in random_q(rng, 300):
        T = kin.fk(q)
        sol = kin.ik(T, q)
        assert sol is not None
        assert residual(kin, sol, T) <= RESIDUAL
        assert np.abs(sol - q).max() < 1e-8


def test_round_trip_from_a_fixed_seed(kin: URKinematics) -> None:
    """From one seed for all poses, some branch is always found within limits."""
    q = random_q(np.random.default_rng(5), 1000)
    T = kin.fk_batch(q)
    seed = np.array([0.0, -math.pi / 2, math.pi / 2, -math.pi / 2, -math.pi / 2, 0.0])
    qs, ok = kin.ik_batch(T, seed)
    assert ok.all()
    assert max(residual(kin, qs[i], T[i]) for i in range(len(q))) <= RESIDUAL
    assert np.all((qs >= kin.lower) & (qs <= kin.upper))


def test_accepts_nested_lists() -> None:
    k = URKinematics.from_name("ur5e")
    q = np.array([0.3, -1.2, 1.1, -0.7, 0.9, 0.5])
    sol = k.ik(k.fk(q).tolist(), q.tolist())
    assert sol is not None and np.allclose(sol, q)


# ---------------------------------------------------------------------- the eight branches


def test_eight_distinct_branches(kin: URKinematics) -> None:
    rng = np.random.default_rng(6)
    for q in random_q(rng, 200):
        T = kin.fk(q)
        qa, valid = kin.ik_all(T)
        if not valid.all():  # a pose near the workspace edge: some elbows cannot reach
            continue
        assert residual(kin, qa, T) <= RESIDUAL
        for i in range(8):
            for j in range(i + 1, 8):
                assert angle_diff(qa[i], qa[j]).max() > 1e-6, (i, j)
        # one of them is the configuration the pose came from
        assert angle_diff(qa, q).max(axis=1).min() < 1e-8


def test_branch_bits() -> None:
    """Branch index 4 * shoulder + 2 * wrist + elbow: wrist bit = sin q5 < 0, elbow bit = sin
    q3 < 0."""
    k = URKinematics.from_name("ur5e")
    q = np.array([0.4, -1.0, 1.2, -1.3, 1.1, 0.2])
    qa, valid = k.ik_all(k.fk(q))
    assert valid.all()
    for b in range(8):
        wrist, elbow = (b >> 1) & 1, b & 1
        assert (math.sin(qa[b, 4]) < 0) == bool(wrist)
        assert (math.sin(qa[b, 2]) < 0) == bool(elbow)
    # the shoulder pairs share q1 within a pair and differ between pairs
    assert np.allclose(qa[:4, 0], qa[0, 0]) and np.allclose(qa[4:, 0], qa[4, 0])
    assert angle_diff(qa[0, 0], qa[4, 0]) > 0.1


def test_all_branches_batch_equals_single(kin: URKinematics) -> None:
    q = random_q(np.random.default_rng(7), 300)
    T = kin.fk_batch(q)
    qb, vb = kin.solve(T)
    for i in range(len(q)):
        qa, va = kin.ik_all(T[i])
        assert (va == vb[i]).all()
        assert angle_diff(qa[va], qb[i][va]).max() < 1e-9


# ---------------------------------------------------------------------- nearest seed


def test_nearest_seed_picks_each_branch() -> None:
    k = URKinematics.from_name("ur5e")
    rng = np.random.default_rng(8)
    for q in random_q(rng, 50):
        T = k.fk(q)
        qa, valid = k.ik_all(T)
        for b in np.flatnonzero(valid):
            # a seed near branch b (but not on it) must bring back branch b, wrapped near it
            seed = qa[b] + rng.normal(0.0, 0.02, 6)
            if not np.all((seed > k.lower) & (seed < k.upper)):
                continue
            sol = k.ik(T, seed)
            assert sol is not None
            assert angle_diff(sol, qa[b]).max() < 1e-9


def test_angles_wrapped_to_the_seed() -> None:
    """Each joint is moved by 2 pi multiples to the representative nearest the seed."""
    k = URKinematics.from_name("ur5e")
    q = np.array([0.3, -1.2, 1.1, -0.7, 0.9, 0.5])
    shift = np.array([-2 * math.pi, 2 * math.pi, 0.0, 2 * math.pi, -2 * math.pi, -2 * math.pi])
    sol = k.ik(k.fk(q), q + shift + 0.1)
    assert sol is not None and np.allclose(sol, q + shift)
    batch, ok = k.ik_batch(k.fk(q)[None], q + shift + 0.1)
    assert ok[0] and np.allclose(batch[0], q + shift)


def test_seed_per_pose_in_batch() -> None:
    k = URKinematics.from_name("ur5e")
    q = random_q(np.random.default_rng(9), 100)
    T = k.fk_batch(q)
    qa, valid = k.solve(T)
    # seed each pose next to its last valid branch
    pick = np.array([np.flatnonzero(v)[-1] for v in valid])
    target = qa[np.arange(100), pick]
    qs, ok = k.ik_batch(T, target + 0.01, lower=np.full(6, -10.0), upper=np.full(6, 10.0))
    assert ok.all() and np.abs(qs - target).max() < 1e-9


# ---------------------------------------------------------------------- limits


def test_limits_exclude_all_solutions_give_none() -> None:
    k = URKinematics.from_name("ur5e")
    q = np.array([0.3, -1.2, 1.1, -0.7, 0.9, 0.5])
    T = k.fk(q)
    qa, valid = k.ik_all(T)
    q1s = sorted({round(x, 9) for x in qa[valid, 0]})
    assert len(q1s) == 2
    # an interval for q1 between the two shoulder solutions (and their 2 pi copies)
    mid = 0.5 * (q1s[0] + q1s[1])
    lower = np.array([mid - 0.05, *UR_LOWER[1:]])
    upper = np.array([mid + 0.05, *UR_UPPER[1:]])
    assert k.ik(T, q, lower, upper) is None
    qs, ok = k.ik_batch(T[None], q, lower, upper)
    assert not ok[0] and np.isnan(qs[0]).all()


def test_limits_select_the_allowed_branch() -> None:
    """Limits that admit only the far branch make it the answer even for a seed on another."""
    k = URKinematics.from_name("ur5e")
    q = np.array([0.3, -1.2, 1.1, -0.7, 0.9, 0.5])
    T = k.fk(q)
    qa, _valid = k.ik_all(T)
    far = int(np.argmax(angle_diff(qa, q).sum(axis=1)))
    lower = qa[far] - 1e-3
    upper = qa[far] + 1e-3
    sol = k.ik(T, q, lower, upper)
    assert sol is not None and np.allclose(sol, qa[far], atol=1e-9)
    qs, ok = k.ik_batch(T[None], q, lower, upper)
    assert ok[0] and np.allclose(qs[0], sol, atol=1e-9)


def test_wrapping_respects_limits() -> None:
    """The representative nearest the seed is outside the limits: the next one inside is used."""
    lower = np.array([-1.0, *UR_LOWER[1:]])
    upper = np.array([1.0, *UR_UPPER[1:]])
    k = URKinematics.from_name("ur5e", lower, upper)
    q = np.array([0.8, -1.2, 1.1, -0.7, 0.9, 0.5])
    seed = q.copy()
    seed[0] += 2 * math.pi  # nearest copy of q1 is q1 + 2 pi, beyond the limit
    sol = k.ik(k.fk(q), seed)
    assert sol is not None and np.all(sol >= lower) and np.all(sol <= upper)
    assert np.allclose(sol[0], 0.8)


def test_elbow_limit_of_builtin_models() -> None:
    k = URKinematics.from_name("ur5e")
    assert k.upper[2] == pytest.approx(math.pi) and k.upper[0] == pytest.approx(2 * math.pi)


# ---------------------------------------------------------------------- singular and unreachable


SINGULAR = {
    "wrist": [0.3, -1.2, 1.1, -0.7, 0.0, 0.5],
    "wrist flipped": [0.3, -1.2, 1.1, -0.7, math.pi, 0.5],
    "shoulder": [0.2, -math.pi / 2, 0.0, math.pi / 2, 0.7, 0.3],
    "shoulder and wrist": [0.2, -math.pi / 2, 0.0, math.pi / 2, 0.0, 0.3],
    "elbow stretched": [0.2, -0.8, 0.0, -0.4, 1.0, 0.3],
    "all zero": [0.0] * 6,
}


@pytest.mark.parametrize("case", sorted(SINGULAR))
def test_singular_poses_have_no_nan(kin: URKinematics, case: str) -> None:
    q = np.array(SINGULAR[case])
    T = kin.fk(q)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no numpy 'invalid value' either
        qa, valid = kin.ik_all(T, seed6=q[5])
        qb, vb = kin.solve(T[None], q[5])
        sol = kin.ik(T, q)
        batch, ok = kin.ik_batch(T[None], q)
    assert valid.any() and vb.any() and ok[0] and sol is not None
    assert np.isfinite(qa).all() and np.isfinite(qb).all()
    assert residual(kin, qa[valid], T) <= RESIDUAL
    assert residual(kin, sol, T) <= RESIDUAL
    assert residual(kin, batch[0], T) <= RESIDUAL
    # at a singularity the angles are ill-conditioned (q3 ~ sqrt(rounding) when stretched), so
    # numpy and Python rounding may pick solutions 1e-8 apart: both exact in the pose
    assert np.allclose(batch[0], sol, atol=1e-6)


def test_wrist_singularity_takes_q6_from_the_seed() -> None:
    """With q5 = 0 the axes of joints 2, 3, 4 and 6 are parallel: a one-parameter family of
    solutions (q2 + q3 + q4 + q6 fixed). The solution keeps the seed's q6."""
    k = URKinematics.from_name("ur5e")
    q = np.array([0.3, -1.2, 1.1, -0.7, 0.0, 0.5])
    T = k.fk(q)
    seed = q.copy()
    seed[5] = -1.3
    sol = k.ik(T, seed)
    assert sol is not None and sol[5] == pytest.approx(-1.3)
    assert residual(k, sol, T) <= RESIDUAL
    assert angle_diff(sol[[1, 2, 3, 5]].sum(), q[[1, 2, 3, 5]].sum()) < 1e-9


def test_unreachable_pose() -> None:
    k = URKinematics.from_name("ur5e")
    T = np.eye(4)
    T[:3, 3] = [2.0, 0.0, 0.5]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert k.ik(T) is None
        _q, valid = k.ik_all(T)
        qs, vs = k.solve(T[None])
        _qb, ok = k.ik_batch(T[None], np.zeros(6))
    assert not valid.any() and not vs.any() and not ok[0]
    assert np.isfinite(qs).all()


def test_inside_the_shoulder_cylinder_is_unreachable() -> None:
    """A wrist point closer to the base axis than d4 has no solution."""
    k = URKinematics.from_name("ur5e")
    T = np.eye(4)
    T[:3, 3] = [0.0, 0.0, 0.5 + 0.0996]  # flange up, wrist point on the base axis
    assert k.ik(T) is None


# ---------------------------------------------------------------------- batch == single


def test_batch_equals_single_with_limits_and_misses() -> None:
    k = URKinematics.from_name("ur10e")
    rng = np.random.default_rng(10)
    q = random_q(rng, 400)
    T = k.fk_batch(q)
    T[::7, :3, 3] *= 3.0  # some poses out of reach
    seeds = random_q(rng, 400)
    lower = np.array([-1.0, -4.0, -2.5, -5.0, -3.0, -1.0])
    upper = np.array([1.5, 0.5, 2.5, 5.0, 3.0, 6.0])
    qs, ok = k.ik_batch(T, seeds, lower, upper)
    assert 0 < ok.sum() < len(q)
    for i in range(len(q)):
        sol = k.ik(T[i], seeds[i], lower, upper)
        assert (sol is not None) == ok[i]
        if sol is not None:
            assert np.abs(sol - qs[i]).max() < 1e-9
            assert np.all(sol >= lower) and np.all(sol <= upper)


def test_from_dh_equals_from_name() -> None:
    a = URKinematics.from_dh(UR_DH["ur3e"], UR_LOWER, UR_UPPER)
    b = URKinematics.from_name("ur3e")
    q = np.array([0.3, -1.2, 1.1, -0.7, 0.9, 0.5])
    assert np.array_equal(a.fk(q), b.fk(q)) and np.array_equal(a.upper, b.upper)


def test_not_a_ur_geometry() -> None:
    dh = UR_DH["ur5e"]
    with pytest.raises(ValueError, match="not a UR geometry"):
        URKinematics(dh.d, (0.1, *dh.a[1:]), dh.alpha)
    with pytest.raises(ValueError, match="alpha"):
        URKinematics(dh.d, dh.a, (0.0,) * 6)
