"""Joint kinds for the page's units."""

from __future__ import annotations

from cellengine.report.joints import joint_kinds
from tests.report.programs import cable_cell
from tests.report.test_objects import lab_cell


def test_the_cartesian_robots_axes_are_prismatic_and_their_wrists_revolute() -> None:
    _, cell = lab_cell()
    kinds = dict(zip(cell.joint_names, joint_kinds(cell), strict=True))
    assert kinds == {
        "robot1_z": "prismatic",
        "robot1_x": "prismatic",
        "robot1_y": "prismatic",
        "robot1_roll": "revolute",
        "robot2_z": "prismatic",
        "robot2_x": "prismatic",
        "robot2_y": "prismatic",
        "robot2_turn": "revolute",
    }


def test_a_ur_arm_is_revolute() -> None:
    _, cell = cable_cell()
    assert set(joint_kinds(cell)) == {"revolute"} and len(joint_kinds(cell)) == 12
