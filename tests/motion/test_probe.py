"""The tool probe on the reference cable cell: the tool's real solids (fingers at the jaw
mode's opening) against the environment, with coal."""

from __future__ import annotations

import numpy as np
import pytest

from cellengine.context import build_context
from cellengine.info.load import load_plan
from cellengine.motion.probe import ToolProbe
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


def test_comes_within_is_whether_nearest_finds_an_object(ctx) -> None:  # type: ignore[no-untyped-def]
    """comes_within stops at the first pair under the distance: the same yes or no as
    nearest, also asked in the other order (nearest's answer then serves it)."""
    slot = ctx.world.pose("routing.guide1")[:3, 3]
    paths = [[tcp(0.9, 0.5, 0.03)], [tcp(*slot)], [tcp(0.9, 0.5, 0.03), tcp(*slot)]]
    for within in (0.01, 0.02, 0.05):
        for only in (None, {"routing.guide2"}):
            for poses in paths:
                alone = ToolProbe(ctx.cell, ctx.scene)
                found = alone.comes_within("left", poses, "grasp", (), within, only)
                near = alone.nearest("left", poses, "grasp", within=within, only=only)
                assert found == (near is not None)
                assert ctx.probe.comes_within("left", poses, "grasp", (), within, only) == found
    assert ctx.probe.comes_within("left", [tcp(*slot)], "grasp", (), 0.01)
    assert not ctx.probe.comes_within("left", [tcp(0.9, 0.5, 0.03)], "grasp", (), 0.02)


def test_two_tools_side_by_side_are_their_fingers_gap_apart(ctx) -> None:  # type: ignore[no-untyped-def]
    """Both hands pointing down at one height, 100 mm apart along the TCP x: the bodies
    (cell.yaml: 50 mm along x) are 100 - 50 = 50 mm apart, nearer than the fingers
    (8 mm along x: 92 mm)."""
    near = ctx.probe.between(
        "left", [tcp(0.5, 0.1, 0.2)], "grasp", "right", tcp(0.6, 0.1, 0.2), "grasp"
    )
    assert near is not None
    assert near.distance == pytest.approx(0.050, abs=1e-9)
    assert (near.tool, near.other) == ("left/tool", "right/tool")


def test_a_path_asked_about_again_gives_the_same_answer(ctx) -> None:  # type: ignore[no-untyped-def]
    poses = [tcp(0.9, 0.5, 0.03), tcp(0.9, 0.5, 0.04)]
    first = ctx.probe.nearest("left", poses, "grasp", within=0.05)
    assert first is not None and first.distance == pytest.approx(0.03, abs=1e-9)
    assert ctx.probe.nearest("left", poses, "grasp", within=0.05) == first
    # another jaw opening is another question
    assert ctx.probe.nearest("left", poses, "open", within=0.05) is not None


def test_only_measures_the_objects_it_names(ctx) -> None:  # type: ignore[no-untyped-def]
    """At guide1's slot the fingers are in guide1; asked only about guide2 (its slot 110 mm
    on), guide2 is what is reported, and nothing within 10 mm."""
    slot = ctx.world.pose("routing.guide1")[:3, 3]
    at_slot = [tcp(*slot)]
    near = ctx.probe.nearest("left", at_slot, "grasp", within=0.2, only={"routing.guide2"})
    assert near is not None and near.other.split("#")[0] == "routing.guide2"
    assert ctx.probe.nearest("left", at_slot, "grasp", within=0.01, only={"routing.guide2"}) is None


def test_under_names_what_lies_wholly_below_a_level(ctx) -> None:  # type: ignore[no-untyped-def]
    """On the reference cell the table's top is at z = 0, the platforms' 10 mm plates on it,
    and the guides and combs stand about 60 mm: at 5 mm only the table lies under, up to
    the slots' 65 mm the plates too, at 200 mm everything does."""
    probe = ctx.probe
    up = np.array([0.0, 0.0, 1.0])
    assert probe.under(0.005, up) == {"table"}
    assert probe.under(0.065, up) == {"table", "routing.plate", "holder.plate"}
    assert {"routing.guide1", "holder.comb_a", "table"} <= probe.under(0.2, up)


def test_the_bounds_never_exceed_the_distance_coal_measures(ctx) -> None:  # type: ignore[no-untyped-def]
    """The bounds that decide which pairs coal measures (spheres, the tool's capsules, the
    statics' boxes) are lower bounds: at 200 seeded tool poses over the routing board, turned
    every way, no (pose, static, tool solid) bound is above that pair's distance (none above
    zero where they overlap: coal's penetration depth is an estimate, not a distance)."""
    import coal

    from cellengine import geometry as g
    from cellengine.motion import probe as P

    rng = np.random.default_rng(7)
    tool = ctx.probe._tool("left", "grasp")
    statics = ctx.probe.statics
    centre = ctx.world.pose("routing.guide2")[:3, 3]
    poses = []
    for _ in range(200):
        R = g.axis_angle_to_matrix(g.unit(rng.normal(size=3)), rng.uniform(0.0, np.pi))
        poses.append(g.transform(R, centre + rng.uniform(-0.15, 0.15, size=3)))
    P_ = np.array(poses)
    bound = P._bounds(P_, tool, statics)
    request, result = coal.DistanceRequest(), coal.DistanceResult()
    tight = 0
    for i, T in enumerate(poses):
        for m, t in enumerate(tool):
            placed = P._transform(T @ t.T)
            for k, s in enumerate(statics):
                result.clear()
                d = coal.distance(t.shape, placed, s.shape, s.placed, request, result)
                assert bound[i, k, m] <= max(d, 0.0) + 1e-9
                tight += bound[i, k, m] > d - 0.05
    assert tight  # some bounds are within 50 mm of the distance: they do prune
