"""The IK branches the cable family keeps for each arm (skills/cable_family.py ``_narrowed``):
an arm does not change branch between its transits, so a candidate whose Cartesian paths no
branch the arm may be on can follow is not offered, and the skills' later checks look only
at the branches left. On the reference cell, with the left tool tipped 30 deg on an arc
around its base (the tool meets the shoulder on some branches, tests/execute)."""

from __future__ import annotations

import math

import numpy as np

from cellengine import geometry as g
from cellengine.context import build_context
from cellengine.info.load import load_world
from cellengine.program import ArmPath, Segment
from cellengine.skills.cable_family import _narrowed
from cellengine.skills.cable_state import ANY_BRANCH, CableState
from tests.execute.scenes import CELL


def arc(base: np.ndarray, tilt_deg: float) -> np.ndarray:
    """The tool tipped ``tilt_deg`` about its y, 80 mm over the table, on 1.2 rad of an arc
    180 mm around ``base``."""
    poses = []
    for a in np.linspace(-0.6, 0.6, 61):
        p = base + np.array(
            [0.18 * math.cos(a - math.pi / 2), 0.18 * math.sin(a - math.pi / 2), 0.08]
        )
        R = g.rot_z(a) @ g.rot_x(math.pi) @ g.rot_y(math.radians(tilt_deg))
        poses.append(g.transform(R, p))
    return np.array(poses)


def test_an_arms_branches_narrow_along_its_paths_and_open_again_at_a_transit() -> None:
    ctx = build_context(load_world(CELL, CELL.parent / "objects.yaml"))
    state = CableState.at_home(ctx)
    base = ctx.cell.arms["left"].T_cell_base[:3, 3]
    tipped, other_way = arc(base, 30.0), arc(base, -30.0)
    one = [Segment(0, "around", (ArmPath("left", "cartesian", tipped),))]
    after = _narrowed(ctx, state, one, state)
    assert after is not None
    kept = after.branches_of("left")
    assert kept and kept < ANY_BRANCH  # some branches meet the shoulder, some do not
    assert after.branches_of("right") == ANY_BRANCH  # it did not move
    # tipped the other way, the tool meets the shoulder on every branch left
    back = Segment(0, "back", (ArmPath("left", "cartesian", other_way),))
    alone = _narrowed(ctx, state, [back], state)
    assert alone is not None and not kept & alone.branches_of("left")
    assert _narrowed(ctx, state, [*one, back], state) is None
    # a transit between them: the arm may reach the second arc's start on any branch
    hop = Segment(0, "hop", (ArmPath("left", "transit", other_way[:1]),))
    assert _narrowed(ctx, state, [*one, hop, back], state) is not None
