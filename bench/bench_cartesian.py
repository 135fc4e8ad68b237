"""Cartesian paths on the cable-routing cell's left UR5e: a reachable 1 m line in 1000 steps.

Run: .venv/bin/python bench/bench_cartesian.py [--repeats N]   (prints the figures as JSON)

The line: TCP pointing down, x = 0.45, z = 0.25, y from 0.85 to -0.15 (cell frame, m), 1001
waypoints 1 mm apart, from the IK solution nearest an elbow-up "ready" configuration. The right
arm stands at its home.

- ``cartesian_1m_ik_ms``: ``cartesian_path`` without collision checks: the waypoints to the
  base frame, all eight branches of all waypoints in one numpy pass, the start's branch taken
  and unwrapped, limits, both jump tests, the fraction.
- ``cartesian_1m_checked_ms``: the same with the real collision checker
  (cellengine.motion.collision, the whole cell: both arms, table, platform meshes): every step
  proved free by ``check_segment`` (conservative advancement; one check per step in free space).
- ``cartesian_1m_states_ms``: the same with ``segments=False``: one ``check_batch`` of the 1001
  waypoint states, no proof between them (what "check the waypoints only" would cost).
- ``cartesian_dual_1m_checked_ms``: both arms at once, each along its own 1 m line (the right
  arm's the same relative to its base, 0.7 m further along -y), checked against each other's
  motion: twice the IK and one segment proof per step of the whole cell.

Goal (issue #3): at most 10 ms for the IK, at most 30 ms with collision checks.
Times are medians over repeated runs, the garbage collector off, after one warm-up run.
"""

from __future__ import annotations

import argparse
import gc
import json
import math
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from cellengine import geometry as g  # noqa: E402
from cellengine.info.load import load_world  # noqa: E402
from cellengine.motion import interpolate as itp  # noqa: E402
from cellengine.motion.cartesian import (  # noqa: E402
    ArmInCell,
    CartesianResult,
    cartesian_path,
    dual_cartesian_path,
)
from cellengine.motion.collision import CollisionChecker  # noqa: E402
from cellengine.motion.ik import arm_ik  # noqa: E402
from cellengine.motion.robot import build_cell_model  # noqa: E402
from cellengine.motion.scene import build_scene  # noqa: E402

CELL = ROOT / "cells" / "cable_routing" / "cell.yaml"
READY = np.array([math.pi, -1.9, 1.9, -1.57, -1.57, 0.0])
R_DOWN = np.array([[0.0, -1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])


def _median_ms(run: Callable[[], CartesianResult], repeats: int) -> float:
    result = run()  # warm-up (IK objects, pinocchio data)
    if not result.ok:
        raise RuntimeError(f"the benchmark path must be complete: {result.stop}")
    times = []
    gc.disable()
    try:
        for _ in range(repeats):
            t0 = time.perf_counter()
            run()
            times.append(time.perf_counter() - t0)
    finally:
        gc.enable()
    return 1e3 * statistics.median(times)


def run(repeats: int = 30) -> dict[str, float]:
    world = load_world(CELL)
    cell = build_cell_model(world)
    checker = CollisionChecker(build_scene(cell, world))
    left, right = cell.arms["left"], cell.arms["right"]

    def line(y0: float, y1: float) -> np.ndarray:
        T0, T1 = g.transform(R_DOWN, [0.45, y0, 0.25]), g.transform(R_DOWN, [0.45, y1, 0.25])
        return itp.line(T0, T1, max_translation=0.001)

    W = line(0.85, -0.15)
    assert len(W) == 1001
    q0 = arm_ik(left).solve(W[0], READY)
    assert q0 is not None
    q_cell = cell.join({"left": q0, "right": np.array(right.home)})
    check = ArmInCell(checker, cell, "left", q_cell)

    # the dual case: the right arm along the same line relative to its base (0.7 m further
    # along -y), both moving together, 0.7 m apart
    WR = line(0.15, -0.85)
    qr = arm_ik(right).solve(WR[0], READY)
    assert qr is not None
    seeds = {"left": q0, "right": qr}

    return {
        "cartesian_1m_ik_ms": _median_ms(lambda: cartesian_path(left, W, q0), repeats),
        "cartesian_1m_checked_ms": _median_ms(
            lambda: cartesian_path(left, W, q0, check=check), repeats
        ),
        "cartesian_1m_states_ms": _median_ms(
            lambda: cartesian_path(left, W, q0, check=check, segments=False), repeats
        ),
        "cartesian_dual_1m_checked_ms": _median_ms(
            lambda: dual_cartesian_path(cell, {"left": W, "right": WR}, seeds, check=checker),
            max(repeats // 3, 3),
        ),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=30)
    args = parser.parse_args()
    print(json.dumps(run(args.repeats), indent=2))


if __name__ == "__main__":
    main()
