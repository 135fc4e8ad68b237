"""The per-arm IK facade: TCP poses in the cell frame, closed form for the UR arms of the
cable-routing cell (base offset, 200 mm tool), numerical for a cartesian robot with a
continuous joint."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cellengine import geometry as g
from cellengine.info.load import load_world
from cellengine.motion.ik import ArmIK, arm_ik
from cellengine.motion.robot import Arm, CellModel, build_cell_model
from tests.conftest import CELLS, DATA

READY = np.array([math.pi, -1.9, 1.9, -1.57, -1.57, 0.0])  # elbow up, tool down, facing +x


@pytest.fixture(scope="module")
def cable_cell() -> CellModel:
    return build_cell_model(load_world(CELLS / "cable_routing" / "cell.yaml"))


@pytest.fixture(scope="module")
def gantry() -> Arm:
    return build_cell_model(load_world(DATA / "urdf" / "cartesian" / "cell.yaml")).arms["gantry"]


def residual(arm: Arm, q: np.ndarray, T: np.ndarray) -> tuple[float, float]:
    M = arm.fk(q)
    dp = float(np.linalg.norm(M[:3, 3] - T[:3, 3]))
    dr = float(np.linalg.norm(g.inverse(M)[:3, :3] @ T[:3, :3] - np.eye(3)))
    return dp, dr


def random_configurations(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    q = rng.uniform(-math.pi, math.pi, size=(n, 6))
    q[:, 2] = rng.uniform(-2.8, 2.8, size=n)  # away from the elbow limit
    return q


# ------------------------------------------------------------------------------ closed form


def test_closed_form_is_used_for_a_ur_and_targets_go_through_base_and_tool(
    cable_cell: CellModel,
) -> None:
    arm = cable_cell.arms["left"]
    ik = ArmIK(arm)
    assert ik.closed_form is not None and ik.numeric is None
    q = READY
    # T_base_flange = inv(T_cell_base) @ T_cell_tcp @ inv(T_flange_tcp)
    T_base_flange = g.inverse(arm.T_cell_base) @ arm.fk_flange(q)
    np.testing.assert_allclose(ik.base_flange(arm.fk(q)), T_base_flange, atol=1e-9)
    np.testing.assert_allclose(ik.closed_form.fk(q), T_base_flange, atol=1e-9)


@pytest.mark.parametrize("name", ["left", "right"])
def test_round_trip_in_the_cell_frame(cable_cell: CellModel, name: str) -> None:
    arm = cable_cell.arms[name]
    ik = arm_ik(arm)
    for q in random_configurations(50, seed=1):
        T = arm.fk(q)
        found = ik.solve(T, q + 0.01)
        assert found is not None
        np.testing.assert_allclose(found, q, atol=1e-9)  # the nearest is the one it came from
        assert max(residual(arm, found, T)) <= 1e-9


def test_solve_all_gives_every_branch_and_branch_names_them(cable_cell: CellModel) -> None:
    arm = cable_cell.arms["left"]
    ik = arm_ik(arm)
    T = g.transform(g.rot_x(math.pi) @ g.rot_z(0.3), [0.4, 0.3, 0.25])
    sols = ik.solve_all(T, READY)
    assert sols.shape == (8, 6)
    assert sorted(ik.branch(q) for q in sols) == list(range(8))
    for q in sols:
        assert max(residual(arm, q, T)) <= 1e-9
        assert np.all(q >= arm.limits.lower) and np.all(q <= arm.limits.upper)
        # each angle the representative nearest READY among those within the limits
        for other in (q - 2 * math.pi, q + 2 * math.pi):
            inside = (other >= arm.limits.lower) & (other <= arm.limits.upper)
            assert np.all(~inside | (np.abs(q - READY) <= np.abs(other - READY)))


def test_solve_all_of_an_unreachable_pose_is_empty(cable_cell: CellModel) -> None:
    ik = arm_ik(cable_cell.arms["left"])
    far = g.pose([2.0, 0.35, 0.3])
    assert ik.solve_all(far).shape == (0, 6)
    assert ik.solve(far) is None


def test_batch_equals_one_pose_at_a_time(cable_cell: CellModel) -> None:
    arm = cable_cell.arms["right"]
    ik = arm_ik(arm)
    qs = random_configurations(40, seed=2)
    Ts = np.array([arm.fk(q) for q in qs])
    Ts[5, 0, 3] += 5.0  # one out of reach
    q, ok = ik.solve_batch(Ts, READY)
    assert ok.tolist() == [i != 5 for i in range(40)]
    assert np.isnan(q[5]).all()
    for i in np.flatnonzero(ok):
        single = ik.solve(Ts[i], READY)
        assert single is not None
        np.testing.assert_allclose(q[i], single, atol=1e-9)


def test_branches_of_many_poses(cable_cell: CellModel) -> None:
    arm = cable_cell.arms["left"]
    ik = arm_ik(arm)
    qs = random_configurations(20, seed=3)
    sols, valid = ik.branches(np.array([arm.fk(q) for q in qs]))
    assert sols.shape == (20, 8, 6) and valid.shape == (20, 8)
    for q, s, v in zip(qs, sols, valid, strict=True):
        b = ik.branch(q)
        assert v[b]
        np.testing.assert_allclose(np.cos(s[b]), np.cos(q), atol=1e-9)
        np.testing.assert_allclose(np.sin(s[b]), np.sin(q), atol=1e-9)


def test_by_branch_puts_each_branch_in_its_row(cable_cell: CellModel) -> None:
    """Row k is branch k's solution (nearest home within limits), NaN where a branch does not
    reach the pose; along a short move each row changes a little (one continuous motion)."""
    arm = cable_cell.arms["left"]
    ik = arm_ik(arm)
    T = g.transform(g.rot_x(math.pi) @ g.rot_z(0.3), [0.4, 0.3, 0.25])
    rows = ik.by_branch(T)
    assert rows is not None and rows.shape == (8, 6)
    reached = ~np.isnan(rows).any(axis=1)
    assert reached.sum() == len(ik.solve_all(T))
    for k in np.flatnonzero(reached):
        assert ik.branch(rows[k]) == k
        assert max(residual(arm, rows[k], T)) <= 1e-9
    moved = ik.by_branch(g.transform(T[:3, :3], T[:3, 3] + [0.002, 0.0, 0.0]))
    assert moved is not None
    assert np.nanmax(np.abs(moved - rows)) < 0.05  # rad, for 2 mm
    assert ik.by_branch(g.pose([2.0, 0.35, 0.3])) is not None
    assert np.isnan(ik.by_branch(g.pose([2.0, 0.35, 0.3]))).all()


def test_by_branch_answers_a_pose_asked_again_as_the_first_time(cable_cell: CellModel) -> None:
    """by_branch keeps its answers per pose: asked again, the same rows, and the caller's
    copy, which it may change."""
    ik = ArmIK(cable_cell.arms["left"])
    T = g.transform(g.rot_x(math.pi) @ g.rot_z(0.3), [0.4, 0.3, 0.25])
    first = ik.by_branch(T)
    assert first is not None
    kept = first.copy()
    first[:] = 0.0
    again = ik.by_branch(T.copy())
    assert again is not None
    np.testing.assert_array_equal(again, kept)
    fresh = ArmIK(cable_cell.arms["left"]).by_branch(T)
    np.testing.assert_array_equal(again, fresh)


def test_arm_ik_is_built_once_per_arm(cable_cell: CellModel) -> None:
    left, right = cable_cell.arms["left"], cable_cell.arms["right"]
    assert arm_ik(left) is arm_ik(left)
    assert arm_ik(left) is not arm_ik(right)


def test_seed_shape_is_checked(cable_cell: CellModel) -> None:
    with pytest.raises(ValueError, match="seed has shape"):
        arm_ik(cable_cell.arms["left"]).solve(np.eye(4), np.zeros(5))


# ------------------------------------------------------------------------------ numerical


def test_numerical_for_an_arm_without_dh(gantry: Arm) -> None:
    ik = arm_ik(gantry)
    assert ik.closed_form is None and ik.numeric is not None
    with pytest.raises(ValueError, match="no closed-form IK"):
        ik.branch(ik.home)
    rng = np.random.default_rng(4)
    for _ in range(20):
        x, y, z, a = rng.uniform([0.05, 0.05, 0.02, -3.0], [0.95, 0.55, 0.28, 3.0])
        q = np.array([x, y, z, a])
        T = gantry.fk(q)
        found = ik.solve(T)  # from the arm's nominal seed
        assert found is not None
        dp, dr = residual(gantry, found, T)
        assert dp <= 1e-5 and dr <= 1e-5
        all_ = ik.solve_all(T)
        assert all_.shape == (1, 4)


def test_a_numerical_arm_has_no_branches(gantry: Arm) -> None:
    assert arm_ik(gantry).by_branch(gantry.fk(np.zeros(gantry.nq))) is None


def test_numerical_out_of_reach(gantry: Arm) -> None:
    ik = ArmIK(gantry, max_restarts=2)
    T = gantry.fk(ik.home)
    T[2, 3] += 1.0  # a metre above the z axis's travel
    assert ik.solve(T) is None
    assert ik.solve_all(T).shape == (0, 4)
    q, ok = ik.solve_batch(np.array([T, gantry.fk(ik.home)]))
    assert ok.tolist() == [False, True] and np.isnan(q[0]).all()
