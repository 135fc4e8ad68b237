"""Success rate of the cable skills on generated boards nobody tuned for (issue #13, point 5).

Run: .venv/bin/python bench/bench_boards.py --boards 50 --seed 1 [--strategies split,sync,async]
     [--remodel [--remodel-arms auto|file]] [--out DIR] [--jobs 2] [--timeout 900]
     [--only 15,82 (these boards instead)] [--work-clearance MM (in every board's cell.yaml)]

Board k is drawn from seed S + k by bench/boards.py (its docstring says what a board is and
what is rejected); with --remodel the REMODEL sample is added at 8 placements, imported with
``--arms auto`` (the engine chooses the placing arm; the sequence's L and R were written for
REMODEL's own cell) unless --remodel-arms file. Each board
is compiled with each strategy by ``cellengine.pipeline.compile_plan`` and each compiled
program checked by bench/board_check.py (independent of the skills). Printed and written to
DIR/results.json: the success rate per strategy, a histogram of the failure reasons
(messages normalised into classes) and the compile times; each outcome is also appended to
DIR/outcomes.jsonl as it finishes (a run cut short keeps its figures). A compile still running
after --timeout seconds is stopped and counted a failure ("not done in time"). The folders of the
boards that failed with some strategy stay in DIR/boards/; the others are deleted. Results
do not depend on --jobs: every task is a pure function of its board and strategy.
"""

from __future__ import annotations

import argparse
import json
import re
import shutil
import signal
import statistics
import subprocess
import sys
import time
from collections import Counter
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import TYPE_CHECKING

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from bench.boards import make_board, remodel_placements  # noqa: E402

if TYPE_CHECKING:
    from collections.abc import Callable

    from cellengine.arrays import Mat

STRATEGIES = ("split", "sync", "async")


@dataclass(frozen=True)
class Outcome:
    board: str
    strategy: str
    ok: bool
    reason: str  # the failure class ("" when ok)
    message: str  # the first failure as the engine or the checker says it
    compile_s: float
    min_arm_distance_mm: float | None


# ----------------------------------------------------------------------------- classes

_CLASSES: tuple[tuple[str, str], ...] = (
    (r"Cartesian path stops at", "Cartesian path stops"),
    (r"closed chain .* stops at", "closed-chain path stops"),
    (r"no sliding angle clears the guide", "no sliding angle clears the guide"),
    (r"out of reach|no inverse kinematics|no IK branch reaches", "out of reach"),
    (r"every IK solution .* is in collision", "every IK solution in collision"),
    (r"too short|cable .* (long|length)", "cable too short"),
    (r"no collision-free|transit|OMPL|could not plan", "no transit path"),
)


def classify(message: str) -> str:
    """A failure message as a class: the fixed phrases above, a collision by the kinds of the
    parts (arm link, guide, holder, table...), else the message with numbers and names
    blanked."""
    for pattern, name in _CLASSES:
        if re.search(pattern, message):
            if name == "Cartesian path stops":
                return f"{name}: {classify(_after_waypoint(message))}"
            return name
    m = re.search(r"collision between (\S+) and (\S+)", message) or re.search(
        r"(\S+) / (\S+): collision", message
    )
    if m:
        a, b = sorted((_part_kind(m.group(1)), _part_kind(m.group(2))))
        return f"collision between {a} and {b}"
    tail = message.split(": ", 2)[-1]
    return re.sub(r"-?\d+(\.\d+)?", "N", re.sub(r"'[^']*'", "'X'", tail))[:90]


def _after_waypoint(message: str) -> str:
    """Why a Cartesian path stopped: what follows 'waypoint N: '."""
    m = re.search(r"waypoint \d+: (.*)", message)
    return m.group(1) if m else "why unknown"


def _part_kind(name: str) -> str:
    name = re.sub(r"#\d+$", "", name.strip("(),'"))  # a link's second capsule
    if "/" in name:  # an arm's link: left/wrist_1_link
        return "arm " + re.sub(r"_\d+_link|_link", "", name.split("/", 1)[1])
    if name.startswith("routing.") or name.startswith("platform."):
        return "guide" if "connector" not in name else "connector guide"
    if name.startswith("holder.") or name.startswith("combs."):
        return "comb"
    if "cable" in name or "connector" in name:
        return "cable"
    return re.sub(r"\d+", "", name)


# ------------------------------------------------------------------------------- tasks


class _OutOfTime(BaseException):
    """Not an Exception: no ``except Exception`` in the engine swallows it."""


def _out_of_time(signum: int, frame: object) -> None:
    raise _OutOfTime


