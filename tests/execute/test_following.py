"""Which transit goals can follow the arm's Cartesian paths ahead (execute/following.py), on
the reference cable-routing cell: the tool tipped 30 deg, 80 mm above the table, on an arc
180 mm around the left arm's base (where the tool meets the shoulder on some branches)."""

from __future__ import annotations

import math
import re
from dataclasses import replace

import numpy as np

from cellengine import geometry as g
from cellengine.execute import solve
from cellengine.execute.following import followable, required, surviving, touching
from cellengine.execute.refused import Refused
from cellengine.motion.ik import arm_ik
from cellengine.program import ArmPath, Segment
from tests.execute.scenes import cable_cell, home


def arc_near_the_base(base: np.ndarray) -> np.ndarray:
    poses = []
    for a in np.linspace(-0.6, 0.6, 61):  # 1.2 deg and 3.6 mm apart
        p = base + np.array(
            [0.18 * math.cos(a - math.pi / 2), 0.18 * math.sin(a - math.pi / 2), 0.08]
        )
        poses.append(g.transform(g.rot_z(a) @ g.rot_x(math.pi) @ g.rot_y(math.radians(30)), p))
    return np.array(poses)


def stop_of(cell: object, checker: object, arm: str, poses: np.ndarray, start: np.ndarray) -> str:
    """Why the arm's Cartesian path along ``poses`` from ``start`` stops ("" when it runs)."""
    try:
        solve.cartesian(cell, checker, arm, poses, start)  # type: ignore[arg-type]
    except Refused as e:
        return str(e)
    return ""


def test_a_goal_follows_the_poses_ahead_unless_its_path_runs_into_the_arm_itself() -> None:
    """A goal that does not follow: its Cartesian path stops on the arm itself (two of its
    own parts, or out of its branch's reach). One that does: its path runs, or stops on
    something else (the table: the compiler's to find out)."""
    _, cell, checker = cable_cell()
    q = home(cell)
    arm = "left"
    poses = arc_near_the_base(cell.arms[arm].T_cell_base[:3, 3])
    sols = arm_ik(cell.arms[arm]).solve_all(poses[0])
    flags = followable(cell, checker, arm, sols, poses, q)
    assert True in flags and False in flags
    for sol, follows in zip(sols, flags, strict=True):
        start = q.copy()
        start[cell.slices[arm]] = sol
        why = stop_of(cell, checker, arm, poses, start)
        itself = re.search(r"between 'left/[^']*' and 'left/", why) or "IK" in why
        assert bool(itself) == (not follows), why


def test_without_poses_ahead_every_goal_follows() -> None:
    _, cell, checker = cable_cell()
    sols = arm_ik(cell.arms["left"]).solve_all(
        arc_near_the_base(cell.arms["left"].T_cell_base[:3, 3])[0]
    )
    assert followable(cell, checker, "left", sols, None, home(cell)) == [True] * len(sols)


def test_the_branches_required_after_a_transit_are_those_up_to_the_next() -> None:
    """following.required: what the segments from a transit of the arm up to its next one
    require of it, all of them at once; none when they require nothing."""
    T = arc_near_the_base(np.zeros(3))
    go = Segment(0, "go", (ArmPath("left", "transit", T[:1]),))
    along = Segment(0, "along", (ArmPath("left", "cartesian", T),))
    again = Segment(0, "again", (ArmPath("left", "transit", T[:1]),))

    def need(s: Segment, branches: set[int]) -> Segment:
        return replace(s, branches=(("left", frozenset(branches)),))

    assert required([go, along, again], "left") is None
    got = required([go, need(along, {1, 2, 3}), need(along, {2, 3, 6}), need(again, {5})], "left")
    assert got == frozenset({2, 3})
    assert required([go, need(along, {1})], "right") is None


def test_a_goal_on_a_branch_not_required_does_not_follow() -> None:
    _, cell, checker = cable_cell()
    ik = arm_ik(cell.arms["left"])
    poses = arc_near_the_base(cell.arms["left"].T_cell_base[:3, 3])
    sols = ik.solve_all(poses[0])
    free = followable(cell, checker, "left", sols, poses, home(cell))
    one = next(ik.branch(s) for s, f in zip(sols, free, strict=True) if f)
    only = followable(cell, checker, "left", sols, poses, home(cell), frozenset({one}))
    assert only == [f and ik.branch(s) == one for s, f in zip(sols, free, strict=True)]
    assert followable(cell, checker, "left", sols, None, home(cell), frozenset({one})) == [
        ik.branch(s) == one for s in sols
    ]


def test_branches_clear_of_themselves_may_still_pass_through_a_fixture() -> None:
    """The right tool pointing down 60 mm above guide3's slot: every branch keeps clear of
    itself, and two of them take the arm's upper links through the cable holder's comb."""
    world, cell, checker = cable_cell()
    q = home(cell)
    slot = world.pose("routing.guide3.slot")[:3, 3]
    poses = g.transform(g.rot_x(math.pi), slot + np.array([0.0, 0.0, 0.06]))[None]
    alive, _ = surviving(cell, checker, "right", poses, q)
    hit = touching(cell, checker, "right", poses, q, alive)
    assert alive == set(range(8))
    assert set(hit) == {0, 7}
    for a, b in hit.values():
        link = a if a.startswith("right/") else b
        assert "holder.comb_b" in (a, b) and not link.startswith("right/tool")


def test_touching_within_a_clearance_adds_the_branches_that_pass_near_a_fixture() -> None:
    """The right tool 150 mm above guide3's slot: no branch touches the cell; held to 20 mm,
    the two whose upper links pass over the cable holder's comb (about 11 mm) do, each
    measured there nearer than that, and the others stay farther."""
    world, cell, checker = cable_cell()
    q = home(cell)
    slot = world.pose("routing.guide3.slot")[:3, 3]
    poses = g.transform(g.rot_x(math.pi), slot + np.array([0.0, 0.0, 0.15]))[None]
    row = arm_ik(cell.arms["right"]).by_branch(poses[0])
    assert row is not None
    reached = {k for k in range(8) if not np.isnan(row[k]).any()}
    assert touching(cell, checker, "right", poses, q, reached) == {}
    near = touching(cell, checker, "right", poses, q, reached, keep=0.02)
    assert set(near) == {0, 7}
    for k in reached:
        here = q.copy()
        here[cell.slices["right"]] = row[k]
        d, pair = checker.distance(here, between=("right", None))
        assert (d < 0.02) == (k in near)
        if k in near:
            assert near[k] == pair and "holder.comb_b" in pair
