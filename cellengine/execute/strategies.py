"""The execution strategies: how one segment's arm paths become joint rows, in parts.

- ``split`` (the published one): two Cartesian paths are planned each on its own, the other
  arm standing where it is, and split where one arm's waypoint comes within a threshold of the
  other arm (:mod:`cellengine.execute.split`); the parts run one after the other, each planned
  from where the previous one left the arms.
- ``sync``: both arms as one 12-DOF group, following both Cartesian paths together on one grid
  (:func:`~cellengine.motion.cartesian.dual_cartesian_path`).
- ``async``: each arm planned on its own, the arms before it (in the segment's order)
  standing where they end and those after it where they start; the scheduler
  (:mod:`cellengine.execute.schedule`) starts each as soon as it is safe.

What every strategy shares: a transit of both arms is one 12-DOF query (one planner proves the
pair free; planning each arm against the other standing would free neither), except under
async, whose point is that the arms move on their own. A segment whose arms are coupled (a
closed chain, or a distance to keep while both move) is always solved on one grid, whatever
the strategy: only one time law for both keeps the coupling (the published method too follows
one arm's waypoints with the other there). A transit of one arm and a Cartesian path of the
other are solved apart.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from cellengine.arrays import Vec
from cellengine.execute import solve
from cellengine.execute.refused import Refused
from cellengine.execute.solve import Accept, Ahead
from cellengine.execute.split import SPLIT_THRESHOLD, split_point
from cellengine.motion.collision import CollisionChecker
from cellengine.motion.ik import arm_ik
from cellengine.motion.robot import CellModel
from cellengine.program import ArmPath, Segment

Strategy = Literal["split", "sync", "async"]
STRATEGIES: tuple[Strategy, ...] = ("split", "sync", "async")
Solved = Literal["still", "one_arm", "together", "apart"]


@dataclass(frozen=True)
class Part:
    """Joint rows of a piece of a segment, before timing.

    ``rows``: each moving arm's joint rows, the start first, in the segment's path order.
    ``coupled``: the whole-cell rows when the arms were solved on one grid (row i of every arm
    belongs to one moment), else None. ``fraction``: each Cartesian arm's path fraction (a
    transit has none; a short path is refused before a Part exists, so these are 1)."""

    start: Vec
    rows: Mapping[str, Vec]
    coupled: Vec | None
    fraction: Mapping[str, float]
    solved: Solved
    split_at: Mapping[str, int] = field(default_factory=dict)  # waypoint index per arm

    def end(self, cell: CellModel) -> Vec:
        if self.coupled is not None:
            out: Vec = self.coupled[-1].copy()
            return out
        q = self.start.copy()
        for arm, r in self.rows.items():
            q[cell.slices[arm]] = r[-1]
        return q


def solve_segment(
    cell: CellModel,
    checker: CollisionChecker,
    segment: Segment,
    q: Vec,
    strategy: Strategy,
    threshold: float = SPLIT_THRESHOLD,
    accept: Accept | None = None,
    choice: int = 0,
    clearance: float | None = None,
    ahead: Ahead | None = None,
) -> list[Part]:
    """The parts of ``segment`` from the cell configuration ``q``. ``accept``: whether the
    segments after this one can run from a configuration: a transit prefers goals it accepts.
    ``choice``: which goal configuration a transit takes (0: the first that works; see
    solve.transit). ``clearance``: what transits keep (m; None: only collisions refused).
    ``ahead``: each arm's Cartesian poses up to its next transit (solve.transit)."""
    paths = _by_arm(cell, segment)
    if not paths:
        return [Part(q, {}, None, {}, "still")]
    kinds = {p.kind for p in paths.values()}
    if segment.closed_chain is not None:
        return [_closed_chain(cell, checker, segment.closed_chain, paths, q)]
    if len(paths) == 1:
        return [
            _apart(
                cell,
                checker,
                paths,
                q,
                "one_arm",
                accept=accept,
                choice=choice,
                clearance=clearance,
                ahead=ahead,
            )
        ]
    coupled = segment.keep_distance is not None
    if kinds == {"transit"}:
        goals = {a: p.poses[-1] for a, p in paths.items()}
        if strategy == "async":
            return [_async_transit(cell, checker, paths, q, accept, choice, clearance, ahead)]
        rows = solve.transit(cell, checker, goals, q, accept, choice, clearance, ahead)
        return [_coupled_part(cell, q, rows, {}, tuple(paths))]
    if kinds == {"cartesian"} and (strategy == "sync" or coupled):
        return [_cartesian_together(cell, checker, paths, q)]
    if kinds == {"cartesian"} and strategy == "split":
        return _split(cell, checker, paths, q, threshold)
    # async: each arm against those before it standing where they end (see _apart)
    async_ = strategy == "async"
    return [
        _apart(
            cell,
            checker,
            paths,
            q,
            "apart",
            prioritised=async_,
            accept=accept,
            choice=choice,
            clearance=clearance,
            ahead=ahead,
        )
    ]


