"""The task allocator (issue #5): time to an optimal mission, and to a feasible one.

Run: .venv/bin/python bench/bench_allocate.py
Problems: tests/test_allocate.py's random_problem, two mirrored robots with a private zone
each and a shared zone between, one handover position; tasks are relocations, weighings
(only robot 1 weighs) and unscrews (robot 1 holds, robot 2 turns the cap), half of their
places in the shared zone, each task after each earlier one with probability 0.25.
Goals: 12 tasks optimal (proved by the exact search) in <= 1 s; 50 tasks a feasible mission
in <= 2 s. Times are the best of 3 runs of `allocate` (building the options included); the
worst over 20 seeds (12 tasks) and 5 seeds (50 tasks) is reported too, and 12 tasks with no
precedence at all (more orders to rule out) for comparison. The 50-task mission is not
proved optimal; its cost over the exact search's lower bound caps how far off it can be.
The cap is loose: 12-task optima are 1.21-1.32x that bound (seeds 0-2).
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # the problem generator and the mission checks live with the tests

from cellengine.allocate import Mission, Problem, allocate, expand  # noqa: E402
from cellengine.allocation.search import compile_problem, lower_bound  # noqa: E402
from tests.test_allocate import check_valid, random_problem  # noqa: E402

REPEATS = 3


def _timed(p: Problem, **kw: int) -> tuple[float, Mission]:
    best = float("inf")
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        m = allocate(p, **kw)
        best = min(best, time.perf_counter() - t0)
    return best, m


def run() -> dict[str, float]:
    out: dict[str, float] = {}
    p12 = random_problem(12, 0)
    t, m = _timed(p12)
    check_valid(p12, m)
    _, h = _timed(p12, exact_limit=0)
    out |= {
        "allocate_12_tasks_s": t,
        "allocate_12_tasks_optimal": float(m.optimal),
        "allocate_12_tasks_cost_m": m.cost,
        "allocate_12_heuristic_over_optimal": h.cost / m.cost,
    }
    runs = [_timed(random_problem(12, seed)) for seed in range(20)]
    out["allocate_12_tasks_worst_of_20_s"] = max(t for t, _ in runs)
    out["allocate_12_tasks_optimal_of_20"] = float(sum(m.optimal for _, m in runs))
    free = [_timed(random_problem(12, seed, p_after=0.0)) for seed in range(5)]
    out["allocate_12_no_precedence_worst_of_5_s"] = max(t for t, _ in free)
    out["allocate_12_no_precedence_optimal_of_5"] = float(sum(m.optimal for _, m in free))
    p50 = random_problem(50, 0)
    t, m = _timed(p50)
    check_valid(p50, m)
    bound = lower_bound(compile_problem(expand(p50)))
    out |= {
        "allocate_50_tasks_s": t,
        "allocate_50_tasks_cost_m": m.cost,
        "allocate_50_tasks_over_lower_bound": m.cost / bound,
    }
    out["allocate_50_tasks_worst_of_5_s"] = max(
        _timed(random_problem(50, seed))[0] for seed in range(5)
    )
    return out


if __name__ == "__main__":
    print(json.dumps(run(), indent=2))
