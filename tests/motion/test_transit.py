"""Transit planning with OMPL on joint spaces with obstacles whose answers are known."""

from __future__ import annotations

import numpy as np
import pytest

from cellengine.motion.transit import plan_transit, request

N = 12
LOWER, UPPER = -np.pi * np.ones(N), np.pi * np.ones(N)


def wall(q: np.ndarray) -> bool:
    """Free unless joints 0 and 1 are both inside a wall |q0| < 0.5, |q1| < 2.5: a path from
    q0 = -2 to q0 = +2 must go round it, with |q1| >= 2.5."""
    return not (abs(q[0]) < 0.5 and abs(q[1]) < 2.5)


def start_goal() -> tuple[np.ndarray, np.ndarray]:
    start, goal = np.zeros(N), np.zeros(N)
    start[0], goal[0] = -2.0, 2.0
    return start, goal


def segment_free(a: np.ndarray, b: np.ndarray) -> bool:
    return all(wall(a + t * (b - a)) for t in np.linspace(0.0, 1.0, 400))


def test_goes_round_the_wall_and_every_segment_is_free() -> None:
    start, goal = start_goal()
    result = plan_transit(request(start, goal, LOWER, UPPER, seed=3), wall, segment_free)
    assert result.ok, result.reason
    assert result.path is not None
    np.testing.assert_array_equal(result.path[0], start)
    np.testing.assert_array_equal(result.path[-1], goal)
    assert max(abs(result.path[:, 1])) >= 2.5  # it went round
    assert result.goal_index == 0 and result.checks > 0


def test_same_request_same_path_and_seed_matters() -> None:
    start, goal = start_goal()
    a = plan_transit(request(start, goal, LOWER, UPPER, seed=5, simplify=False), wall)
    b = plan_transit(request(start, goal, LOWER, UPPER, seed=5, simplify=False), wall)
    c = plan_transit(request(start, goal, LOWER, UPPER, seed=6, simplify=False), wall)
    assert a.path is not None and b.path is not None and c.path is not None
    np.testing.assert_array_equal(a.path, b.path)
    assert a.path.shape != c.path.shape or not np.array_equal(a.path, c.path)


def test_reaches_one_of_several_goals() -> None:
    start, goal = start_goal()
    blocked = goal.copy()
    blocked[0] = 0.0  # inside the wall
    result = plan_transit(request(start, [blocked, goal], LOWER, UPPER), wall)
    assert result.ok and result.goal_index == 1


@pytest.mark.parametrize(
    ("goals", "reason"),
    [
        ([np.zeros(N)], "all 1 goal configuration(s) are invalid"),
        ([np.full(N, 4.0)], "all 1 goal configuration(s) are invalid"),  # out of bounds
    ],
)
def test_clear_failures(goals: list[np.ndarray], reason: str) -> None:
    start, _ = start_goal()
    result = plan_transit(request(start, goals, LOWER, UPPER), wall)
    assert (result.ok, result.reason, result.path) == (False, reason, None)


def test_no_path_within_the_time_limit() -> None:
    start, goal = start_goal()

    def sealed(q: np.ndarray) -> bool:  # a wall across the whole of joint 0
        return abs(q[0]) >= 0.5

    result = plan_transit(request(start, goal, LOWER, UPPER, time_limit=0.05), sealed)
    assert not result.ok
    assert result.reason == "RRTConnect: no path found within 0.05 s"


def test_start_in_collision() -> None:
    _, goal = start_goal()
    result = plan_transit(request(np.zeros(N), goal, LOWER, UPPER), wall)
    assert result.reason == "the start configuration is in collision or out of bounds"


def test_planner_by_name_and_unknown_planner() -> None:
    start, goal = start_goal()
    assert plan_transit(request(start, goal, LOWER, UPPER, planner="RRT", seed=1), wall).ok
    with pytest.raises(ValueError, match=r"unknown planner 'RRT\*'; known: AORRTC, BFMT, BITstar"):
        request(start, goal, LOWER, UPPER, planner="RRT*")


@pytest.fixture(scope="module")
def cable_cell():  # type: ignore[no-untyped-def]
    from cellengine.info.load import load_world
    from cellengine.motion.collision import CollisionChecker
    from cellengine.motion.robot import build_cell_model
    from cellengine.motion.scene import build_scene
    from tests.conftest import CELLS

    world = load_world(CELLS / "cable_routing" / "cell.yaml")
    cell = build_cell_model(world)
    return cell, CollisionChecker(build_scene(cell, world))


def test_both_arms_swap_sides_in_the_cable_cell(cable_cell) -> None:  # type: ignore[no-untyped-def]
    """Both arms (12 DOF) from home to a pose where each reaches over the routing platform;
    every segment of the result is proved free by the conservative segment check."""
    from cellengine.motion.transit import plan_for_arms

    cell, checker = cable_cell
    home = cell.join({n: a.home for n, a in cell.arms.items()})
    goal = home.copy()
    goal[[0, 6]] = [-0.9, 0.9]  # shoulder pans turned towards each other's side
    assert not checker.in_collision(home) and not checker.in_collision(goal)
    result = plan_for_arms(cell, checker, ("left", "right"), home, goal, seed=1)
    assert result.ok, result.reason
    assert result.path is not None
    np.testing.assert_allclose(result.path[[0, -1]], [home, goal])
    assert all(
        checker.check_segment(a, b) is None
        for a, b in zip(result.path[:-1], result.path[1:], strict=True)
    )
    again = plan_for_arms(cell, checker, ("left", "right"), home, goal, seed=1)
    assert again.path is not None and np.array_equal(again.path, result.path)


def test_one_arm_moves_the_other_stays(cable_cell) -> None:  # type: ignore[no-untyped-def]
    from cellengine.motion.transit import plan_for_arms

    cell, checker = cable_cell
    home = cell.join({n: a.home for n, a in cell.arms.items()})
    goal = home.copy()
    goal[0] = -0.6
    result = plan_for_arms(cell, checker, ("left",), home, goal)
    assert result.ok and result.path is not None
    np.testing.assert_array_equal(result.path[:, 6:], np.tile(home[6:], (len(result.path), 1)))
    with pytest.raises(ValueError, match=r"unknown arm\(s\) \['middle'\]; known: left, right"):
        plan_for_arms(cell, checker, ("middle",), home, goal)
