"""Which robot does what: the task allocator of the cooperative lab platform, generalised.

Build an ``AllocationProblem`` (robots with skills, starts and reach; zones; handover
positions; tasks made of motion primitives, with precedence and blockers), then ``allocate``
it. Building the options (``expand``) is separate from searching them, so both can be
inspected.

The mission minimises the distance the robots travel, summed: between tasks (the paper's
cost) and within them, where handovers and alliances make it differ. Up to
``exact_limit`` tasks (relocations included) an A* search proves the minimum; beyond, or if
it would expand more than ``max_expansions`` states, a heuristic (greedy construction,
re-insertion of tasks, seeded shakes) gives a feasible mission (``optimal`` False). Same
problem, same mission.
"""

from __future__ import annotations

from cellengine.allocation.mission import Entry, Mission, build_mission
from cellengine.allocation.model import (
    AllocationError,
    AllocationProblem,
    AnyOf,
    Blocker,
    Point,
    Primitive,
    Robot,
    Task,
    Zone,
)
from cellengine.allocation.options import Action, Expanded, Option, Stint, expand
from cellengine.allocation.search import compile_problem, exact, heuristic

__all__ = [
    "Action",
    "AllocationError",
    "AllocationProblem",
    "AnyOf",
    "Blocker",
    "Entry",
    "Expanded",
    "Mission",
    "Option",
    "Point",
    "Primitive",
    "Robot",
    "Stint",
    "Task",
    "Zone",
    "allocate",
    "expand",
]

EXACT_LIMIT = 16
MAX_EXPANSIONS = 30_000  # about 3 s at worst on a 2-core laptop


def allocate(
    problem: AllocationProblem,
    *,
    exact_limit: int = EXACT_LIMIT,
    max_expansions: int = MAX_EXPANSIONS,
) -> Mission:
    """The mission of least travel (provably, when ``optimal``). Raises ValueError naming the
    task and what is missing when no alliance can do a task."""
    ex = expand(problem)
    c = compile_problem(ex)
    best = heuristic(c)
    proved = exact(c, best, max_expansions) if len(c.ids) <= exact_limit else None
    optimal = proved is not None
    best = proved or best
    order = [c.ids[t] for t in best.order]
    chosen = {c.ids[t]: ex.options[c.ids[t]][k] for t, k in enumerate(best.choice)}
    return build_mission(ex, order, chosen, optimal, "exact" if optimal else "heuristic")
