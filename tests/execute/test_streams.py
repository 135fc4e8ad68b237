"""Issue 16: both lab robots at once. On every lab plan and both lab cells, the program the
streams make respects the plan's precedence, never has both TCPs in a shared zone outside a
cooperation (sampled every 10 ms), keeps the robots apart by the cell's clearance, and is
shorter than the robots one after another; overlaps the rules forbid are refused."""

from __future__ import annotations

import itertools
from dataclasses import replace
from functools import cache
from typing import Any
from unittest import mock

import numpy as np
import pytest

import cellengine.pipeline as pipeline
from cellengine.concurrency import Overlap
from cellengine.execute.held import Holding
from cellengine.execute.streams import Streams
from cellengine.pipeline import Compiled, compile_plan
from cellengine.program import Program, Scheduled
from tests.conftest import CELLS

LAB = CELLS / "lab_bench"
CELL_FILES = {"cartesian": LAB / "cell.yaml", "ur": LAB / "cell_ur.yaml"}
PLANS = ("plan_weigh_handover", "plan_relocate", "plan_pour_heavier", "plan_cluttered")
DT = 0.01


@cache
def _compiled(plan: str, cell: str, execution: str | None = None) -> Compiled:
    return compile_plan(LAB / f"{plan}.yaml", strategy=execution, cell=CELL_FILES[cell])


@cache
def _before_streams(plan: str, cell: str) -> tuple[Program, Overlap, tuple[Any, ...]]:
    """The program compiled one segment after another, the family's rules, and what the
    streams are made with (world, cell model, scene, clearance)."""
    seen: dict[str, Any] = {}
    real = pipeline.overlapped

    def grab(program: Program, rules: Overlap, *rest: Any) -> Any:
        seen.update(program=program, rules=rules, rest=rest)
        return real(program, rules, *rest)

    with mock.patch.object(pipeline, "overlapped", grab):
        compile_plan(LAB / f"{plan}.yaml", cell=CELL_FILES[cell])
    return seen["program"], seen["rules"], seen["rest"]


def _placed(plan: str, cell: str, rules: Overlap | None = None) -> tuple[Scheduled, ...]:
    program, own, (world, model, scene, clearance) = _before_streams(plan, cell)
    q0 = np.array(program.segments[0].trajectory.q[0])
    holding = Holding(world, scene)
    streams = Streams(program.segments, rules or own, model, holding, q0, clearance)
    return streams.place_all()


def _track(c: Compiled) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """Times every DT over the program, the cell's q then, and each robot's TCP."""
    t = np.append(np.arange(0.0, c.program.duration, DT), c.program.duration)
    starts = np.array([s.trajectory.start_time for s in c.program.segments])
    k = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(starts) - 1)
    q = np.vstack([c.program.segments[j].trajectory.sample(t[k == j])[0] for j in np.unique(k)])
    tcp = {
        name: np.array([arm.fk(row[c.cell.slices[name]])[:3, 3] for row in q])
        for name, arm in c.cell.arms.items()
    }
    return t, q, tcp


def _presence(inside: np.ndarray, k: int) -> tuple[int, int]:
    """The samples of the run of True in ``inside`` around sample ``k``."""
    lo = k
    while lo > 0 and inside[lo - 1]:
        lo -= 1
    hi = k
    while hi + 1 < len(inside) and inside[hi + 1]:
        hi += 1
    return lo, hi


@pytest.mark.parametrize("plan", PLANS)
@pytest.mark.parametrize("cell", sorted(CELL_FILES))
def test_the_streams_keep_order_zones_and_clearance(plan: str, cell: str) -> None:
    c = _compiled(plan, cell)
    streams = c.program.streams
    assert streams and c.report["streams"]["refused"] is None
    # precedence: no step starts before the steps in its `after` end
    steps = c.loaded.plan.steps
    index = {s.id: i for i, s in enumerate(steps)}
    span = {
        i: (
            min(s.start for s in streams if s.step == i),
            max(s.end for s in streams if s.step == i),
        )
        for i in {s.step for s in streams}
    }
    for i, step in enumerate(steps):
        for dep in step.after:
            assert span[index[dep]][1] <= span[i][0] + 1e-9, (step.id, dep)
    # each robot's own segments one after another, in the order they were compiled
    for arm in c.cell.arms:
        mine = [s for s in streams if arm in s.arms]
        assert all(a.end <= b.start + 1e-9 for a, b in itertools.pairwise(mine))
        assert [s.index for s in mine] == sorted(s.index for s in mine)
    # never both TCPs in a shared zone, but for two robots that came in for one cooperation
    t, q, tcp = _track(c)
    mission = c.mission or []
    coop = [e for e in mission if e["inserted"] == "cooperation"]
    for name, zone in c.world.cell.zones.items():
        if len(zone.robots) < 2:
            continue
        inside = {r: np.array([zone.contains(p) for p in tcp[r]]) for r in zone.robots}
        both = np.logical_and.reduce(list(inside.values()))
        for k in np.flatnonzero(both):
            runs = {r: _presence(inside[r], int(k)) for r in zone.robots}
            assert any(
                all(
                    t[lo] <= e["end"] + 1e-6 and e["start"] <= t[hi] + 1e-6
                    for lo, hi in runs.values()
                )
                for e in coop
            ), (name, float(t[k]))
    # the robots apart by the cell's clearance all along (what they hold aside)
    d = min(c.context.checker.distance(row, ("robot1", "robot2"))[0] for row in q)
    assert d >= c.context.clearance - 1e-9
    # and never longer than its own segments one after another (bench_lab compares with
    # --execution sequential on every plan; experiment 3 below)
    alone = c.report["streams"]["one_after_another_s"]
    assert c.program.duration <= alone + 1e-6


