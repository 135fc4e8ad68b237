"""The harness reference cell (cells/harness/): its plan compiles and passes the independent
check, each group of cables leaves its harness as the pins say, the taping arm changes to the
gun and back through the tool changer (each tool left in its slot, the next locked), no arm
works with a tool the work cannot use, the trunk is taped with the bundle held beside its
guide, and the simulated cell plays it all."""

from __future__ import annotations

from functools import cache

import numpy as np
import pytest

from bench.board_check import check_compiled
from cellengine import geometry as g
from cellengine.drivers.play import play
from cellengine.drivers.record import ToolChanged, Triggered
from cellengine.drivers.registry import make_driver
from cellengine.pipeline import Compiled, compile_plan
from cellengine.program import CompiledSegment
from cellengine.skills import cable_geometry as cg
from tests.conftest import CELLS

PLAN = CELLS / "harness" / "plan.yaml"
UP = np.array([0.0, 0.0, 1.0])


@cache
def compiled() -> Compiled:
    return compile_plan(PLAN)


def _at(c: Compiled, segment: CompiledSegment, t: float, arm: str) -> tuple[np.ndarray, np.ndarray]:
    """T_cell_flange and T_cell_tcp of ``arm`` at ``t`` within ``segment``, with its tool then."""
    tools = c.program.tools_at(t - 1e-9)  # before a change at t: the segment's own tools
    cell = c.context.tooled(tools).cell
    q = cell.split(segment.trajectory.sample(t)[0])[arm]
    return cell.arms[arm].fk_flange(q), cell.arms[arm].fk(q)


def test_the_plan_compiles_and_passes_the_independent_check() -> None:
    c = compiled()
    result = check_compiled(c)
    assert result.ok, result.failures
    assert result.min_arm_distance is not None and result.min_arm_distance >= 0.010 - 1e-9
    steps = [s.skill for s in c.loaded.plan.steps]
    assert steps.count("RouteCable") == 3 and "Tape" in steps


def test_each_group_leaves_its_harness_as_the_pins_say() -> None:
    takes = [
        s.segment.facts
        for s in compiled().program.segments
        if "takes the group" in s.segment.label and ": down" in s.segment.label
    ]
    assert [(f["group"], f["below"]) for f in takes] == [
        (["W1d", "W1e"], ["W1a", "W1b", "W1c"]),  # TOP separated from the rest
        (["W1a", "W1b", "W1c"], []),  # the rest grasped
    ]


def test_each_change_leaves_the_old_tool_in_its_slot_and_locks_the_new() -> None:
    c = compiled()
    program, world = c.program, c.world
    assert [(x.arm, x.tool, x.was) for x in program.changes] == [
        ("right", None, "gripper_right"),
        ("right", "taping_gun", None),
        ("right", None, "taping_gun"),
        ("right", "gripper_right", None),
    ]
    assert program.tools_at(program.duration) == dict(program.tools)
    ends = {s.trajectory.end_time: s for s in program.segments}
    for x in program.changes:
        segment = ends[x.time]
        T_flange, _ = _at(c, segment, x.time, x.arm)
        T_slot = world.slot(x.tool or x.was or "")
        assert np.linalg.norm(T_flange[:3, 3] - T_slot[:3, 3]) <= 1e-6
        assert g.rotation_angle(T_flange, T_slot) <= 1e-6


def test_no_arm_works_with_a_tool_the_work_cannot_use() -> None:
    c = compiled()
    program, tools = c.program, c.world.cell.tools
    for s in program.segments:
        t0, t1 = s.trajectory.start_time, s.trajectory.end_time
        for when, events in ((t0, s.segment.before), (t1, s.segment.after)):
            for e in events:
                carried = program.tools_at(when - 1e-9)[e.arm]
                assert carried is not None and tools[carried].kind == "parallel_gripper", (
                    s.segment.label
                )
        for arm in s.segment.triggers:
            carried = program.tools_at(t0)[arm]
            assert carried is not None and tools[carried].kind == "taping_gun"


