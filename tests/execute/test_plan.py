"""The executor on the cable skills' segments: the first two steps of the straight reference
plan (PickCable, PlaceConnector), then the whole four-guide plan."""

from __future__ import annotations

from functools import cache

import numpy as np
import pytest

from cellengine.context import build_context
from cellengine.execute import STRATEGIES, Compiler, home_configuration, program_trajectory
from cellengine.execute.candidates import compile_candidates
from cellengine.execute.checks import KEEP_DISTANCE_TOLERANCE, tcp_distances
from cellengine.info.load import load_plan
from cellengine.motion.collision import CollisionChecker
from cellengine.motion.gate import check_cell_trajectory
from cellengine.motion.robot import CellModel, build_cell_model
from cellengine.motion.scene import build_scene, with_jaw
from cellengine.program import Program
from cellengine.report.replay import jaw_openings
from cellengine.skills.cable_family import FAMILY
from tests.conftest import CELLS
from tests.execute.scenes import states, tcp

PLANS = CELLS / "cable_routing"


@cache
def models() -> tuple[CellModel, CollisionChecker]:
    world = load_plan(PLANS / "plan_straight.yaml").world
    cell = build_cell_model(world)
    return cell, CollisionChecker(build_scene(cell, world))


def compiled(plan: str, strategy: str, steps: int | None = None) -> Program:
    """The plan's steps (the first ``steps``) through the skills' candidates and the
    compiler's search, as `cellengine plan` compiles them."""
    loaded = load_plan(PLANS / plan)
    chosen = loaded.plan.steps if steps is None else loaded.plan.steps[:steps]
    cell, checker = models()
    ctx = build_context(loaded.world)
    c = Compiler(
        loaded.world,
        cell,
        checker,
        home_configuration(cell),
        strategy,  # type: ignore[arg-type]
        clearance=ctx.clearance,
    )
    compile_candidates(c, FAMILY.plan(ctx, chosen))
    return c.program()


@pytest.mark.parametrize("strategy", STRATEGIES)
def test_pick_and_place_of_the_straight_plan(strategy: str) -> None:
    cell, checker = models()
    program = compiled("plan_straight.yaml", strategy, steps=2)
    assert {s.segment.step for s in program.segments} == {0, 1}
    whole = program_trajectory(program)
    assert check_cell_trajectory(whole, cell, checker).ok
    for s in program.segments:
        assert s.report["checks_passed"] is True
        assert all(f == 1.0 for f in s.report["fraction"].values())
        if s.segment.keep_distance is not None and len(s.trajectory) > 1:
            d = tcp_distances(cell, states(s.trajectory, 0.002), s.segment.keep_distance)
            assert np.ptp(d) <= KEEP_DISTANCE_TOLERANCE + 1e-9, s.segment.label
    # the connector-side fingertip reaches the connector guide's keypoint (to 1 mm)
    insert = next(s for s in program.segments if "guide" in s.segment.facts)
    arm = insert.segment.facts["connector_arm"]
    slot = load_plan(PLANS / "plan_straight.yaml").world.pose("routing.connector")[:3, 3]
    fingertip = tcp(cell, arm, states(insert.trajectory, 0.005))[:, :3, 3]
    assert np.linalg.norm(fingertip - slot, axis=1).min() < 1e-3


def all_segments_pass(program: Program, cell: CellModel, checker: CollisionChecker) -> bool:
    """Each segment through the gate again, the fingers at its grippers' openings (the
    program's events so far); one checker for the whole program would hold them at their
    widest, wider than the fingers that move close to a guide."""
    times = np.array([s.trajectory.start_time for s in program.segments])
    openings = jaw_openings(program, cell, times)
    scenes: dict[tuple[tuple[str, float], ...], CollisionChecker] = {}
    for s, jaw in zip(program.segments, openings, strict=True):
        key = tuple(sorted(jaw.items()))
        if key not in scenes:
            scenes[key] = CollisionChecker(with_jaw(checker.scene, jaw))
        if len(s.trajectory) > 1 and not check_cell_trajectory(s.trajectory, cell, scenes[key]).ok:
            return False
    return True


def test_the_four_guide_plan_compiles_with_every_strategy() -> None:
    cell, checker = models()
    durations = {}
    for strategy in STRATEGIES:
        program = compiled("plan_two_turns.yaml", strategy)
        assert {s.segment.step for s in program.segments} == {0, 1, 2}
        assert all_segments_pass(program, cell, checker)
        durations[strategy] = program.duration
    assert all(10.0 < d < 120.0 for d in durations.values())


def test_the_plan_compiles_the_same_twice() -> None:
    a = compiled("plan_straight.yaml", "split", steps=2)
    b = compiled("plan_straight.yaml", "split", steps=2)
    assert [s.segment.label for s in a.segments] == [s.segment.label for s in b.segments]
    for x, y in zip(a.segments, b.segments, strict=True):
        assert np.array_equal(x.trajectory.q, y.trajectory.q)
        assert np.array_equal(x.trajectory.t, y.trajectory.t)
