"""Choosing transit goals: looking ahead, and coming back to a transit when a later segment
cannot run from where it left the arms."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pytest

from cellengine.errors import InputError
from cellengine.execute import preview as preview_module
from cellengine.execute import solve
from cellengine.execute.held import Holding
from cellengine.execute.preview import PREVIEW_SEGMENTS, preview, upcoming
from cellengine.execute.refused import ChoicesExhausted, NoMoreChoices, Refused
from cellengine.execute.search import BUDGET, add_all
from cellengine.execute.solve import Lookahead
from cellengine.motion.ik import arm_ik
from cellengine.motion.robot import CellModel
from cellengine.program import ArmPath, GripperEvent, Segment
from tests.execute.scenes import LEFT_READY, cable_cell, home, line, pose

TRANSIT = ArmPath("left", "transit", np.eye(4)[None])
LINE = ArmPath("left", "cartesian", np.repeat(np.eye(4)[None], 2, axis=0))


def seg(i: int, kind: str) -> Segment:
    return Segment(0, f"s{i}", (TRANSIT if kind == "t" else LINE,))


@dataclass
class Fake:
    """A compiler whose segment ``fails_at`` fails unless the transit ``needs[0]`` was added
    with choice ``needs[1]``; transits have ``choices`` goal configurations."""

    fails_at: int
    needs: tuple[int, int]
    choices: int = 8
    added: list[tuple[int, int]] = field(default_factory=list)  # (segment, choice), as added
    tried: list[tuple[int, int]] = field(default_factory=list)

    def mark(self) -> int:
        return len(self.added)

    def restore(self, mark: int) -> None:
        del self.added[mark:]

    def add(self, segment: Segment, following: object, choice: int) -> None:
        i = int(segment.label[1:])
        self.tried.append((i, choice))
        if segment.paths[0].kind == "transit" and choice >= self.choices:
            raise ChoicesExhausted.at(f"s{i}: no more", None)
        if i == self.fails_at and (self.needs[0], self.needs[1]) not in self.added:
            raise InputError.at(f"s{i} fails", None)
        self.added.append((i, choice))


def test_a_later_failure_sends_the_compiler_back_to_the_latest_transit() -> None:
    plan = [seg(0, "c"), seg(1, "t"), seg(2, "c"), seg(3, "c"), seg(4, "c")]
    fake = Fake(fails_at=3, needs=(1, 2))
    add_all(fake, plan)  # type: ignore[arg-type]
    assert fake.added == [(0, 0), (1, 2), (2, 0), (3, 0), (4, 0)]
    assert fake.tried[:4] == [(0, 0), (1, 0), (2, 0), (3, 0)]
    assert (1, 1) in fake.tried and fake.tried.count((3, 0)) == 3


def test_a_transit_out_of_choices_sends_it_further_back() -> None:
    plan = [seg(0, "t"), seg(1, "c"), seg(2, "t"), seg(3, "c")]
    fake = Fake(fails_at=3, needs=(0, 1), choices=2)
    add_all(fake, plan)  # type: ignore[arg-type]
    assert fake.added == [(0, 1), (1, 0), (2, 0), (3, 0)]
    assert (2, 2) in fake.tried  # transit 2 ran out of choices first


def test_out_of_budget_the_furthest_error_is_raised() -> None:
    plan = [seg(0, "t"), seg(1, "c"), seg(2, "c")]
    fake = Fake(fails_at=2, needs=(0, 10 * BUDGET), choices=10 * BUDGET)
    with pytest.raises(InputError, match="s2 fails"):
        add_all(fake, plan)  # type: ignore[arg-type]
    assert len(fake.tried) < 4 * (BUDGET + 1)


def test_without_a_transit_before_the_error_is_raised_at_once() -> None:
    plan = [seg(0, "c"), seg(1, "c")]
    fake = Fake(fails_at=1, needs=(0, 1))
    with pytest.raises(InputError, match="s1 fails"):
        add_all(fake, plan)  # type: ignore[arg-type]
    assert fake.tried == [(0, 0), (1, 0)]


def test_upcoming_stops_at_the_next_transit() -> None:
    plan = [seg(1, "c"), seg(2, "c"), seg(3, "t"), seg(4, "c")]
    assert [s.label for s in upcoming(plan)] == ["s1", "s2"]
    assert len(upcoming([seg(i, "c") for i in range(20)])) == PREVIEW_SEGMENTS


def test_a_transit_takes_the_goal_the_look_ahead_accepts() -> None:
    _, cell, checker = cable_cell()
    q = home(cell)
    goal = {"left": pose(LEFT_READY)}
    ik = arm_ik(cell.arms["left"])
    now = ik.branch(q[cell.slices["left"]])
    default = solve.transit(cell, checker, goal, q)[-1]
    assert ik.branch(default[cell.slices["left"]]) == now  # its own branch first

    def elsewhere(g: np.ndarray) -> bool:
        return ik.branch(g[cell.slices["left"]]) != now

    other = solve.transit(cell, checker, goal, q, elsewhere)[-1]
    assert ik.branch(other[cell.slices["left"]]) != now
    assert np.allclose(cell.arms["left"].fk(other[cell.slices["left"]]), goal["left"], atol=1e-9)
    # nothing accepted: the goals it refused are still tried, last
    fallback = solve.transit(cell, checker, goal, q, lambda g: False)[-1]
    assert np.array_equal(fallback, default)


def test_choices_go_through_the_goals_then_run_out() -> None:
    _, cell, checker = cable_cell()
    q = home(cell)
    goal = {"left": pose(LEFT_READY)}
    ends = []
    for choice in range(20):
        try:
            ends.append(solve.transit(cell, checker, goal, q, None, choice)[-1])
        except NoMoreChoices as e:
            assert "has no other goal configuration to try" in str(e)
            break
    assert 2 <= len(ends) <= 8
    assert len({tuple(np.round(e, 9)) for e in ends}) == len(ends)  # each a different goal


def test_preview_solves_what_follows_from_a_configuration() -> None:
    world, cell, checker = cable_cell()
    holding = Holding(world, checker.scene)
    q = home(cell)
    ready = solve.transit(cell, checker, {"left": pose(LEFT_READY)}, q)[-1]
    lx, ly, lz = LEFT_READY
    reachable = Segment(
        1, "line", (ArmPath("left", "cartesian", line(LEFT_READY, (lx + 0.1, ly, lz))),)
    )
    too_far = Segment(1, "far", (ArmPath("left", "cartesian", line(LEFT_READY, (1.2, ly, lz))),))
    assert preview(cell, holding, [reachable])(ready)
    assert not preview(cell, holding, [reachable, too_far])(ready)
    assert preview(cell, holding, [reachable, Segment(1, "t", (TRANSIT,)), too_far])(ready)


def test_preview_solves_each_segment_with_the_jaw_and_contacts_it_has(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A closed hand's fingers are elsewhere than an open one's: each segment is solved with
    its events applied (as the compiler applies them), and the holding is put back after."""
    world, cell, checker = cable_cell()
    holding = Holding(world, checker.scene)
    q = home(cell)
    ready = solve.transit(cell, checker, {"left": pose(LEFT_READY)}, q)[-1]
    lx, ly, lz = LEFT_READY
    out = ArmPath("left", "cartesian", line(LEFT_READY, (lx + 0.05, ly, lz)))
    back = ArmPath("left", "cartesian", out.poses[::-1])
    close = GripperEvent("left", "grasp")
    grasped = Segment(1, "closing", (back,), before=(close,), contacts=(("left", "cable1"),))
    seen = []
    solved = preview_module._solved

    def spy(cell_: object, checker_: object, seg: Segment, at: np.ndarray) -> np.ndarray:
        assert checker_ is holding.checker
        seen.append((seg.label, dict(holding.state.jaw), holding.state.contacts))
        return solved(cell_, checker_, seg, at)  # type: ignore[arg-type]

    monkeypatch.setattr(preview_module, "_solved", spy)
    before = holding.state
    assert preview(cell, holding, [Segment(1, "open", (out,)), grasped])(ready)
    grasp = cell.arms["left"].fingers.opening("grasp")  # type: ignore[union-attr]
    assert seen == [
        ("open", {}, frozenset()),
        ("closing", {"left": grasp}, frozenset({("left", "cable1")})),
    ]
    assert holding.state == before


