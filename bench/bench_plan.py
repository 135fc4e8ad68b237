"""Dual-arm transit planning in the reference cable-routing cell (issue #3, point 5).

Run: .venv/bin/python bench/bench_plan.py
Queries: both arms (12 DOF) from one pair of TCP poses to the next, each pose 60-160 mm
above a random keypoint of the cell with the gripper pointing down, solved by IK from home
and kept when collision-free. RRTConnect, simplification on, seeds 0..N-1, 1 s limit.
Goals: median planning <= 5 ms, simplification <= 10 ms, 100 % success within 1 s.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from cellengine import geometry as g
from cellengine.info.load import load_world
from cellengine.motion.collision import CollisionChecker
from cellengine.motion.ik import arm_ik
from cellengine.motion.robot import build_cell_model
from cellengine.motion.scene import build_scene
from cellengine.motion.transit import plan_for_arms

CELL = Path(__file__).resolve().parent.parent / "cells" / "cable_routing" / "cell.yaml"
QUERIES = 60


def configurations(n: int, seed: int = 0) -> list[np.ndarray]:
    world = load_world(CELL)
    cell = build_cell_model(world)
    checker = CollisionChecker(build_scene(cell, world))
    keypoints = list(world.keypoints().values())
    rng = np.random.default_rng(seed)
    iks = {a: arm_ik(arm) for a, arm in cell.arms.items()}
    out: list[np.ndarray] = []
    while len(out) < n:
        qs = {}
        for name, arm in cell.arms.items():
            T_kp = keypoints[rng.integers(len(keypoints))]
            up = rng.uniform(0.06, 0.16)
            T = g.pose(T_kp[:3, 3] + [0, 0, up], [math.pi, 0, rng.uniform(-math.pi, math.pi)])
            qs[name] = iks[name].solve(T, seed=arm.home)
        if any(q is None for q in qs.values()):
            continue
        q = cell.join(qs)
        if not checker.in_collision(q):
            out.append(q)
    return out


def run() -> dict[str, float]:
    world = load_world(CELL)
    cell = build_cell_model(world)
    checker = CollisionChecker(build_scene(cell, world))
    qs = configurations(QUERIES + 1)
    plan, simplify, ok, checks = [], [], 0, []
    for i in range(QUERIES):
        r = plan_for_arms(cell, checker, ("left", "right"), qs[i], qs[i + 1], seed=i)
        ok += r.ok
        plan.append(r.plan_time * 1e3)
        simplify.append(r.simplify_time * 1e3)
        checks.append(r.checks)
    return {
        "plan_dualarm_median_ms": float(np.median(plan)),
        "plan_dualarm_p90_ms": float(np.percentile(plan, 90)),
        "plan_dualarm_simplify_median_ms": float(np.median(simplify)),
        "plan_dualarm_success": ok / QUERIES,
        "plan_dualarm_checks_median": float(np.median(checks)),
    }


if __name__ == "__main__":
    print(json.dumps(run(), indent=2))
