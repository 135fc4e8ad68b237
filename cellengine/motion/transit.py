"""Free-space (transit) moves with OMPL: one arm or both together, to a configuration or to
any of a set of goal configurations (e.g. IK solutions sampled from a Task Space Region).

Building the request is separate from solving it. The validity of states is a callable, so
the planner does not depend on how collisions are checked. Every query re-seeds OMPL's
random number generator, so the same request gives the same path in any process.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike
from ompl import base as ob
from ompl import geometric as og
from ompl import util as ou

from cellengine.arrays import Vec
from cellengine.errors import known
from cellengine.motion.robot import CellModel

StateValid = Callable[[Vec], bool]
SegmentValid = Callable[[Vec, Vec], bool]

# OMPL geometric planners callable by name; RRTConnect is the default.
PLANNERS = (
    "RRTConnect",
    "RRT",
    "RRTstar",
    "InformedRRTstar",
    "SORRTstar",
    "AORRTC",
    "BITstar",
    "PRM",
    "PRMstar",
    "KPIECE1",
    "BKPIECE1",
    "LBKPIECE1",
    "FMT",
    "BFMT",
)

ou.setLogLevel(ou.LOG_NONE)  # OMPL's own log lines are not for our users; results say why


@dataclass(frozen=True)
class TransitRequest:
    start: Vec  # (n,)
    goals: Vec  # (k, n): reaching any one of them is success
    lower: Vec  # (n,) joint bounds for the search
    upper: Vec
    planner: str = "RRTConnect"
    time_limit: float = 1.0  # seconds
    seed: int = 0
    simplify: bool = True
    step: float = 0.1  # joint-space step (L2 over all joints) between states OMPL checks
    # search inside the box around start and goals widened by this (rad or m) first, the
    # whole joint range on the last attempt: a smaller space samples where the moves are
    box_margin: float | None = 1.0
    attempts: int = 3  # a path refused by the final segment check is planned again

    def __post_init__(self) -> None:
        n = len(self.start)
        for name in ("lower", "upper"):
            if np.shape(getattr(self, name)) != (n,):
                raise ValueError(
                    f"{name} must have shape ({n},), got {np.shape(getattr(self, name))}"
                )
        if np.ndim(self.goals) != 2 or np.shape(self.goals)[1] != n or len(self.goals) == 0:
            raise ValueError(
                f"goals must have shape (k, {n}) with k >= 1, got {np.shape(self.goals)}"
            )
        if self.planner not in PLANNERS:
            raise ValueError(f"unknown planner '{self.planner}'" + known(PLANNERS))
        if not self.time_limit > 0 or not self.step > 0:
            raise ValueError("time_limit and step must be positive")


def request(
    start: ArrayLike,
    goals: ArrayLike,
    lower: ArrayLike,
    upper: ArrayLike,
    **options: object,
) -> TransitRequest:
    """A request with arrays converted and a single goal accepted as (n,)."""
    g = np.atleast_2d(np.asarray(goals, dtype=float))
    return TransitRequest(
        np.asarray(start, dtype=float),
        g,
        np.asarray(lower, dtype=float),
        np.asarray(upper, dtype=float),
        **options,  # type: ignore[arg-type]
    )


@dataclass(frozen=True)
class TransitResult:
    path: Vec | None  # (m, n) waypoints from start to the reached goal; None on failure
    reason: str  # empty on success, else why it failed
    goal_index: int  # which goal was reached (-1 on failure)
    plan_time: float  # seconds in the planner
    simplify_time: float  # seconds in path simplification
    checks: int  # state validity checks made

    @property
    def ok(self) -> bool:
        return self.path is not None


def plan_transit(
    req: TransitRequest, is_valid: StateValid, segment_valid: SegmentValid | None = None
) -> TransitResult:
    """Plan from ``req.start`` to one of ``req.goals``. ``segment_valid``, when given, is the
    final word on each segment of the returned path (e.g. a conservative collision check
    that no sample can slip past); a path it refuses is a failure, never returned."""
    n = len(req.start)
    counter = [0]

    def valid(state: ob.State) -> bool:
        counter[0] += 1
        return bool(is_valid(np.array([state[i] for i in range(n)])))

    if not is_valid(req.start):
        return _failed("the start configuration is in collision or out of bounds", counter)
    goals = [g for g in req.goals if _inside(g, req) and is_valid(g)]
    if not goals:
        return _failed(f"all {len(req.goals)} goal configuration(s) are invalid", counter)
    deadline = time.perf_counter() + req.time_limit
    plan_time = simplify_time = 0.0
    reason = ""
    for attempt in range(req.attempts):
        # a share of what is left, so a search box without a way through leaves time for more
        budget = (deadline - time.perf_counter()) / (req.attempts - attempt)
        if budget <= 0:
            break
        # OMPL's seed must be positive; re-seeded for every query, so any process agrees
        ou.RNG.setSeed(req.seed * 7919 + attempt + 1)
        last = attempt == req.attempts - 1
        lower, upper = _search_bounds(req, goals, whole_range=last)
        paths, dt_plan, dt_simplify = _solve(req, valid, goals, budget, lower, upper)
        plan_time, simplify_time = plan_time + dt_plan, simplify_time + dt_simplify
        if not paths:
            reason = f"{req.planner}: no path found within {req.time_limit:g} s"
            continue
        # the simplified path first; shortcuts can graze an obstacle between OMPL's checked
        # states, and then the planner's own path, whose segments are short, often passes
        for path in paths:
            bad = _first_bad_segment(path, segment_valid)
            if bad is None:
                return TransitResult(
                    path, "", _goal_index(req, goals, path), plan_time, simplify_time, counter[0]
                )
            reason = f"segment {bad} of the planned path failed the final collision check"
    return _failed(reason or f"{req.planner}: out of time", counter, plan_time)


def _goal_index(req: TransitRequest, goals: list[Vec], path: Vec) -> int:
    reached = goals[int(np.argmin(np.linalg.norm(np.array(goals) - path[-1], axis=1)))]
    return next(k for k, g in enumerate(req.goals) if np.array_equal(g, reached))


def _search_bounds(req: TransitRequest, goals: list[Vec], whole_range: bool) -> tuple[Vec, Vec]:
    if whole_range or req.box_margin is None:
        return req.lower, req.upper
    points = np.vstack([req.start, *goals])
    lower = np.maximum(req.lower, points.min(axis=0) - req.box_margin)
    upper = np.minimum(req.upper, points.max(axis=0) + req.box_margin)
    return lower, upper


def _solve(
    req: TransitRequest,
    valid: Callable[[ob.State], bool],
    goals: list[Vec],
    budget: float,
    lower: Vec,
    upper: Vec,
) -> tuple[list[Vec], float, float]:
    """One OMPL query: the simplified path and the planner's own (none when no path was
    found), planning seconds, simplification seconds."""
    n = len(req.start)
    si = _space_information(req.step, lower, upper, valid)
    pdef = ob.ProblemDefinition(si)
    pdef.addStartState(_state(si, req.start))
    goal_states = ob.GoalStates(si)
    for g in goals:
        goal_states.addState(_state(si, g))
    pdef.setGoal(goal_states)
    planner = getattr(og, req.planner)(si)
    planner.setProblemDefinition(pdef)
    planner.setup()
    t0 = time.perf_counter()
    planner.solve(budget)
    plan_time = time.perf_counter() - t0
    if not pdef.hasExactSolution():
        return [], plan_time, 0.0
    path = pdef.getSolutionPath()
    raw = _waypoints(path, n)
    if not req.simplify:
        return [raw], plan_time, 0.0
    t1 = time.perf_counter()
    og.PathSimplifier(si).simplifyMax(path)
    simplify_time = time.perf_counter() - t1
    return [_waypoints(path, n), raw], plan_time, simplify_time


def _waypoints(path: og.PathGeometric, n: int) -> Vec:
    states = [path.getState(i) for i in range(path.getStateCount())]
    return np.array([[s[j] for j in range(n)] for s in states])


def _first_bad_segment(path: Vec, segment_valid: SegmentValid | None) -> int | None:
    if segment_valid is None:
        return None
    return next((i for i in range(len(path) - 1) if not segment_valid(path[i], path[i + 1])), None)


def _space_information(
    step: float, lower: Vec, upper: Vec, valid: Callable[[ob.State], bool]
) -> ob.SpaceInformation:
    n = len(lower)
    space = ob.RealVectorStateSpace(n)
    bounds = ob.RealVectorBounds(n)
    for i in range(n):
        bounds.setLow(i, float(lower[i]))
        bounds.setHigh(i, float(upper[i]))
    space.setBounds(bounds)
    si = ob.SpaceInformation(space)
    si.setStateValidityChecker(valid)
    extent = math.sqrt(float(np.sum((upper - lower) ** 2)))
    si.setStateValidityCheckingResolution(min(1.0, step / extent))
    si.setup()
    return si


def _state(si: ob.SpaceInformation, q: Vec) -> ob.State:
    s = si.allocState()  # states from the space information: ob.State() cannot be built here
    for i, v in enumerate(q):
        s[i] = float(v)
    return s


def _inside(q: Vec, req: TransitRequest) -> bool:
    return bool(np.all(q >= req.lower) and np.all(q <= req.upper))


def _failed(reason: str, counter: list[int], plan_time: float = 0.0) -> TransitResult:
    return TransitResult(None, reason, -1, plan_time, 0.0, counter[0])


class CellChecker(Protocol):
    def in_collision(self, q: Vec) -> bool: ...
    def check_segment(self, q0: Vec, q1: Vec) -> object | None: ...


def plan_for_arms(
    cell: CellModel,
    checker: CellChecker,
    arms: Sequence[str],
    start: ArrayLike,
    goals: ArrayLike,
    **options: object,
) -> TransitResult:
    """Plan the joints of ``arms`` (one arm, or both together as one 12-DOF problem) from the
    cell configuration ``start`` to any of ``goals`` (cell configurations; only the planned
    arms' joints are read); the other arms stay where ``start`` has them. The returned path
    holds whole cell configurations, each segment proved free by ``checker.check_segment``."""
    unknown = [a for a in arms if a not in cell.arms]
    if unknown or not arms:
        raise ValueError(f"unknown arm(s) {unknown}" + known(cell.arms))
    full = np.asarray(start, dtype=float)
    cols = np.concatenate([np.arange(cell.nq)[cell.slices[a]] for a in arms])

    def whole(q: Vec) -> Vec:
        out = full.copy()
        out[cols] = q
        return out

    sub_goals = np.atleast_2d(np.asarray(goals, dtype=float))[:, cols]
    req = request(
        full[cols], sub_goals, cell.limits.lower[cols], cell.limits.upper[cols], **options
    )
    result = plan_transit(
        req,
        lambda q: not checker.in_collision(whole(q)),
        lambda a, b: checker.check_segment(whole(a), whole(b)) is None,
    )
    if result.path is None:
        return result
    path = np.array([whole(q) for q in result.path])
    return TransitResult(
        path, "", result.goal_index, result.plan_time, result.simplify_time, result.checks
    )
