"""One segment's arm paths to joint rows: geometry only, no timing.

Each function starts from a whole-cell configuration ``q`` and returns joint rows that begin
with the moving arms at ``q`` (so the rows of consecutive motions join up), or raises
:class:`~cellengine.execute.refused.Refused` saying why in motion terms.

- transit: IK solutions of the goal pose (every branch the limits allow, :meth:`ArmIK.solve_all`),
  the nearest collision-free one reached in a straight joint-space line when the checker proves
  that line free, else planned with OMPL (:func:`plan_for_arms`), one arm or both as one
  12-DOF problem;
- cartesian: one arm (:func:`cartesian_path`, the other arms standing), both arms on one grid
  (:func:`dual_cartesian_path`), or a closed chain (:func:`closed_chain_path`). A path short of
  its end (fraction < 1) is refused with the path's own stop message.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence

import numpy as np
from numpy.typing import NDArray

from cellengine.execute.refused import Refused
from cellengine.motion.cartesian import (
    ArmInCell,
    CartesianResult,
    cartesian_path,
    closed_chain_path,
    dual_cartesian_path,
)
from cellengine.motion.collision import CollisionChecker
from cellengine.motion.ik import arm_ik
from cellengine.motion.robot import CellModel
from cellengine.motion.transit import plan_for_arms

Vec = NDArray[np.float64]
Poses = NDArray[np.float64]

PLANNER_SEED = 0  # OMPL is re-seeded per query: the same segment gives the same path
PLANNER_TIME = 2.0  # s per transit query
DIRECT_TRIES = 4  # nearest goals tried as a straight joint-space line before planning
# Transit rows are cut into steps of at most this (rad, largest joint) so that the timing
# spline, which passes through every row, stays on the planner's straight segments.
TRANSIT_STEP = 0.1


def transit(
    cell: CellModel,
    checker: CollisionChecker,
    goals: Mapping[str, Poses],
    q: Vec,
) -> Vec:
    """Whole-cell rows from ``q`` to a configuration putting each arm's TCP at its goal pose
    (4, 4), the arms moving together; the other arms stand."""
    arms = tuple(goals)
    per_arm = [_ik_goals(cell, arm, goals[arm], q) for arm in arms]
    candidates = _goal_configurations(cell, arms, per_arm, q)
    free = [g for g in candidates if not checker.in_collision(g)]
    if not free:
        contact = checker.check(candidates[0])
        raise Refused(
            f"every IK solution of the transit goal of {_names(arms)} is in collision "
            f"(the nearest: {contact})"
        )
    for goal in free[:DIRECT_TRIES]:
        if checker.check_segment(q, goal) is None:
            return _densified(np.vstack([q, goal]))
    result = plan_for_arms(
        cell, checker, arms, q, np.array(free), seed=PLANNER_SEED, time_limit=PLANNER_TIME
    )
    if result.path is None:
        raise Refused(f"no collision-free transit for {_names(arms)}: {result.reason}")
    return _densified(result.path)


def _ik_goals(cell: CellModel, arm: str, T_cell_tcp: Poses, q: Vec) -> Vec:
    seed = q[cell.slices[arm]]
    sols = arm_ik(cell.arms[arm]).solve_all(T_cell_tcp, seed=seed)
    if len(sols) == 0:
        x, y, z = (1000.0 * T_cell_tcp[:3, 3]).tolist()
        raise Refused(
            f"the {arm} arm cannot reach its transit goal at ({x:.1f}, {y:.1f}, {z:.1f}) mm: "
            "no IK solution within its joint limits"
        )
    return sols


def _goal_configurations(
    cell: CellModel, arms: Sequence[str], per_arm: Sequence[Vec], q: Vec
) -> list[Vec]:
    """Every combination of the arms' IK solutions as a cell configuration, nearest ``q``
    first (joint-space distance; ties keep the solvers' order, so the result is
    deterministic)."""
    out = []
    for combo in itertools.product(*per_arm):
        g = q.copy()
        for arm, sol in zip(arms, combo, strict=True):
            g[cell.slices[arm]] = sol
        out.append(g)
    out.sort(key=lambda g: float(np.linalg.norm(g - q)))
    return out


def _densified(path: Vec) -> Vec:
    """The path with rows inserted on each straight segment, at most TRANSIT_STEP apart."""
    rows = [path[:1]]
    for a, b in itertools.pairwise(path):
        n = max(1, int(np.ceil(np.abs(b - a).max() / TRANSIT_STEP)))
        f = np.arange(1, n + 1)[:, None] / n
        rows.append(a + f * (b - a))
    out: Vec = np.vstack(rows)
    return out


def cartesian(
    cell: CellModel, checker: CollisionChecker, arm: str, poses: Poses, q: Vec
) -> tuple[Vec, float]:
    """One arm's joint rows (``q``'s first) along its TCP poses, the other arms standing at
    ``q``; and the fraction reached (always 1: short paths are refused)."""
    seed = q[cell.slices[arm]]
    result = cartesian_path(cell.arms[arm], poses, seed, check=ArmInCell(checker, cell, arm, q))
    _refuse_short(result, f"the {arm} arm's Cartesian path")
    return np.vstack([seed, result.q]), result.fraction


def dual_cartesian(
    cell: CellModel, checker: CollisionChecker, poses: Mapping[str, Poses], q: Vec
) -> tuple[Vec, float]:
    """Whole-cell rows (``q`` first) moving every arm along its poses at once, on one grid
    (each arm at the same fraction of its own path length)."""
    result = dual_cartesian_path(cell, poses, q, check=checker)
    _refuse_short(result, f"the Cartesian paths of {_names(tuple(poses))}, followed together,")
    return np.vstack([q, result.q]), result.fraction


def closed_chain(
    cell: CellModel, checker: CollisionChecker, leader: str, follower: str, poses: Poses, q: Vec
) -> tuple[Vec, float]:
    """Whole-cell rows (``q`` first): the leader's TCP along ``poses``, the follower's keeping
    the relative pose it has at ``q`` (both hands on one object)."""
    result = closed_chain_path(cell, leader, follower, poses, q, check=checker)
    _refuse_short(result, f"the closed chain of {leader} (leading) and {follower}")
    return np.vstack([q, result.q]), result.fraction


def _refuse_short(result: CartesianResult, what: str) -> None:
    if result.stop is not None:
        raise Refused(
            f"{what} stops at {100.0 * result.fraction:.0f} % of its length: {result.stop.message}"
        )


def _names(arms: Sequence[str]) -> str:
    return " and ".join(arms)
