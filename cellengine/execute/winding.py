"""Which turn of a wrist a transit leaves it on.

A joint whose range spans more than a full turn (a UR's wrist 3 turns 2 pi either way) reaches
a goal pose at angles 2 pi apart. Inverse kinematics gives the one nearest where the joint is;
the Cartesian paths after the transit then turn it further, and a route that keeps turning
one way runs it into its limit many segments later (the cable skills turn the routing hand
with every guide), where no choice of the search within reach can undo it. Before a transit
commits to a goal, each such joint is put on the turn from which the arm's paths up to its
next transit stay within the joint's limits: the paths are followed by inverse kinematics
from the goal (every ``STRIDE``-th pose, each seeded with the one before, as a Cartesian path
is followed) and the joint's excursion is read off them.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from cellengine.arrays import Poses, Vec
from cellengine.motion.ik import arm_ik
from cellengine.motion.robot import CellModel
from cellengine.program import Segment

STRIDE = 4  # poses: a Cartesian path turns at most 2 deg per pose, so 8 deg between samples
MARGIN = math.radians(10.0)  # kept from the limit: the paths between samples, the timing


def ahead(following: Sequence[Segment], arm: str) -> Poses | None:
    """``arm``'s poses on its Cartesian paths after this segment, up to its next transit (a
    closed chain's too); None when it has none."""
    out: list[Poses] = []
    for seg in following:
        paths = [p for p in seg.paths if p.arm == arm]
        if any(p.kind == "transit" for p in paths):
            break
        out += [p.poses for p in paths]
    return np.concatenate(out) if out else None


def rewound(cell: CellModel, arm: str, sols: Vec, poses: Poses | None, q_arm: Vec) -> Vec:
    """Each of ``sols`` (k, n) with its multi-turn joints moved by whole turns, within their
    limits, so that following ``poses`` from it keeps them MARGIN inside their limits (the
    least overshoot when no turn does); of the turns that do, the one nearest ``q_arm``."""
    a = cell.arms[arm]
    lower, upper = np.asarray(a.limits.lower, float), np.asarray(a.limits.upper, float)
    multi = np.flatnonzero(upper - lower > 2.0 * math.pi + 1e-9)
    if poses is None or len(multi) == 0 or len(sols) == 0:
        return sols
    out = np.array(sols, dtype=float)
    for i, sol in enumerate(out):
        swing = _excursion(cell, arm, sol, poses)
        if swing is None:
            continue
        for j in multi:
            out[i, j] = _best_turn(sol[j], swing[0][j], swing[1][j], lower[j], upper[j], q_arm[j])
    return out


def _excursion(cell: CellModel, arm: str, sol: Vec, poses: Poses) -> tuple[Vec, Vec] | None:
    """How far below and above its value in ``sol`` each joint goes following ``poses``
    from it (unwrapped, as a continuous path turns it); None where the poses leave the
    solver's reach (the compiler reports that itself)."""
    ik = arm_ik(cell.arms[arm])
    sampled = [*poses[::STRIDE], poses[-1]]
    q = np.array(sol, dtype=float)
    lo, hi = np.zeros_like(q), np.zeros_like(q)
    for T in sampled:
        nxt = ik.solve(T, q)
        if nxt is None:
            return None
        q = q + _wrapped(nxt - q)
        d = q - sol
        lo, hi = np.minimum(lo, d), np.maximum(hi, d)
    return lo, hi


def _wrapped(d: Vec) -> Vec:
    out: Vec = (d + math.pi) % (2.0 * math.pi) - math.pi
    return out


def _best_turn(w: float, lo: float, hi: float, lower: float, upper: float, now: float) -> float:
    """The angle w + 2 pi k within [lower, upper] whose excursion [w + lo, w + hi] overshoots
    [lower + MARGIN, upper - MARGIN] least, the nearest ``now`` among equals."""
    turns = [w + 2.0 * math.pi * k for k in range(-3, 4)]
    turns = [t for t in turns if lower <= t <= upper]

    def overshoot(t: float) -> float:
        return max(0.0, lower + MARGIN - (t + lo)) + max(0.0, (t + hi) - (upper - MARGIN))

    return min(turns, key=lambda t: (round(overshoot(t), 9), abs(t - now)), default=w)
