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
from collections.abc import Callable, Iterator, Mapping, Sequence
from typing import NamedTuple

import numpy as np

from cellengine.arrays import Poses, Vec
from cellengine.execute.failure import FailedAt, Kind
from cellengine.execute.following import followable
from cellengine.execute.refused import NoMoreChoices, Refused
from cellengine.execute.retime import fastest, thinned
from cellengine.execute.winding import rewound
from cellengine.motion.cartesian import (
    ArmInCell,
    CartesianResult,
    Stop,
    cartesian_path,
    closed_chain_path,
    dual_cartesian_path,
)
from cellengine.motion.collision import CollisionChecker, Contact
from cellengine.motion.ik import arm_ik
from cellengine.motion.margins import keeping_clearance
from cellengine.motion.robot import CellModel
from cellengine.motion.speed import tcp_limit
from cellengine.motion.topp import SplinePath
from cellengine.motion.transit import CellChecker, plan_for_arms

Accept = Callable[[Vec], bool]  # a goal configuration -> whether what follows can run from it


class Lookahead(NamedTuple):
    """What follows a transit of one arm, up to its next: its Cartesian poses, and the IK
    branches those segments require of it (following.required)."""

    poses: Poses | None
    on: frozenset[int] | None = None


Ahead = Mapping[str, Lookahead]

PLANNER_SEED = 0  # OMPL is re-seeded per query: the same segment gives the same path
PLANNER_TIME = 1.0  # s per transit query
# Queries per tier of goals (seeds PLANNER_SEED, PLANNER_SEED + 1, ...), the quickest path
# kept: RRTConnect returns the first path it connects, and the simplifier only shortens it
# where it is (in joint-space length, not time). On the cable cell's pick configuration,
# ten seeds give paths of 2.3 to 6.6 s: one query leaves the cycle time to chance.
PLANNER_RUNS = 4
DIRECT_TRIES = 4  # nearest goals tried as a straight joint-space line before planning
# Transit rows are cut into steps of at most this (rad, largest joint) so that the timing
# spline, which passes through every row, stays on the planner's straight segments.
TRANSIT_STEP = 0.1
# ... except at a sharp corner, more so where the timing's thinning drops a short segment's
# row: there the spline cuts the corner (20 mm on a lab cell's transit). A planned path's
# rows are cut finer, halving the step down to this, until the spline keeps what the
# planner kept, checked at states this far apart (L2, rad or m).
FINEST_STEP = TRANSIT_STEP / 8
SPLINE_CHECK_STEP = 0.01


def transit(
    cell: CellModel,
    checker: CollisionChecker,
    goals: Mapping[str, Poses],
    q: Vec,
    accept: Accept | None = None,
    choice: int = 0,
    clearance: float | None = None,
    ahead: Ahead | None = None,
) -> Vec:
    """Whole-cell rows from ``q`` to a configuration putting each arm's TCP at its goal pose
    (4, 4), the arms moving together; the other arms stand. ``clearance`` (m): what the arms
    keep from each other and from the environment on the way (:mod:`~cellengine.motion.margins`;
    less where the start or the goal is closer); None: only collisions are refused.

    Goal configurations are tried in tiers (:func:`_goal_configurations`: every arm on its IK
    branch first), each tier its own query, since a planner given several goals reaches
    whichever it connects to first. ``accept``: whether what comes next can be done from a
    goal configuration (:mod:`~cellengine.execute.preview`); goals it refuses go last. Which
    configuration a pose is reached in decides what the arms can do from there, and only the
    next moves tell.

    ``ahead``: each arm's Cartesian poses after the transit, up to its next one: a joint
    that turns more than a full turn is put on the turn from which they stay within its
    limits (:mod:`~cellengine.execute.winding`); goals on a branch the segments there do
    not require of the arm (:class:`Lookahead`) go last, as goals that cannot follow them.

    ``choice`` > 0: the choice-th goal configuration in that order, and only it (the compiler
    comes back with the next choice when a later segment cannot run from the first);
    :class:`NoMoreChoices` past the last."""
    arms = tuple(goals)
    ahead = {arm: (ahead or {}).get(arm, Lookahead(None)) for arm in arms}
    per_arm = [
        rewound(
            cell,
            arm,
            _required_only(cell, arm, _ik_goals(cell, arm, goals[arm], q), ahead[arm].on),
            ahead[arm].poses,
            q[cell.slices[arm]],
        )
        for arm in arms
    ]
    follows = [
        followable(cell, checker, arm, sols, ahead[arm].poses, q, ahead[arm].on)
        for arm, sols in zip(arms, per_arm, strict=True)
    ]
    tiers = _goal_configurations(cell, arms, per_arm, q, follows)
    free = [[g for g in tier if not checker.in_collision(g)] for tier in tiers]
    targets = {arm: goals[arm][:3, 3] for arm in arms}
    if not any(free):
        contact = checker.check(tiers[0][0])
        raise Refused(
            f"every IK solution of the transit goal of {_names(arms)} is in collision "
            f"(the nearest: {contact})",
            at=FailedAt("collision", tiers[0][0], _pair(contact), targets=targets),
        )
    order = _looking_ahead(free, accept)
    if choice > 0:
        every = [g for tier in order for g in tier]
        if choice >= len(every):
            raise NoMoreChoices(
                f"the transit of {_names(arms)} has no other goal configuration to try "
                f"({len(every)} in all)"
            )
        order = iter([[every[choice]]])
    reason, first = "", None
    for tier in order:
        first = tier[0] if first is None else first
        rows, reason = _reach(cell, checker, arms, q, tier, clearance)
        if rows is not None:
            return rows
    raise Refused(
        f"no collision-free transit for {_names(arms)}: {reason}",
        at=_blocked(checker, q, first, targets),
    )


