"""Tape: the bundle held beside the hold guide while the taping gun, taken from the tool
changer, tapes it at the midpoint of two guides of its route for the gun's dwell."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from cellengine.drivers.play import play
from cellengine.drivers.record import Triggered
from cellengine.drivers.registry import make_driver
from cellengine.errors import InputError
from cellengine.info.load import load_plan
from cellengine.pipeline import compile_plan, trajectory_json
from cellengine.skills import cable_geometry as cg
from tests.skills.atc import atc_cell

ROUTE = (
    "  - {skill: PickCable, cable: cable1, from: [holder.comb_a, holder.comb_b]}\n"
    "  - {skill: PlaceConnector, cable: cable1, guide: routing.connector}\n"
    "  - {skill: RouteCable, cable: cable1, guides: [routing.guide1, routing.guide2, "
    "routing.guide3]}\n"
)
TAPE = "  - {skill: Tape, cable: cable1, between: [routing.guide2, routing.guide3], hold: %s}\n"


def test_the_gun_tapes_at_the_midpoint_with_the_bundle_held_beside_the_guide(
    tmp_path: Path,
) -> None:
    compiled = compile_plan(atc_cell(tmp_path, ROUTE + TAPE % "routing.guide2"))
    program, world = compiled.program, compiled.world
    taping = next(s for s in program.segments if s.segment.triggers)
    t0, t1 = taping.trajectory.start_time, taping.trajectory.end_time
    # the gun's dwell, both arms standing still
    assert taping.segment.triggers == ("left",)
    assert t1 - t0 == pytest.approx(3.0, abs=1e-6)
    assert np.abs(taping.trajectory.q - taping.trajectory.q[0]).max() <= 1e-9
    # the left arm carries the gun (changed to from the tool changer), the right a gripper
    tools = program.tools_at(t0)
    assert tools == {"left": "taping_gun", "right": "cable_gripper"}
    ctx = compiled.context.tooled(tools)
    q = ctx.cell.split(taping.trajectory.q[0])
    T_gun, T_hold = ctx.cell.arms["left"].fk(q["left"]), ctx.cell.arms["right"].fk(q["right"])
    # the gun's TCP at the midpoint of the two slots
    a, b = (cg.position(world, f"routing.guide{k}") for k in (2, 3))
    assert np.linalg.norm(T_gun[:3, 3] - (a + b) / 2) <= 1e-6
    # the right hand holds the cable, its fingertips on the route, within 20 mm of guide2's face
    held = [e for e in program.events if e.time <= t0 and e.event.arm == "right"]
    assert held[-1].event.holds == "cable1"
    x = cg.horizontal(cg.keypoint_x(world, "routing.guide2"), np.array([0.0, 0.0, 1.0]))
    offset = T_hold[:3, 3] - a
    assert np.linalg.norm(offset - (offset @ x) * x) <= 1e-6  # on the guide's line
    length = cg.GuideDims.of(world, "routing.guide2", "").length
    assert 0.0 < abs(offset @ x) - length / 2 <= 0.020
    assert taping.segment.facts["hold_guide"] == "routing.guide2"
    # trajectory.json: the gun's work, the tool at it, its duration
    triggers = [e for e in trajectory_json(program)["events"] if e["kind"] == "trigger"]
    assert triggers == [
        {
            "time_from_start": t0,
            "arm": "left",
            "kind": "trigger",
            "tool": "taping_gun",
            "duration": pytest.approx(3.0, abs=1e-6),
        }
    ]
    # the simulated cell plays it and records the gun's work over those 3 s
    joints = {n: arm.joint_names for n, arm in compiled.cell.arms.items()}
    driver = make_driver(
        world.cell, joints, objects=world.objects, q0=program.segments[0].trajectory.q[0]
    )
    driver.configure()
    driver.activate()
    play(driver, program)
    assert [(r.arm, r.tool, r.start, r.end) for r in driver.recorder.of(Triggered)] == [
        ("left", "taping_gun", t0, t1)
    ]
    assert json.dumps(driver.recorder.to_json(every=1000))  # the record is JSON


@pytest.mark.parametrize(
    ("steps", "message"),
    [
        (
            TAPE % "routing.guide2",
            "plan.yaml:4:26: steps[0].cable: cable1 is not routed before this step: tape it "
            "after the RouteCable that lays it",
        ),
        (
            ROUTE + "  - {skill: Tape, cable: cable1, between: [routing.guide1, routing.guide3], "
            "hold: routing.guide2}\n",
            "plan.yaml:7:43: steps[3].between: cable1 does not run straight from "
            "routing.guide1.slot to routing.guide3.slot: its route is routing.connector.slot, "
            "routing.guide1.slot, routing.guide2.slot, routing.guide3.slot (tape between two "
            "guides next to each other on it)",
        ),
        (
            ROUTE + TAPE % "routing.guide4",
            "plan.yaml:7:83: steps[3].hold: cable1 does not lie in routing.guide4.slot: its "
            "route is routing.connector.slot, routing.guide1.slot, routing.guide2.slot, "
            "routing.guide3.slot (hold it beside a guide it lies in)",
        ),
    ],
)
def test_a_tape_off_the_cables_route_is_refused_before_any_motion(
    tmp_path: Path, steps: str, message: str
) -> None:
    with pytest.raises(InputError) as e:
        load_plan(atc_cell(tmp_path, steps))
    assert message in str(e.value)
