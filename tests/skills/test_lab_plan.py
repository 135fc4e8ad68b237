"""A lab plan the allocator cannot do is an error at the line of the step concerned, its
lengths in the cell file's unit."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from cellengine.cli import main
from tests.conftest import CELLS

PLAN = """\
cell: cell.yaml
objects: objects.yaml
steps:
  - id: weigh
    skill: Weigh
    object: vial3
  - id: move
    skill: Place
    object: vial1
    to: bench.free3.place
    arm: robot2
"""


def test_an_allocation_error_is_at_its_step_in_the_cell_s_unit(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """vial1 stands in robot1's private rack (bench.rack1.slot1, 6 mm up: cell.yaml is in mm);
    the second step gives the move to robot2."""
    cell = tmp_path / "lab"
    shutil.copytree(CELLS / "lab_bench", cell)
    plan = cell / "plan_bad.yaml"
    plan.write_text(PLAN)
    assert main(["validate", str(plan)]) == 1
    out = capsys.readouterr()
    assert f"{out.out}{out.err}".splitlines()[0] == (
        f"{plan}:7:5: task 'move': primitive 1 (pick) at (300, 150, 6) mm: robot2 cannot reach it"
    )
