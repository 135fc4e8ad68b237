"""Peak memory of scene building and compiling as a cell and a plan grow (issue #19).

Run: PYTHONPATH=$PWD .venv/bin/python bench/bench_memory.py [--guides 50,500]
     [--weighs 100] [--no-compile] [--out DIR]

Each figure is the peak resident set size (``ru_maxrss``) of a fresh Python process doing
one thing, so nothing one measurement loads is counted in another:

- ``guides N``: board 3 of bench/boards.py (its connector guide and four U-guides, which
  compile) with N - 4 more U-guides (10 x 20 x 15 mm, an 8 mm gap) on a 30 mm grid within
  the arms' reach and off the board's own area, the nearest first. Measured: ``cellengine
  validate --no-compile`` of the folder (files, references, the robots), building the
  planning context (the collision scene, its checker, IK) and, unless ``--no-compile``,
  ``cellengine plan`` of the board's plan (PickCable, PlaceConnector, RouteCable through
  its own four guides).
- ``weighs N``: cells/lab_bench with a plan of N Weigh steps of vial1, one after the
  other: ``cellengine plan`` of it (compile and the three output files).

Printed, and written to DIR/memory.json: each figure in MB with its wall time (s) and
whether the command succeeded.
"""

from __future__ import annotations

import argparse
import json
import math
import shutil
import subprocess
import sys
import tempfile
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from bench.boards import Board, Guide, draw_board, write_board  # noqa: E402

BOARD_SEED = 3  # a board whose plan compiles (bench/RESULTS.md, issue #13)
# mm: the grid of the extra guides' slots (their pads overlap), off the board's own guides,
# connector guide and holder plate (KEEP_OFF: x0, x1, y0, y1), within an arm's reach
GRID_X = (150.0, 800.0)
GRID_Y = (-690.0, 690.0)
PITCH = 30.0
KEEP_OFF = (100.0, 620.0, -320.0, 320.0)
REACH = 800.0  # mm from a base, horizontally (a UR5e reaches 850)
BASE_KEEP_OUT = 150.0
LAB = ROOT / "cells" / "lab_bench"

# The child measures one thing and prints its peak RSS (MB) on the last line.
_CHILD = """
import resource, sys, time
from pathlib import Path
sys.argv = {argv!r}
t0 = time.perf_counter()
ok = True
try:
{body}
except SystemExit as e:
    ok = e.code in (0, None)
print(ok, time.perf_counter() - t0, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)
"""
_CLI = "    from cellengine.cli import main\n    ok = main(sys.argv[1:]) == 0"
_CONTEXT = (
    "    from cellengine.info.load import load_world\n"
    "    from cellengine.context import build_context\n"
    "    build_context(load_world(Path(sys.argv[1])))"
)


def extra_guides(n: int, bases: tuple[tuple[float, float], ...]) -> tuple[Guide, ...]:
    """``n`` small U-guides on a grid within the arms' reach, off the board's own area
    (KEEP_OFF), the nearest to the bases' midpoint first: every one is in some arm's
    reach, so each adds collision pairs as a guide of the route would."""
    spots = [
        (x, y)
        for x in _range(*GRID_X)
        for y in _range(*GRID_Y)
        if not (KEEP_OFF[0] <= x <= KEEP_OFF[1] and KEEP_OFF[2] <= y <= KEEP_OFF[3])
        and min(math.dist((x, y), b) for b in bases) <= REACH
        and min(math.dist((x, y), b) for b in bases) >= BASE_KEEP_OUT
    ]
    if len(spots) < n:
        raise ValueError(f"{n} extra guides do not fit ({len(spots)} spots)")
    spots.sort(key=lambda p: (math.hypot(*p), p))
    return tuple(
        Guide(f"extra{k + 1}", x, y, 0.0, 10.0, 20.0, 15.0, 8.0, 8.0)
        for k, (x, y) in enumerate(spots[:n])
    )


