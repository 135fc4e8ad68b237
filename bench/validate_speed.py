"""Wall time of `cellengine validate --no-compile cells/`, interpreter start included.

Run: .venv/bin/python bench/validate_speed.py [--runs N]
Goal (issue #2): at most 1.0 s on a 2-core machine.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=10)
    args = ap.parse_args()
    exe = Path(sys.executable).parent / "cellengine"
    # the files and references (issue #2); compiling plans to motion is measured in bench_execute
    cmd = [str(exe), "validate", "--no-compile", "cells/"]
    subprocess.run(cmd, cwd=ROOT, check=True, capture_output=True)  # warm the file cache
    times = []
    for _ in range(args.runs):
        t0 = time.perf_counter()
        subprocess.run(cmd, cwd=ROOT, check=True, capture_output=True)
        times.append(time.perf_counter() - t0)
    print(
        f"cellengine validate --no-compile cells/: median {statistics.median(times):.3f} s, "
        f"min {min(times):.3f} s, max {max(times):.3f} s over {args.runs} runs"
    )


if __name__ == "__main__":
    main()