def _async_transit(
    cell: CellModel,
    checker: CollisionChecker,
    paths: Mapping[str, ArmPath],
    q: Vec,
    accept: Accept | None,
    choice: int,
    clearance: float | None,
    ahead: Ahead | None,
) -> Part:
    """A transit of two arms under async: each on its own (prioritised), unless that leaves
    an arm on an IK branch its segments ahead do not require, or finds no goal at all (the
    arm before it standing at its goal can take the only free ones): then both as one, as
    the other strategies plan it (merged on one time law: Compiler._assembled). Only for the
    first choice: the compiler's next choices (``choice`` > 0) are the apart plan's
    alternatives, each as it is, whatever branch it takes."""
    try:
        part = _apart(
            cell, checker, paths, q, "apart", prioritised=True, accept=accept, choice=choice,
            clearance=clearance, ahead=ahead,
        )  # fmt: skip
    except Refused as e:
        if choice > 0:
            raise
        apart: Part | Refused = e
    else:
        if choice > 0 or not _off_ahead(cell, part, ahead):
            return part
        apart = part
    goals = {a: p.poses[-1] for a, p in paths.items()}
    try:
        rows = solve.transit(cell, checker, goals, q, accept, choice, clearance, ahead)
    except Refused:
        if isinstance(apart, Refused):
            raise apart from None
        return apart
    return _coupled_part(cell, q, rows, {}, tuple(paths))


def _off_ahead(cell: CellModel, part: Part, ahead: Ahead | None) -> bool:
    """Whether an arm of ``part`` ends on an IK branch its segments ahead do not require."""
    for arm, rows in part.rows.items():
        on = (ahead or {}).get(arm)
        ik = arm_ik(cell.arms[arm])
        if on is None or on.on is None or ik.closed_form is None:
            continue
        if ik.branch(rows[-1]) not in on.on:
            return True
    return False


def _by_arm(cell: CellModel, segment: Segment) -> dict[str, ArmPath]:
    for what, pair in (
        ("closed_chain", segment.closed_chain),
        ("keep_distance", segment.keep_distance),
    ):
        for arm in pair or ():
            if arm not in cell.arms:
                raise Refused(
                    f"{what} names an unknown arm '{arm}' (the cell has {', '.join(cell.arms)})"
                )
    out: dict[str, ArmPath] = {}
    for p in segment.paths:
        if p.arm not in cell.arms:
            raise Refused(f"unknown arm '{p.arm}' (the cell has {', '.join(cell.arms)})")
        if p.arm in out:
            raise Refused(f"the {p.arm} arm has two paths in one segment")
        out[p.arm] = p
    return out


def _closed_chain(
    cell: CellModel,
    checker: CollisionChecker,
    chain: tuple[str, str],
    paths: Mapping[str, ArmPath],
    q: Vec,
) -> Part:
    leader, follower = chain
    path = paths.get(leader)
    if path is None or path.kind != "cartesian":
        raise Refused(f"a closed chain needs a Cartesian path of its leader, the {leader} arm")
    rows, fraction = solve.closed_chain(cell, checker, leader, follower, path.poses, q)
    return _coupled_part(cell, q, rows, {leader: fraction, follower: fraction}, chain)


