"""The cell page (`cellengine show CELL --html`): the report page of a program with no motion
(the robots at home, the platforms, elements and obstacles), its replay carrying ``reach``:
each keypoint's arms that reach it (cellengine/reach.py), which assets/reach.js draws as
labelled keypoints coloured by it, with a table of them."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from cellengine.motion.robot import CellModel
from cellengine.program import Program
from cellengine.report.data import report_data
from cellengine.report.page import render_page
from cellengine.report.replay import replay_data
from cellengine.world import World


def cell_page_data(
    world: World, cell: CellModel, reach: Mapping[str, Sequence[str]]
) -> tuple[dict[str, Any], dict[str, Any]]:
    """report.json's and the replay's content of the page: nothing moves."""
    program = Program(cell.joint_names, (), ())
    report = report_data(program, cell, extra={"cell": str(world.cell_file)})
    replay = replay_data(program, cell, world)
    replay["reach"] = {name: list(reach.get(name, ())) for name in world.keypoints()}
    return report, replay


def cell_page(world: World, cell: CellModel, reach: Mapping[str, Sequence[str]]) -> str:
    """The page's HTML."""
    report, replay = cell_page_data(world, cell, reach)
    return render_page(report, replay, f"cellengine show: {world.cell.name}")
