"""A two-arm transit under async (execute/strategies.py): each arm on its own, unless that
leaves an arm on an IK branch its segments ahead do not require; then both as one."""

from __future__ import annotations

import pytest

from cellengine.execute import strategies
from cellengine.execute.solve import Lookahead
from cellengine.execute.strategies import solve_segment
from cellengine.motion.ik import arm_ik
from cellengine.program import ArmPath, Segment
from tests.execute.scenes import cable_cell, home, pose

GOALS = {"left": (0.45, 0.25, 0.25), "right": (0.45, -0.25, 0.25)}


def transit() -> Segment:
    paths = tuple(ArmPath(a, "transit", pose(xyz)[None]) for a, xyz in GOALS.items())
    return Segment(step=0, label="to both goals", paths=paths)


def test_apart_when_each_arm_ends_on_a_branch_ahead_requires() -> None:
    _, cell, checker = cable_cell()
    (part,) = solve_segment(cell, checker, transit(), home(cell), "async")
    assert part.solved == "apart"


def test_together_when_apart_leaves_an_arm_off_the_branches_ahead(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The left arm's segments ahead require a branch other than the one the arms planned
    each on its own end on (here: the apart plan made without looking ahead, as when the arm
    planned first stands where the other's goals on that branch are): the transit is planned
    as one, and ends on the required branch."""
    _, cell, checker = cable_cell()
    q = home(cell)
    (apart,) = solve_segment(cell, checker, transit(), q, "async")
    ik = arm_ik(cell.arms["left"])
    taken = ik.branch(apart.rows["left"][-1])
    others = {ik.branch(s) for s in ik.solve_all(pose(GOALS["left"]))} - {taken}
    want = min(others)
    blind = strategies._apart
    monkeypatch.setattr(strategies, "_apart", lambda *a, **k: blind(*a, **{**k, "ahead": None}))
    ahead = {"left": Lookahead(None, frozenset({want}))}
    (part,) = solve_segment(cell, checker, transit(), q, "async", ahead=ahead)
    assert part.solved == "together"
    assert part.coupled is not None
    assert ik.branch(part.coupled[-1][cell.slices["left"]]) == want
    (part,) = solve_segment(cell, checker, transit(), q, "async", ahead=ahead, choice=1)
    assert part.solved == "apart"  # the compiler's next choices: the apart plan's