def _blocked(
    checker: CollisionChecker, q: Vec, goal: Vec | None, targets: Mapping[str, Vec]
) -> FailedAt:
    """Where a transit that found no path shows best: the first contact on the straight
    joint-space line from ``q`` to its nearest goal (the start itself, when it is in
    collision), else the start."""
    contact = None if goal is None else checker.check_segment(q, goal)
    if contact is None:
        return FailedAt("transit", q, targets=targets)
    return FailedAt("transit", contact.q, contact.pair, targets=targets)


def _pair(contact: Contact | None) -> tuple[str, str] | None:
    return None if contact is None else contact.pair


def to_configuration(
    cell: CellModel,
    checker: CollisionChecker,
    arms: Sequence[str],
    q: Vec,
    goal: Vec,
    clearance: float | None = None,
) -> Vec:
    """Whole-cell rows from ``q`` to the configuration ``goal`` (``arms`` move, the others
    stand), keeping ``clearance`` as a transit does; Refused when there is none."""
    rows, reason = _reach(cell, checker, arms, q, [goal], clearance)
    if rows is None:
        raise Refused(f"no collision-free transit for {_names(arms)}: {reason}")
    return rows


def _reach(
    cell: CellModel,
    checker: CollisionChecker,
    arms: Sequence[str],
    q: Vec,
    goals: list[Vec],
    clearance: float | None = None,
) -> tuple[Vec | None, str]:
    """Rows to one of ``goals`` (nearest first): a straight line when it is free, else
    planned; or None and why not. Each keeps ``clearance`` where its ends allow."""
    for goal in goals[:DIRECT_TRIES]:
        if _keeping(checker, clearance, [q, goal]).check_segment(q, goal) is None:
            return _densified(np.vstack([q, goal])), ""
    return _quickest(cell, _keeping(checker, clearance, [q, *goals]), arms, q, goals)


def _quickest(
    cell: CellModel, checker: CellChecker, arms: Sequence[str], q: Vec, goals: list[Vec]
) -> tuple[Vec | None, str]:
    """Rows of the quickest of PLANNER_RUNS planned paths (time-optimal duration; the first
    seed's on a tie), or None and why not. A first query that fails ends it: the others
    would only spend their time limits finding the same."""
    best: tuple[float, Vec] | None = None
    reason = ""
    for run in range(PLANNER_RUNS):
        result = plan_for_arms(
            cell,
            checker,
            arms,
            q,
            np.array(goals),
            seed=PLANNER_SEED + run,
            time_limit=PLANNER_TIME,
        )
        if result.path is None:
            reason = result.reason
            if best is None:
                break
            continue
        rows = _on_spline(result.path, checker)
        if rows is None:
            reason = "the timing spline through the planned path leaves its clearance"
            continue
        duration = max(
            fastest(rows[:, cell.slices[a]], cell.timing_limits(a), tcp_limit(cell, (a,)))
            for a in arms
        )
        if best is None or duration < best[0]:
            best = (duration, rows)
    return (None, reason) if best is None else (best[1], "")