def run_one(plan: str, board: str, strategy: str, timeout: float = 0.0) -> Outcome:
    """Compile and check one board with one strategy (in a worker process); a compile still
    running after ``timeout`` s (0: none) is stopped and counted a failure."""
    import cellengine.skills.cable  # noqa: F401  (registers the cable skills)
    from bench.board_check import check_compiled
    from cellengine.errors import InputError
    from cellengine.pipeline import compile_plan

    t0 = time.perf_counter()
    signal.signal(signal.SIGALRM, _out_of_time)
    signal.setitimer(signal.ITIMER_REAL, timeout)
    try:
        compiled = compile_plan(Path(plan), strategy)
    except _OutOfTime:
        dt = time.perf_counter() - t0
        msg = f"not compiled within {timeout:g} s (stopped)"
        return Outcome(board, strategy, False, "not done in time", msg, dt, None)
    except InputError as e:
        dt = time.perf_counter() - t0
        msg = str(e).split("\n")[0]
        return Outcome(board, strategy, False, classify(msg), msg, dt, None)
    except Exception as e:  # an engine bug: counted and kept, the other boards still run
        dt = time.perf_counter() - t0
        msg = f"{type(e).__name__}: {e}".split("\n")[0]
        return Outcome(board, strategy, False, f"crash: {type(e).__name__}", msg, dt, None)
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
    dt = time.perf_counter() - t0
    try:
        result = check_compiled(compiled)
    except ValueError as e:  # the program itself is broken (a trajectory that jumps)
        msg = f"{type(e).__name__}: {e}".split("\n")[0]
        return Outcome(board, strategy, False, "check: broken program", msg, dt, None)
    d = None if result.min_arm_distance is None else round(result.min_arm_distance * 1000, 1)
    if result.ok:
        return Outcome(board, strategy, True, "", "", dt, d)
    first = result.failures[0]
    reason = f"check: {first.kind}" + (
        f" ({first.message.split(': ', 1)[1].split(' ')[0]})" if first.kind == "insert" else ""
    )
    return Outcome(board, strategy, False, reason, first.message, dt, d)


def make_boards(
    seeds: Sequence[int],
    remodel: bool,
    out: Path,
    arms: str = "auto",
    work_clearance: float | None = None,
) -> dict[str, Path]:
    """Each board's plan file, written under out/boards/; ``work_clearance`` (mm): set in
    each board's cell.yaml (None: the cell's default)."""
    plans: dict[str, Path] = {}
    for seed in seeds:
        name = f"board_{seed}"
        make_board(seed, out / "boards" / name)
        if work_clearance is not None:
            cell = out / "boards" / name / "cell.yaml"
            cell.write_text(cell.read_text() + f"work_clearance: {work_clearance}\n")
        plans[name] = out / "boards" / name / "plan.yaml"
    if remodel:
        plans.update(_remodel_boards(out, arms))
    return plans


def _remodel_boards(out: Path, arms: str) -> dict[str, Path]:
    from tests.conftest import REMODEL

    # imported 20 m away: its keypoints' poses, and a cell whose arms meet only themselves
    probe = out / "boards" / "remodel_probe"
    _import_remodel(REMODEL, probe, f"{PROBE_AWAY * 1000} 0 0 0 0 0", arms)
    keypoints, reaches = _probe_reach(probe / "cell.yaml")
    shutil.rmtree(probe)
    plans = {}
    for name, pose in remodel_placements(keypoints, reaches):
        _import_remodel(REMODEL, out / "boards" / name, pose, arms)
        plans[name] = out / "boards" / name / "plan.yaml"
    return plans


PROBE_AWAY = 20.0  # m: where the probe's platforms are, out of the arms' way
REACH_MARGIN = 0.050  # m: how far inside both arms' workspaces every keypoint is


def _probe_reach(cell_yaml: Path) -> tuple[list[Mat], Callable[[Mat], bool]]:
    """The probe's keypoints as if imported at the origin, and whether both arms reach a
    keypoint pose: each with the tool coming down its z (cellengine.reach.approach) at it and
    RETRACT_HEIGHT above it (the skills come down onto a keypoint and leave upwards), and so
    REACH_MARGIN away on every side (the hands work around it: no keypoint on the edge of an
    arm's workspace), each on an IK branch clear of the arm itself and of the other arm at
    home."""
    from cellengine.context import build_context
    from cellengine.info.load import load_world
    from cellengine.reach import approach
    from cellengine.skills.cable_geometry import RETRACT_HEIGHT

    ctx = build_context(load_world(cell_yaml))
    home, slices = ctx.home, ctx.cell.slices
    keypoints = []
    for T in ctx.world.keypoints().values():
        T = T.copy()
        T[0, 3] -= PROBE_AWAY
        keypoints.append(T)

    def arm_reaches(arm: str, T: Mat) -> bool:
        q = home.copy()
        for T_tcp in approach(T):
            for sol in ctx.iks[arm].solve_all(T_tcp):
                q[slices[arm]] = sol
                if not ctx.checker.in_collision(q):
                    return True
        return False

    # at the keypoint, and REACH_MARGIN from it horizontally in the cell's x and y either way
    shifts = [np.zeros(3)] + [
        sign * REACH_MARGIN * axis for axis in np.eye(3)[:2] for sign in (1, -1)
    ]

    def reaches(T: Mat) -> bool:
        for arm in ctx.cell.arms:
            for height in (0.0, RETRACT_HEIGHT):
                for shift in shifts:
                    P = T.copy()
                    P[:3, 3] += height * T[:3, 2] + shift
                    if not arm_reaches(arm, P):
                        return False
        return True

    return keypoints, reaches


