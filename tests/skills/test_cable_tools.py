"""ChangeTool: an arm leaves its tool seated in its changer slot and takes another; the
compiler plans on the new tool from then on; a cable step on an arm without a gripper gets
its change first."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from cellengine import geometry as g
from cellengine.errors import InputError
from cellengine.pipeline import Compiled, compile_plan, trajectory_json
from cellengine.program import Program
from cellengine.runner.cycles import check_cycles
from tests.skills.atc import atc_cell

GUN = "  - {skill: ChangeTool, arm: left, tool: taping_gun}\n"
BACK = "  - {skill: ChangeTool, arm: left, tool: gripper_left}\n"
POSITION, ANGLE = 1e-6, 1e-6  # m, rad: where a Cartesian path ends (its IK's tolerance)


def _flange(compiled: Compiled, t: float) -> np.ndarray:
    """T_cell_flange of the left arm at program time ``t``."""
    program: Program = compiled.program
    k = next(i for i, s in enumerate(program.segments) if s.trajectory.end_time >= t - 1e-9)
    q = compiled.cell.split(program.segments[k].trajectory.sample(t)[0])["left"]
    return compiled.cell.arms["left"].fk_flange(q)


def _at(T: np.ndarray, T_want: np.ndarray) -> bool:
    return bool(
        np.linalg.norm(T[:3, 3] - T_want[:3, 3]) <= POSITION
        and g.rotation_angle(T, T_want) <= ANGLE
    )


def test_a_change_seats_the_old_tool_in_its_slot_and_locks_the_new(tmp_path: Path) -> None:
    compiled = compile_plan(atc_cell(tmp_path, GUN + BACK, head="return_home: true\n"))
    program, world = compiled.program, compiled.world
    assert [(c.arm, c.tool, c.was) for c in program.changes] == [
        ("left", None, "gripper_left"),
        ("left", "taping_gun", None),
        ("left", None, "taping_gun"),
        ("left", "gripper_left", None),
    ]
    assert program.tools == {"left": "gripper_left", "right": "cable_gripper"}
    # each unlock with the old tool seated in its slot, each lock on the new one in its own
    for c in program.changes:
        assert _at(_flange(compiled, c.time), world.slot(c.tool or c.was or ""))
    # the tool out of its slot along its exit: the TCP is the new tool's from the lock on
    after_gun = next(
        s for s in program.segments if s.segment.label.endswith("taping_gun out of its slot")
    )
    ctx = compiled.context.tooled({"left": "taping_gun"})
    q_end = ctx.cell.split(after_gun.trajectory.q[-1])["left"]
    exit_ = g.transform(np.eye(3), (0.07, 0.0, -0.1))
    tcp = world.cell.tools["taping_gun"].tcp.matrix()
    assert _at(ctx.cell.arms["left"].fk(q_end), world.slot("taping_gun") @ exit_ @ tcp)
    # trajectory.json says so, after the gripper events of the same instant
    events = trajectory_json(program)["events"]
    tools = [(e["arm"], e["tool"], e["was"]) for e in events if e["kind"] == "tool"]
    assert tools == [(c.arm, c.tool, c.was) for c in program.changes]
    assert [e["time_from_start"] for e in events] == sorted(e["time_from_start"] for e in events)
    # the plan ends with the tools it started with: it may run in cycles
    check_cycles(compiled, 2)


def test_the_tool_left_in_its_slot_is_an_obstacle(tmp_path: Path) -> None:
    compiled = compile_plan(atc_cell(tmp_path, GUN))
    statics = {s.name for s in compiled.context.scene.statics}
    assert "taping_gun@slot" in statics and "gripper_left@slot" not in statics
    gun = compiled.context.tooled({"left": "taping_gun"})
    statics = {s.name for s in gun.scene.statics}
    assert "gripper_left@slot" in statics and "taping_gun@slot" not in statics
    assert gun.cell.arms["left"].fingers is None  # the gun has none
    # a plan that ends on other tools than it starts with cannot run in cycles
    with pytest.raises(InputError) as e:
        check_cycles(compiled, 2)
    assert "the left arm carrying 'taping_gun', and starts with it carrying 'gripper_left'" in (
        str(e.value)
    )


def test_a_cable_step_gets_its_gripper_back_first(tmp_path: Path) -> None:
    steps = GUN + "  - {skill: PickCable, cable: cable1, from: [holder.comb_a, holder.comb_b]}\n"
    compiled = compile_plan(atc_cell(tmp_path, steps))
    program = compiled.program
    labels = [s.segment.label for s in program.segments]
    inserted = [k for k, label in enumerate(labels) if "(for PickCable)" in label]
    assert inserted and all(program.segments[k].segment.step == 1 for k in inserted)
    pick = next(s for s in program.segments if s.segment.label.startswith("PickCable"))
    assert program.tools_at(pick.trajectory.start_time)["left"] == "gripper_left"
    assert any(e.event.arm == "left" and e.event.holds == "cable1" for e in program.events)


def test_a_run_on_the_simulated_cell_journals_each_change(tmp_path: Path) -> None:
    from cellengine.cli import main

    plan = atc_cell(tmp_path, GUN + BACK)
    out = tmp_path / "run"
    assert main(["run", str(plan), "--out", str(out), "-q"]) == 0
    lines = [json.loads(x) for x in (out / "journal.jsonl").read_text().splitlines()]
    changes = [(e["arm"], e["tool"], e["was"]) for e in lines if e["entry"] == "tool"]
    assert changes == [
        ("left", None, "gripper_left"),
        ("left", "taping_gun", None),
        ("left", None, "taping_gun"),
        ("left", "gripper_left", None),
    ]
    # each change journaled before its segment's end is
    kinds = [(e["entry"], e.get("segment")) for e in lines if e["entry"] in ("tool", "finished")]
    for k, (kind, segment) in enumerate(kinds):
        if kind == "tool":
            assert kinds[k + 1] in (("finished", segment), ("tool", segment))


@pytest.mark.parametrize(
    ("steps", "edit", "message"),
    [
        (
            "  - {skill: ChangeTool, tool: taping_gun}\n",
            ("", ""),
            "plan.yaml:4:5: steps[0]: arm: name the arm that changes its tool (a robot of the "
            "cell)",
        ),
        (
            "  - {skill: ChangeTool, arm: left, tool: cable_gripper}\n",
            ("", ""),
            "plan.yaml:4:42: steps[0].tool: tool 'cable_gripper' has no slot in the tool "
            "changer (tools.cable_gripper.slot)",
        ),
        (
            GUN,
            ("tool: cable_gripper", "tool: gripper_left"),
            "cell.yaml:16:11: robots.right.tool: 'gripper_left' has a slot in the tool changer, "
            "so it is one tool, and robots.left carries it: give each robot a tool of its own",
        ),
    ],
)
def test_bad_tool_changes(tmp_path: Path, steps: str, edit: tuple[str, str], message: str) -> None:
    with pytest.raises(InputError) as e:
        compile_plan(atc_cell(tmp_path, steps, edit))
    assert message in str(e.value)


def test_a_driver_without_the_changers_output_refuses_before_anything_moves(
    tmp_path: Path,
) -> None:
    from cellengine.drivers.fault import DriverRefused
    from cellengine.drivers.registry import make_driver

    driver_spec = "driver: {kind: ur_rtde, arms: {left: 127.0.0.2, right: 127.0.0.3}}"
    compiled = compile_plan(atc_cell(tmp_path, GUN, ("driver: {kind: sim}", driver_spec)))
    joints = {n: arm.joint_names for n, arm in compiled.cell.arms.items()}
    driver = make_driver(compiled.world.cell, joints, objects=compiled.world.objects)
    with pytest.raises(DriverRefused) as e:
        driver.check_program(compiled.program)
    assert str(e.value) == (
        "ur_rtde driver: arm 'left' changes tools, and the cell's ur_rtde driver names no tool "
        "changer output (driver.changer_release)"
    )
    assert driver.recorder.entries == []  # nothing sent, not even connected
