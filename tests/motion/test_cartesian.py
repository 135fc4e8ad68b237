"""Cartesian paths that must stop at a known waypoint for a known reason (out of the
workspace, a wrist flip, a joint limit, a collision with a stand-in obstacle and with the real
checker on the cable-routing cell), dual-arm paths checked against each other's motion,
closed chains, determinism."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import pytest

from cellengine import geometry as g
from cellengine.info.load import load_world
from cellengine.motion import cartesian
from cellengine.motion import interpolate as itp
from cellengine.motion.cartesian import (
    ArmInCell,
    CartesianResult,
    JumpThreshold,
    cartesian_path,
    closed_chain_path,
    dual_cartesian_path,
)
from cellengine.motion.collision import CollisionChecker
from cellengine.motion.ik import arm_ik
from cellengine.motion.robot import Arm, CellModel, build_cell_model
from cellengine.motion.scene import build_scene
from tests.conftest import CELLS, DATA

READY = np.array([math.pi, -1.9, 1.9, -1.57, -1.57, 0.0])  # elbow up, tool down, facing +x
R_DOWN = np.array([[0.0, -1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])  # READY's TCP axes
D4_UR5E = 0.1333


def down(x: float, y: float, z: float) -> np.ndarray:
    return g.transform(R_DOWN, [x, y, z])


@pytest.fixture(scope="module")
def world() -> Any:
    return load_world(CELLS / "cable_routing" / "cell.yaml")


@pytest.fixture(scope="module")
def cell(world: Any) -> CellModel:
    return build_cell_model(world)


@pytest.fixture(scope="module")
def checker(cell: CellModel, world: Any) -> CollisionChecker:
    return CollisionChecker(build_scene(cell, world))


def start(arm: Arm, T: np.ndarray) -> np.ndarray:
    q = arm_ik(arm).solve(T, READY)
    assert q is not None
    return q


def residuals(arm: Arm, q: np.ndarray, Ts: np.ndarray) -> float:
    return max(float(np.abs(arm.fk(qi) - T).max()) for qi, T in zip(q, Ts, strict=True))


# ------------------------------------------------------------------------------ stand-ins


@dataclass(frozen=True)
class Touch:
    """A stand-in contact: two names, a distance and where on a segment."""

    a: str
    b: str
    distance: float = 0.0
    t: float | None = None

    @property
    def pair(self) -> tuple[str, str]:
        return (self.a, self.b)


class TcpRegion:
    """A stand-in checker over one arm's q: in collision when the TCP is inside a region
    (a sphere, or a slab between two planes x = lo, x = hi). Segments are sampled every
    1/400 (fine enough for the tests' shapes)."""

    def __init__(self, arm: Arm, inside: Any, name: str) -> None:
        self.arm, self.inside, self.name = arm, inside, name
        self.calls = {"check": 0, "batch": 0, "segment": 0}

    def _hit(self, q: np.ndarray) -> bool:
        return bool(self.inside(self.arm.fk(q)[:3, 3]))

    def check(self, q: np.ndarray) -> Touch | None:
        self.calls["check"] += 1
        return Touch(f"{self.arm.name}/tcp", self.name) if self._hit(q) else None

    def check_batch(self, Q: np.ndarray) -> np.ndarray:
        self.calls["batch"] += 1
        return np.array([self._hit(q) for q in Q], dtype=bool)

    def check_segment(self, q0: np.ndarray, q1: np.ndarray) -> Touch | None:
        self.calls["segment"] += 1
        for t in np.linspace(0.0, 1.0, 401):
            if self._hit(q0 + t * (q1 - q0)):
                return Touch(f"{self.arm.name}/tcp", self.name, 0.0, float(t))
        return None


class TcpsApart:
    """A stand-in checker over the cell's q: in collision when the two TCPs are closer than
    ``d``."""

    def __init__(self, cell: CellModel, d: float) -> None:
        self.cell, self.d = cell, d

    def _gap(self, q: np.ndarray) -> float:
        qs = self.cell.split(q)
        p = [self.cell.arms[n].fk(qs[n])[:3, 3] for n in ("left", "right")]
        return float(np.linalg.norm(p[0] - p[1]))

    def check(self, q: np.ndarray) -> Touch | None:
        gap = self._gap(q)
        return Touch("left/tcp", "right/tcp", gap - self.d) if gap < self.d else None

    def check_batch(self, Q: np.ndarray) -> np.ndarray:
        return np.array([self._gap(q) < self.d for q in Q], dtype=bool)

    def check_segment(self, q0: np.ndarray, q1: np.ndarray) -> Touch | None:
        for t in np.linspace(0.0, 1.0, 101):
            if self._gap(q0 + t * (q1 - q0)) < self.d:
                return Touch("left/tcp", "right/tcp", 0.0, float(t))
        return None


# ------------------------------------------------------------------------------ reach


def test_a_reachable_1_m_line_is_followed_on_one_branch(cell: CellModel) -> None:
    arm = cell.arms["left"]
    W = itp.line(down(0.45, 0.85, 0.25), down(0.45, -0.15, 0.25), max_translation=0.001)
    q0 = start(arm, W[0])
    r = cartesian_path(arm, W, q0)
    assert r.ok and r.stop is None and r.fraction == 1.0
    assert r.q.shape == (1001, 6) and r.n_waypoints == 1001
    assert residuals(arm, r.q, W) <= 1e-9
    np.testing.assert_allclose(r.s, np.linspace(0.0, 1.0, 1001), atol=1e-9)
    assert np.abs(np.diff(np.vstack([q0, r.q]), axis=0)).max() < 0.05  # continuous
    ik = arm_ik(arm)
    assert {ik.branch(q) for q in r.q[::50]} == {ik.branch(q0)}


def test_an_arc_is_followed_exactly(cell: CellModel) -> None:
    arm = cell.arms["right"]
    T0 = down(0.5, -0.2, 0.2)
    W = itp.arc_about(T0, [0.4, -0.2, 0.2], [0, 0, 1], math.radians(120), max_translation=0.002)
    r = cartesian_path(arm, W, start(arm, T0))
    assert r.ok, r.stop
    assert residuals(arm, r.q, W) <= 1e-9


def test_steps_of_different_lengths_are_not_jumps(cell: CellModel) -> None:
    """900 steps of 1 mm, then 10 of 1 cm: MoveIt's test (a step against factor x the MEAN
    step, here 1.1 mm) would stop at the first 1 cm step for any factor under 9; joint motion
    per metre of path does not change, so the relative test lets it pass even at 2 x."""
    arm = cell.arms["left"]
    a = itp.line(down(0.45, 0.8, 0.25), down(0.45, -0.1, 0.25), max_translation=0.001)
    b = itp.line(a[-1], down(0.45, -0.2, 0.25), max_translation=0.01)
    W = itp.concatenate([a, b])
    assert len(W) == 911
    r = cartesian_path(arm, W, start(arm, W[0]), jump=JumpThreshold(relative=2.0))
    assert r.ok, r.stop


def test_leaving_the_workspace_stops_at_the_first_unreachable_waypoint(cell: CellModel) -> None:
    """Tool down, the wrist point is straight above the TCP; it cannot come nearer than d4
    to the base's z axis. A line along x through the base's y from x = 0.6 leaves the
    workspace at the first x < d4: x = 0.6 - 0.001 i, i = 467."""
    arm = cell.arms["left"]
    y = float(arm.T_cell_base[1, 3])
    W = itp.line(down(0.6, y, 0.3), down(-0.4, y, 0.3), max_translation=0.001)
    first_out = math.ceil((0.6 - D4_UR5E) / 0.001)
    assert first_out == 467
    r = cartesian_path(arm, W, start(arm, W[0]), jump=JumpThreshold(relative=None))
    assert r.stop is not None and r.stop.kind == "unreachable"
    assert r.stop.waypoint == first_out and len(r.q) == first_out
    assert "no IK branch reaches it" in r.stop.message and r.stop.arm == "left"
    assert r.stop.waypoints == {"left": first_out}
    assert r.fraction == pytest.approx((first_out - 1) / 1000, abs=1e-9)
    assert residuals(arm, r.q, W[:first_out]) <= 1e-9


def test_the_relative_jump_test_stops_at_the_workspace_edge_and_says_so(cell: CellModel) -> None:
    arm = cell.arms["left"]
    y = float(arm.T_cell_base[1, 3])
    W = itp.line(down(0.6, y, 0.3), down(-0.4, y, 0.3), max_translation=0.001)
    r = cartesian_path(arm, W, start(arm, W[0]))
    assert r.stop is not None and r.stop.kind == "joint_jump"
    # q1 (and q6 with it, keeping the orientation) speeds up as sqrt(r^2 - d4^2) vanishes
    assert 457 <= r.stop.waypoint < 467
    assert r.stop.joint in ("left_shoulder_pan_joint", "left_wrist_3_joint")
    assert "waypoint 467 is out of reach" in r.stop.message
    assert r.stop.value > r.stop.bound


def test_a_wrist_flip_stops_the_path_at_the_singularity(cell: CellModel) -> None:
    """A line through a pose with q5 = 0, midway between waypoints 99 and 100: the branch
    (wrist bit: sign of sin q5) is kept, so q4 and q6 turn by pi there."""
    arm = cell.arms["left"]
    q_singular = np.array([0.3, -1.2, 1.5, -1.9, 0.0, 0.4])
    T_s = arm.fk(q_singular)
    p = T_s[:3, 3] - arm.T_cell_base[:3, 3]
    u = np.cross([0.0, 0.0, 1.0], [p[0], p[1], 0.0])
    u /= np.linalg.norm(u)  # round the base: q1 changes, which moves z1 across the tool axis
    W = np.array(
        [g.transform(T_s[:3, :3], T_s[:3, 3] + (i - 99.5) * 0.001 * u) for i in range(200)]
    )
    q0 = arm_ik(arm).solve(W[0], q_singular)  # on the branch that meets the singularity
    for jump in (JumpThreshold(), JumpThreshold(revolute=None)):  # both tests catch it
        r = cartesian_path(arm, W, q0, jump=jump)
        assert r.stop is not None and r.stop.kind == "joint_jump"
        assert r.stop.waypoint == 100 and len(r.q) == 100
        assert r.stop.joint in ("left_wrist_1_joint", "left_wrist_3_joint")
    r = cartesian_path(arm, W, q0)
    assert r.stop is not None and r.stop.value == pytest.approx(math.pi, abs=0.01)
    assert r.stop.bound == 0.3
    assert r.fraction == pytest.approx(99 / 199, abs=1e-9)


def test_a_joint_limit_stops_the_path_where_it_is_crossed(cell: CellModel) -> None:
    """Turning the TCP about its own axis turns q6 alone: from 6.0 rad by 0.01 rad a step,
    q6 passes 2 pi (its limit) at waypoint 29."""
    arm = cell.arms["left"]
    q0 = READY.copy()
    q0[5] = 6.0
    T0 = arm.fk(q0)
    W = itp.arc_about(T0, T0[:3, 3], T0[:3, 2], 0.5, max_rotation=0.01)
    assert len(W) == 51
    r = cartesian_path(arm, W, q0)
    assert r.stop is not None and r.stop.kind == "limit"
    assert r.stop.waypoint == 29 and r.stop.joint == "left_wrist_3_joint"
    assert r.stop.bound == pytest.approx(2 * math.pi)
    assert r.stop.value == pytest.approx(6.29, abs=1e-9)
    np.testing.assert_allclose(r.q[:, 5], 6.0 + 0.01 * np.arange(29), atol=1e-9)
    np.testing.assert_allclose(r.q[:, :5], np.broadcast_to(q0[:5], (29, 5)), atol=1e-9)


def test_a_start_far_from_the_first_waypoint_is_a_jump_at_waypoint_0(cell: CellModel) -> None:
    arm = cell.arms["left"]
    W = itp.line(down(0.45, 0.5, 0.25), down(0.45, 0.3, 0.25))
    r = cartesian_path(arm, W, np.array(arm.home))
    assert r.stop is not None and r.stop.kind == "joint_jump" and r.stop.waypoint == 0
    assert "from the start configuration to waypoint 0" in r.stop.message
    assert len(r.q) == 0 and r.fraction == 0.0


def test_a_tcp_standing_still_while_a_joint_turns_is_a_jump(cell: CellModel) -> None:
    """No branch change can do this (the branch is kept and angles are unwrapped), but a
    joint turning a full turn between two equal poses is what the zero-length test is for."""
    arm = cell.arms["left"]
    q = READY + np.array([0.0, 0.0, 0.0, 0.0, 0.0, 2 * math.pi])
    T = arm.fk(READY)
    stop = cartesian._first_jump(arm_ik(arm), q[None], READY, T[None], JumpThreshold(None))
    assert stop is not None and stop.kind == "joint_jump" and stop.waypoint == 0
    assert "TCP stays put" in stop.message and stop.joint == "left_wrist_3_joint"


# ------------------------------------------------------------------------------ collisions


def test_a_stand_in_sphere_stops_the_path_at_the_waypoint_entering_it(cell: CellModel) -> None:
    arm = cell.arms["left"]
    W = itp.line(down(0.45, 0.6, 0.25), down(0.45, 0.2, 0.25), max_translation=0.001)
    # edge at y = 0.4505: between waypoints 149 (y = 0.451) and 150 (y = 0.450)
    centre, radius = np.array([0.45, 0.35, 0.25]), 0.1005
    sphere = TcpRegion(arm, lambda p: np.linalg.norm(p - centre) < radius, "sphere")
    r = cartesian_path(arm, W, start(arm, W[0]), check=sphere)
    assert r.stop is not None and r.stop.kind == "collision"
    assert r.stop.waypoint == 150 and len(r.q) == 150
    assert r.stop.pair == ("left/tcp", "sphere") and r.stop.arm == "left"
    assert "on the way there from waypoint 149" in r.stop.message
    assert r.fraction == pytest.approx(149 / 400, abs=1e-9)
    assert sphere.calls["segment"] == 151  # start -> 0, then 0 -> 1 ... 149 -> 150


def test_an_obstacle_thinner_than_a_step_is_caught_on_the_segment(cell: CellModel) -> None:
    """A 0.4 mm slab between two waypoints 1 mm apart: no waypoint is in it. Segments
    find it; the per-state batch (segments=False) cannot, which is why it is not the default."""
    arm = cell.arms["left"]
    W = itp.line(down(0.45, 0.6, 0.25), down(0.45, 0.2, 0.25), max_translation=0.001)
    slab = TcpRegion(arm, lambda p: abs(p[1] - 0.4505) < 0.0002, "slab")
    q0 = start(arm, W[0])
    r = cartesian_path(arm, W, q0, check=slab)
    assert r.stop is not None and r.stop.kind == "collision" and r.stop.waypoint == 150
    states_only = cartesian_path(arm, W, q0, check=slab, segments=False)
    assert states_only.ok and slab.calls["batch"] == 1


def test_the_left_tcp_driven_into_the_table_stops_there(
    cell: CellModel, checker: CollisionChecker
) -> None:
    """The tool's fingers end at the TCP and the table's top is z = 0; the checker refuses
    anything within its 1 mm clearance. TCP z = 0.30125 - 0.0025 i: waypoint 120 is 1.25 mm
    above the table, 121 is 1.25 mm into it."""
    arm = cell.arms["left"]
    W = np.array([down(0.4, 0.5, 0.30125 - 0.0025 * i) for i in range(201)])
    q0 = start(arm, W[0])
    q_cell = cell.join({"left": q0, "right": np.array(cell.arms["right"].home)})
    check = ArmInCell(checker, cell, "left", q_cell)
    for segments in (True, False):
        r = cartesian_path(arm, W, q0, check=check, segments=segments)
        assert r.stop is not None and r.stop.kind == "collision"
        assert r.stop.waypoint == 121 and r.stop.pair == ("left/tool/finger_left", "table")
        assert r.stop.arm == "left"
        assert r.fraction == pytest.approx(120 / 200, abs=1e-9)


def test_a_free_line_passes_the_real_checker(cell: CellModel, checker: CollisionChecker) -> None:
    arm = cell.arms["left"]
    W = itp.line(down(0.45, 0.85, 0.25), down(0.45, -0.15, 0.25), max_translation=0.002)
    q0 = start(arm, W[0])
    q_cell = cell.join({"left": q0, "right": np.array(cell.arms["right"].home)})
    r = cartesian_path(arm, W, q0, check=ArmInCell(checker, cell, "left", q_cell))
    assert r.ok, r.stop


def test_arm_in_cell_places_the_arm_in_the_cell(cell: CellModel) -> None:
    q_cell = np.arange(12.0)
    lifted = ArmInCell(TcpsApart(cell, 0.1), cell, "right", q_cell).lift(np.full((3, 6), -1.0))
    assert lifted.shape == (3, 12)
    np.testing.assert_array_equal(lifted[:, cell.slices["right"]], -1.0)
    np.testing.assert_array_equal(
        lifted[:, cell.slices["left"]], np.broadcast_to(q_cell[:6], (3, 6))
    )


# ------------------------------------------------------------------------------ both arms


def head_on(cell: CellModel, step: float = 0.001) -> tuple[dict[str, Any], dict[str, Any]]:
    """Both TCPs at x = 0.45, z = 0.3 moving towards each other along y, 0.3 m each: left
    from y = 0.25 to -0.05, right from -0.25 to 0.05. Either alone, with the other at its
    start, stays 0.2 m away; together the gap closes as 0.5 - 0.6 s."""
    W = {
        "left": itp.line(down(0.45, 0.25, 0.3), down(0.45, -0.05, 0.3), step),
        "right": itp.line(down(0.45, -0.25, 0.3), down(0.45, 0.05, 0.3), step),
    }
    seeds = {name: start(cell.arms[name], W[name][0]) for name in W}
    return W, seeds


def test_dual_paths_collide_only_when_both_move_stand_in(cell: CellModel) -> None:
    W, seeds = head_on(cell)
    apart = TcpsApart(cell, 0.101)  # gap 0.5 - 0.002 i < 0.101 first at row 200
    r = dual_cartesian_path(cell, W, seeds, check=apart)
    assert r.stop is not None and r.stop.kind == "collision"
    assert r.stop.waypoint == 200 and r.q.shape == (200, 12)
    assert r.stop.pair == ("left/tcp", "right/tcp") and r.stop.arm is None
    assert r.stop.waypoints == {"left": 200, "right": 200}
    assert r.fraction == pytest.approx(199 / 300, abs=1e-9)
    q_cell = cell.join(seeds)
    for name in ("left", "right"):  # each against the other standing still: free
        alone = cartesian_path(
            cell.arms[name], W[name], seeds[name], check=ArmInCell(apart, cell, name, q_cell)
        )
        assert alone.ok, alone.stop


def test_dual_paths_collide_only_when_both_move_real_checker(
    cell: CellModel, checker: CollisionChecker
) -> None:
    W, seeds = head_on(cell)
    q_cell = cell.join(seeds)
    for name in ("left", "right"):
        alone = cartesian_path(
            cell.arms[name], W[name], seeds[name], check=ArmInCell(checker, cell, name, q_cell)
        )
        assert alone.ok, alone.stop
    r = dual_cartesian_path(cell, W, seeds, check=checker)
    assert r.stop is not None and r.stop.kind == "collision" and r.stop.pair is not None
    assert sorted(n.split("/")[0] for n in r.stop.pair) == ["left", "right"]
    assert 150 < r.stop.waypoint < 250 and r.stop.arm is None
    assert r.fraction == pytest.approx(r.s[-1])
    # every row holds both arms where their own paths have them at that moment
    for row in (0, 100, r.stop.waypoint - 1):
        qs = cell.split(r.q[row])
        for name in ("left", "right"):
            np.testing.assert_allclose(cell.arms[name].fk(qs[name]), W[name][row], atol=1e-9)


def test_dual_grid_is_the_union_of_both_arms_waypoints(cell: CellModel) -> None:
    W, seeds = head_on(cell)
    W["right"] = itp.line(W["right"][0], W["right"][-1], 0.005)  # 61 waypoints against 301
    r = dual_cartesian_path(cell, W, seeds)
    assert r.ok and r.q.shape == (301, 12)
    right = cell.arms["right"]
    for row in range(0, 301, 5):  # the right arm's own waypoints are rows 0, 5, 10, ...
        q = cell.split(r.q[row])["right"]
        np.testing.assert_allclose(right.fk(q), W["right"][row // 5], atol=1e-9)
    for row in range(1, 301, 7):  # in between: on its line, where its fraction says
        p = right.fk(cell.split(r.q[row])["right"])[:3, 3]
        np.testing.assert_allclose(p, [0.45, -0.25 + 0.3 * r.s[row], 0.3], atol=1e-9)


def test_dual_stop_names_the_arm_and_its_own_waypoint(cell: CellModel) -> None:
    left, right = cell.arms["left"], cell.arms["right"]
    y = float(left.T_cell_base[1, 3])
    W = {
        "left": itp.line(down(0.6, y, 0.3), down(-0.4, y, 0.3), 0.001),  # out at 467
        "right": itp.line(down(0.45, -0.25, 0.3), down(0.45, -0.45, 0.3), 0.002),  # 101
    }
    seeds = {"left": start(left, W["left"][0]), "right": start(right, W["right"][0])}
    r = dual_cartesian_path(cell, W, seeds, jump=JumpThreshold(relative=None))
    assert r.stop is not None and r.stop.kind == "unreachable" and r.stop.arm == "left"
    assert r.stop.waypoint == 467
    assert r.stop.waypoints == {"left": 467, "right": math.ceil(467 / 10)}
    assert r.fraction == pytest.approx(0.466, abs=1e-9)


def test_an_arm_without_waypoints_stands_at_its_seed(cell: CellModel) -> None:
    W, seeds = head_on(cell)
    r = dual_cartesian_path(cell, {"left": W["left"]}, seeds)
    assert r.ok
    np.testing.assert_array_equal(
        r.q[:, cell.slices["right"]], np.broadcast_to(seeds["right"], (301, 6))
    )
    with pytest.raises(ValueError, match="unknown arm"):
        dual_cartesian_path(cell, {"middle": W["left"]}, seeds)


# ------------------------------------------------------------------------------ closed chain


def test_closed_chain_keeps_the_relative_pose(cell: CellModel) -> None:
    """Both hands on one bar 0.2 m long: the left TCP turns it by 40 degrees about the
    vertical through its middle while lifting it; the right keeps its grip to 1e-9."""
    left, right = cell.arms["left"], cell.arms["right"]
    TL, TR = down(0.45, 0.1, 0.25), down(0.45, -0.1, 0.25)
    seeds = {"left": start(left, TL), "right": start(right, TR)}
    turn = itp.arc_about(TL, [0.45, 0.0, 0.25], [0, 0, 1], math.radians(40), max_translation=0.001)
    lift = itp.line(turn[-1], g.pose([0, 0, 0.1]) @ turn[-1], max_translation=0.001)
    W = itp.concatenate([turn, lift])
    r = closed_chain_path(cell, "left", "right", W, seeds)
    assert r.ok, r.stop
    T_lf = g.inverse(TL) @ TR
    for q in r.q:
        qs = cell.split(q)
        rel = g.inverse(left.fk(qs["left"])) @ right.fk(qs["right"])
        np.testing.assert_allclose(rel, T_lf, atol=1e-9)
    explicit = closed_chain_path(cell, "left", "right", W, seeds, T_lf)
    np.testing.assert_allclose(explicit.q, r.q, atol=1e-9)
    with pytest.raises(ValueError, match="two arms"):
        closed_chain_path(cell, "left", "left", W, seeds)


def test_closed_chain_stops_when_the_follower_cannot_follow(cell: CellModel) -> None:
    left, right = cell.arms["left"], cell.arms["right"]
    TL, TR = down(0.45, 0.1, 0.25), down(0.45, -0.1, 0.25)
    seeds = {"left": start(left, TL), "right": start(right, TR)}
    W = itp.line(TL, down(0.45, 1.1, 0.25), max_translation=0.002)  # the right is dragged away
    r = closed_chain_path(cell, "left", "right", W, seeds, jump=JumpThreshold(relative=None))
    assert r.stop is not None and r.stop.arm == "right" and r.stop.kind == "unreachable"
    assert 0 < r.fraction < 1


# ------------------------------------------------------------------------------ others


def test_same_inputs_same_path(cell: CellModel, checker: CollisionChecker) -> None:
    W, seeds = head_on(cell)
    a = dual_cartesian_path(cell, W, seeds, check=checker)
    b = dual_cartesian_path(cell, W, seeds, check=checker)
    np.testing.assert_array_equal(a.q, b.q)
    assert a.stop is not None and b.stop is not None and a.stop.message == b.stop.message
    single = [cartesian_path(cell.arms["left"], W["left"], seeds["left"]) for _ in range(2)]
    np.testing.assert_array_equal(single[0].q, single[1].q)


def test_a_result_never_stops_short_silently() -> None:
    with pytest.raises(ValueError, match="must say why it stops"):
        CartesianResult(np.zeros((3, 6)), np.zeros(3), 0.5, None, 10)


def test_a_numerical_arm_follows_a_line_until_its_axis_ends() -> None:
    """The gantry's x axis runs along the cell's y (base turned 90 degrees), 0 .. 1 m: from
    the middle (0.5), a line 0.8 m along y leaves its travel after waypoint 500."""
    gantry = build_cell_model(load_world(DATA / "urdf" / "cartesian" / "cell.yaml")).arms["gantry"]
    q0 = np.array([0.5, 0.3, 0.1, 0.2])
    T0 = gantry.fk(q0)
    W = itp.line(T0, g.pose([0.0, 0.8, 0.0]) @ T0, max_translation=0.001)
    r = cartesian_path(gantry, W, q0)
    assert r.stop is not None and r.stop.kind == "unreachable" and r.stop.waypoint == 501
    assert "against the limit: gantry_x" in r.stop.message
    np.testing.assert_allclose(r.q[:, 0], 0.5 + 0.001 * np.arange(501), atol=1e-6)
    assert r.fraction == pytest.approx(500 / 800, abs=1e-9)
