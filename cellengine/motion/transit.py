"""Free-space (transit) moves with OMPL: one arm or both together, to a configuration or to
any of a set of goal configurations (e.g. IK solutions sampled from a Task Space Region).

Building the request is separate from solving it. The validity of states is a callable, so
the planner does not depend on how collisions are checked. Every query re-seeds OMPL's
random number generator, so the same request gives the same path in any process.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from ompl import base as ob
from ompl import geometric as og
from ompl import util as ou

from cellengine.errors import known

Vec = NDArray[np.float64]
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
    step: float = 0.05  # joint-space step (L2 over all joints) between states OMPL checks
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
        budget = deadline - time.perf_counter()
        if budget <= 0:
            break
        # OMPL's seed must be positive; re-seeded for every query, so any process agrees
        ou.RNG.setSeed(req.seed * 7919 + attempt + 1)
        path, status, dt_plan, dt_simplify = _solve(req, valid, goals, budget)
        plan_time, simplify_time = plan_time + dt_plan, simplify_time + dt_simplify
        if path is None:
            return _failed(
                f"{req.planner}: {status} within {req.time_limit:g} s", counter, plan_time
            )
        bad = _first_bad_segment(path, segment_valid)
        if bad is None:
            reached = int(np.argmin(np.linalg.norm(np.array(goals) - path[-1], axis=1)))
            index = next(k for k, g in enumerate(req.goals) if np.array_equal(g, goals[reached]))
            return TransitResult(path, "", index, plan_time, simplify_time, counter[0])
        reason = f"segment {bad} of the planned path failed the final collision check"
    return _failed(reason or f"{req.planner}: out of time", counter, plan_time)


def _solve(
    req: TransitRequest, valid: Callable[[ob.State], bool], goals: list[Vec], budget: float
) -> tuple[Vec | None, str, float, float]:
    """One OMPL query: (path or None, why, planning seconds, simplification seconds)."""
    n = len(req.start)
    si = _space_information(req, valid)
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
        return None, "no path found", plan_time, 0.0
    path = pdef.getSolutionPath()
    t1 = time.perf_counter()
    if req.simplify:
        og.PathSimplifier(si).simplifyMax(path)
    simplify_time = time.perf_counter() - t1
    states = [path.getState(i) for i in range(path.getStateCount())]
    return np.array([[s[j] for j in range(n)] for s in states]), "", plan_time, simplify_time


def _first_bad_segment(path: Vec, segment_valid: SegmentValid | None) -> int | None:
    if segment_valid is None:
        return None
    return next((i for i in range(len(path) - 1) if not segment_valid(path[i], path[i + 1])), None)


def _space_information(
    req: TransitRequest, valid: Callable[[ob.State], bool]
) -> ob.SpaceInformation:
    n = len(req.start)
    space = ob.RealVectorStateSpace(n)
    bounds = ob.RealVectorBounds(n)
    for i in range(n):
        bounds.setLow(i, float(req.lower[i]))
        bounds.setHigh(i, float(req.upper[i]))
    space.setBounds(bounds)
    si = ob.SpaceInformation(space)
    si.setStateValidityChecker(valid)
    extent = math.sqrt(float(np.sum((req.upper - req.lower) ** 2)))
    si.setStateValidityCheckingResolution(min(1.0, req.step / extent))
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
