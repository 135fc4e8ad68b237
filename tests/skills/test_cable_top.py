"""RouteCable over the top (skills/cable_top.py): a guide too close to the one before for
the published slide and pivot, laid over its top and pushed in, on a copy of the reference
cell with guide2 moved close behind guide1."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from bench.board_check import check_compiled
from cellengine.context import PlanningContext, build_context
from cellengine.errors import InputError
from cellengine.execute.following import surviving
from cellengine.info.load import load_plan
from cellengine.pipeline import compile_plan
from cellengine.skills import cable as C
from cellengine.skills import cable_family, cable_top
from cellengine.skills.cable_state import ANY_BRANCH, CableState
from cellengine.skills.cable_top import TopPlan
from tests.skills.test_cable_search import board

GUIDE2, GUIDE3 = "Guide_U_001", "Guide_U_002"  # routing.guide2, routing.guide3 (map.csv)
TOP = (
    "lay the cable over the top",
    "pusher over the cable",
    "push into the slot",
    "insert",
)


def close_board(tmp_path: Path) -> Path:
    """plan_straight with guide2 32 mm after guide1 (slot to slot; the guides are 10 mm
    thick, so 22 mm between them for 8 mm fingers that keep 5 mm from each) and guide3
    118 mm after guide2, as far as the reference run's spacing (110 mm)."""
    cell = board(tmp_path, {GUIDE2: (150.0, 182.0), GUIDE3: (150.0, 300.0)})
    return cell / "plan_straight.yaml"


def test_a_guide_close_behind_the_last_is_laid_over_the_top_and_pushed_in(
    tmp_path: Path,
) -> None:
    """guide1 and guide3 are routed the published way; guide2 over the top: the routing
    hand lays the cable over it, the other hand's closed fingers push it down behind the
    guide, the routing hand lays it along the slot on the circle about them. The program
    passes the benchmark's independent check (each slot between the fingertips at its
    insert, in order, limits)."""
    compiled = compile_plan(close_board(tmp_path), "split")
    segments = [s.segment for s in compiled.program.segments]
    labels = [s.label for s in segments]
    guide2 = [s.removeprefix("RouteCable routing.guide2: ") for s in labels if "guide2" in s]
    assert guide2 == ["release the previous guide", *TOP]
    for guide in ("guide1", "guide3"):
        assert f"RouteCable routing.{guide}: slide R_cable" in labels
    over = [s for s in segments if s.facts.get("way") == "over the top"]
    assert [s.label.split(": ")[1] for s in over] == [TOP[0], TOP[2], TOP[3]]
    (push,) = [s for s in segments if s.label.endswith("push into the slot")]
    (path,) = push.paths
    (event,) = push.after
    assert (event.arm, event.mode, event.holds) == (path.arm, "grasp", "cable1")
    # the pusher's fingers work by guide2 and guide1 (declared), and come straight down
    assert {(path.arm, "routing.guide2"), (path.arm, "routing.guide1")} <= set(push.near)
    drop = path.poses[0][:3, 3] - path.poses[-1][:3, 3]
    assert np.linalg.norm(drop[:2]) < 1e-9 and drop[2] > 0.0
    result = check_compiled(compiled)
    assert result.ok, result.failures