def _import_remodel(src: Path, dest: Path, pose: str, arms: str) -> None:
    dest.parent.mkdir(parents=True, exist_ok=True)  # with --boards 0 nothing made it yet
    cmd = [sys.executable, "-m", "cellengine", "import", "remodel", str(src), str(dest)]
    subprocess.run([*cmd, f"--pose={pose}", f"--arms={arms}"], check=True, capture_output=True)


# ----------------------------------------------------------------------------- summary


def summarise(outcomes: list[Outcome], strategies: tuple[str, ...]) -> dict[str, object]:
    per: dict[str, object] = {}
    for s in strategies:
        mine = [o for o in outcomes if o.strategy == s]
        times = [o.compile_s for o in mine]
        dists = [o.min_arm_distance_mm for o in mine if o.min_arm_distance_mm is not None]
        per[s] = {
            "boards": len(mine),
            "succeeded": sum(o.ok for o in mine),
            "success_rate": round(sum(o.ok for o in mine) / max(1, len(mine)), 3),
            "failures": dict(Counter(o.reason for o in mine if not o.ok).most_common()),
            "compile_s_median": round(statistics.median(times), 2) if times else None,
            "compile_s_max": round(max(times), 2) if times else None,
            "min_arm_distance_mm": min(dists) if dists else None,
            "arms_under_10mm": sum(d < 10.0 for d in dists),
        }
    return per


def _print(summary: dict[str, object], outcomes: list[Outcome]) -> None:
    for s, v in summary.items():
        assert isinstance(v, dict)
        print(
            f"{s}: {v['succeeded']}/{v['boards']} ({100 * v['success_rate']:.0f} %), compile "
            f"median {v['compile_s_median']} s, max {v['compile_s_max']} s, least arm "
            f"distance {v['min_arm_distance_mm']} mm ({v['arms_under_10mm']} compiled programs "
            "under 10 mm)"
        )
    print("failure reasons (all strategies):")
    for reason, n in Counter(o.reason for o in outcomes if not o.ok).most_common():
        example = next(o for o in outcomes if o.reason == reason)
        print(f"  {n:4d}  {reason}   e.g. {example.board} {example.strategy}")


def _run_all(
    tasks: list[tuple[str, str, str]], jobs: int, log: Path, timeout: float
) -> list[Outcome]:
    """Every task's outcome in the tasks' order; each is also appended to ``log`` (one JSON
    line) as it finishes, so that a run cut short still leaves its figures."""
    log.parent.mkdir(parents=True, exist_ok=True)
    log.unlink(missing_ok=True)
    done: dict[int, Outcome] = {}
    with ProcessPoolExecutor(max_workers=jobs) as pool, log.open("a") as f:
        futures = {pool.submit(run_one, *t, timeout): i for i, t in enumerate(tasks)}
        for fut in as_completed(futures):
            o = done[futures[fut]] = fut.result()
            f.write(json.dumps(asdict(o)) + "\n")
            f.flush()
            print(f"[{len(done)}/{len(tasks)}] {o.board} {o.strategy}: "
                  f"{'ok' if o.ok else o.reason} ({o.compile_s:.0f} s)", flush=True)  # fmt: skip
    return [done[i] for i in range(len(tasks))]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--boards", type=int, default=50)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--strategies", default=",".join(STRATEGIES))
    ap.add_argument("--remodel", action="store_true")
    ap.add_argument("--remodel-arms", choices=("auto", "file"), default="auto")
    ap.add_argument("--out", type=Path, default=Path("bench_boards_out"))
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--timeout", type=float, default=900.0, help="s per compile; 0: none")
    ap.add_argument("--only", help="these boards' seeds (comma-separated), not --seed/--boards")
    ap.add_argument("--work-clearance", type=float, help="mm, set in every board's cell.yaml")
    args = ap.parse_args(argv)
    strategies = tuple(args.strategies.split(","))
    shutil.rmtree(args.out / "boards", ignore_errors=True)
    seeds = (
        [int(s) for s in args.only.split(",")]
        if args.only
        else list(range(args.seed, args.seed + args.boards))
    )
    plans = make_boards(seeds, args.remodel, args.out, args.remodel_arms, args.work_clearance)
    tasks = [(str(p), b, s) for b, p in plans.items() for s in strategies]
    t0 = time.perf_counter()
    outcomes = _run_all(tasks, args.jobs, args.out / "outcomes.jsonl", args.timeout)
    wall = time.perf_counter() - t0
    summary = summarise(outcomes, strategies)
    _print(summary, outcomes)
    print(f"{len(tasks)} compiles in {wall:.0f} s wall time, {args.jobs} jobs")
    failed = {o.board for o in outcomes if not o.ok}
    for b in set(plans) - failed:
        shutil.rmtree(plans[b].parent)
    result = {
        "command": " ".join(["bench/bench_boards.py", *(argv or sys.argv[1:])]),
        "wall_s": round(wall, 1),
        "per_strategy": summary,
        "outcomes": [asdict(o) for o in outcomes],
    }
    (args.out / "results.json").write_text(json.dumps(result, indent=1) + "\n")
    print(f"written {args.out / 'results.json'}; failed boards in {args.out / 'boards'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
