"""The IK branches the cable family keeps for each arm (skills/cable_family.py ``_narrowed``):
an arm does not change branch between its transits, so a candidate whose Cartesian paths no
branch the arm may be on can follow is not offered, and the skills' later checks look only
at the branches left. On the reference cell, with the left tool tipped 30 deg on an arc
around its base (the tool meets the shoulder on some branches, tests/execute)."""

from __future__ import annotations

import math
import shutil
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from cellengine import geometry as g
from cellengine.context import build_context
from cellengine.errors import InputError, StepError
from cellengine.info.load import load_plan, load_world
from cellengine.pipeline import compile_plan
from cellengine.program import ArmPath, Segment
from cellengine.skills import cable_family
from cellengine.skills.cable_family import _narrowed
from cellengine.skills.cable_state import ANY_BRANCH, CableState
from tests.conftest import CELLS
from tests.execute.scenes import CELL


def arc(base: np.ndarray, tilt_deg: float) -> np.ndarray:
    """The tool tipped ``tilt_deg`` about its y, 80 mm over the table, on 1.2 rad of an arc
    180 mm around ``base``."""
    poses = []
    for a in np.linspace(-0.6, 0.6, 61):
        p = base + np.array(
            [0.18 * math.cos(a - math.pi / 2), 0.18 * math.sin(a - math.pi / 2), 0.08]
        )
        R = g.rot_z(a) @ g.rot_x(math.pi) @ g.rot_y(math.radians(tilt_deg))
        poses.append(g.transform(R, p))
    return np.array(poses)


def test_an_arms_branches_narrow_along_its_paths_and_open_again_at_a_transit() -> None:
    ctx = build_context(load_world(CELL, CELL.parent / "objects.yaml"))
    state = CableState.at_home(ctx)
    base = ctx.cell.arms["left"].T_cell_base[:3, 3]
    tipped, other_way = arc(base, 30.0), arc(base, -30.0)
    one = [Segment(0, "around", (ArmPath("left", "cartesian", tipped),))]
    narrowed = _narrowed(ctx, state, one, state)
    assert not isinstance(narrowed, str)
    segments, after = narrowed
    kept = after.branches_of("left")
    assert kept and kept < ANY_BRANCH  # some branches meet the shoulder, some do not
    assert after.branches_of("right") == ANY_BRANCH  # it did not move
    assert segments[0].branches == (("left", kept),)  # what the compiler holds the arm to
    # tipped the other way, the tool meets the shoulder on every branch left
    back = Segment(0, "back", (ArmPath("left", "cartesian", other_way),))
    alone = _narrowed(ctx, state, [back], state)
    assert not isinstance(alone, str) and not kept & alone[1].branches_of("left")
    assert _narrowed(ctx, state, [*one, back], state) == "left"  # the arm left with none
    # the skill's own checks kept fewer: those
    fewer = replace(state, branches={"left": frozenset(sorted(kept)[:1])})
    narrowed = _narrowed(ctx, state, one, fewer)
    assert not isinstance(narrowed, str)
    assert narrowed[1].branches_of("left") == fewer.branches["left"]
    # a transit between them: the arm may reach the second arc's start on any branch, and
    # the segments before it and after it require each their own
    hop = Segment(0, "hop", (ArmPath("left", "transit", other_way[:1]),))
    narrowed = _narrowed(ctx, state, [*one, hop, back], state)
    assert not isinstance(narrowed, str)
    required = [s.branches_of("left") for s in narrowed[0]]
    assert required[0] == kept and required[1] == required[2] == alone[1].branches_of("left")


def test_a_step_whose_every_way_strands_an_arm_says_so(monkeypatch: pytest.MonkeyPatch) -> None:
    """When every way of a step leaves an arm on no branch (every candidate dropped), the
    family raises an error naming the step and the arm, not an empty offer the compiler can
    only call 'no way to do the plan'; remembered for that state like any other."""
    loaded = load_plan(CELLS / "cable_routing" / "plan_straight.yaml")
    ctx = build_context(loaded.world)
    monkeypatch.setattr(cable_family, "_narrowed", lambda *a: "left")
    with pytest.raises(StepError) as err:
        next(cable_family.FAMILY.plan(ctx, loaded.plan.steps))
    assert err.value.problems[0].message == (
        "steps[0] PickCable: every way of doing it leaves an arm (left) on no inverse "
        "kinematics branch that follows its Cartesian paths within reach and clear of itself "
        "from where the steps before left it"
    )


def test_a_cable_picked_twice_is_refused_at_the_second_pick(tmp_path: Path) -> None:
    shutil.copytree(CELLS / "cable_routing", tmp_path / "cell")
    plan = tmp_path / "cell" / "plan.yaml"
    pick = "  - {skill: PickCable, cable: cable1, from: [holder.comb_a, holder.comb_b]}\n"
    plan.write_text("cell: cell.yaml\nobjects: objects.yaml\nsteps:\n" + pick * 2)
    with pytest.raises(InputError) as e:
        compile_plan(plan)
    assert str(e.value) == (
        f"{plan}:5:5: steps[1] PickCable: 'cable1' was picked by steps[0]; a cable is picked "
        "from its combs once"
    )


def test_the_first_guide_with_no_way_sends_the_search_to_the_other_routing_arm(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The first guide is routed from where the connector was placed: when none of its ways
    passes, the error blames which arm routes (PlaceConnector decides it), so the search
    tries the other arm's placing before the same arm's other ones (they are still tried
    after). A later guide's error blames nothing: the guide before it decides its state."""
    loaded = load_plan(CELLS / "cable_routing" / "plan_straight.yaml")
    ctx, steps = build_context(loaded.world), loaded.plan.steps
    state = CableState.at_home(ctx)

    def refused(*_: object) -> object:
        raise InputError.at("no way", None)
        yield  # a generator, as the guide's ways

    monkeypatch.setattr(cable_family, "_ways", refused)
    for k, blames in ((0, "arms"), (1, None)):
        with pytest.raises(InputError) as err:
            next(cable_family._guide(ctx, steps, 2, state, k, {}))
        assert err.value.blames == blames