def test_a_transit_offers_only_the_branches_the_segments_ahead_require() -> None:
    """A goal on a branch the next segments were not checked on is refused by the compiler
    at the first of them: it is no choice, and choosing it would spend the search's retries."""
    _, cell, checker = cable_cell()
    q = home(cell)
    goal = {"left": pose(LEFT_READY)}
    ik = arm_ik(cell.arms["left"])
    now = ik.branch(q[cell.slices["left"]])
    sols = ik.solve_all(goal["left"], seed=q[cell.slices["left"]])
    free = [s for s in sols if not checker.in_collision(put(cell, q, "left", s))]
    other = next(b for b in (ik.branch(s) for s in free) if b != now)
    ends = []
    for choice in range(8):
        try:
            rows = solve.transit(
                cell,
                checker,
                goal,
                q,
                None,
                choice,
                ahead={"left": Lookahead(None, frozenset({other}))},
            )
        except NoMoreChoices:
            break
        ends.append(ik.branch(rows[-1][cell.slices["left"]]))
    assert ends and set(ends) == {other}
    # farther out, the elbow reaches the goal one way only: half the branches are missing
    lx, ly, lz = LEFT_READY
    far = {"left": pose((lx + 0.4, ly, lz))}
    found = sorted({ik.branch(s) for s in ik.solve_all(far["left"], seed=q[cell.slices["left"]])})
    missing = next(b for b in range(8) if b not in found)
    with pytest.raises(Refused) as e:
        solve.transit(cell, checker, far, q, ahead={"left": Lookahead(None, frozenset({missing}))})
    assert str(e.value) == (
        f"the left arm reaches its transit goal on IK branches {found} only; the segments "
        f"after it were checked on branches [{missing}]"
    )


def put(cell: CellModel, q: np.ndarray, arm: str, joints: np.ndarray) -> np.ndarray:
    out = q.copy()
    out[cell.slices[arm]] = joints
    return out
