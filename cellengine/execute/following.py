"""Which of a transit's goal configurations can follow the arm's Cartesian paths after it.

A Cartesian path never changes IK branch, and the cable skills keep an arm on Cartesian paths
from one transit to its next through many segments (RouteCable slides the routing hand from
guide to guide). Near the arm's base, a tool turned to a guide can meet the arm's own shoulder
on one branch and not on another, guides after the transit that chose it. Before a transit
commits to a goal, each goal's branch is followed over the arm's poses up to its next transit
(every ``STRIDE``-th, as :mod:`~cellengine.execute.winding` samples them): a branch that
leaves the arm's reach or brings the arm within the checker's clearance of itself there
cannot run them. Only the arm's own links and tool are measured: where the other arm and the
cell will be is the compiler's to find out.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Collection, Iterable

import numpy as np

from cellengine.arrays import Poses, Vec
from cellengine.motion.collision import DEFAULT_CLEARANCE, CollisionChecker
from cellengine.motion.ik import arm_ik
from cellengine.motion.robot import CellModel
from cellengine.motion.scene import Pair
from cellengine.program import Segment

STRIDE = 4  # poses: as winding.STRIDE, 8 deg or 20 mm between samples at most
# m: where a sample comes this near the clearance, the poses between it and the next are
# checked too (a tool turning past the shoulder dips below it between samples)
NEAR = 0.010


def followable(
    cell: CellModel,
    checker: CollisionChecker,
    arm: str,
    sols: Vec,
    poses: Poses | None,
    q: Vec,
    on: frozenset[int] | None = None,
) -> list[bool]:
    """For each of ``sols`` (k, n): whether its IK branch follows ``poses`` (the arm's poses
    up to its next transit) within reach and clear of itself, the other joints as in ``q``,
    and is one of ``on`` (:func:`required`) when given. All True for an arm without branches
    (solved numerically) or without poses ahead and nothing required."""
    ik = arm_ik(cell.arms[arm])
    if (poses is None and on is None) or len(sols) == 0 or ik.closed_form is None:
        return [True] * len(sols)
    branches = {ik.branch(sol) for sol in sols} & (set(range(8)) if on is None else set(on))
    if poses is not None:
        branches, _ = surviving(cell, checker, arm, poses, q, branches)
    return [ik.branch(sol) in branches for sol in sols]


def required(segments: Iterable[Segment], arm: str) -> frozenset[int] | None:
    """The IK branches ``segments`` require of ``arm`` (Segment.branches), from the first
    (a transit of it) up to its next transit; None when they require none."""
    out: frozenset[int] | None = None
    for k, segment in enumerate(segments):
        if k > 0 and any(p.arm == arm and p.kind == "transit" for p in segment.paths):
            break
        on = segment.branches_of(arm)
        if on is not None:
            out = on if out is None else out & on
    return out


def surviving(
    cell: CellModel,
    checker: CollisionChecker,
    arm: str,
    poses: Poses,
    q: Vec,
    branches: Collection[int] = range(8),
) -> tuple[set[int], tuple[float, Pair]]:
    """Which of ``branches`` follow ``poses`` (every STRIDE-th and the last, and every pose
    between two samples where either comes within NEAR of the clearance) within reach and
    the checker's clearance of the arm itself, the other joints as in ``q``; and the closest
    the arm came to itself on a branch that did not (inf when none came too close). Every
    branch survives for an arm solved numerically (it has none)."""
    ik = arm_ik(cell.arms[arm])
    alive, nearest = set(branches), (math.inf, ("", ""))
    here = np.array(q, dtype=float)
    rows: dict[int, Vec | None] = {}

    def distance(i: int, k: int) -> tuple[float, Pair] | None:
        """Branch k's distance to itself at pose i (-inf: out of reach); None: no IK."""
        if i not in rows:
            rows[i] = ik.by_branch(poses[i])
        row = rows[i]
        if row is None:
            return None
        if np.isnan(row[k]).any():
            return -math.inf, ("", "")
        here[cell.slices[arm]] = row[k]
        return checker.distance(here, between=(arm, arm))

    samples = sorted({*range(0, len(poses), STRIDE), len(poses) - 1})
    before: dict[int, float] = {}
    for a, b in itertools.pairwise([samples[0], *samples]):
        for k in sorted(alive):
            # between two samples, each pose where either comes near
            found = distance(b, k)
            if found is None:
                return alive, nearest
            near = min(found[0], before.get(k, math.inf)) < DEFAULT_CLEARANCE + NEAR
            checked = [found, *(distance(i, k) for i in range(a + 1, b) if near)]
            worst = min((f for f in checked if f is not None), key=lambda f: f[0])
            before[k] = found[0]
            if worst[0] < DEFAULT_CLEARANCE:
                alive.discard(k)
                if worst[0] > -math.inf:
                    nearest = min(nearest, worst)
        if not alive:
            break
    return alive, nearest


def touching(
    cell: CellModel,
    checker: CollisionChecker,
    arm: str,
    poses: Poses,
    q: Vec,
    branches: Collection[int],
    keep: float = 0.0,
) -> dict[int, Pair]:
    """Which of ``branches`` put ``arm`` (its links, its tool, what it holds) in contact with
    the cell's environment (or within ``keep`` m of it) at some of ``poses`` (every STRIDE-th
    and the last), the other joints as in ``q``, each with the first such pair: a branch
    whose upper arm passes through a fixture reaches the pose clear of itself all the same
    (:func:`surviving`)."""
    ik = arm_ik(cell.arms[arm])
    out: dict[int, Pair] = {}
    if ik.closed_form is None:
        return out
    here = np.array(q, dtype=float)
    for i in sorted({*range(0, len(poses), STRIDE), len(poses) - 1}):
        row = ik.by_branch(poses[i])
        if row is None:
            break
        for k in sorted(set(branches) - set(out)):
            if np.isnan(row[k]).any():
                continue  # out of reach there: surviving's to say
            here[cell.slices[arm]] = row[k]
            d, pair = checker.distance(here, between=(arm, None))
            if d <= 0.0 or d < keep:
                out[k] = pair
    return out