def _keeping(
    checker: CollisionChecker, clearance: float | None, ends: Sequence[Vec]
) -> CellChecker:
    """The checker a transit between ``ends`` keeps ``clearance`` with (one query: its margins
    are lowered only as far as its own ends need)."""
    if clearance is None:
        return checker
    return keeping_clearance(checker, clearance, np.array(ends))


def _looking_ahead(tiers: list[list[Vec]], accept: Accept | None) -> Iterator[list[Vec]]:
    """The tiers with the goals ``accept`` refuses taken out and put last. Lazy: a tier is
    looked at only when the tiers before it led nowhere."""
    deferred: list[Vec] = []
    for tier in tiers:
        if not tier:
            continue
        good = [g for g in tier if accept is None or accept(g)]
        deferred += [g for g in tier if not any(g is x for x in good)]
        if good:
            yield good
    if deferred:
        yield deferred


def _required_only(cell: CellModel, arm: str, sols: Vec, on: frozenset[int] | None) -> Vec:
    """The solutions on the IK branches the segments ahead require (``on``): from a goal
    on another the compiler refuses the first of them (Segment.branches), so it is no
    choice; Refused when there is none."""
    ik = arm_ik(cell.arms[arm])
    if on is None or ik.closed_form is None:
        return sols
    keep = np.array([ik.branch(sol) in on for sol in sols], dtype=bool)
    if not keep.any():
        found = sorted({ik.branch(sol) for sol in sols})
        raise Refused(
            f"the {arm} arm reaches its transit goal on IK branches {found} only; the "
            f"segments after it were checked on branches {sorted(on)}"
        )
    out: Vec = sols[keep]
    return out


def _ik_goals(cell: CellModel, arm: str, T_cell_tcp: Poses, q: Vec) -> Vec:
    seed = q[cell.slices[arm]]
    sols = arm_ik(cell.arms[arm]).solve_all(T_cell_tcp, seed=seed)
    if len(sols) == 0:
        x, y, z = (1000.0 * T_cell_tcp[:3, 3]).tolist()
        raise Refused(
            f"the {arm} arm cannot reach its transit goal at ({x:.1f}, {y:.1f}, {z:.1f}) mm: "
            "no IK solution within its joint limits",
            at=FailedAt("unreachable", q, targets={arm: T_cell_tcp[:3, 3]}),
        )
    return sols


def _goal_configurations(
    cell: CellModel,
    arms: Sequence[str],
    per_arm: Sequence[Vec],
    q: Vec,
    follows: Sequence[Sequence[bool]] | None = None,
) -> list[list[Vec]]:
    """Every combination of the arms' IK solutions as a cell configuration, in tiers by how
    many arms cannot follow their paths ahead from it (``follows``, per arm and solution:
    :mod:`~cellengine.execute.following`), then by how many leave their current IK branch
    (shoulder, elbow and wrist as they are): none first. Within a tier, nearest ``q`` first
    (joint-space distance; ties keep the solvers' order: deterministic).

    The branch first because a Cartesian path never changes branch: an arm that a transit
    flips to the nearest solution in joint space (a shoulder flip can be nearer than staying)
    may find the next Cartesian moves out of that branch's reach, where the branch it came
    from, the one the plan was made from, reaches them."""
    keep = [_same_branch(cell, arm, sols, q) for arm, sols in zip(arms, per_arm, strict=True)]
    follows = follows or [[True] * len(sols) for sols in per_arm]
    out = []
    for combo in itertools.product(*(range(len(sols)) for sols in per_arm)):
        g = q.copy()
        for arm, sols, k in zip(arms, per_arm, combo, strict=True):
            g[cell.slices[arm]] = sols[k]
        stuck = sum(not follows[i][k] for i, k in enumerate(combo))
        flips = sum(not keep[i][k] for i, k in enumerate(combo))
        out.append(((stuck, flips), float(np.linalg.norm(g - q)), g))
    out.sort(key=lambda item: item[:2])
    return [[g for t, _, g in out if t == tier] for tier in sorted({t for t, _, _ in out})]


def _same_branch(cell: CellModel, arm: str, sols: Vec, q: Vec) -> list[bool]:
    """For each IK solution, whether it is on the arm's current branch (always, for an arm
    without a closed form: its solver has no branches)."""
    ik = arm_ik(cell.arms[arm])
    if ik.closed_form is None:
        return [True] * len(sols)
    now = ik.branch(q[cell.slices[arm]])
    return [ik.branch(sol) == now for sol in sols]


