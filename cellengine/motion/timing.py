"""Time parameterisation: joint waypoints to timed trajectories, and ruckig moves.

Entry points:

- `time_optimal(waypoints, limits)`: the fastest trajectory along a C2 spline through the
  waypoints within joint velocity and acceleration limits (and an optional TCP speed
  limit). TOPP-RA on the path (topp.py), accelerations ramped over one 2 ms servo period
  so the result is C2, then checked between samples and slowed where needed (jerk.py).
- `time_parameterize(waypoints, limits, jerk=...)`: the same, jerk-limited; what the
  motion layer hands to the executor.
- `ptp(q0, q1, limits)`: ruckig point-to-point, all joints synchronised (otg.py).
- `retargeter(q0, limits)`: ruckig online generation for streaming at a fixed period.

Every trajectory returned is on the path (its samples lie on the spline), starts and ends
at rest, and stays within the limits at any sampling rate (Trajectory.peaks bounds).

"No jerk limit" means accelerations ramp over one 2 ms servo period (otg.UNLIMITED_JERK_RAMP):
a Trajectory is C2, a bang-bang profile is not. With jerk limits j, the on-path filter's
window is 2 a / j (an acceleration flip from +a to -a then ramps at j).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike

from cellengine.arrays import FloatArray
from cellengine.motion import otg
from cellengine.motion.jerk import PathLimits, smooth
from cellengine.motion.topp import SpeedPlanner, SpeedProfile, SplinePath
from cellengine.motion.trajectory import Trajectory

# Grid of the speed profile: points per waypoint interval, within these bounds.
GRID_PER_SEGMENT = 10
LIMIT_ROUNDING = 1e-12  # rad or m
MIN_GRID_POINTS = 101
MAX_GRID_POINTS = 2001


class KinematicLimits(Protocol):
    """Per-joint limits: positions (rad or m), velocity, acceleration (symmetric)."""

    @property
    def lower(self) -> FloatArray: ...
    @property
    def upper(self) -> FloatArray: ...
    @property
    def velocity(self) -> FloatArray: ...
    @property
    def acceleration(self) -> FloatArray: ...


@dataclass(frozen=True)
class JointLimits:
    """Kinematic limits per joint, with optional jerk limits. Any object with `lower`,
    `upper`, `velocity` and `acceleration` (robot.Limits) works where limits are asked
    for; `jerk` is read when present."""

    lower: FloatArray
    upper: FloatArray
    velocity: FloatArray
    acceleration: FloatArray
    jerk: FloatArray | None = None

    def __post_init__(self) -> None:
        resolved = _checked(self)
        for key in ("lower", "upper", "velocity", "acceleration", "jerk"):
            object.__setattr__(self, key, getattr(resolved, key))


@dataclass(frozen=True)
class TcpSpeedLimit:
    """A Cartesian speed limit (m/s) on tool points. `position` maps joint positions
    (M, n) to tool point positions (M, 3), or (M, k, 3) for k tool points (both arms'
    TCPs): batched forward kinematics. Each point's speed stays within `speed`."""

    speed: float
    position: Callable[[FloatArray], FloatArray]


@dataclass(frozen=True)
class _Resolved:
    lower: FloatArray
    upper: FloatArray
    velocity: FloatArray
    acceleration: FloatArray
    jerk: FloatArray | None


def _checked(limits: KinematicLimits, dof: int | None = None) -> _Resolved:
    arrays = {}
    for key in ("lower", "upper", "velocity", "acceleration"):
        try:
            arr = np.asarray(getattr(limits, key), dtype=np.float64)
        except (AttributeError, TypeError, ValueError) as exc:
            raise ValueError(f"limits.{key}: {exc}") from None
        if arr.ndim != 1 or (dof is not None and arr.size != dof):
            want = f"{dof} values" if dof is not None else "one value per joint"
            raise ValueError(f"limits.{key} must hold {want}, got shape {arr.shape}")
        arrays[key] = arr
    size = arrays["velocity"].size
    for key, arr in arrays.items():
        if arr.size != size:
            raise ValueError(f"limits.{key} has {arr.size} values, limits.velocity {size}")
    for key in ("velocity", "acceleration"):
        if not np.all((arrays[key] > 0.0) & np.isfinite(arrays[key])):
            raise ValueError(f"limits.{key} must be positive and finite: {arrays[key].tolist()}")
    if np.any(arrays["lower"] > arrays["upper"]):
        j = int(np.argmax(arrays["lower"] > arrays["upper"]))
        raise ValueError(f"limits: joint {j} has lower {arrays['lower'][j]} > upper")
    raw_jerk = getattr(limits, "jerk", None)
    jerk = None if raw_jerk is None else otg.jerk_or_default(arrays["acceleration"], raw_jerk)
    return _Resolved(jerk=jerk, **arrays)


