"""Which turn of the wrist a transit leaves it on (execute/winding.py), on the reference
cell's left UR5e: wrist 3 turns 2 pi either way."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cellengine import geometry as g
from cellengine.execute import winding
from cellengine.motion.ik import arm_ik
from cellengine.program import ArmPath, Segment
from tests.execute.scenes import DOWN, cable_cell, home, pose

GOAL = (0.40, 0.15, 0.20)


def spin(turn_deg: float, n: int = 150) -> np.ndarray:
    """The TCP at GOAL turning about its own (vertical) axis by ``turn_deg`` in n steps."""
    return np.array(
        [pose(GOAL, DOWN @ g.axis_angle_to_matrix([0, 0, 1], math.radians(turn_deg) * k / n))
         for k in range(n + 1)]
    )  # fmt: skip


def test_best_turn_leaves_room_for_what_follows_else_stays_nearest() -> None:
    lo, hi = -2 * math.pi, 2 * math.pi
    # a goal at -2.7 rad followed by 3.6 rad more the same way: -6.3 is past the limit,
    # the turn above (3.58) ends at -0.02
    assert winding._best_turn(-2.7, -3.6, 0.0, lo, hi, 0.0) == pytest.approx(-2.7 + 2 * math.pi)
    # a small excursion: the nearest stays
    assert winding._best_turn(-2.7, -0.5, 0.5, lo, hi, 0.0) == pytest.approx(-2.7)


def test_a_transit_goal_before_a_long_turn_is_taken_on_the_turn_that_allows_it() -> None:
    """From home (wrist 3 at 0), the goal pose's nearest solutions have wrist 3 within pi of
    0; a spin of -300 deg after it would take that past -2 pi on some of them. Rewound, every
    solution can follow it: its wrist 3 goes no lower than -2 pi + MARGIN."""
    _, cell, _ = cable_cell()
    q = home(cell)
    sl = cell.slices["left"]
    sols = arm_ik(cell.arms["left"]).solve_all(pose(GOAL), seed=q[sl])
    poses = spin(-300.0)
    out = winding.rewound(cell, "left", sols, poses, q[sl])
    assert len(out) == len(sols)
    moved = 0
    for before, after in zip(sols, out, strict=True):
        turns = (after - before) / (2 * math.pi)
        assert np.allclose(turns, np.round(turns), atol=1e-9)  # whole turns only
        assert np.allclose(after[:5], before[:5], atol=1e-9)  # only wrist 3 may turn
        lo, hi = winding._excursion(cell, "left", after, poses)  # type: ignore[misc]
        assert after[5] + lo[5] >= -2 * math.pi + winding.MARGIN - 1e-9
        assert after[5] + hi[5] <= 2 * math.pi - winding.MARGIN + 1e-9
        moved += not np.allclose(after, before)
    assert moved > 0  # some nearest solution could not have followed


def test_ahead_takes_the_arms_cartesian_poses_up_to_its_next_transit() -> None:
    first, second = spin(-30.0, 3), spin(30.0, 3)
    segs = [
        Segment(0, "turn", (ArmPath("left", "cartesian", first),)),
        Segment(0, "other", (ArmPath("right", "cartesian", second),)),
        Segment(0, "turn back", (ArmPath("left", "cartesian", second),)),
        Segment(0, "away", (ArmPath("left", "transit", first[-1:]),)),
        Segment(0, "after", (ArmPath("left", "cartesian", first),)),
    ]
    got = winding.ahead(segs, "left")
    assert got is not None and len(got) == 8
    assert winding.ahead(segs[3:], "left") is None
