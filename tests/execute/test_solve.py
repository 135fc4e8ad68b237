"""Which arm's IK branch a Cartesian path that stops short blames (execute/solve.py): the
search goes back to that arm's transit (execute/search.py, candidates.py)."""

from __future__ import annotations

from cellengine.execute.solve import _branch_of
from cellengine.motion.cartesian import Stop


def test_an_arm_hitting_itself_or_a_limit_blames_its_branch() -> None:
    itself = Stop("collision", 6, "", pair=("left/shoulder_link", "left/tool"))
    assert _branch_of(itself) == "left"
    assert _branch_of(Stop("limit", 11, "", arm="left", joint="left_wrist_3_joint")) == "left"
    assert _branch_of(Stop("joint_jump", 3, "", arm="right")) == "right"


def test_a_path_stopped_by_the_other_arm_or_the_cell_blames_no_branch() -> None:
    arms = Stop("collision", 13, "", pair=("left/wrist_1_link", "right/wrist_3_link"))
    cell = Stop("collision", 3, "", arm="left", pair=("left/tool/finger_right", "routing.g2"))
    assert _branch_of(arms) is None and _branch_of(cell) is None