def _cartesian_together(
    cell: CellModel, checker: CollisionChecker, paths: Mapping[str, ArmPath], q: Vec
) -> Part:
    rows, fraction = solve.dual_cartesian(cell, checker, {a: p.poses for a, p in paths.items()}, q)
    return _coupled_part(cell, q, rows, {a: fraction for a in paths}, tuple(paths))


def _coupled_part(
    cell: CellModel, q: Vec, rows: Vec, fraction: Mapping[str, float], arms: tuple[str, ...]
) -> Part:
    per_arm = {a: rows[:, cell.slices[a]] for a in arms}
    return Part(q, per_arm, rows, dict(fraction), "together")


def _apart(
    cell: CellModel,
    checker: CollisionChecker,
    paths: Mapping[str, ArmPath],
    q: Vec,
    solved: Solved,
    *,
    prioritised: bool = False,
    accept: Accept | None = None,
    choice: int = 0,
    clearance: float | None = None,
    ahead: Ahead | None = None,
) -> Part:
    """Each arm on its own from ``q``, the other arms standing there (the published way).

    ``prioritised`` (LaValle's prioritised planning): each arm is planned with the arms
    before it standing where they end, the arms after it where they start. Then running the
    arms one after the other is free by construction, so the async scheduler, which can always
    fall back to that, never meets an arm whose goal is taken by another's."""
    rows: dict[str, Vec] = {}
    fraction: dict[str, float] = {}
    here = q.copy()
    for arm, p in paths.items():
        if p.kind == "transit":
            found = solve.transit(
                cell, checker, {arm: p.poses[-1]}, here, accept, choice, clearance, ahead
            )
            rows[arm] = found[:, cell.slices[arm]]
        else:
            rows[arm], fraction[arm] = solve.cartesian(cell, checker, arm, p.poses, here)
        if prioritised:
            here[cell.slices[arm]] = rows[arm][-1]
    return Part(q, rows, None, fraction, solved)


def _split(
    cell: CellModel,
    checker: CollisionChecker,
    paths: Mapping[str, ArmPath],
    q: Vec,
    threshold: float,
) -> list[Part]:
    """The published loop: split, plan the first parts apart, move on from their end."""
    left = {a: np.asarray(p.poses) for a, p in paths.items()}
    done = {a: 0 for a in paths}  # waypoints of each arm already in earlier parts
    parts: list[Part] = []
    while any(len(w) for w in left.values()):
        tcp = {a: cell.arms[a].fk(q[cell.slices[a]])[:3, 3] for a in left if len(left[a])}
        point = split_point({a: w for a, w in left.items() if len(w)}, tcp, threshold)
        cut = {a: len(w) for a, w in left.items()}
        if point is not None:
            cut.update(point.index)
        now = {
            a: ArmPath(a, "cartesian", _at_least_two(cell, a, q, w[: cut[a]]))
            for a, w in left.items()
            if cut[a] > 0
        }
        part = _apart(cell, checker, now, q, "apart")
        if point is not None:
            part = Part(
                part.start,
                part.rows,
                None,
                part.fraction,
                "apart",
                {a: done[a] + cut[a] for a in left},
            )
        parts.append(part)
        q = part.end(cell)
        for a in left:
            done[a] += cut[a]
            left[a] = left[a][cut[a] :]
    return parts


def _at_least_two(cell: CellModel, arm: str, q: Vec, W: Vec) -> Vec:
    """An ArmPath needs two poses: a one-waypoint piece gets the arm's own pose first (the
    Cartesian path starts there anyway)."""
    if len(W) >= 2:
        return W
    out: Vec = np.concatenate([cell.arms[arm].fk(q[cell.slices[arm]])[None], W])
    return out
