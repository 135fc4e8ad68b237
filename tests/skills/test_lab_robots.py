"""Robot skills derived from tools and kinematics."""

from __future__ import annotations

import shutil
from pathlib import Path

from cellengine.info.load import load_world
from cellengine.motion.robot import build_cell_model
from cellengine.skills.lab_robots import describe, robot_skills
from tests.conftest import CELLS


def test_ur_arms_with_a_top_gripper_pick_place_turn_caps_and_pour() -> None:
    world = load_world(CELLS / "cable_routing" / "cell.yaml")
    skills = robot_skills(world, build_cell_model(world))
    want = frozenset({"pick", "place", "turn_cap", "pour"})
    assert skills == {"left": want, "right": want}


def test_a_side_gripper_with_a_load_cell_holds_and_weighs(tmp_path: Path) -> None:
    folder = tmp_path / "cell"
    shutil.copytree(CELLS / "cable_routing", folder)
    cell = folder / "cell.yaml"
    text = cell.read_text().replace(
        "tools:\n  cable_gripper:",
        "tools:\n  side:\n    kind: parallel_gripper\n    tcp: {xyz: [0, 0, 150]}\n"
        "    grasp: side\n    load_cell: true\n    jaw: {open: 60, grasp: 20}\n"
        "  cable_gripper:",
    )
    text = text.replace("tool: cable_gripper", "tool: side", 1)  # the left arm
    cell.write_text(text)
    world = load_world(cell)
    skills = robot_skills(world, build_cell_model(world))
    assert skills["left"] == frozenset({"pick", "place", "hold", "weigh", "pour"})
    assert "turn_cap" in skills["right"] and "weigh" not in skills["right"]
    assert describe(skills) == (
        "left: hold, pick, place, pour, weigh; right: pick, place, pour, turn_cap"
    )
