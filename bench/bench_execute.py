"""The executor on the cable-routing cell (issue #4): compile time and the merges' cycle times.

Run: .venv/bin/python bench/bench_execute.py
Plans: the four-guide reference plan (cells/cable_routing/plan_two_turns.yaml, segments from
skills/cable.py), and the hand-made segments of tests/execute/scenes.py (a transit of both
arms, a Cartesian line, a dual Cartesian move, a closed chain, a kept-distance arc).
Times: compile only (models and segments ready), a fresh process doing what `cellengine
plan` does before writing files (imports, loading, models, skills, compile), and the whole
`cellengine plan` command (median of 5, files written).
Merges: every part where both arms move, under split and under sync; per part the joint and
the published merge are timed on the same rows. Ratios are sums of durations over sums of
bounds: ``bound`` is the slower arm's time-optimal (TOPP-RA) duration alone, velocity and
acceleration limits only; ``jerk_bound`` the slower arm's jerk-limited duration alone (jerk
retime.JERK_PER_ACCELERATION = 50x acceleration per second), what a jerk-limited merge is
up against.
"""

from __future__ import annotations

import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # the hand-made segments live with the executor's tests

from cellengine.context import build_context  # noqa: E402
from cellengine.execute import Compiler, compile_segments  # noqa: E402
from cellengine.info.load import load_plan  # noqa: E402
from cellengine.program import CompiledSegment  # noqa: E402
from cellengine.skills.cable import plan_cable_steps  # noqa: E402
from tests.execute import scenes  # noqa: E402

FOUR_GUIDES = ROOT / "cells" / "cable_routing" / "plan_two_turns.yaml"
REPEATS = 3

PROCESS = f"""
import sys, time
t0 = time.perf_counter()
from pathlib import Path
from cellengine.context import build_context
from cellengine.execute import Compiler
from cellengine.info.load import load_plan
from cellengine.skills.cable import plan_cable_steps
loaded = load_plan(Path({str(FOUR_GUIDES)!r}))
ctx = build_context(loaded.world)
segments = plan_cable_steps(ctx, loaded.plan.steps)[0]
c = Compiler(loaded.world, ctx.cell, ctx.checker, ctx.home, loaded.plan.execution)
c.add_all(segments)
print(time.perf_counter() - t0)
"""


def run() -> dict[str, float]:
    out: dict[str, float] = {}
    out.update(_four_guides())
    out.update(_hand_made())
    return out


def _four_guides() -> dict[str, float]:
    loaded = load_plan(FOUR_GUIDES)
    world = loaded.world
    ctx = build_context(world)
    cell, checker = ctx.cell, ctx.checker
    segments = plan_cable_steps(ctx, loaded.plan.steps)[0]
    q0 = ctx.home
    times = []
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        program = compile_segments(world, cell, checker, segments, q0, "split")
        times.append(time.perf_counter() - t0)
    t0 = time.perf_counter()
    inner = float(
        subprocess.run(
            [sys.executable, "-c", PROCESS], check=True, capture_output=True, text=True, cwd=ROOT
        ).stdout.split()[-1]
    )
    process = time.perf_counter() - t0
    command = _plan_command()
    parts = []
    for strategy in ("split", "sync"):
        c = Compiler(world, cell, checker, q0, strategy)
        parts += c.add_all(segments).segments
    ratios = _ratios(parts)
    return {
        "execute_four_guide_segments": float(len(segments)),
        "execute_four_guide_compile_s": min(times),
        "execute_four_guide_compile_cold_s": times[0],
        "execute_four_guide_process_s": process,
        "execute_four_guide_process_after_start_s": inner,
        "execute_four_guide_plan_command_s": command,
        "execute_four_guide_cycle_s": program.duration,
        **{f"execute_four_guide_{k}": v for k, v in ratios.items()},
    }


def _plan_command(runs: int = 5) -> float:
    """Median wall time of the whole `cellengine plan` command (start-up, compile, files)."""
    times = []
    with tempfile.TemporaryDirectory() as out:
        argv = [sys.executable, "-m", "cellengine.cli", "plan", str(FOUR_GUIDES), "-q"]
        for _ in range(runs):
            t0 = time.perf_counter()
            subprocess.run([*argv, "--out", out], check=True, cwd=ROOT)
            times.append(time.perf_counter() - t0)
    return statistics.median(times)


def _hand_made() -> dict[str, float]:
    world, cell, checker = scenes.cable_cell()
    q0 = scenes.home(cell)
    segments = scenes.reference_segments()
    times = []
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        compile_segments(world, cell, checker, segments, q0, "split")
        times.append(time.perf_counter() - t0)
    parts: list[CompiledSegment] = []
    for strategy in ("split", "sync"):
        c = Compiler(world, cell, checker, q0, strategy)
        parts += c.add_all(segments).segments
        for s in scenes.synchronised().values():
            c = Compiler(world, cell, checker, q0, strategy)
            parts += c.add_all([scenes.ready(), s]).segments[1:]
    c = Compiler(world, cell, checker, q0, "split")
    parts += c.add_all(list(scenes.crossing())).segments[1:]
    return {
        "execute_hand_made_compile_s": min(times),
        **{f"execute_hand_made_{k}": v for k, v in _ratios(parts).items()},
    }


def _ratios(segments: list[CompiledSegment]) -> dict[str, float]:
    two_arm = [s for s in segments if s.report["merge"] not in ("none", "async")]
    sums = {k: sum(_figure(s, k) for s in two_arm) for k in ("joint", "published", "b", "jb")}
    return {
        "two_arm_segments": float(len(two_arm)),
        "joint_over_bound": sums["joint"] / sums["b"],
        "published_over_bound": sums["published"] / sums["b"],
        "joint_over_jerk_bound": sums["joint"] / sums["jb"],
        "published_over_jerk_bound": sums["published"] / sums["jb"],
        "joint_over_published": sums["joint"] / sums["published"],
    }


def _figure(s: CompiledSegment, key: str) -> float:
    r: Any = s.report
    if key in ("joint", "published"):
        return float(r["durations_s"][key])
    return float(r["time_optimal_bound_s" if key == "b" else "jerk_limited_bound_s"])


if __name__ == "__main__":
    print(json.dumps(run(), indent=2))
