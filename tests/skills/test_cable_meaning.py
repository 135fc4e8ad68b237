"""The cable plans' meaning checks (skills/cable_meaning.py). Their messages are asserted
by the bad-input corpus (plan_guide_across, plan_connector_backwards,
plan_connector_into_u_guide, plan_route_reversed, plan_route_through_guide); here, the
geometry under them and that correct plans pass."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from cellengine.info.load import load_plan
from cellengine.skills.cable_meaning import _box_meets_triangles, check

CELLS = Path(__file__).resolve().parents[2] / "cells" / "cable_routing"
HALF = np.array([0.0175, 0.0155, 0.008])  # a VGA connector's half sizes


def test_a_triangle_through_the_box_with_no_corner_inside_meets_it() -> None:
    # a wall's face crossing the whole box, its corners far outside
    wall = np.array([[[-1.0, 0.0, -1.0], [1.0, 0.0, -1.0], [0.0, 0.0, 1.0]]])
    assert _box_meets_triangles(HALF, wall)


def test_a_triangle_beside_the_box_does_not_meet_it() -> None:
    beside = np.array([[[-1.0, 0.02, -1.0], [1.0, 0.02, -1.0], [0.0, 0.02, 1.0]]])
    assert not _box_meets_triangles(HALF, beside)
    # over a corner, its plane slanted: the face axes overlap, the triangle's normal does not
    over = np.array([[[0.05, 0.0, 0.0], [0.0, 0.05, 0.0], [0.0, 0.0, 0.05]]])
    assert not _box_meets_triangles(HALF, over)  # x + y + z = 0.05 > 0.041 at the corner


def test_no_triangles_meet_nothing() -> None:
    assert not _box_meets_triangles(HALF, np.zeros((0, 3, 3)))


@pytest.mark.parametrize("plan", ["plan_straight", "plan_one_turn", "plan_two_turns"])
def test_the_reference_plans_mean_what_they_say(plan: str) -> None:
    loaded = load_plan(CELLS / f"{plan}.yaml")
    assert check(loaded.world, loaded.plan.steps) == []
