"""The page's names for steps, segments and collision objects."""

from __future__ import annotations

from cellengine.report.names import part_name, part_names, segment_name, step_title


def test_steps_count_from_one_without_their_index() -> None:
    assert step_title(0, "Weigh vial1") == "step 1 Weigh vial1"
    assert step_title(2, "steps[2] Unscrew") == "step 3 Unscrew"


def test_segments_drop_what_their_step_says() -> None:
    assert segment_name("steps[0] Weigh: to vial1", "Weigh vial1") == "to vial1"
    assert segment_name("steps[0] Weigh: to vial1", "steps[0] Weigh") == "to vial1"
    assert segment_name("RouteCable guide2: lift", "RouteCable guide2") == "lift"
    # another head than the step's: kept, so the name still says what it is about
    assert segment_name("cable1: release", "RouteCable") == "cable1: release"
    assert segment_name("steps[1] transit", "Weigh vial2") == "transit"


def test_parts_by_their_link_or_their_tool() -> None:
    tools = {"robot1": "side_gripper", "left": "gripper"}
    assert part_name("robot1/gripper#2", tools) == "robot1 gripper"
    assert part_name("robot1/y_arm", tools) == "robot1 y arm"
    assert part_name("left/tool", tools) == "left gripper"
    assert part_name("left/tool/finger_left", tools) == "left gripper finger left"
    assert part_name("right/tool", tools) == "right tool"  # no tool named in the cell
    assert part_name("bench.rack1#3", tools) == "bench.rack1"
    assert part_name("table", tools) == "table"
    assert part_names(["table", "robot1/frame#2"], tools) == {"robot1/frame#2": "robot1 frame"}
