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
    dt: float = BLOCK_DT,
) -> list[Block]:
    """One robot's blocks over ``traj`` (its axes' columns); ``accel``: each axis'
    acceleration in GRBL (units/s^2, its $120...), for the feeds (see :func:`feed`)."""
    n = max(1, math.ceil(traj.duration / dt - 1e-9))
    times = np.linspace(traj.start_time, traj.end_time, n + 1)
    q, qd, _ = traj.sample(times)
    M = np.column_stack([np.round(a.machine(q), DIGITS) for a in axes])
    # the robot's speed at each cut (machine units/s)
    V = np.linalg.norm(np.column_stack([a.sign * a.scale * qd[:, a.joint] for a in axes]), axis=1)
    limits = np.array(accel if accel is not None else [math.inf] * len(axes), dtype=float)
    entry = 0.0  # GRBL's speed where the block begins (it starts from rest)
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
        unit = np.abs(M[k + 1] - M[k]) / d
        a = float(min(limits[i] / u for i, u in enumerate(unit) if u > 1e-12))
        f = feed(d, t1 - t0, min(entry, float(V[k])), float(V[k + 1]), a)
        words = "".join(f"{x.letter}{v:.{DIGITS}f}" for x, v in zip(axes, target, strict=True))
        out.append(Block(t0, t1, f"G1{words}F{f * 60.0:.1f}", target))
        entry = min(f, float(V[k + 1]))
    return out


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
