"""DESIGN section 3 is a contract: its example files must validate unchanged.

The examples are read from DESIGN.md itself, set beside the reference cell's platform files
and the REMODEL sample (as board/), and validated.
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

from cellengine.cli import main
from tests.conftest import CELLS, REMODEL, SHARED

DESIGN = SHARED / "DESIGN.md"
U_GUIDES = ("", "_001", "_002", "_003", "_004", "_005", "_006")  # the reference X3D's DEFs


def example(heading: str) -> str:
    text = DESIGN.read_text()
    section = text[text.index(heading) :]
    return re.search(r"```yaml\n(.*?)```", section, re.S).group(1)  # type: ignore[union-attr]


@pytest.fixture
def design_cell(tmp_path: Path) -> Path:
    for platform in ("holder", "routing"):
        shutil.copytree(CELLS / "cable_routing" / platform, tmp_path / platform)
    # DESIGN's plan places the connector into routing.guide1 and routes through guide2 and
    # guide3 after it: the reference connector guide and the two U guides after it, named so
    (tmp_path / "routing" / "map.csv").write_text(
        "cad_name,model,name\nConn_Holder,connector_guide,guide1\n"
        + "".join(f"Guide_U{s},guide_u,guide{i + 2}\n" for i, s in enumerate(U_GUIDES))
        + "Routing_Plate,obstacle,plate\n"
    )
    shutil.copytree(REMODEL, tmp_path / "board")
    (tmp_path / "cell.yaml").write_text(example("### 3.1 cell.yaml"))
    (tmp_path / "objects.yaml").write_text(example("### 3.3 objects.yaml"))
    (tmp_path / "plan.yaml").write_text(example("### 3.4 plan.yaml"))
    return tmp_path


def test_design_examples_validate_unchanged(
    design_cell: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(design_cell)
    # the formats contract; running these files end to end is issue #4's
    assert main(["validate", "--no-compile", "."]) == 0, capsys.readouterr().out
    assert capsys.readouterr().out.splitlines() == [
        "cell.yaml: ok (cell)",
        "objects.yaml: ok (objects)",
        "plan.yaml: ok (plan)",
    ]


def test_design_board_is_the_remodel_sample(
    design_cell: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import json

    assert main(["show", str(design_cell / "cell.yaml"), "--json"]) == 0
    keypoints = json.loads(capsys.readouterr().out)["keypoints"]
    # board at (400, 0, 0) mm, no rotation; J3 guide 1's slot centre in the platform frame is
    # (-323.000001, -156.330002, 112.25) mm (see tests/info/test_remodel.py)
    assert keypoints["board.J3.1"]["xyz"] == pytest.approx([0.077, -0.15633, 0.11225], abs=1e-6)
