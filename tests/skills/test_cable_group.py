"""RouteCable of a harness's branches: the group taken at the connector (separated from the
cables below it, or the rest grasped), routed as one thicker cable, each through its slots."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from bench.board_check import check_compiled
from cellengine.errors import InputError
from cellengine.info.load import load_plan
from cellengine.pipeline import compile_plan
from cellengine.report.replay import cables

CELL = Path(__file__).resolve().parents[2] / "cells" / "cable_routing"
HARNESS = """
harnesses:
  WH1:
    connector: {type: VGA, length: 35, width: 31, height: 16}
    cables:
      CA1: {length: 650, diameter: 2.5, color: red, pin: [0, 0]}
      CA2: {length: 650, diameter: 2.5, color: blue, pin: [1, 0]}
      CA3: {length: 650, diameter: 2.5, color: black, pin: [2, 0]}
    branches:
      TOP: {cables: [CA3, CA2]}
      BOT: {cables: [CA1]}
"""
HEAD = """cell: cell.yaml
objects: objects.yaml
steps:
  - {skill: PickCable, cable: WH1, from: [holder.comb_a, holder.comb_b]}
  - {skill: PlaceConnector, cable: WH1, guide: routing.connector}
"""


def _cell(tmp_path: Path, routes: str) -> Path:
    cell = tmp_path / "cell"
    shutil.copytree(CELL, cell)
    text = (cell / "cell.yaml").read_text()
    # a gripper that holds a 2.5 mm cable (the reference one grasps at 4 mm, for 6 mm)
    (cell / "cell.yaml").write_text(text.replace("slide: 7, grasp: 4", "slide: 8, grasp: 2"))
    with (cell / "objects.yaml").open("a") as f:
        f.write(HARNESS)
    (cell / "plan.yaml").write_text(HEAD + routes)
    return cell / "plan.yaml"


def test_the_top_branch_is_separated_then_the_rest_grasped(tmp_path: Path) -> None:
    plan = _cell(
        tmp_path,
        # the branches share guide1 and guide2; BOT turns off to guide4 there
        "  - {skill: RouteCable, cable: TOP, guides: [routing.guide1, routing.guide2, "
        "routing.guide3]}\n"
        "  - {skill: RouteCable, cable: BOT, guides: [routing.guide1, routing.guide2, "
        "routing.guide4]}\n",
    )
    compiled = compile_plan(plan)
    downs = [s.segment for s in compiled.program.segments if "takes the group" in s.segment.label]
    separating, grasping = (s for s in downs if ": down" in s.label)  # each take's way down
    assert separating.label.endswith("down, separating it") and grasping.label.endswith("down")
    # the fingertips (the TCP) above every cable left below and at or below each group
    # cable's middle, in the column of the pins' rows (2.5 mm each, centred on the hold)
    column = {"CA1": (-3.75e-3, -1.25e-3), "CA2": (-1.25e-3, 1.25e-3), "CA3": (1.25e-3, 3.75e-3)}
    facts = separating.facts
    assert (facts["group"], facts["below"]) == (["CA2", "CA3"], ["CA1"])
    for name, (bottom, top) in column.items():
        assert facts["column"][name] == pytest.approx([bottom, top], abs=1e-9)
    tip = facts["tcp_height"]
    assert all(column[n][1] < tip for n in facts["below"])
    assert all((column[n][0] + column[n][1]) / 2 >= tip - 1e-9 for n in facts["group"])
    assert grasping.facts["below"] == [] and grasping.facts["group"] == ["CA1"]
    # each group held by both hands through each of its slots, in plan order
    result = check_compiled(compiled)
    assert result.ok, result.failures
    held = [e.event.holds for e in compiled.program.events if e.event.holds]
    assert held.index("TOP") < held.index("BOT")
    # the page draws each group from the connector through its slots, a line per cable in
    # its objects.yaml colour
    drawn = {c["name"]: c for c in cables(compiled.program, compiled.world)}
    assert drawn["TOP"]["members"] == [
        {"name": "CA2", "color": "blue"},
        {"name": "CA3", "color": "black"},
    ]
    connector = drawn["WH1"]["anchors"][0]
    assert connector["guide"] == "routing.connector"
    route = ["routing.connector", "routing.guide1", "routing.guide2"]
    assert [a["guide"] for a in drawn["TOP"]["anchors"]] == [*route, "routing.guide3"]
    assert [a["guide"] for a in drawn["BOT"]["anchors"]] == [*route, "routing.guide4"]
    # the arms kept the cell's clearance throughout
    assert result.min_arm_distance is not None and result.min_arm_distance >= 0.010 - 1e-9


def test_a_bottom_branch_first_needs_a_separation_guide(tmp_path: Path) -> None:
    plan = _cell(tmp_path, "  - {skill: RouteCable, cable: BOT, guides: [routing.guide1]}\n")
    with pytest.raises(InputError) as e:
        load_plan(plan)  # before any motion: `validate` says so too
    assert e.value.problems[0].message == (
        "steps[2].cable: BOT's cables (CA1) leave the connector below CA2, CA3, still to be "
        "routed: route TOP before BOT, or lay those aside in a separation guide first "
        "(separate_into: <guide>, REMODEL's J<n>S)"
    )


def test_a_branch_is_not_picked_or_placed_alone(tmp_path: Path) -> None:
    plan = _cell(tmp_path, "")
    plan.write_text(
        plan.read_text().replace("PlaceConnector, cable: WH1", "PlaceConnector, cable: TOP")
    )
    with pytest.raises(InputError) as e:
        load_plan(plan)  # before any motion: `validate` says so too
    assert [p.message for p in e.value.problems] == [
        "steps[1].cable: TOP is a branch of harness WH1: PlaceConnector takes the whole "
        "harness (cable: WH1)"
    ]


def test_a_slot_must_take_the_group_beside_what_lies_in_it(tmp_path: Path) -> None:
    plan = _cell(
        tmp_path,
        "  - {skill: RouteCable, cable: TOP, guides: [routing.guide1, routing.guide2]}\n"
        "  - {skill: RouteCable, cable: BOT, guides: [routing.guide1]}\n",
    )
    cell = plan.parent / "cell.yaml"  # cables 4.8 mm thick: two fit a 10 mm slot, three not
    cell.write_text(cell.read_text().replace("slide: 8, grasp: 2", "slide: 12, grasp: 2"))
    objects = plan.parent / "objects.yaml"
    objects.write_text(objects.read_text().replace("diameter: 2.5", "diameter: 4.8"))
    with pytest.raises(InputError) as e:
        load_plan(plan)  # before any motion: `validate` says so too
    assert e.value.problems[0].message == (
        "steps[3].guides[0]: guide 'routing.guide1' has a 10.0 mm slot (its gap); CA2, CA3 "
        "lie in it already, and with BOT (CA1) the bundle is 10.3 mm thick: it does not fit"
    )


def test_the_whole_harness_after_a_branch_is_refused(tmp_path: Path) -> None:
    plan = _cell(
        tmp_path,
        "  - {skill: RouteCable, cable: TOP, guides: [routing.guide1]}\n"
        "  - {skill: RouteCable, cable: WH1, guides: [routing.guide1]}\n",
    )
    with pytest.raises(InputError) as e:
        load_plan(plan)  # before any motion: `validate` says so too
    assert e.value.problems[0].message == (
        "steps[3].cable: its branch TOP is routed already; route the others by name (BOT)"
    )


def test_a_branch_before_its_connector_is_placed(tmp_path: Path) -> None:
    plan = _cell(tmp_path, "  - {skill: RouteCable, cable: TOP, guides: [routing.guide1]}\n")
    plan.write_text(plan.read_text().replace("  - {skill: PlaceConnector", "  # - {skill: PlaceC"))
    with pytest.raises(InputError) as e:
        load_plan(plan)
    assert [p.message for p in e.value.problems] == [
        "steps[1].cable: TOP is a branch of harness WH1, whose connector is not placed before "
        "it: plan PlaceConnector (cable: WH1) first"
    ]
    assert e.value.problems[0].line == 6  # the RouteCable step's line
