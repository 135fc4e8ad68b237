"""A timed trajectory as GRBL G-code blocks, one robot's axes.

The trajectory is cut every ``BLOCK_DT`` (the knots' times do not matter to GRBL): each piece
is a ``G1`` to where the robot is at its end, at the feed that covers it in its time, so GRBL,
which plans its own acceleration within the limits the driver checked it has ($120...),
plays the blocks on the trajectory's timing. A piece in which the robot does not move is a
``G4`` dwell of its time (GRBL holds in place, and waits for the blocks before it to end).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from cellengine.arrays import Vec
from cellengine.motion.trajectory import Trajectory

BLOCK_DT = 0.05  # s of trajectory per block: 20 blocks/s, ~0.9 s in GRBL's buffers
STILL = 1e-3  # machine units (mm, deg): a block shorter than this is a dwell
DIGITS = 3  # GRBL's 0.001 mm
JUNCTION_DEVIATION = 0.01  # mm, GRBL's default $11
SPLITS = 2  # a block at a bend halved at most this many times (to 12.5 ms)


@dataclass(frozen=True)
class AxisMap:
    """A joint of the cell's q as a GRBL axis: machine = offset + sign x scale x q."""

    joint: int  # index in the cell's q
    letter: str  # X, Y, Z, A
    sign: float
    offset: float  # GRBL's units
    scale: float  # GRBL units per joint unit: 1000 (m to mm) or 180/pi (rad to deg)

    def machine(self, q: Vec) -> Vec:
        return self.offset + self.sign * self.scale * np.asarray(q)[..., self.joint]

    def joint_value(self, machine: float) -> float:
        return (machine - self.offset) / (self.sign * self.scale)


@dataclass(frozen=True)
class Block:
    start: float  # s, program time the robot begins it
    end: float
    line: str
    target: tuple[float, ...]  # machine position at its end, in the axes' order


def blocks(
    traj: Trajectory,
    axes: Sequence[AxisMap],
    accel: Sequence[float] | None = None,
    deviation: float = JUNCTION_DEVIATION,
    dt: float = BLOCK_DT,
) -> list[Block]:
    """One robot's blocks over ``traj`` (its axes' columns); ``accel``: each axis'
    acceleration in GRBL (units/s^2, its $120...), ``deviation``: its junction deviation
    ($11, mm), for the feeds (see :func:`feed`)."""
    limits = np.array(accel if accel is not None else [math.inf] * len(axes), dtype=float)
    times = _cuts(traj, axes, limits, deviation, dt)
    n = len(times) - 1
    q, qd, _ = traj.sample(times)
    M = np.column_stack([np.round(a.machine(q), DIGITS) for a in axes])
    # the robot's speed at each cut (machine units/s)
    V = _speeds(qd, axes)
    entry = 0.0  # GRBL's speed where the block begins (it starts from rest)
    units = [_unit(M[k + 1] - M[k]) for k in range(n)]
    out: list[Block] = []
    for k in range(n):
        t0, t1 = float(times[k]), float(times[k + 1])
        d = float(np.linalg.norm(M[k + 1] - M[k]))
        target = tuple(float(v) for v in M[k + 1])
        if d < STILL:
            if out and out[-1].line.startswith("G4"):  # one dwell for a stretch at rest
                t0 = out.pop().start
            out.append(Block(t0, t1, f"G4P{t1 - t0:.3f}", target))
            entry = 0.0
            continue
        a = _accel(units[k], limits)
        # GRBL's speeds at the block's corners: what the plan has there, no more than its
        # junction deviation lets it turn at
        nxt = units[k + 1] if k + 1 < n else None
        exit_speed = float(V[k + 1])
        if nxt is not None:
            exit_speed = min(
                exit_speed, junction(units[k], nxt, min(a, _accel(nxt, limits)), deviation)
            )
        f = feed(d, t1 - t0, min(entry, float(V[k])), exit_speed, a)
        words = "".join(f"{x.letter}{v:.{DIGITS}f}" for x, v in zip(axes, target, strict=True))
        out.append(Block(t0, t1, f"G1{words}F{f * 60.0:.1f}", target))
        entry = min(f, exit_speed)
    return out


