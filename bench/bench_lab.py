"""Cycle times of the lab plans on both lab cells (issues #5 and #16).

For each plan of cells/lab_bench and each cell (the cartesian robots, two UR5e):
`cellengine plan PLAN --cell CELL --no-cache` in a fresh process, and from its report.json
the cycle time, each robot's busy time (the segments in which it moves) and the allocator's
estimate. The busiest robot's time is a floor for any schedule that only overlaps the two
robots' segments as they are compiled: what overlap alone could reach.

Run: .venv/bin/python bench/bench_lab.py [--out F.json]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
LAB = ROOT / "cells" / "lab_bench"
CELLS = {"cartesian": LAB / "cell.yaml", "ur5e": LAB / "cell_ur.yaml"}
EXE = [sys.executable, "-m", "cellengine", "plan"]


def measure(plan: Path, cell: Path) -> dict[str, Any]:
    with tempfile.TemporaryDirectory() as tmp:
        args = [str(plan), "--cell", str(cell), "--out", tmp, "-q", "--no-cache"]
        subprocess.run(EXE + args, check=True, cwd=ROOT)
        report = json.loads((Path(tmp) / "report.json").read_text())
    busy: dict[str, float] = {}
    for segment in report["segments"]:
        for arm in segment["arms"]:  # the arms that move in it
            busy[arm] = busy.get(arm, 0.0) + segment["duration_s"]
    return {
        "cycle_s": report["duration"],
        "busy_s": busy,
        "overlap_floor_s": max(busy.values(), default=0.0),
        "estimate_s": max((p["estimate"][1] for p in report["mission"]), default=0.0),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, help="write the figures here as JSON")
    args = ap.parse_args()
    results: dict[str, dict[str, Any]] = {}
    print("| plan | cell | cycle | busy per robot | busiest robot | allocator's estimate |")
    print("|---|---|---|---|---|---|")
    for plan in sorted(LAB.glob("plan_*.yaml")):
        for name, cell in CELLS.items():
            r = results.setdefault(plan.stem, {})[name] = measure(plan, cell)
            busy = ", ".join(f"{a} {t:.1f} s" for a, t in sorted(r["busy_s"].items()))
            print(
                f"| {plan.stem} | {name} | {r['cycle_s']:.1f} s | {busy} | "
                f"{r['overlap_floor_s']:.1f} s | {r['estimate_s']:.1f} s |",
                flush=True,
            )
    if args.out:
        args.out.write_text(json.dumps(results, indent=2) + "\n")


if __name__ == "__main__":
    main()
