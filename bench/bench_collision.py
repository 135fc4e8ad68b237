"""Collision checking in the cable-routing cell: two UR5e arms (capsule links, box tools), the
table, and ten platform elements (X3D meshes as BVHs), 31 objects and about 270 checked pairs.

Run: .venv/bin/python bench/bench_collision.py [--quick]   (prints the figures as JSON)

States: 10 000 configurations of both arms drawn uniformly within the joint limits (seed 2024);
most of them collide (an arm through the table or itself), which ends a check at its first
contact, so the collision-free ones are timed apart too: they are the worst case (every pair's
bounding boxes tested) and the case a planner's accepted states are in. Segments: from
collision-free states, a step of N(0, 0.002 rad) per joint ("tiny": about a millimetre at the
TCP, a Cartesian path's step), N(0, 0.05 rad) (a short planner step) and N(0, 0.5 rad) (a
long transit edge), checked by conservative advancement at 1 mm clearance.

Goal (issue #3): at most 15 us per dual-arm state with capsule links.

Each figure is the median over its states of one call each, timed by perf_counter_ns with the
garbage collector off. ``collision_pairloop_free_us`` is pinocchio's loop over every checked
pair without a broad phase, on the same free states: what the broad phase saves.
"""

from __future__ import annotations

import argparse
import gc
import json
import statistics
import sys
import time
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from cellengine.info.load import load_world  # noqa: E402
from cellengine.motion.collision import CollisionChecker  # noqa: E402
from cellengine.motion.robot import CellModel, build_cell_model  # noqa: E402
from cellengine.motion.scene import build_scene  # noqa: E402

Array = NDArray[np.float64]
CELL = ROOT / "cells" / "cable_routing"
SEED = 2024


def _median_us(f: Callable[[Any], object], items: Iterable[Any]) -> float:
    """Median over items of one call each, in microseconds."""
    times = []
    gc.disable()
    try:
        for x in items:
            t0 = time.perf_counter_ns()
            f(x)
            times.append(time.perf_counter_ns() - t0)
    finally:
        gc.enable()
    return statistics.median(times) / 1000.0


def _states(cell: CellModel, n: int, rng: np.random.Generator) -> Array:
    limits = cell.limits
    return rng.uniform(limits.lower, limits.upper, (n, cell.nq))


def run(quick: bool = False) -> dict[str, float]:
    n = 2000 if quick else 10_000
    world = load_world(CELL / "cell.yaml", CELL / "objects.yaml")
    cell = build_cell_model(world)
    t0 = time.perf_counter()
    scene = build_scene(cell, world)
    build_s = time.perf_counter() - t0
    checker = CollisionChecker(scene)
    rng = np.random.default_rng(SEED)
    Q = _states(cell, n, rng)
    hits = checker.check_batch(Q)
    free = Q[~hits]
    model, data = cell.model, cell.model.createData()
    plain = pin.GeometryData(scene.geometry)

    def pair_loop(q: Array) -> bool:
        return bool(pin.computeCollisions(model, data, scene.geometry, plain, q, True))

    t0 = time.perf_counter()
    checker.check_batch(Q)
    batch_us = (time.perf_counter() - t0) / len(Q) * 1e6
    tiny = [(q, q + rng.normal(0.0, 0.002, cell.nq)) for q in free[:1000]]
    short = [(q, q + rng.normal(0.0, 0.05, cell.nq)) for q in free[:1000]]
    long = [(q, q + rng.normal(0.0, 0.5, cell.nq)) for q in free[:300]]
    short_free = np.mean([checker.check_segment(a, b) is None for a, b in short])
    long_free = np.mean([checker.check_segment(a, b) is None for a, b in long])
    return {
        "collision_state_us": _median_us(checker.in_collision, Q),
        "collision_free_state_us": _median_us(checker.in_collision, free),
        "collision_check_named_us": _median_us(checker.check, Q),
        "collision_batch_us_per_state": batch_us,
        "collision_distance_us": _median_us(checker.distance, free[:2000]),
        "collision_arm_distance_us": _median_us(
            lambda q: checker.distance(q, between=("left", "right")), free[:1000]
        ),
        "collision_segment_tiny_us": _median_us(lambda s: checker.check_segment(*s), tiny),
        "collision_segment_us": _median_us(lambda s: checker.check_segment(*s), short),
        "collision_segment_long_us": _median_us(lambda s: checker.check_segment(*s), long),
        "collision_pairloop_free_us": _median_us(pair_loop, free[:2000]),
        "collision_random_state_hit_rate": float(hits.mean()),
        "collision_segment_free_rate": float(short_free),
        "collision_segment_long_free_rate": float(long_free),
        "collision_pairs_checked": float(len(scene.pairs)),
        "collision_acm_pairs": float(len(scene.acm.reasons)),
        "collision_scene_build_s": build_s,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="2000 states instead of 10 000")
    args = parser.parse_args()
    print(json.dumps(run(args.quick), indent=2))


if __name__ == "__main__":
    main()