def _cuts(
    traj: Trajectory, axes: Sequence[AxisMap], limits: Vec, deviation: float, dt: float
) -> Vec:
    """Where the trajectory is cut into blocks: every ``dt``, and, where the path bends
    more at a cut than GRBL may turn at the plan's speed there (its junction deviation),
    the blocks on either side halved, up to SPLITS times: shorter chords of a curve turn
    less at each junction."""
    n = max(1, math.ceil(traj.duration / dt - 1e-9))
    times = np.linspace(traj.start_time, traj.end_time, n + 1)
    for _ in range(SPLITS):
        q, qd, _ = traj.sample(times)
        M = np.column_stack([a.machine(q) for a in axes])
        V = np.linalg.norm(
            np.column_stack([a.sign * a.scale * qd[:, a.joint] for a in axes]), axis=1
        )
        units = [_unit(M[k + 1] - M[k]) for k in range(len(times) - 1)]
        split = set()
        for k in range(1, len(times) - 1):
            a, b = units[k - 1], units[k]
            if a is None or b is None:
                continue
            if junction(a, b, min(_accel(a, limits), _accel(b, limits)), deviation) < V[k]:
                split |= {k - 1, k}
        if not split:
            break
        mids = [0.5 * (times[k] + times[k + 1]) for k in sorted(split)]
        times = np.sort(np.concatenate([times, mids]))
    return times


def _speeds(qd: Vec, axes: Sequence[AxisMap]) -> Vec:
    """The robot's speed (machine units/s) at each row of joint velocities ``qd``."""
    speeds: Vec = np.linalg.norm(
        np.column_stack([a.sign * a.scale * qd[:, a.joint] for a in axes]), axis=1
    )
    return speeds


def _unit(v: Vec) -> Vec | None:
    n = float(np.linalg.norm(v))
    return None if n < STILL else np.asarray(v) / n


def _accel(unit: Vec | None, limits: Vec) -> float:
    if unit is None:
        return math.inf
    return float(min(limits[i] / abs(u) for i, u in enumerate(unit) if abs(u) > 1e-12))


def junction(a: Vec | None, b: Vec | None, accel: float, deviation: float) -> float:
    """GRBL's speed limit where block ``a`` turns into ``b`` (their unit vectors), from its
    junction deviation: 0 at a reversal or a stop, unlimited straight on."""
    if a is None or b is None:
        return 0.0
    cos = -float(np.dot(a, b))  # GRBL's convention: -1 straight on
    if cos > 0.999999:
        return 0.0
    if cos < -0.999999 or not math.isfinite(accel):
        return math.inf
    sin_half = math.sqrt(0.5 * (1.0 - cos))
    return math.sqrt(accel * deviation * sin_half / (1.0 - sin_half))


def feed(d: float, dt: float, entry: float, exit: float, accel: float) -> float:
    """The feed (units/s) at which GRBL covers ``d`` in ``dt``: it enters at ``entry``,
    speeds up or slows at ``accel`` to the feed, and leaves at ``exit`` (its planner's
    trapezoid). The block's average speed would be too slow wherever the plan accelerates,
    GRBL falling behind at every block. Where no feed makes it (an acceleration past
    GRBL's), the one that takes least time."""
    average = d / dt
    if not math.isfinite(accel):
        return average

    def covered(f: float) -> float:
        up = max(f - entry, 0.0) ** 2 / (2.0 * accel)
        down = max(f - exit, 0.0) ** 2 / (2.0 * accel)
        return f * dt - up - down

    lo = average
    hi = max(average, entry, exit) + 2.0 * accel * dt  # past the top of covered()
    if covered(lo) >= d:
        return lo
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        # covered() rises to its top and falls after: keep to the rising side
        rising = covered(mid + 1e-9) >= covered(mid)
        if covered(mid) >= d or not rising:
            hi = mid
        else:
            lo = mid
    return hi