def _on_spline(path: Vec, checker: CellChecker) -> Vec | None:
    """Rows along ``path`` whose timing spline (the C2 spline through the thinned rows, as
    the timing builds it for one arm or for the arms together) is free for ``checker`` at
    states SPLINE_CHECK_STEP apart: TRANSIT_STEP apart, halved while it is not, down to
    FINEST_STEP; None below that. A path whose spline keeps it is as it always was."""
    step = TRANSIT_STEP
    while step >= FINEST_STEP:
        rows = _densified(path, step)
        if _spline_free(rows, checker):
            return rows
        step /= 2
    return None


def _spline_free(rows: Vec, checker: CellChecker) -> bool:
    spline = SplinePath(thinned(rows))
    n = int(np.ceil(spline.length / SPLINE_CHECK_STEP)) + 1
    states, _, _ = spline.derivatives(np.linspace(0.0, spline.length, n))
    return not any(checker.in_collision(q) for q in states)


def _densified(path: Vec, step: float = TRANSIT_STEP) -> Vec:
    """The path with rows inserted on each straight segment, at most ``step`` apart."""
    rows = [path[:1]]
    for a, b in itertools.pairwise(path):
        n = max(1, int(np.ceil(np.abs(b - a).max() / step)))
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
    reached = q.copy()
    reached[cell.slices[arm]] = result.q[-1] if len(result.q) else seed
    _refuse_short(result, f"the {arm} arm's Cartesian path", reached, {arm: poses})
    return np.vstack([seed, result.q]), result.fraction


def dual_cartesian(
    cell: CellModel, checker: CollisionChecker, poses: Mapping[str, Poses], q: Vec
) -> tuple[Vec, float]:
    """Whole-cell rows (``q`` first) moving every arm along its poses at once, on one grid
    (each arm at the same fraction of its own path length)."""
    result = dual_cartesian_path(cell, poses, q, check=checker)
    reached = result.q[-1] if len(result.q) else q
    what = f"the Cartesian paths of {_names(tuple(poses))}, followed together,"
    _refuse_short(result, what, reached, poses)
    return np.vstack([q, result.q]), result.fraction


def closed_chain(
    cell: CellModel, checker: CollisionChecker, leader: str, follower: str, poses: Poses, q: Vec
) -> tuple[Vec, float]:
    """Whole-cell rows (``q`` first): the leader's TCP along ``poses``, the follower's keeping
    the relative pose it has at ``q`` (both hands on one object)."""
    result = closed_chain_path(cell, leader, follower, poses, q, check=checker)
    reached = result.q[-1] if len(result.q) else q
    what = f"the closed chain of {leader} (leading) and {follower}"
    _refuse_short(result, what, reached, {leader: poses})
    return np.vstack([q, result.q]), result.fraction


def _refuse_short(result: CartesianResult, what: str, at: Vec, poses: Mapping[str, Poses]) -> None:
    """Refused when the path stops short; ``at``: the whole cell's last configuration
    reached (the report shows the colliding one, for a collision); ``poses``: each arm's
    waypoints (the report marks the first not reached)."""
    stop = result.stop
    if stop is not None:
        raise Refused(
            f"{what} stops at {100.0 * result.fraction:.0f} % of its length: {stop.message}",
            _own(stop),
            _stopped_at(stop, at, poses),
        )


def _stopped_at(stop: Stop, q: Vec, poses: Mapping[str, Poses]) -> FailedAt:
    contact = stop.contact
    if stop.kind == "collision" and isinstance(contact, Contact):
        return FailedAt("collision", contact.q, contact.pair)
    kind: Kind = "limit" if stop.kind in ("limit", "joint_jump") else "unreachable"
    targets = {
        arm: P[min(stop.waypoints.get(arm, stop.waypoint), len(P) - 1)][:3, 3]
        for arm, P in poses.items()
        if stop.arm is None or arm == stop.arm
    }
    return FailedAt(kind, q, targets=targets)


def _own(stop: Stop) -> bool:
    """Whether an arm's own configuration stopped the path: a limit, a jump, its branch out
    of reach, two of its own links meeting."""
    if stop.kind == "collision":  # objects of an arm are named "arm/link"
        return stop.pair is not None and len({n.split("/", 1)[0] for n in stop.pair}) == 1
    return stop.kind != "unreachable"


def _names(arms: Sequence[str]) -> str:
    return " and ".join(arms)