def _names(joint_names: Sequence[str] | None, dof: int) -> tuple[str, ...]:
    if joint_names is None:
        return otg.default_names(dof)
    names = tuple(joint_names)
    if len(names) != dof:
        raise ValueError(f"{len(names)} joint names for {dof} joints")
    return names


def grid_points_for(waypoint_count: int) -> int:
    """Default size of the speed profile's grid: GRID_PER_SEGMENT points per waypoint
    interval (the path's curvature changes at that scale), within the bounds."""
    wanted = GRID_PER_SEGMENT * max(waypoint_count - 1, 1) + 1
    return int(min(max(wanted, MIN_GRID_POINTS), MAX_GRID_POINTS))


@dataclass(frozen=True)
class _Problem:
    path: SplinePath
    planner: SpeedPlanner
    limits: _Resolved
    names: tuple[str, ...]
    tcp_speed: float | None
    tcp_ds: FloatArray | None


def _problem(
    waypoints: ArrayLike,
    limits: KinematicLimits,
    joint_names: Sequence[str] | None,
    tcp: TcpSpeedLimit | None,
    grid_points: int | None,
) -> _Problem:
    wp = np.asarray(waypoints, dtype=np.float64)
    if wp.ndim != 2:
        raise ValueError(f"waypoints must be (N, n), got shape {wp.shape}")
    lim = _checked(limits, wp.shape[1])
    outside = (wp < lim.lower - LIMIT_ROUNDING) | (wp > lim.upper + LIMIT_ROUNDING)
    if np.any(outside):
        k = int(np.argmax(outside.any(axis=1)))
        otg._check_in_range(f"waypoint {k}", wp[k], lim.lower, lim.upper)
    # a waypoint on a limit can come out of a computation a rounding error past it (-1e-20
    # for a prismatic joint at 0): that is on the limit
    wp = np.clip(wp, lim.lower, lim.upper)
    path = SplinePath(wp)
    planner = SpeedPlanner(
        path, lim.velocity, lim.acceleration, grid_points or grid_points_for(len(path.knots))
    )
    _check_path_in_range(path, lim)
    tcp_ds = None
    if tcp is not None:
        if not (np.isfinite(tcp.speed) and tcp.speed > 0.0):
            raise ValueError(f"TCP speed limit must be positive, got {tcp.speed!r}")
        tcp_ds = _tcp_path_speed(path, planner.s, tcp.position)
    return _Problem(
        path,
        planner,
        lim,
        _names(joint_names, wp.shape[1]),
        None if tcp is None else float(tcp.speed),
        tcp_ds,
    )


class PathOutOfRange(ValueError):
    """The spline through the waypoints bulges past a joint's range between two of them."""


def _check_path_in_range(path: SplinePath, lim: _Resolved) -> None:
    """A cubic spline can bulge past the waypoints: refuse a path that leaves a joint's
    range rather than time it (each piece's extremes, exactly)."""
    low, high = path.extremes()
    outside = (low < lim.lower) | (high > lim.upper)
    if np.any(outside):
        k, j = np.argwhere(outside)[0]
        value = low[k, j] if low[k, j] < lim.lower[j] else high[k, j]
        raise PathOutOfRange(
            f"the spline through the waypoints leaves joint {j}'s range "
            f"[{lim.lower[j]:.6g}, {lim.upper[j]:.6g}] between waypoints {k} and {k + 1} "
            f"(reaching {value:.6g}); add waypoints there"
        )


def _tcp_path_speed(
    path: SplinePath, grid: FloatArray, position: Callable[[FloatArray], FloatArray]
) -> FloatArray:
    """|dp/ds| at each grid point, the largest over the tool points: central differences
    of the forward kinematics over a step far below the grid's."""
    h = 1e-4 * float(grid[1] - grid[0])
    ahead = np.minimum(grid + h, path.length)
    behind = np.maximum(grid - h, 0.0)
    q_ahead, _, _ = path.derivatives(ahead)
    q_behind, _, _ = path.derivatives(behind)
    p = np.asarray(position(np.vstack([q_ahead, q_behind])), dtype=np.float64)
    if p.ndim == 2:
        p = p[:, None, :]
    if p.ndim != 3 or p.shape[0] != 2 * grid.size or p.shape[2] != 3:
        raise ValueError(f"TCP position must return (M, 3) or (M, k, 3), got shape {p.shape}")
    moved = np.linalg.norm(p[: grid.size] - p[grid.size :], axis=2).max(axis=1)
    return np.asarray(moved / (ahead - behind))


