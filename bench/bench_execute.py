"""The executor on the cable-routing cell (issue #4): compile time and the merges' cycle times.

Run: .venv/bin/python bench/bench_execute.py
Plan: the hand-made segments of tests/execute/scenes.py (a transit of both arms, a Cartesian
line, a dual Cartesian move, a closed chain, a kept-distance arc), compiled with the split
strategy. Until skills/cable.py turns plans into segments, that is the plan timed here.
Merges: every segment where both arms move (those segments, plus two-arm lines beside lines
and beside a corner, and the crossing the split is for), under split and sync; per
segment the joint and the published merge are timed on the same rows. Ratios are sums of
durations over sums of bounds: ``bound`` is the slower arm's time-optimal duration alone
(velocity and acceleration limits only), ``jerk_bound`` the same with the executor's jerk
limits (10x acceleration per second), which no jerk-limited merge can beat.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # the hand-made segments live with the executor's tests

from cellengine.execute import Compiler, compile_segments  # noqa: E402
from cellengine.program import CompiledSegment  # noqa: E402
from tests.execute import scenes  # noqa: E402

REPEATS = 3


def run() -> dict[str, float]:
    t0 = time.perf_counter()
    world, cell, checker = scenes.cable_cell()
    load = time.perf_counter() - t0
    q0 = scenes.home(cell)
    segments = scenes.reference_segments()
    compile_times = []
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        program = compile_segments(world, cell, checker, segments, q0, "split")
        compile_times.append(time.perf_counter() - t0)
    two_arm = [s for s in _merge_cases() if s.report["merge"] not in ("none", "async")]
    sums = {
        key: sum(_figure(s, key) for s in two_arm)
        for key in ("joint", "published", "bound", "jerk_bound")
    }
    return {
        "execute_load_cell_s": load,
        "execute_compile_reference_cold_s": compile_times[0],  # held-object scenes built
        "execute_compile_reference_s": min(compile_times),
        "execute_reference_segments": float(len(segments)),
        "execute_reference_cycle_s": program.duration,
        "execute_two_arm_segments": float(len(two_arm)),
        "execute_joint_over_bound": sums["joint"] / sums["bound"],
        "execute_published_over_bound": sums["published"] / sums["bound"],
        "execute_joint_over_jerk_bound": sums["joint"] / sums["jerk_bound"],
        "execute_published_over_jerk_bound": sums["published"] / sums["jerk_bound"],
        "execute_joint_over_published": sums["joint"] / sums["published"],
    }


def _merge_cases() -> list[CompiledSegment]:
    world, cell, checker = scenes.cable_cell()
    out: list[CompiledSegment] = []
    for strategy in ("split", "sync"):
        c = Compiler(world, cell, checker, scenes.home(cell), strategy)
        for s in scenes.reference_segments():
            out.append(c.add(s))
        for s in scenes.synchronised().values():
            c = Compiler(world, cell, checker, scenes.home(cell), strategy)
            c.add(scenes.ready())
            out.append(c.add(s))
    c = Compiler(world, cell, checker, scenes.home(cell), "split")
    out += [c.add(s) for s in scenes.crossing()]
    return out


def _figure(s: CompiledSegment, key: str) -> float:
    r: Any = s.report
    if key in ("joint", "published"):
        return float(r["durations_s"][key])
    return float(r["time_optimal_bound_s" if key == "bound" else "jerk_limited_bound_s"])


if __name__ == "__main__":
    print(json.dumps(run(), indent=2))
