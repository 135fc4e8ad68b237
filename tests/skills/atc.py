"""The reference cable cell with a tool changer beside the left arm: its own gripper
(gripper_left, the reference cable gripper) and a taping gun, each in a slot, both taken
from above and slid out sideways."""

from __future__ import annotations

import shutil
from pathlib import Path

CELL = Path(__file__).resolve().parents[2] / "cells" / "cable_routing"
SLOT = "exit: [[70, 0, 0], [70, 0, -100]], retreat: [[0, 0, -50]]"
TOOLS = f"""
  gripper_left:
    kind: parallel_gripper
    tcp: {{xyz: [0, 0, 200]}}
    finger_width: 20
    finger_thickness: 8
    jaw: {{open: 60, slide: 7, grasp: 4}}
    shape:
      - {{name: body, box: [50, 90, 110], pose: {{xyz: [0, 0, 55]}}}}
    fingers: {{size: [8, 6, 90]}}
    slot: {{at: {{xyz: [250, 520, 320], rpy: [180, 0, 0]}}, {SLOT}}}
  taping_gun:
    kind: taping_gun
    tcp: {{xyz: [0, 0, 180]}}
    dwell: 3
    shape:
      - {{name: body, box: [60, 60, 150], pose: {{xyz: [0, 0, 75]}}}}
    slot: {{at: {{xyz: [250, 400, 320], rpy: [180, 0, 0]}}, {SLOT}}}
"""


def atc_cell(tmp_path: Path, steps: str, edit: tuple[str, str] = ("", ""), head: str = "") -> Path:
    """The cell in ``tmp_path``/cell with a plan.yaml of ``steps`` (YAML list items) after
    ``head`` (plan keys); its cell.yaml's text ``edit[0]`` replaced by ``edit[1]`` after the
    tools are added."""
    cell = tmp_path / "cell"
    shutil.copytree(CELL, cell)
    text = (cell / "cell.yaml").read_text()
    left = "    base: {xyz: [0, 350, 0], rpy: [0, 0, 0]}\n    tool: cable_gripper"
    assert left in text
    text = text.replace(left, left.replace("cable_gripper", "gripper_left"))
    text = text.replace("\n# The platforms' X3D", TOOLS + "\n# The platforms' X3D", 1)
    if edit[0]:
        assert edit[0] in text
        text = text.replace(*edit)
    (cell / "cell.yaml").write_text(text)
    plan = "cell: cell.yaml\nobjects: objects.yaml\n" + head + "steps:\n" + steps
    (cell / "plan.yaml").write_text(plan)
    return cell / "plan.yaml"
