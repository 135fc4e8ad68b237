"""Time parameterisation against toppra 0.6.10 on the same waypoints, limits and path.

Run: .venv/bin/python bench/bench_timing.py   (prints JSON; bench/run_all.py collects it)

Workload: 50 waypoints x 6 joints, a seeded random walk (start uniform in [-1, 1] rad,
steps uniform in [-0.3, 0.3] rad per joint), within UR5e-like limits: positions +-2 pi,
velocity pi rad/s, acceleration 5 rad/s^2, jerk 50 rad/s^3 where jerk is limited.
Five seeds; times are medians over all runs, ratios medians over the seeds (max noted).

Paths: ours is the not-a-knot cubic spline through the waypoints with chord-length knots.
toppra's SplineInterpolator is the same kind of spline; given the same knots it is the same
path, so `timing_duration_ratio_vs_toppra` compares both on it. toppra's usual call uses
knots evenly spaced in [0, 1], another path: the `_toppra_path` figures run our TOPP on
that spline too.

What is timed:
- timing_50wp_ms: `time_optimal` end to end: spline, TOPP-RA, the C2 trajectory checked
  between samples and slowed where needed, a Trajectory out.
- timing_topp_profile_ms: the TOPP-RA profile alone (spline, grid, passes): the work
  toppra's figure stands for.
- peer_toppra_*_ms: toppra's constraints, TOPPRA instance and compute_trajectory (its
  default cubic-spline output) at 100 and 1000 grid points.
- timing_worst_limit_ratio / peer_toppra_1000_worst_limit_ratio: the largest |velocity|
  or |acceleration| over its limit, ours from Trajectory.peaks (bounds between samples),
  toppra's output at 1 ms samples (its limits hold at grid points only, and its spline
  output is refitted through them).
"""

from __future__ import annotations

import json
import statistics
import time
from collections.abc import Callable
from functools import partial
from typing import Any

import numpy as np

from cellengine.motion.jerk import PathLimits, smooth
from cellengine.motion.otg import UNLIMITED_JERK_RAMP
from cellengine.motion.timing import (
    JointLimits,
    ptp,
    retargeter,
    speed_profile,
    time_optimal,
    time_parameterize,
)
from cellengine.motion.topp import FloatArray, SpeedPlanner, SplinePath

SEEDS = (0, 1, 2, 3, 4)
REPEATS = 15
DOF = 6
LIMITS = JointLimits(
    lower=np.full(DOF, -2 * np.pi),
    upper=np.full(DOF, 2 * np.pi),
    velocity=np.full(DOF, np.pi),
    acceleration=np.full(DOF, 5.0),
    jerk=np.full(DOF, 50.0),
)


def waypoints(seed: int, count: int = 50) -> FloatArray:
    rng = np.random.default_rng(seed)
    start = rng.uniform(-1.0, 1.0, DOF)
    return np.vstack([start, start + np.cumsum(rng.uniform(-0.3, 0.3, (count - 1, DOF)), 0)])


def median_ms(fn: Callable[[], Any], repeats: int = REPEATS) -> tuple[float, Any]:
    fn()  # warm: imports, caches
    times = []
    out = None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return 1e3 * statistics.median(times), out


