"""The lab plans on the emulated lab bench through the real lab driver (issue #17): two GRBL
1.1 controllers, two Dynamixel grippers and a load cell on pseudo-terminals
(tests/drivers/labbench.py), each plan's program played part by part in this process.

For each plan of cells/lab_bench: whether it completed, its motion time and wall time, the
G-code blocks streamed and their sustained rate, the least time a block went to its
controller before its planned start (the streaming's margin: at or below 0 GRBL would have
run dry), bytes lost to a full receive buffer (character counting: must be 0), and where each
robot ended against the plan.

Run: .venv/bin/python bench/bench_lab_bench.py [--plans a,b] [--out F.json]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from cellengine.drivers.lab import LabBenchDriver  # noqa: E402
from cellengine.drivers.play import segment_events  # noqa: E402
from cellengine.info.load import load_plan  # noqa: E402
from cellengine.pipeline import compile_plan  # noqa: E402
from cellengine.program import Measure  # noqa: E402
from cellengine.runner.driver import joint_specs  # noqa: E402
from tests.drivers.labbench import emulated_bench, machine  # noqa: E402

PLANS = ("plan_relocate", "plan_weigh_handover", "plan_cluttered", "plan_pour_heavier")
# robot1's grasps, in order (g): objects.yaml's masses of what it picks
MASSES = {"plan_weigh_handover": [36.0], "plan_pour_heavier": [30.0, 42.0]}


def measure(plan: str) -> dict[str, Any]:
    c = compile_plan(ROOT / "cells" / "lab_bench" / f"{plan}.yaml")
    q0 = c.program.segments[0].trajectory.q[0]
    joints = {n: a.joint_names for n, a in c.cell.arms.items()}
    with (
        tempfile.TemporaryDirectory() as tmp,
        emulated_bench(Path(tmp), q0, MASSES.get(plan, [])) as bench,
    ):
        world = load_plan(bench.folder / f"{plan}.yaml").world
        driver = LabBenchDriver(world.cell, joints, specs=joint_specs(c.cell))
        started = time.perf_counter()
        with driver:
            driver.configure()
            driver.activate()
            events = segment_events(c.program)
            masses = {}
            for seg, evs in zip(c.program.segments, events, strict=True):
                driver.execute(seg, evs)
                for m in (a for a in seg.segment.annotations if isinstance(a, Measure)):
                    masses[m.object] = driver.read_mass(m.arm, of=m.object)
        wall = time.perf_counter() - started
        end = c.program.segments[-1].trajectory.q[-1]
        off = max(
            float(np.max(np.abs(np.array(p.device.position) - machine(end[4 * k : 4 * k + 4]))))
            for k, p in enumerate(bench.grbl)
        )
        overflows = sum(p.device.overflows for p in bench.grbl)
    duration = sum(d for d, _, _ in driver.streamed)
    blocks = sum(n for _, n, _ in driver.streamed)
    return {
        "motion_s": c.program.duration,
        "wall_s": wall,
        "blocks": blocks,
        "block_rate_hz": blocks / duration if duration else 0.0,
        "least_lead_s": min(lead for _, _, lead in driver.streamed),
        "overflows": overflows,
        "end_off_mm": off,
        "masses_g": {k: round(1000 * v, 2) for k, v in masses.items()},
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--plans", default=",".join(PLANS))
    ap.add_argument("--out", type=Path)
    args = ap.parse_args()
    results = {}
    head = "| plan | motion | wall | blocks | block rate | least lead | overflows | end off |"
    print(head + " weighed |")
    print("|---|---|---|---|---|---|---|---|---|")
    for plan in args.plans.split(","):
        r = results[plan] = measure(plan)
        print(
            f"| {plan} | {r['motion_s']:.1f} s | {r['wall_s']:.1f} s | {r['blocks']} | "
            f"{r['block_rate_hz']:.1f}/s | {1000 * r['least_lead_s']:.0f} ms | {r['overflows']} | "
            f"{r['end_off_mm']:.3f} mm | {r['masses_g'] or '-'} |",
            flush=True,
        )
    if args.out:
        args.out.write_text(json.dumps(results, indent=2) + "\n")


if __name__ == "__main__":
    main()
