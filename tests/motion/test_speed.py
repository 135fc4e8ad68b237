"""Speed knobs: the timing's velocity and acceleration limits scaled and the TCPs capped,
while the gate checks the arms' own limits."""

from __future__ import annotations

import numpy as np
import pytest

from cellengine.execute import compile_segments, program_trajectory
from cellengine.info.cell import Cell
from cellengine.info.plan import Plan
from cellengine.info.speed import SpeedScaling
from cellengine.motion.gate import check_cell_trajectory
from cellengine.motion.speed import Speed, resolve, tcp_points, tcp_speeds
from cellengine.motion.trajectory import Trajectory
from tests.execute.scenes import cable_cell, home, reference_segments

CELL = {"name": "c", "robots": {"left": {"model": "ur5e"}}}


def _timed(speed: Speed) -> Trajectory:
    world, cell, checker = cable_cell()
    slowed = cell.with_speed(speed)
    program = compile_segments(world, slowed, checker, reference_segments(), home(cell))
    traj = program_trajectory(program)
    assert check_cell_trajectory(traj, slowed, checker).ok  # the arms' own limits
    return traj


@pytest.fixture(scope="module")
def full() -> Trajectory:
    return _timed(Speed())


def test_half_speed_is_slower_as_the_limits_say(full: Trajectory) -> None:
    """Velocity, acceleration and jerk limits halved (the jerk limit follows acceleration):
    each move takes between 2^(1/3) times (jerk-bound) and 2 times (velocity-bound) as long,
    and no joint goes faster than half its velocity limit."""
    _, cell, _ = cable_cell()
    half = _timed(Speed(0.5, 0.5))
    ratio = half.duration / full.duration
    assert 2 ** (1 / 3) < ratio < 2.0
    assert ratio > 1.3  # most of it is acceleration-bound: sqrt(2)
    v = np.abs(half.sample(np.arange(0.0, half.end_time, 0.001))[1]).max(axis=0)
    assert np.all(v <= 0.5 * cell.limits.velocity * (1 + 1e-6))
    assert np.abs(full.qd).max() > 0.5 * cell.limits.velocity.min()  # the halving could fail


def test_the_tcp_speed_cap_is_kept(full: Trajectory) -> None:
    _, cell, _ = cable_cell()
    cap = 0.1  # m/s
    assert max(v.max() for v in tcp_speeds(cell, full).values()) > 1.5 * cap
    capped = _timed(Speed(tcp=cap))
    fastest = max(v.max() for v in tcp_speeds(cell, capped, dt=0.0005).values())
    assert cap * 0.9 < fastest <= cap + 1e-6


def test_the_timing_limits_are_scaled_and_the_arms_own_are_not() -> None:
    _, cell, _ = cable_cell()
    slowed = cell.with_speed(Speed(0.5, 0.25))
    timing = slowed.timing_limits("left")
    own = cell.arms["left"].limits
    assert np.array_equal(timing.velocity, 0.5 * own.velocity)
    assert np.array_equal(timing.acceleration, 0.25 * own.acceleration)
    assert np.array_equal(timing.lower, own.lower) and np.array_equal(timing.upper, own.upper)
    assert np.array_equal(slowed.limits.velocity, cell.limits.velocity)  # what the gate checks
    assert np.array_equal(slowed.timing_limits().velocity[:6], timing.velocity)


def _plan(speed: SpeedScaling | None = None, tcp: float | None = None) -> Plan:
    return Plan(None, "cell.yaml", None, "split", (), (), speed, tcp)  # type: ignore[arg-type]


def test_a_plan_s_speed_replaces_the_cell_s_and_the_lower_tcp_cap_holds() -> None:
    cell = Cell.model_validate({**CELL, "speed": 0.5, "tcp_speed": 0.2})
    assert resolve(cell) == Speed(0.5, 0.5, 0.2)
    assert resolve(cell, _plan()) == Speed(0.5, 0.5, 0.2)
    plan = _plan(SpeedScaling(velocity=0.8), tcp=0.3)
    assert resolve(cell, plan) == Speed(0.8, 1.0, 0.2)  # a plan cannot raise the cell's cap
    assert resolve(cell, _plan(tcp=0.1), 0.5) == Speed(0.25, 0.25, 0.05, 0.5)
    assert resolve(Cell.model_validate(CELL)) == Speed(1.0, 1.0, None)


def test_tcp_points_of_a_built_in_arm_all_at_once_are_its_forward_kinematics() -> None:
    _, cell, _ = cable_cell()
    arm = cell.arms["right"]
    Q = np.random.default_rng(0).uniform(-3.0, 3.0, (50, 6))
    one_by_one = np.array([arm.fk(q)[:3, 3] for q in Q])
    assert np.abs(tcp_points(arm, Q) - one_by_one).max() < 1e-9