def test_experiment_3_is_a_third_shorter_on_the_cartesian_robots() -> None:
    at_once = _compiled("plan_pour_heavier", "cartesian").program.duration
    alone = _compiled("plan_pour_heavier", "cartesian", "sequential").program.duration
    assert at_once <= 0.7 * alone


@pytest.mark.parametrize("cell", sorted(CELL_FILES))
def test_both_robots_next_parts_in_the_shared_zone_are_refused(cell: str) -> None:
    """plan_relocate: each robot moves a vial within the shared zone. The second robot's
    first move could start at once by its order; the shared zone makes it wait, and says
    so. Without the zone rule the same move starts earlier: the zone is what refused."""
    placed = _placed("plan_relocate", cell)
    first = {arm: next(s for s in placed if arm in s.arms) for arm in ("robot1", "robot2")}
    later = max(first.values(), key=lambda s: s.start)
    assert later.ready == 0.0 and later.start > 1.0
    assert later.why is not None and "shared zone 'shared'" in later.why
    _, rules, _ = _before_streams("plan_relocate", cell)
    free = _placed("plan_relocate", cell, replace(rules, zones=()))
    assert free[later.index].start < later.start - 1.0


@pytest.mark.parametrize("cell", sorted(CELL_FILES))
def test_a_handover_taker_comes_in_after_the_giver_has_let_go_and_left(cell: str) -> None:
    c = _compiled("plan_weigh_handover", cell)
    streams = c.program.streams
    # robot2 puts vial3 down at the handover place, robot1 takes it there
    put = next(s for s in streams if s.arms == ("robot2",) and "put down vial3" in s.label)
    taken = next(s for s in streams if s.arms == ("robot1",) and "grasp vial3" in s.label)
    assert put.end <= taken.start + 1e-9
    t, _, tcp = _track(c)
    shared = c.world.cell.zones["shared"]
    inside = {r: np.array([shared.contains(p) for p in tcp[r]]) for r in ("robot1", "robot2")}
    came = t[np.argmax(inside["robot1"] & (t >= put.start))]
    assert came >= put.end
    assert not (inside["robot1"] & inside["robot2"]).any()


def test_sequential_is_the_program_of_one_robot_after_another() -> None:
    """--execution sequential: no streams, each robot back to its rest after its work."""
    c = _compiled("plan_pour_heavier", "cartesian", "sequential")
    assert not c.program.streams and "streams" not in c.report
    rests = [s for s in c.program.segments if "back to its rest" in s.segment.label]
    assert len(rests) == 6


def test_streams_json_lanes_and_waits() -> None:
    c = _compiled("plan_relocate", "cartesian")
    out = c.report["streams"]
    assert out["at_once"] and out["duration_s"] == pytest.approx(c.program.duration, abs=1e-9)
    assert set(out["lanes"]) == {"robot1", "robot2"}
    assert out["one_after_another_s"] > out["duration_s"]
    (wait,) = [w for w in out["waits"] if w["wait_s"] > 1.0]
    assert "shared zone" in wait["why"]


@pytest.mark.parametrize("cell", sorted(CELL_FILES))
def test_a_handover_taker_that_would_come_before_the_giver_let_go_is_refused(cell: str) -> None:
    """plan_weigh_handover with the mission's order taken away (each segment a task of its
    own): robot1's way to the handover could start at once. The shared zone refuses it
    until robot2 has put the vial down and gone, and its grasp waits for the vial."""
    program, rules, (world, model, scene, clearance) = _before_streams("plan_weigh_handover", cell)
    q0 = np.array(program.segments[0].trajectory.q[0])
    streams = Streams(program.segments, rules, model, Holding(world, scene), q0, clearance)
    streams.parts = [None if p is None else (f"own{i}", 0) for i, p in enumerate(streams.parts)]
    placed = streams.place_all()
    put = next(s for s in placed if s.arms == ("robot2",) and "put down vial3" in s.label)
    back = next(s for s in placed if s.arms == ("robot2",) and "back to its rest" in s.label)
    come = next(s for s in placed if s.arms == ("robot1",))
    grasp = next(s for s in placed if s.arms == ("robot1",) and "grasp vial3" in s.label)
    assert come.ready == 0.0 and come.start >= put.end
    assert come.why is not None and "shared zone 'shared'" in come.why
    assert come.start >= back.start - 1e-9 and grasp.start >= put.end
