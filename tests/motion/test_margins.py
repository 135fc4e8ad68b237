"""Transits keeping the clearance: per-pair security margins in the planner's checks, lowered
where a transit's own ends are closer."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from cellengine.motion.collision import CollisionChecker
from cellengine.motion.margins import keeping_clearance
from cellengine.motion.robot import CellModel
from cellengine.motion.transit import plan_for_arms
from tests.execute.scenes import cable_cell

CLEARANCE = 0.010
# The left arm from A to B, the right arm standing: the straight line passes 4.7 mm from the
# right arm (found by a seeded random search), each end is more than 30 mm from it.
A = [0.688, -1.19, 1.617, -2.38, -1.008, -1.19, -0.326, -1.608, 1.386, -2.03, -1.887, -0.53]
B = [0.385, -2.374, 0.752, -0.596, -0.545, 0.529, -0.326, -1.608, 1.386, -2.03, -1.887, -0.53]


def arms_apart(checker: CollisionChecker, q: np.ndarray) -> float:
    return checker.distance(q, between=("left", "right"))[0]


def along(path: np.ndarray, step: float = 0.005) -> np.ndarray:
    """States on the path's straight segments at most ``step`` apart (L2)."""
    out = [path[:1]]
    for a, b in itertools.pairwise(path):
        n = max(1, int(np.ceil(np.linalg.norm(b - a) / step)))
        out.append(a + (np.arange(1, n + 1)[:, None] / n) * (b - a))
    return np.vstack(out)


def closest_on_line(checker: CollisionChecker) -> tuple[np.ndarray, float]:
    a, b = np.array(A), np.array(B)
    states = [a + t * (b - a) for t in np.linspace(0.0, 1.0, 201)]
    d = [arms_apart(checker, q) for q in states]
    return states[int(np.argmin(d))], min(d)


@pytest.fixture(scope="module")
def cell_and_checker() -> tuple[CellModel, CollisionChecker]:
    _, cell, checker = cable_cell()
    return cell, checker


def test_the_straight_line_is_free_but_passes_within_the_clearance(cell_and_checker) -> None:  # type: ignore[no-untyped-def]
    _, checker = cell_and_checker
    a, b = np.array(A), np.array(B)
    assert checker.check_segment(a, b) is None  # no collision: the exact check lets it pass
    assert 0.002 < closest_on_line(checker)[1] < 0.007
    refused = keeping_clearance(checker, CLEARANCE, [a, b]).check_segment(a, b)
    assert refused is not None and refused.distance < CLEARANCE + 1e-4
    assert {refused.a.split("/")[0], refused.b.split("/")[0]} == {"left", "right"}


def test_a_transit_keeps_the_clearance_where_the_straight_line_would_not(cell_and_checker) -> None:  # type: ignore[no-untyped-def]
    cell, checker = cell_and_checker
    a, b = np.array(A), np.array(B)
    keep = keeping_clearance(checker, CLEARANCE, [a, b])
    result = plan_for_arms(cell, keep, ("left",), a, b, seed=0)
    assert result.ok and result.path is not None, result.reason
    np.testing.assert_allclose(result.path[[0, -1]], [a, b])
    assert len(result.path) > 2  # not the straight line
    assert min(arms_apart(checker, q) for q in along(result.path)) >= CLEARANCE
    again = plan_for_arms(cell, keep, ("left",), a, b, seed=0)
    assert again.path is not None and np.array_equal(again.path, result.path)


def test_a_start_closer_than_the_clearance_lowers_that_pair_only(cell_and_checker) -> None:  # type: ignore[no-untyped-def]
    cell, checker = cell_and_checker
    start, d = closest_on_line(checker)  # 4.7 mm from the right arm
    goal = np.array(A)
    keep = keeping_clearance(checker, CLEARANCE, [start, goal])
    lowered = np.flatnonzero((keep.margins > 0) & (keep.margins < CLEARANCE))
    assert len(lowered) >= 1
    assert keep.margins[lowered].max() < d  # the start itself keeps what is asked
    assert keep.margins.max() == CLEARANCE  # the other measured pairs keep the clearance
    assert not keep.in_collision(start)
    with_full = keeping_clearance(checker, CLEARANCE, [goal, np.array(B)])
    assert with_full.in_collision(start)  # without lowering, the start would be refused
    result = plan_for_arms(cell, keep, ("left",), start, goal, seed=0)
    assert result.ok and result.path is not None, result.reason
    assert min(arms_apart(checker, q) for q in along(result.path)) >= keep.margins[lowered].min()


def test_pairs_not_measured_keep_the_exact_check(cell_and_checker) -> None:  # type: ignore[no-untyped-def]
    """An arm's own links and the pairs the task touches have margin 0."""
    _, checker = cell_and_checker
    keep = keeping_clearance(checker, CLEARANCE, [np.array(A)])
    scene = keep.checker.scene
    for p in range(len(scene.pairs)):
        a, b = scene.pair_names(p)
        same_arm = a.split("/")[0] == b.split("/")[0] and "/" in a and "/" in b
        if same_arm:
            assert keep.margins[p] == 0.0, (a, b)