def _range(lo: float, hi: float) -> list[float]:
    return [lo + k * PITCH for k in range(int((hi - lo) // PITCH) + 1)]


def guides_board(n: int, dest: Path) -> Board:
    """Board BOARD_SEED with guides up to ``n`` in all; its plan routes through its own."""
    board = draw_board(BOARD_SEED)
    own = board.guides
    half = board.base_distance / 2
    extra = extra_guides(max(0, n - len(own)), ((0.0, half), (0.0, -half)))
    board = replace(board, guides=own + extra)
    write_board(board, dest)
    # the plan routes through the board's own guides only
    plan = (dest / "plan.yaml").read_text()
    names = ", ".join(f"routing.{g.name}" for g in own)
    head, _ = plan.split("guides: [", 1)
    (dest / "plan.yaml").write_text(f"{head}guides: [{names}]\n")
    return board


def weighs_plan(n: int, dest: Path) -> Path:
    shutil.copytree(LAB, dest, dirs_exist_ok=True)
    plan = dest / f"plan_weigh_{n}.yaml"
    steps = "".join("  - {skill: Weigh, object: vial1}\n" for _ in range(n))
    plan.write_text(f"cell: cell.yaml\nobjects: objects.yaml\nsteps:\n{steps}")
    return plan


def measure(body: str, argv: list[str]) -> dict[str, object]:
    """Run ``body`` in a fresh interpreter: ok, seconds, peak RSS (MB)."""
    code = _CHILD.format(argv=argv, body=body)
    # cwd ROOT: the child imports the cellengine of this tree
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    last = r.stdout.strip().splitlines()[-1] if r.stdout.strip() else ""
    try:
        ok, seconds, mb = last.split()
    except ValueError:
        return {"ok": False, "error": (r.stderr or r.stdout)[-500:]}
    out: dict[str, object] = {"ok": ok == "True", "s": round(float(seconds), 1)}
    out["peak_mb"] = round(float(mb), 1)
    if ok != "True":
        out["error"] = (r.stderr or r.stdout)[-500:]
    return out


def run(
    guides: list[int], weighs: list[int], compile_: bool, work: Path
) -> dict[str, dict[str, object]]:
    results: dict[str, dict[str, object]] = {}
    for n in guides:
        folder = work / f"guides_{n}"
        guides_board(n, folder)
        results[f"guides {n}: validate --no-compile"] = measure(
            _CLI, ["cellengine", "validate", "--no-compile", str(folder)]
        )
        results[f"guides {n}: build_context"] = measure(_CONTEXT, ["x", str(folder / "cell.yaml")])
        if compile_:
            results[f"guides {n}: plan"] = measure(
                _CLI, ["cellengine", "plan", str(folder / "plan.yaml"), "-q", "--out",
                       str(folder / "run")],
            )  # fmt: skip
        _show(results, n)
    for n in weighs:
        plan = weighs_plan(n, work / "lab")
        results[f"weighs {n}: plan"] = measure(
            _CLI, ["cellengine", "plan", str(plan), "-q", "--out", str(work / f"run_weigh_{n}")]
        )
        _show(results, n)
    return results


def _show(results: dict[str, dict[str, object]], n: int) -> None:
    for name, r in results.items():
        if name.split(":")[0].endswith(f" {n}"):
            print(f"{name}: {r}", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--guides", default="50,500", help="comma-separated guide counts")
    ap.add_argument("--weighs", default="100", help="comma-separated Weigh step counts")
    ap.add_argument("--no-compile", action="store_true", help="no plan of the guide boards")
    ap.add_argument("--out", type=Path, default=None, help="keep the files and memory.json here")
    args = ap.parse_args()
    counts = [int(x) for x in args.guides.split(",") if x]
    weighs = [int(x) for x in args.weighs.split(",") if x]
    work = args.out or Path(tempfile.mkdtemp(prefix="bench_memory_"))
    work.mkdir(parents=True, exist_ok=True)
    results = run(counts, weighs, not args.no_compile, work)
    (work / "memory.json").write_text(json.dumps(results, indent=1) + "\n")
    print(f"written: {work / 'memory.json'}")
    if args.out is None:
        shutil.rmtree(work / "lab", ignore_errors=True)


if __name__ == "__main__":
    main()