class _ToppraPath:
    """toppra's SplineInterpolator seen through our path protocol (for our TOPP on it)."""

    def __init__(self, spline: Any) -> None:
        self._spline = spline
        self._breakpoints = np.asarray(spline.ss_waypoints[1:-1], dtype=np.float64)

    @property
    def length(self) -> float:
        return float(self._spline.duration)

    @property
    def breakpoints(self) -> FloatArray:
        return self._breakpoints

    def derivatives(self, s: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        return self._spline(s), self._spline(s, 1), self._spline(s, 2)

    def derivatives3(self, s: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        return self._spline(s), self._spline(s, 1), self._spline(s, 2), self._spline.cspl(s, 3)


def toppra_run(wp: FloatArray, knots: FloatArray, grid: int) -> Any:
    import toppra
    import toppra.algorithm as algo
    import toppra.constraint as constraint

    path = toppra.SplineInterpolator(knots, wp)
    vlim = np.vstack([-LIMITS.velocity, LIMITS.velocity]).T
    alim = np.vstack([-LIMITS.acceleration, LIMITS.acceleration]).T
    instance = algo.TOPPRA(
        [constraint.JointVelocityConstraint(vlim), constraint.JointAccelerationConstraint(alim)],
        path,
        gridpoints=np.linspace(0.0, path.duration, grid),
    )
    return instance.compute_trajectory(), path


def worst_ratio(traj: Any, duration: float) -> float:
    """The largest |velocity| / limit or |acceleration| / limit at 1 ms samples."""
    t = np.arange(0.0, duration, 1e-3)
    vel = np.abs(traj(t, 1)) / LIMITS.velocity
    acc = np.abs(traj(t, 2)) / LIMITS.acceleration
    return float(max(vel.max(), acc.max()))


def run() -> dict[str, float]:
    import toppra

    toppra.setup_logging("WARNING")
    ours_ms, topp_ms, jerk_ms, peer_100_ms, peer_1000_ms = [], [], [], [], []
    ratio, raw_ratio, ratio_toppra_path, peer_100_ratio, jerk_ratio = [], [], [], [], []
    peer_worst, ours_worst = [], []
    for seed in SEEDS:
        wp = waypoints(seed)
        knots = SplinePath(wp).knots
        ms, ours = median_ms(partial(time_optimal, wp, LIMITS))
        ours_ms.append(ms)
        ms, raw = median_ms(partial(speed_profile, wp, LIMITS))
        topp_ms.append(ms)
        ms, jerky = median_ms(partial(time_parameterize, wp, LIMITS))
        jerk_ms.append(ms)
        ms, (peer, _) = median_ms(partial(toppra_run, wp, knots, 1000), 5)
        peer_1000_ms.append(ms)
        ms, (peer100, _) = median_ms(partial(toppra_run, wp, knots, 100))
        peer_100_ms.append(ms)
        ratio.append(ours.duration / peer.duration)
        raw_ratio.append(raw.duration / peer.duration)
        peer_100_ratio.append(peer100.duration / peer.duration)
        jerk_ratio.append(jerky.duration / ours.duration)
        peer_worst.append(worst_ratio(peer, peer.duration))
        peaks = ours.peaks()
        ours_worst.append(
            max(
                (peaks.velocity / LIMITS.velocity).max(),
                (peaks.acceleration / LIMITS.acceleration).max(),
            )
        )
        # toppra's usual call: knots evenly spaced in [0, 1]; our TOPP on that same spline
        peer_even, spline = toppra_run(wp, np.linspace(0.0, 1.0, len(wp)), 1000)
        tp = _ToppraPath(spline)
        planner = SpeedPlanner(tp, LIMITS.velocity, LIMITS.acceleration, 10 * (len(wp) - 1) + 1)
        names = tuple(f"joint_{i + 1}" for i in range(DOF))
        on_theirs = smooth(
            tp,
            planner,
            PathLimits(LIMITS.velocity, LIMITS.acceleration),
            UNLIMITED_JERK_RAMP,
            names,
        )
        ratio_toppra_path.append(on_theirs.duration / peer_even.duration)

    start, goal = np.zeros(DOF), np.array([1.0, -0.5, 0.8, -1.2, 0.3, 2.0])
    ptp_ms, _ = median_ms(lambda: ptp(start, goal, LIMITS), 200)
    both = np.concatenate([goal, -goal])
    limits12 = JointLimits(*(np.tile(getattr(LIMITS, k), 2) for k in LIMITS.__dataclass_fields__))
    ptp12_ms, _ = median_ms(lambda: ptp(np.zeros(12), both, limits12), 200)
    gen = retargeter(start, LIMITS)
    gen.set_target(goal)
    step_ms, _ = median_ms(gen.step, 2000)

    return {
        "timing_50wp_ms": statistics.median(ours_ms),
        "timing_topp_profile_ms": statistics.median(topp_ms),
        "timing_jerk_limited_50wp_ms": statistics.median(jerk_ms),
        "peer_toppra_1000_ms": statistics.median(peer_1000_ms),
        "peer_toppra_100_ms": statistics.median(peer_100_ms),
        "timing_duration_ratio_vs_toppra": statistics.median(ratio),
        "timing_duration_ratio_vs_toppra_max": max(ratio),
        "timing_raw_profile_ratio_vs_toppra": statistics.median(raw_ratio),
        "timing_duration_ratio_vs_toppra_on_toppra_path": statistics.median(ratio_toppra_path),
        "peer_toppra_100_duration_ratio": statistics.median(peer_100_ratio),
        "timing_jerk_limited_duration_ratio": statistics.median(jerk_ratio),
        "timing_worst_limit_ratio": max(ours_worst),
        "peer_toppra_1000_worst_limit_ratio": max(peer_worst),
        # load-independent views: the machine is shared and figures move +-30 % with load
        "timing_50wp_speedup_vs_toppra_1000": statistics.median(peer_1000_ms)
        / statistics.median(ours_ms),
        "timing_50wp_speedup_vs_toppra_100": statistics.median(peer_100_ms)
        / statistics.median(ours_ms),
        "ptp_6dof_us": 1e3 * ptp_ms,
        "ptp_12dof_us": 1e3 * ptp12_ms,
        "retarget_step_us": 1e3 * step_ms,
    }


if __name__ == "__main__":
    print(json.dumps(run(), indent=2))