def test_the_trunk_is_taped_with_the_bundle_held_beside_its_guide() -> None:
    c = compiled()
    world = c.world
    taping = next(s for s in c.program.segments if s.segment.triggers)
    (taper,) = taping.segment.triggers
    holder = next(a for a in c.cell.arms if a != taper)
    t = taping.trajectory.start_time
    _, T_gun = _at(c, taping, t, taper)
    _, T_hold = _at(c, taping, t, holder)
    a, b = (cg.position(world, f"board.guide{k}") for k in (1, 2))
    assert np.linalg.norm(T_gun[:3, 3] - (a + b) / 2) <= 1e-6
    x = cg.horizontal(cg.keypoint_x(world, "board.guide2"), UP)
    along = float((T_hold[:3, 3] - b) @ x)
    length = cg.GuideDims.of(world, "board.guide2", "").length
    assert 0.0 < abs(along) - length / 2 <= 0.020  # from the guide's face
    assert taping.trajectory.duration == pytest.approx(3.0, abs=1e-6)


def test_the_simulated_cell_plays_it() -> None:
    c = compiled()
    program, world = c.program, c.world
    joints = {n: arm.joint_names for n, arm in c.cell.arms.items()}
    q0 = program.segments[0].trajectory.q[0]
    driver = make_driver(world.cell, joints, objects=world.objects, q0=q0)
    driver.configure()
    driver.activate()
    play(driver, program)
    changed = [(x.arm, x.tool, x.was) for x in driver.recorder.of(ToolChanged)]
    assert changed == [(x.arm, x.tool, x.was) for x in program.changes]
    assert [(x.arm, x.tool) for x in driver.recorder.of(Triggered)] == [("right", "taping_gun")]
    assert driver.tools == dict(program.tools)
    assert np.abs(driver.joint_state() - program.segments[-1].trajectory.q[-1]).max() <= 1e-6


@cache
def separated() -> Compiled:
    return compile_plan(CELLS / "harness" / "plan_separation.yaml")


def test_a_bottom_branch_first_lays_the_others_aside_in_the_separation_guide() -> None:
    """plan_separation.yaml: TOP's cables (the top rows) are laid aside in board.sep, BOT is
    grasped below where they were and routed, then TOP is taken back out of board.sep and
    routed; each group through each slot of its route (the independent check)."""
    c = separated()
    result = check_compiled(c)
    assert result.ok, result.failures
    assert result.min_arm_distance is not None and result.min_arm_distance >= 0.010 - 1e-9
    program, world = c.program, c.world
    labels = [s.segment.label for s in program.segments]
    laid = next(s for s in program.segments if s.segment.label.endswith("into its slot"))
    take = next(s.segment.facts for s in program.segments if "aside" in s.segment.facts)
    assert (take["aside"], take["guide"]) == (["W1d", "W1e"], "board.sep")
    # the cables laid aside run from the connector guide's exit to the fingertips through
    # the separation guide's slot: within half its gap, along its x within 15 deg
    (arm,) = laid.segment.arms()
    _, T_tip = _at(c, laid, laid.trajectory.end_time, arm)
    slot = world.pose("board.sep")
    gap = world.dimensions("board.sep")["gap"]
    connector_exit = cg.position(world, "board.connector.exit")
    a, b = connector_exit, T_tip[:3, 3]
    d = b - a
    s_ = float(np.clip((slot[:3, 3] - a) @ d / (d @ d), 0.0, 1.0))
    assert np.linalg.norm(slot[:3, 3] - (a + s_ * d)) <= gap / 2
    angle = np.degrees(np.arccos(abs(float(d @ slot[:3, 0])) / np.linalg.norm(d)))
    assert angle <= 15.0
    # BOT grasped as all that is left at the connector, then TOP taken back from board.sep
    grasp = next(s.segment.facts for s in program.segments if "group" in s.segment.facts)
    assert (grasp["group"], grasp["below"]) == (["W1a", "W1b", "W1c"], [])
    back = [k for k, label in enumerate(labels) if "takes it back from board.sep" in label]
    first_bot = labels.index(next(x for x in labels if x.startswith("RouteCable board.guide4")))
    assert back and back[0] > first_bot
