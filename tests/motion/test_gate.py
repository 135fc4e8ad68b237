"""The trajectory gate on trajectories whose violations are known."""

from __future__ import annotations

import numpy as np
import pytest

from cellengine.motion.gate import check_trajectory
from cellengine.motion.robot import Limits
from cellengine.motion.trajectory import Trajectory

NAMES = ("a", "b")
LIMITS = Limits(
    np.array([-1.0, -1.0]), np.array([1.0, 1.0]), np.array([2.0, 2.0]), np.array([10.0, 10.0])
)


def quintic(distance: float, duration: float) -> Trajectory:
    """Joint 'a' moves rest-to-rest by ``distance`` with a quintic; 'b' stays at 0.
    Peak speed 1.875 d / T at T/2; peak acceleration 10 d / (sqrt(3) T^2) at T(1/2 -+ sqrt3/6)."""
    t = np.linspace(0.0, duration, 11)
    s = t / duration
    pos = distance * (10 * s**3 - 15 * s**4 + 6 * s**5)
    vel = distance * (30 * s**2 - 60 * s**3 + 30 * s**4) / duration
    acc = distance * (60 * s - 180 * s**2 + 120 * s**3) / duration**2
    z = np.zeros_like(t)
    return Trajectory(NAMES, t, np.c_[pos, z], np.c_[vel, z], np.c_[acc, z])


def test_within_limits_passes_with_1ms_samples() -> None:
    report = check_trajectory(quintic(0.8, 1.0), NAMES, LIMITS)  # 1.5 rad/s, 4.6 rad/s^2
    assert report.ok and report.samples == 1001


def test_velocity_violation_names_joint_time_and_value() -> None:
    report = check_trajectory(quintic(0.8, 0.5), NAMES, LIMITS)  # peak 3.0 rad/s at 0.25 s
    kinds = [v.kind for v in report.violations]
    assert kinds == ["velocity", "acceleration"]  # peak 18.5 rad/s^2
    v = report.violations[0]
    assert v.what == "a" and v.limit == 2.0
    assert 0.05 < v.time < 0.25 and 2.0 < v.value <= 2.01  # first sample over the limit
    assert str(v).startswith("t=") and "a velocity" in str(v) and "outside the limit 2/s" in str(v)


def test_position_violation() -> None:
    report = check_trajectory(quintic(1.5, 2.0), NAMES, LIMITS)
    (v,) = report.violations
    assert (v.kind, v.what, v.limit) == ("position", "a", 1.0)
    assert 1.0 < v.value < 1.001


class Wall:
    """'a' above 0.5 collides with the table."""

    def check_batch(self, Q: np.ndarray) -> np.ndarray:
        return Q[:, 0] > 0.5

    def check(self, q: np.ndarray) -> str | None:
        return "left/wrist_3_link and table" if q[0] > 0.5 else None


def test_first_colliding_sample_is_named() -> None:
    report = check_trajectory(quintic(0.8, 1.0), NAMES, LIMITS, Wall())
    (v,) = report.violations
    assert v.kind == "collision" and v.what == "left/wrist_3_link and table"
    # a(t) = 0.5 where s = 0.5 + ... : the first 1 ms sample past it
    q, _, _ = quintic(0.8, 1.0).sample(np.array([v.time - 0.001, v.time]))
    assert q[0, 0] <= 0.5 < q[1, 0]


def test_minimum_arm_distance_reported() -> None:
    report = check_trajectory(
        quintic(0.8, 1.0), NAMES, LIMITS, arm_distance=lambda q: (1.0 - q[0], ("l", "r"))
    )
    assert report.min_arm_distance == pytest.approx(0.2)
    assert report.closest_pair == ("l", "r")


def test_joint_order_must_match() -> None:
    with pytest.raises(ValueError, match="differ from the model's"):
        check_trajectory(quintic(0.8, 1.0), ("b", "a"), LIMITS)


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


def test_planned_and_timed_move_passes_the_gate(cable_cell) -> None:  # type: ignore[no-untyped-def]
    from cellengine.motion.gate import check_cell_trajectory
    from cellengine.motion.timing import time_parameterize
    from cellengine.motion.transit import plan_for_arms

    cell, checker = cable_cell
    home = cell.join({n: a.home for n, a in cell.arms.items()})
    goal = home.copy()
    goal[[0, 6]] = [-0.9, 0.9]
    path = plan_for_arms(cell, checker, ("left", "right"), home, goal, seed=1).path
    assert path is not None
    waypoints = np.vstack([path[0], (path[0] + path[-1]) / 2, path[-1]]) if len(path) == 2 else path
    traj = time_parameterize(
        waypoints, cell.limits, jerk=10 * cell.limits.acceleration, joint_names=cell.joint_names
    )
    report = check_cell_trajectory(traj, cell, checker)
    assert report.ok, [str(v) for v in report.violations]
    assert report.min_arm_distance is not None and report.min_arm_distance > 0
    assert report.closest_pair is not None and report.closest_pair[0].startswith("left/")


def test_a_move_into_the_table_is_stopped_at_the_gate(cable_cell) -> None:  # type: ignore[no-untyped-def]
    from cellengine.motion.gate import check_cell_trajectory
    from cellengine.motion.timing import ptp

    cell, checker = cable_cell
    home = cell.join({n: a.home for n, a in cell.arms.items()})
    down = home.copy()
    down[1:3] = [0.6, 0.0]  # left upper arm tilted 0.6 rad below level: into the table
    assert checker.in_collision(down)
    traj = ptp(home, down, cell.limits, joint_names=cell.joint_names)
    report = check_cell_trajectory(traj, cell, checker)
    (v,) = report.violations
    assert v.kind == "collision" and "table" in v.what and v.what.startswith("left/")
    assert 0 < v.time < traj.duration
