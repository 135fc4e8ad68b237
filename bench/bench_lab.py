"""Cycle times of the lab plans on both lab cells, both robots at once against one after
another (issues #5 and #16).

For each plan of cells/lab_bench and each cell (the cartesian robots, two UR5e), in a fresh
process each: `cellengine plan PLAN --cell CELL --no-cache --execution sequential` (the
robots one at a time, each back to its rest after its work: the published platform) and
the same with the plan's own execution (both robots at once). From each report.json: the
cycle time, the same segments' cycle one after another (report.json streams'
one_after_another_s: what overlap alone saved), each robot's busy time, the least distance
between the robots over the whole program, the waits the streams inserted, and the
command's wall time.

Run: .venv/bin/python bench/bench_lab.py [--out F.json]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
LAB = ROOT / "cells" / "lab_bench"
CELLS = {"cartesian": LAB / "cell.yaml", "ur5e": LAB / "cell_ur.yaml"}
EXE = [sys.executable, "-m", "cellengine", "plan"]


def measure(plan: Path, cell: Path, sequential: bool) -> dict[str, Any]:
    with tempfile.TemporaryDirectory() as tmp:
        args = [str(plan), "--cell", str(cell), "--out", tmp, "-q", "--no-cache"]
        args += ["--execution", "sequential"] if sequential else []
        started = time.perf_counter()
        subprocess.run(EXE + args, check=True, cwd=ROOT)
        wall = time.perf_counter() - started
        report = json.loads((Path(tmp) / "report.json").read_text())
    busy: dict[str, float] = {}
    streams = report.get("streams")
    if streams and streams["at_once"]:
        for arm, lane in streams["lanes"].items():
            busy[arm] = sum(s["end"] - s["start"] for s in lane)
        waits = [w["wait_s"] for w in streams["waits"]]
        alone = streams["one_after_another_s"]
    else:
        for segment in report["segments"]:
            for arm in segment["arms"]:  # the arms that move in it
                busy[arm] = busy.get(arm, 0.0) + segment["duration_s"]
        waits, alone = [], report["duration"]
    arms = (report["totals"].get("clearance") or {}).get("arms") or {}
    return {
        "cycle_s": report["duration"],
        # its segments one after another (at once: the robots keep what they pick again
        # and go back to rest only out of a shared zone, so fewer segments)
        "segments_in_turn_s": alone,
        "busy_s": busy,
        "min_robot_distance_m": arms.get("distance_m"),
        "waits": len(waits),
        "wait_s": sum(waits),
        "wall_s": wall,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, help="write the figures here as JSON")
    args = ap.parse_args()
    results: dict[str, dict[str, Any]] = {}
    print(
        "| plan | cell | one after another | at once | shorter by | its segments in turn "
        "| busy per robot (at once) | least robot distance | waits | plan wall time |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    for plan in sorted(LAB.glob("plan_*.yaml")):
        for name, cell in CELLS.items():
            alone = measure(plan, cell, sequential=True)
            both = measure(plan, cell, sequential=False)
            results.setdefault(plan.stem, {})[name] = {"sequential": alone, "at_once": both}
            busy = ", ".join(f"{a} {t:.1f} s" for a, t in sorted(both["busy_s"].items()))
            cut = 1.0 - both["cycle_s"] / alone["cycle_s"]
            d = both["min_robot_distance_m"]
            print(
                f"| {plan.stem} | {name} | {alone['cycle_s']:.1f} s | {both['cycle_s']:.1f} s "
                f"| {100 * cut:.1f} % | {both['segments_in_turn_s']:.1f} s | {busy} | "
                f"{'-' if d is None else f'{1000 * d:.1f} mm'} | "
                f"{both['waits']} ({both['wait_s']:.1f} s) | "
                f"{alone['wall_s']:.2f} / {both['wall_s']:.2f} s |",
                flush=True,
            )
    if args.out:
        args.out.write_text(json.dumps(results, indent=2) + "\n")


if __name__ == "__main__":
    main()
