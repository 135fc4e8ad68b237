"""The tool probe on the reference cable cell: the tool's real solids (fingers at the jaw
mode's opening) against the environment, with coal."""

from __future__ import annotations

import numpy as np
import pytest

from cellengine.context import build_context
from cellengine.info.load import load_plan
from tests.conftest import CELLS

DOWN = np.diag([1.0, -1.0, -1.0])  # the tool axis (TCP z) pointing down


def tcp(x: float, y: float, z: float) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = DOWN, (x, y, z)
    return T


@pytest.fixture(scope="module")
def ctx():  # type: ignore[no-untyped-def]
    return build_context(load_plan(CELLS / "cable_routing" / "plan_straight.yaml").world)


def test_fingertips_above_the_table_are_their_height_from_it(ctx) -> None:  # type: ignore[no-untyped-def]
    """Fingers' tips at the TCP, 30 mm over the bare table (its top at z = 0)."""
    near = ctx.probe.nearest("left", [tcp(0.9, 0.5, 0.03)], "grasp", within=0.05)
    assert near is not None and near.other == "table"
    assert near.tool.startswith("left/tool/finger_")
    assert near.distance == pytest.approx(0.03, abs=1e-9)


def test_nothing_within_reports_none_and_skip_leaves_an_object_out(ctx) -> None:  # type: ignore[no-untyped-def]
    assert ctx.probe.nearest("left", [tcp(0.9, 0.5, 0.03)], "grasp", within=0.02) is None
    slot = ctx.world.pose("routing.guide1")[:3, 3]
    at_slot = [tcp(*slot)]
    hit = ctx.probe.nearest("left", at_slot, "grasp", within=0.01)
    assert hit is not None and hit.other == "routing.guide1" and hit.distance < 0.01
    skipped = ctx.probe.nearest("left", at_slot, "grasp", skip={"routing.guide1"}, within=0.01)
    assert skipped is None or skipped.other != "routing.guide1"