def test_without_it_the_close_guide_is_refused(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The same board with the over-the-top way taken away: from where guide1 leaves the
    hands, the published ways alone (the routing arm's, and the other arm's after a hand
    swap) cannot route guide2, so the plan above compiles only through the new way. (Asked
    of guide2's ways directly: a whole compile without it searches every earlier choice
    first, 40 s, to say the same.)"""

    def none(*_: object) -> object:
        raise InputError.at("no way over the top", None)
        yield  # a generator, as top_ways

    monkeypatch.setattr(cable_family.cable_top, "top_ways", none)
    ctx, route, state = at_guide2(tmp_path)
    with pytest.raises(InputError) as e:
        next(cable_family._ways(ctx, route, state, 1, set()))
    assert "RouteCable routing.guide2" in str(e.value)


def test_the_routing_arm_laying_over_the_top_is_screened_for_its_own_links(
    tmp_path: Path,
) -> None:
    """The routing arm lays the cable over guide2 and inserts in lines, on the IK branch it
    was on: a way passes the checks only if the arm follows them clear of itself on a branch
    it may be on (before, the family dropped each such way after building it)."""
    ctx, route, state = at_guide2(tmp_path)
    arms = r_arm, _ = route.arms(ctx, state)
    tp = first_passing(ctx, route, state)
    alive, _ = surviving(
        ctx.cell, ctx.checker, r_arm, np.concatenate([tp.lay, tp.insert]), ctx.home
    )
    on = frozenset(alive)
    assert cable_top._check(ctx, route.cable, tp, arms, {}, on) is None
    failed = cable_top._check(ctx, route.cable, tp, arms, {}, ANY_BRANCH - on)
    assert failed is not None and failed[0] == "routing"
    assert (
        failed[1]
        .problems[0]
        .message.startswith(
            f"steps[2] RouteCable routing.guide2: the routing arm ({r_arm}) cannot follow this "
            "guide's paths on the IK branches it may be on without hitting itself"
        )
    )


def test_the_arms_laying_pushing_and_inserting_are_screened_against_each_other(
    tmp_path: Path,
) -> None:
    """Not only the hands: the arms keep the cell's clearance from each other on the IK
    branch pairs the way hands the compiler (a wrist passes over the other arm's upper arm
    on some boards); where no pair does, the way is refused saying how close they come."""
    ctx, route, state = at_guide2(tmp_path)
    arms = r_arm, o_arm = route.arms(ctx, state)
    tp = first_passing(ctx, route, state)
    apart = cable_top._arms_apart(ctx, state, tp, arms, (ANY_BRANCH, ANY_BRANCH), {})
    assert isinstance(apart, cable_top.Apart)
    ((a, b, pairs),) = apart.push
    assert (a, b) == arms and pairs
    rows_r, rows_o = ctx.iks[r_arm].by_branch(tp.lay[-1]), ctx.iks[o_arm].by_branch(tp.push[-1])
    assert rows_r is not None and rows_o is not None  # UR arms: closed form
    for i, j in pairs:  # pushing down, the routing hand over the guide: apart on that pair
        q = ctx.home.copy()
        q[ctx.cell.slices[r_arm]] = rows_r[i]
        q[ctx.cell.slices[o_arm]] = rows_o[j]
        assert ctx.checker.distance(q, between=arms)[0] >= ctx.clearance
    far = replace(ctx, clearance=0.5)
    refused = cable_top._arms_apart(far, state, tp, arms, (ANY_BRANCH, ANY_BRANCH), {})
    assert isinstance(refused, InputError)
    message = refused.problems[0].message
    head, tail = message.split(" mm of each other ")
    assert head.startswith(
        "steps[2] RouteCable routing.guide2: however the two arms are posed, they come within "
    )
    assert 0.0 < float(head.rsplit(" ", 1)[1]) < 500.0
    assert tail == "laying the cable over the top; the cell's clearance is 500.0 mm"


def test_the_pusher_arm_is_screened_against_the_cell_not_only_its_fingers(
    tmp_path: Path,
) -> None:
    """The hands' checks see the tools only; an upper arm can meet a guide or the holder
    where the pusher's fingers are clear, and the compiler then refuses the pusher's transit
    goal. A way is handed over only if some pair of the arms' configurations is free of
    collisions with the pusher over the cable and pushing it down; else it is refused
    saying which."""
    ctx, route, state = at_guide2(tmp_path)
    arms = r_arm, o_arm = route.arms(ctx, state)
    tp = first_passing(ctx, route, state)
    assert cable_top._free(ctx, tp, arms, "over the cable", tp.above, ANY_BRANCH) is None
    sunk = tp.push[-1].copy()
    sunk[:3, 3] -= 0.15 * tp.up  # the pusher's wrist down in the board
    refused = cable_top._free(ctx, tp, arms, "pushing it down", sunk, ANY_BRANCH)
    assert isinstance(refused, InputError)
    assert refused.problems[0].message.startswith(
        f"steps[2] RouteCable routing.guide2: every inverse kinematics solution of the pusher "
        f"({o_arm}) pushing it down, the routing hand over the top, is in collision ("
    )
    for q_o in ctx.iks[o_arm].solve_all(sunk):  # as the compiler would find
        for q_r in ctx.iks[r_arm].solve_all(tp.lay[-1]):
            q = ctx.home.copy()
            q[ctx.cell.slices[o_arm]], q[ctx.cell.slices[r_arm]] = q_o, q_r
            assert ctx.checker.in_collision(q)


def at_guide2(tmp_path: Path) -> tuple[PlanningContext, C.RouteCable, CableState]:
    """The close board's context, its RouteCable and the state after guide1 (its first
    way), where guide2 is routed over the top."""
    loaded = load_plan(close_board(tmp_path))
    ctx, steps = build_context(loaded.world), loaded.plan.steps
    state = CableState.at_home(ctx)
    for i in range(2):
        _, state = next(C.step_ways(ctx, steps, i, state))
    route = steps[2]
    assert isinstance(route, C.RouteCable)
    state = replace(state, step=2)
    r_arm, o_arm = route.arms(ctx, state)
    state = next(route.guide_plans(ctx, state, 0)).after(state, r_arm, o_arm, route.cable)
    return ctx, route, state


def first_passing(ctx: PlanningContext, route: C.RouteCable, state: CableState) -> TopPlan:
    """guide2's first way over the top that its plan and checks pass (on any branch)."""
    arms = r_arm, o_arm = route.arms(ctx, state)
    for way in cable_top._ways(ctx, state, route, 1, r_arm, o_arm):
        try:
            tp = cable_top._plan(ctx, state, route, 1, r_arm, o_arm, way)
        except InputError:
            continue
        if cable_top._check(ctx, route.cable, tp, arms, {}, ANY_BRANCH) is None:
            return tp
    raise AssertionError("no way over guide2 passes its checks")
