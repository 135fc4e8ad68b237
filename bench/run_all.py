"""Run every motion benchmark in one process and write bench/results.json.

Run: .venv/bin/python bench/run_all.py   (or `make bench`)
Each bench module has `run() -> dict[str, float]`; keys name their units (_us, _ms, ...).
A module that fails is reported and the others still run.
"""

from __future__ import annotations

import importlib
import json
import platform
import sys
import traceback
from pathlib import Path

HERE = Path(__file__).resolve().parent
MODULES = [
    "bench_ik",
    "bench_timing",
    "bench_collision",
    "bench_cartesian",
    "bench_plan",
    "bench_execute",
    "bench_allocate",
    "bench_ur_servo",
]


def main() -> int:
    sys.path.insert(0, str(HERE))
    results: dict[str, object] = {
        "machine": f"{platform.machine()}, {platform.python_implementation()} "
        f"{platform.python_version()}, {len(__import__('os').sched_getaffinity(0))} cores"
    }
    failed = []
    for name in MODULES:
        if not (HERE / f"{name}.py").exists():
            print(f"{name}: not written yet", file=sys.stderr)
            continue
        try:
            figures = importlib.import_module(name).run()
        except Exception:  # a broken benchmark must not hide the others' figures
            traceback.print_exc()
            failed.append(name)
            continue
        for key, value in figures.items():
            print(f"{key:40s} {value}")
        results.update(figures)
    (HERE / "results.json").write_text(json.dumps(results, indent=2, sort_keys=True) + "\n")
    print(f"wrote {HERE / 'results.json'}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
