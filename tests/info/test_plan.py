from pathlib import Path

import pytest

from cellengine.errors import InputError
from cellengine.info.load import check_plan
from cellengine.info.plan import parse_plan
from cellengine.info.yamlio import parse_yaml
from cellengine.skills.cable import PickCable, RouteCable
from cellengine.skills.lab import Pour
from tests.helpers import routing_world

F = Path("plan.yaml")
PLAN = """\
cell: cell.yaml
objects: objects.yaml
steps:
  - skill: PickCable
    cable: cable1
    from: [routing.guide1, routing.guide2.top]
  - skill: RouteCable
    cable: cable1
    guides: [routing.guide2, routing.guide3]
"""


def errors(text: str) -> list[str]:
    doc = parse_yaml(text, F)
    try:
        plan = parse_plan(doc)
    except InputError as e:
        return [str(p) for p in e.problems]
    return [str(p) for p in check_plan(plan, routing_world(), doc)]


def test_steps_are_skill_models() -> None:
    plan = parse_plan(parse_yaml(PLAN, F))
    assert plan.execution == "split"
    pick, route = plan.steps
    assert isinstance(pick, PickCable) and pick.from_ == ("routing.guide1", "routing.guide2.top")
    assert isinstance(route, RouteCable) and route.arm == "auto"
    assert list(route.refs()) == [
        (("cable",), "cable", "cable1"),
        (("guides", 0), "guide", "routing.guide2"),
        (("guides", 1), "guide", "routing.guide3"),
    ]
    assert errors(PLAN) == []


def test_unknown_guide_names_step_and_lists_known() -> None:
    text = PLAN.replace("routing.guide3]", "routing.guide9]")
    assert errors(text) == [
        "plan.yaml:9:30: steps[1].guides[1]: unknown guide 'routing.guide9'; "
        "known: guide1, guide2, guide3, plate"
    ]


def test_unknown_skill_lists_skills() -> None:
    assert errors(PLAN.replace("skill: RouteCable", "skill: RouteCables")) == [
        "plan.yaml:7:12: steps[1]: unknown skill 'RouteCables'; known: BimanualCarry, "
        "ChangeTool, Handover, Pick, PickCable, Place, PlaceConnector, Pour, RouteCable, Tape, "
        "Unscrew, Weigh"
    ]


def test_skill_parameters_validated() -> None:
    text = PLAN.replace("from: [routing.guide1, routing.guide2.top]", "from: [routing.guide1]")
    text = text.replace("    guides: [routing.guide2, routing.guide3]\n", "    guide: x\n")
    assert errors(text) == [
        "plan.yaml:6:11: steps[0].from: expected 2 keypoints [connector end, other end], got 1",
        "plan.yaml:7:5: steps[1]: missing required key 'guides'",
        "plan.yaml:9:5: steps[1]: unknown key 'guide'; known: after, arm, cable, guides, id, "
        "separate_into, skill",
    ]


def test_cable_and_arm_resolve() -> None:
    text = PLAN.replace("cable: cable1\n    from", "cable: cable2\n    arm: middle\n    from")
    assert errors(text) == [
        "plan.yaml:6:10: steps[0].arm: unknown arm 'middle'; known: auto, both, left, right",
        "plan.yaml:5:12: steps[0].cable: unknown cable 'cable2'; known: cable1",
    ]


def test_precedence_graph_checked() -> None:
    text = """\
steps:
  - {id: a, skill: Weigh, object: vial1, after: [c]}
  - {id: b, skill: Weigh, object: vial1, after: [a]}
  - {id: c, skill: Weigh, object: vial1, after: [b]}
  - {id: a, skill: Weigh, object: vial1, after: [z]}
"""
    assert errors(text) == [
        "plan.yaml:5:10: steps[3].id: duplicate step id 'a' (first used by steps[0])",
        "plan.yaml:5:50: steps[3].after[0]: unknown step id 'z'; known: a, b, c",
    ]
    assert errors(text.replace("  - {id: a, skill: Weigh, object: vial1, after: [z]}\n", "")) == [
        "plan.yaml:2:49: steps[0].after: steps wait for each other in a cycle: a -> c -> b -> a"
    ]


def test_a_chain_of_thousands_of_steps_listed_last_first() -> None:
    """Each step waits for the one listed after it: the search for a cycle goes 3000 deep
    (it recursed, and Python stopped at 1000), and finds none; closed, it finds it."""
    n = 3000
    steps = "".join(
        f"  - {{id: s{i}, skill: Weigh, object: vial1, after: [s{i + 1}]}}\n" for i in range(n - 1)
    )
    text = "steps:\n" + steps + f"  - {{id: s{n - 1}, skill: Weigh, object: vial1}}\n"
    assert errors(text) == []
    closed = text.replace("object: vial1}\n", "object: vial1, after: [s0]}\n")
    assert errors(closed) == [
        "plan.yaml:2:50: steps[0].after: steps wait for each other in a cycle: s0 -> s1 -> s2 "
        "-> s3 -> s4 -> s5 -> ... (2992 more) -> s2998 -> s2999 -> s0"
    ]


def test_object_choice_and_plan_units() -> None:
    text = """\
units: {angle: deg}
steps:
  - skill: Pour
    object: {heavier_of: [vial1, vial9]}
    into: vial1
    angle: 90
"""
    doc = parse_yaml(text, F)
    step = parse_plan(doc).steps[0]
    assert isinstance(step, Pour) and step.angle == pytest.approx(1.5707963267948966)
    assert errors(text) == [
        "plan.yaml:4:34: steps[0].object.heavier_of[1]: unknown object 'vial9'; "
        "known: cable1, vial1"
    ]