def speed_profile(
    waypoints: ArrayLike,
    limits: KinematicLimits,
    *,
    tcp: TcpSpeedLimit | None = None,
    grid_points: int | None = None,
) -> SpeedProfile:
    """The raw TOPP-RA profile along the spline (the figure to compare with toppra):
    limits (and `tcp`) met at the grid points, accelerations bang-bang, not checked in
    between."""
    return _raw_profile(_problem(waypoints, limits, None, tcp, grid_points))


def _raw_profile(problem: _Problem) -> SpeedProfile:
    if problem.tcp_speed is None or problem.tcp_ds is None:
        return problem.planner.solve()
    with np.errstate(divide="ignore"):  # a grid point where the TCPs stand: no cap
        return problem.planner.solve((problem.tcp_speed / problem.tcp_ds) ** 2)


def time_optimal(
    waypoints: ArrayLike,
    limits: KinematicLimits,
    *,
    joint_names: Sequence[str] | None = None,
    tcp: TcpSpeedLimit | None = None,
    grid_points: int | None = None,
) -> Trajectory:
    """The fastest trajectory along the spline through `waypoints` (N, n) within the
    velocity and acceleration limits (and `tcp`), accelerations ramping over one servo
    period. Jerk is not limited: see `time_parameterize`."""
    problem = _problem(waypoints, limits, joint_names, tcp, grid_points)
    return _smoothed(problem, None, otg.UNLIMITED_JERK_RAMP)


def time_parameterize(
    waypoints: ArrayLike,
    limits: KinematicLimits,
    *,
    jerk: ArrayLike | None = None,
    joint_names: Sequence[str] | None = None,
    tcp: TcpSpeedLimit | None = None,
    grid_points: int | None = None,
) -> Trajectory:
    """A jerk-limited trajectory along the spline through `waypoints`: the time-optimal
    profile smoothed on the path so that joint jerks stay within `jerk` (per joint, or
    `limits.jerk`), velocities and accelerations within the limits."""
    return _jerk_limited(_problem(waypoints, limits, joint_names, tcp, grid_points), jerk)


def time_parameterize_and_bound(
    waypoints: ArrayLike,
    limits: KinematicLimits,
    *,
    jerk: ArrayLike | None = None,
    joint_names: Sequence[str] | None = None,
    tcp: TcpSpeedLimit | None = None,
) -> tuple[Trajectory, float]:
    """`time_parameterize`'s trajectory and the duration of `speed_profile` (the bound no
    timing of the path beats), on one spline and speed planner: building them is most of
    the bound's cost."""
    problem = _problem(waypoints, limits, joint_names, tcp, None)
    bound = _raw_profile(problem).duration
    return _jerk_limited(problem, jerk), bound


def _jerk_limited(problem: _Problem, jerk: ArrayLike | None) -> Trajectory:
    if jerk is None and problem.limits.jerk is None:
        raise ValueError("time_parameterize needs jerk limits: pass jerk= or limits.jerk")
    j = (
        problem.limits.jerk
        if jerk is None
        else otg.jerk_or_default(problem.limits.acceleration, jerk)
    )
    assert j is not None
    # a step from +a to -a in path acceleration, averaged over W, ramps at 2 a / W
    window = float(np.max(2.0 * problem.limits.acceleration / j))
    return _smoothed(problem, j, window)


def _smoothed(problem: _Problem, jerk: FloatArray | None, window: float) -> Trajectory:
    lim = problem.limits
    path_limits = PathLimits(
        lim.velocity, lim.acceleration, jerk, problem.tcp_speed, problem.tcp_ds
    )
    return smooth(problem.path, problem.planner, path_limits, window, problem.names)


def ptp(
    q0: ArrayLike,
    q1: ArrayLike,
    limits: KinematicLimits,
    *,
    jerk: ArrayLike | None = None,
    joint_names: Sequence[str] | None = None,
) -> Trajectory:
    """ruckig's time-optimal jerk-limited point-to-point move, every joint (both arms
    when given 12) starting and finishing together. Jerk: `jerk`, else `limits.jerk`,
    else accelerations ramping over one servo period."""
    lim = _checked(limits)
    j = otg.jerk_or_default(lim.acceleration, jerk if jerk is not None else lim.jerk)
    return otg.ptp(q0, q1, lim.lower, lim.upper, lim.velocity, lim.acceleration, j, joint_names)


def retargeter(
    q0: ArrayLike,
    limits: KinematicLimits,
    *,
    dt: float = 0.002,
    jerk: ArrayLike | None = None,
) -> otg.Retargeter:
    """A ruckig online generator at period `dt` starting at rest at q0 (see otg.Retargeter)."""
    lim = _checked(limits)
    j = otg.jerk_or_default(lim.acceleration, jerk if jerk is not None else lim.jerk)
    return otg.Retargeter(q0, lim.lower, lim.upper, lim.velocity, lim.acceleration, j, dt)
