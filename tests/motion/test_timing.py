"""Time parameterisation: limits at dense samples, rest at the ends, the path followed,
determinism, analytic cases, TCP speed, ruckig ptp and online re-targeting."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from cellengine.motion.otg import UNLIMITED_JERK_RAMP
from cellengine.motion.timing import (
    JointLimits,
    TcpSpeedLimit,
    ptp,
    retargeter,
    speed_profile,
    time_optimal,
    time_parameterize,
    time_parameterize_and_bound,
)
from cellengine.motion.topp import SplinePath
from cellengine.motion.trajectory import Trajectory

DT = 1e-3  # the trajectory gate's sampling period
# Ratios to a limit allowed at samples: peaks() bounds the interpolant, so this is rounding.
ROUNDING = 1e-9


def ur_limits(dof: int = 6, jerk: float | None = 50.0) -> JointLimits:
    return JointLimits(
        lower=np.full(dof, -2 * np.pi),
        upper=np.full(dof, 2 * np.pi),
        velocity=np.full(dof, np.pi),
        acceleration=np.full(dof, 5.0),
        jerk=None if jerk is None else np.full(dof, jerk),
    )


def random_walk(seed: int, count: int = 50, dof: int = 6, step: float = 0.3) -> np.ndarray:
    rng = np.random.default_rng(seed)
    start = rng.uniform(-1.0, 1.0, dof)
    return np.vstack([start, start + np.cumsum(rng.uniform(-step, step, (count - 1, dof)), 0)])


def dense(traj: Trajectory) -> tuple[np.ndarray, ...]:
    times = np.arange(traj.start_time, traj.end_time, DT)
    q, qd, qdd = traj.sample(times)
    return times, q, qd, qdd, traj.jerk(times)


def assert_within(traj: Trajectory, limits: JointLimits, jerk: bool) -> None:
    _, _, qd, qdd, qddd = dense(traj)
    assert np.all(np.abs(qd) <= limits.velocity * (1 + ROUNDING))
    assert np.all(np.abs(qdd) <= limits.acceleration * (1 + ROUNDING))
    if jerk:
        assert limits.jerk is not None
        assert np.all(np.abs(qddd) <= limits.jerk * (1 + ROUNDING))
        # finite differences of the sampled accelerations (what a driver would see)
        assert np.all(np.abs(np.diff(qdd, axis=0)) / DT <= limits.jerk * (1 + 1e-6))


def assert_well_formed(traj: Trajectory, waypoints: np.ndarray) -> None:
    assert np.all(np.diff(traj.t) > 0)
    for arr in (traj.t, traj.q, traj.qd, traj.qdd):
        assert np.all(np.isfinite(arr))
    np.testing.assert_allclose(traj.q[0], waypoints[0], atol=1e-9)
    np.testing.assert_allclose(traj.q[-1], waypoints[-1], atol=1e-9)
    for k in (0, -1):  # at rest at both ends
        np.testing.assert_array_equal(traj.qd[k], 0.0)
        np.testing.assert_array_equal(traj.qdd[k], 0.0)


def distance_to_path(q: np.ndarray, waypoints: np.ndarray) -> np.ndarray:
    """Distance from each sample to the spline through the waypoints: nearest of 4001
    points along it, then Newton steps on |path(s) - q|^2."""
    path = SplinePath(waypoints)
    grid = np.linspace(0.0, path.length, 4001)
    line = path.derivatives(grid)[0]
    s = np.empty(len(q))
    for i in range(0, len(q), 256):
        d2 = ((q[i : i + 256, None, :] - line[None, :, :]) ** 2).sum(axis=2)
        s[i : i + 256] = grid[d2.argmin(axis=1)]
    for _ in range(6):
        p, d1, dd = path.derivatives(s)
        gap = p - q
        s = np.clip(s - (d1 * gap).sum(1) / ((d1 * d1).sum(1) + (dd * gap).sum(1)), 0, path.length)
    return np.linalg.norm(path.derivatives(s)[0] - q, axis=1)


# -- time-optimal and jerk-limited along a path ------------------------------------------


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_time_optimal_within_limits_at_dense_samples(seed: int) -> None:
    wp = random_walk(seed)
    limits = ur_limits(jerk=None)
    traj = time_optimal(wp, limits)
    assert_well_formed(traj, wp)
    assert_within(traj, limits, jerk=False)
    # and time-optimal: within 3 % of the raw TOPP-RA profile (limits at grid points only)
    raw = speed_profile(wp, limits).duration
    assert raw < traj.duration < raw * 1.03


@pytest.mark.parametrize("seed", [0, 3])
def test_jerk_limited_within_limits_at_dense_samples(seed: int) -> None:
    wp = random_walk(seed)
    limits = ur_limits(jerk=50.0)
    traj = time_parameterize(wp, limits)
    assert_well_formed(traj, wp)
    assert_within(traj, limits, jerk=True)
    assert traj.duration > time_optimal(wp, limits).duration


def test_samples_lie_on_the_geometric_path() -> None:
    wp = random_walk(4, count=12)
    for traj in (time_optimal(wp, ur_limits()), time_parameterize(wp, ur_limits())):
        _, q, _, _, _ = dense(traj)
        # knots are on the path exactly; between them the quintic pieces stray by ~1e-9 rad
        assert distance_to_path(q, wp).max() < 1e-7
        # and every waypoint is passed (within one sample's travel)
        step = np.abs(traj.qd).max() * DT
        for point in wp:
            assert np.linalg.norm(q - point, axis=1).min() < step


def test_same_input_same_output() -> None:
    wp = random_walk(5)
    for make in (time_optimal, time_parameterize):
        a, b = make(wp, ur_limits()), make(wp, ur_limits())
        for x, y in ((a.t, b.t), (a.q, b.q), (a.qd, b.qd), (a.qdd, b.qdd)):
            np.testing.assert_array_equal(x, y)


def test_one_joint_straight_path_matches_the_bang_bang_duration() -> None:
    """0 -> 3 rad at 1 rad/s and 2 rad/s^2: accelerate 0.5 s (0.25 rad), cruise 2.5 rad in
    2.5 s, brake 0.5 s: 3.5 s. Too short to cruise (0 -> 0.5 rad): 2 sqrt(0.5 / 2) = 1 s."""
    limits = JointLimits(np.array([-5.0]), np.array([5.0]), np.array([1.0]), np.array([2.0]))
    for goal, expected in ((3.0, 3.5), (0.5, 1.0)):
        wp = np.array([[0.0], [goal]])
        raw = speed_profile(wp, limits, grid_points=2001)
        assert raw.duration == pytest.approx(expected, rel=1e-3)
        traj = time_optimal(wp, limits)
        # the acceleration ramps add one ramp period, nothing else
        assert traj.duration == pytest.approx(expected + UNLIMITED_JERK_RAMP, rel=2e-3)
        _, q, _, _, _ = dense(traj)
        assert np.all(np.diff(q[:, 0]) >= 0)  # a straight path, never back


def test_one_joint_jerk_limited_close_to_ruckig() -> None:
    """ruckig's time-optimal jerk-limited move is the lower bound; the on-path filter adds
    at most its window (2 a / j)."""
    limits = JointLimits(
        np.array([-5.0]), np.array([5.0]), np.array([1.0]), np.array([2.0]), np.array([20.0])
    )
    wp = np.array([[0.0], [3.0]])
    best = ptp(wp[0], wp[1], limits).duration
    ours = time_parameterize(wp, limits).duration
    assert best <= ours <= best + 2 * 2.0 / 20.0 + 1e-3


def test_tcp_speed_limit_is_respected() -> None:
    links = (0.5, 0.4)

    def tcp(q: np.ndarray) -> np.ndarray:
        a, b = q[:, 0], q[:, 0] + q[:, 1]
        x = links[0] * np.cos(a) + links[1] * np.cos(b)
        y = links[0] * np.sin(a) + links[1] * np.sin(b)
        return np.stack([x, y, np.zeros_like(x)], axis=1)

    wp = np.array([[0.0, 0.3], [0.8, 0.9], [1.6, 0.2], [2.0, -0.6]])
    limits = ur_limits(dof=2, jerk=None)
    free = time_optimal(wp, limits)
    capped = time_optimal(wp, limits, tcp=TcpSpeedLimit(0.3, tcp))
    for traj in (free, capped):
        times = np.arange(0.0, traj.duration, DT)
        q, qd, _ = traj.sample(times)
        a, b = q[:, 0], q[:, 0] + q[:, 1]
        vx = -links[0] * np.sin(a) * qd[:, 0] - links[1] * np.sin(b) * (qd[:, 0] + qd[:, 1])
        vy = links[0] * np.cos(a) * qd[:, 0] + links[1] * np.cos(b) * (qd[:, 0] + qd[:, 1])
        speed = np.hypot(vx, vy)
        if traj is free:
            assert speed.max() > 0.6  # the limit would bind
        else:
            assert speed.max() <= 0.3
            assert speed.max() > 0.29  # and is used
    assert capped.duration > free.duration


@pytest.mark.parametrize("tcp", [None, TcpSpeedLimit(0.3, lambda q: np.c_[q[:, :3]])])
def test_timing_and_bound_on_one_spline_are_each_as_alone(tcp: TcpSpeedLimit | None) -> None:
    """One spline and speed planner for both: the same trajectory as time_parameterize's and
    the same bound as speed_profile's, to the bit (the planner's second solve starts from
    its first)."""
    wp, limits = random_walk(3), ur_limits()
    traj, bound = time_parameterize_and_bound(wp, limits, tcp=tcp)
    alone = time_parameterize(wp, limits, tcp=tcp)
    for a, b in ((traj.t, alone.t), (traj.q, alone.q), (traj.qd, alone.qd)):
        np.testing.assert_array_equal(a, b)
    assert bound == speed_profile(wp, limits, tcp=tcp).duration < traj.duration


def test_both_arms_on_one_time_axis() -> None:
    wp = np.hstack([random_walk(6, count=20), random_walk(7, count=20)])
    limits = ur_limits(dof=12)
    names = [f"{arm}_j{i}" for arm in ("left", "right") for i in range(6)]
    traj = time_parameterize(wp, limits, joint_names=names)
    assert traj.joint_names == tuple(names)
    assert_within(traj, limits, jerk=True)


def test_limits_from_any_object_with_the_attributes() -> None:
    wp = random_walk(8, count=10)
    plain = SimpleNamespace(
        lower=[-7.0] * 6, upper=[7.0] * 6, velocity=[np.pi] * 6, acceleration=[5.0] * 6
    )
    traj = time_optimal(wp, plain)  # type: ignore[arg-type]
    assert_within(traj, ur_limits(jerk=None), jerk=False)
    with pytest.raises(ValueError, match="needs jerk limits"):
        time_parameterize(wp, plain)  # type: ignore[arg-type]
    assert time_parameterize(wp, plain, jerk=40.0).duration > traj.duration  # type: ignore[arg-type]


def test_duplicate_waypoints_are_harmless_and_a_still_path_is_refused() -> None:
    wp = random_walk(9, count=6)
    doubled = np.repeat(wp, 2, axis=0)
    a, b = time_optimal(wp, ur_limits()), time_optimal(doubled, ur_limits())
    assert a.duration == pytest.approx(b.duration)
    with pytest.raises(ValueError, match="all waypoints are the same"):
        time_optimal(np.zeros((3, 6)), ur_limits())


@pytest.mark.parametrize(
    ("waypoints", "message"),
    [
        (np.array([[0.0] * 6, [0.0, 0.0, 7.0, 0.0, 0.0, 0.0]]), "waypoint 1: joint 2 at 7"),
        (np.zeros((3, 5)), r"limits.lower must hold 5 values"),
        (np.zeros(6), r"waypoints must be \(N, n\)"),
    ],
)
def test_bad_waypoints_are_named(waypoints: np.ndarray, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        time_optimal(waypoints, ur_limits())


def test_a_spline_leaving_the_joint_range_is_refused() -> None:
    limits = JointLimits(np.full(2, -1.0), np.full(2, 1.0), np.full(2, 1.0), np.full(2, 1.0))
    # a sharp turn next to the bound: the spline bulges past it
    wp = np.array([[0.0, 0.0], [0.5, 0.0], [0.98, 0.9], [0.5, 0.95], [0.0, 0.9]])
    with pytest.raises(ValueError, match=r"leaves joint 0's range .* between waypoints 1 and 2"):
        time_optimal(wp, limits)


def test_bad_limits_are_named() -> None:
    with pytest.raises(ValueError, match=r"limits\.velocity must be positive"):
        JointLimits(np.zeros(2), np.ones(2), np.array([1.0, 0.0]), np.ones(2))
    with pytest.raises(ValueError, match=r"lower 2\.0 > upper"):
        JointLimits(np.array([2.0]), np.array([1.0]), np.ones(1), np.ones(1))
    with pytest.raises(ValueError, match="jerk limits must be positive"):
        JointLimits(np.zeros(1), np.ones(1), np.ones(1), np.ones(1), np.array([-1.0]))


# -- ruckig: point to point ---------------------------------------------------------------


def test_ptp_synchronises_both_arms_on_a_straight_line() -> None:
    rng = np.random.default_rng(10)
    q0, q1 = rng.uniform(-2, 2, 12), rng.uniform(-2, 2, 12)
    limits = ur_limits(dof=12, jerk=40.0)
    traj = ptp(q0, q1, limits)
    assert_within(traj, limits, jerk=True)
    assert_well_formed(traj, np.vstack([q0, q1]))
    _, q, qd, _, _ = dense(traj)
    # phase-synchronised: every joint the same fraction of its way at every instant
    progress = (q - q0) / (q1 - q0)
    assert np.ptp(progress, axis=1).max() < 1e-9
    # so every joint starts and stops together
    moving = np.abs(qd) > 1e-9
    assert np.all(moving[1:-1].all(axis=1) | ~moving[1:-1].any(axis=1))
    assert traj.duration > 0


def test_ptp_one_joint_matches_the_closed_form() -> None:
    """No jerk limit given: accelerations ramp over UNLIMITED_JERK_RAMP, so the duration is
    the bang-bang one plus one ramp."""
    limits = JointLimits(np.array([-5.0]), np.array([5.0]), np.array([1.0]), np.array([2.0]))
    traj = ptp([0.0], [3.0], limits)
    assert traj.duration == pytest.approx(3.5 + UNLIMITED_JERK_RAMP, abs=1e-9)
    assert_within(traj, limits, jerk=False)


def test_ptp_trajectory_reproduces_ruckig_between_knots() -> None:
    limits = ur_limits(jerk=30.0)
    traj = ptp(np.zeros(6), np.linspace(-1.5, 1.0, 6), limits)
    # between knots each joint is a cubic: the quintic pieces are exact, so the jerk takes
    # only the values 0 and +-j_max of some joint's share
    jerk = traj.jerk(np.arange(0.0, traj.duration, DT))
    assert np.abs(jerk).max() <= 30.0 * (1 + 1e-9)


def test_ptp_refuses_targets_outside_the_range() -> None:
    with pytest.raises(ValueError, match="goal: joint 1 at 9"):
        ptp(np.zeros(6), [0, 9, 0, 0, 0, 0], ur_limits())


def test_ptp_to_where_it_is_is_a_single_point() -> None:
    traj = ptp(np.ones(6), np.ones(6), ur_limits())
    assert len(traj) == 1 and traj.duration == 0.0


# -- ruckig: online re-targeting ----------------------------------------------------------


def test_retargeter_reaches_a_changed_target_within_limits() -> None:
    limits = ur_limits(jerk=60.0)
    gen = retargeter(np.zeros(6), limits, dt=0.002)
    first = np.array([1.0, -0.5, 0.8, 0.0, 0.3, -1.2])
    second = np.array([-0.4, 0.6, 0.2, 1.0, -0.8, 0.5])
    gen.set_target(first)
    states = [gen.state()]
    for _ in range(150):  # 0.3 s toward the first target, then it changes mid-motion
        states.append(gen.step())
    assert not gen.finished
    assert np.abs(states[-1][1]).max() > 0.5  # moving fast when the target changes
    gen.set_target(second)
    for _ in range(5000):
        states.append(gen.step())
        if gen.finished:
            break
    assert gen.finished
    q, qd, qdd = (np.array(x) for x in zip(*states, strict=True))
    np.testing.assert_allclose(q[-1], second, atol=1e-9)
    np.testing.assert_allclose(qd[-1], 0.0, atol=1e-9)
    assert np.all(np.abs(qd) <= limits.velocity * (1 + 1e-9))
    assert np.all(np.abs(qdd) <= limits.acceleration * (1 + 1e-9))
    assert np.all(np.abs(np.diff(qdd, axis=0)) / gen.dt <= 60.0 * (1 + 1e-6))
    # continuous motion: positions follow the velocities
    np.testing.assert_allclose(np.diff(q, axis=0), (qd[1:] + qd[:-1]) / 2 * gen.dt, atol=1e-5)
    # holds still once there
    before = gen.state()[0]
    gen.step()
    np.testing.assert_allclose(gen.state()[0], before, atol=1e-9)


def test_retargeter_refuses_a_target_outside_the_range() -> None:
    gen = retargeter(np.zeros(6), ur_limits())
    with pytest.raises(ValueError, match="target: joint 0 at 7"):
        gen.set_target([7.0, 0, 0, 0, 0, 0])
    with pytest.raises(ValueError, match="dt must be positive"):
        retargeter(np.zeros(6), ur_limits(), dt=0.0)


def test_spline_extremes_are_exact() -> None:
    wp = random_walk(11, count=8)
    path = SplinePath(wp)
    low, high = path.extremes()
    knots = path.knots - path.knots[0]
    for k in range(7):
        piece = path.derivatives(np.linspace(knots[k], knots[k + 1], 100_001))[0]
        assert np.all(piece.min(axis=0) >= low[k] - 1e-9)
        assert np.all(piece.max(axis=0) <= high[k] + 1e-9)
        np.testing.assert_allclose(piece.min(axis=0), low[k], atol=1e-9)
        np.testing.assert_allclose(piece.max(axis=0), high[k], atol=1e-9)


def test_a_solve_after_new_caps_equals_one_from_scratch() -> None:
    """SpeedPlanner re-solves only what changed caps reach: it must not change a thing."""
    from cellengine.motion.topp import SpeedPlanner

    rng = np.random.default_rng(12)
    path = SplinePath(random_walk(12))
    limits = ur_limits()
    planner = SpeedPlanner(path, limits.velocity, limits.acceleration, 300)
    profile = planner.solve()
    cap = np.full(planner.s.size, np.inf)
    for rounds in range(6):
        spots = rng.choice(planner.s.size, size=rng.integers(1, 30), replace=False)
        cap[spots] = np.minimum(cap[spots], profile.x[spots] * rng.uniform(0.3, 1.0, spots.size))
        if rounds == 3:
            cap = cap * 1.1  # and caps that rise
        profile = planner.solve(cap)
        fresh = SpeedPlanner(path, limits.velocity, limits.acceleration, 300).solve(cap)
        np.testing.assert_array_equal(profile.x, fresh.x)
        np.testing.assert_array_equal(profile.u, fresh.u)


def test_time_scaled_trajectory_is_the_same_motion_slower() -> None:
    traj = time_optimal(random_walk(13, count=8), ur_limits())
    slow = traj.time_scaled(2.0)
    assert slow.duration == pytest.approx(2 * traj.duration)
    times = np.linspace(0.0, traj.duration, 777)
    q, qd, qdd = traj.sample(times)
    q2, qd2, qdd2 = slow.sample(2 * times)
    np.testing.assert_allclose(q2, q, atol=1e-9)
    np.testing.assert_allclose(qd2, qd / 2, atol=1e-9)
    np.testing.assert_allclose(qdd2, qdd / 4, atol=1e-9)
    with pytest.raises(ValueError, match="factor must be"):
        traj.time_scaled(0.0)


def test_the_raw_profile_keeps_a_tcp_speed_limit_at_its_grid_points() -> None:
    """A straight TCP path 0.4 m long at most 0.1 m/s takes at least 4 s; the joints alone
    would allow it in well under a second."""

    def tcp(q: np.ndarray) -> np.ndarray:
        return np.stack([q[:, 0], q[:, 1], np.zeros(len(q))], axis=1)  # joints as x, y (m)

    wp = np.array([[0.0, 0.0], [0.2, 0.0], [0.4, 0.0]])
    limits = ur_limits(dof=2, jerk=None)
    free = speed_profile(wp, limits)
    capped = speed_profile(wp, limits, tcp=TcpSpeedLimit(0.1, tcp))
    assert free.duration < 1.0
    assert capped.duration > 4.0 - 1e-6
    assert np.sqrt(capped.x).max() <= 0.1 * (1 + 1e-9)  # s runs along the chords: |dp/ds| = 1
