"""Wall time of `cellengine validate` compiling many plans (issue #18).

  --cells            `validate cells/`: every plan compiled, one worker and one per core,
                     and again with the compile cache filled (goals: <= 8 s, <= 1 s)
  --boards N         N generated boards (bench/boards.py, seeds from --seed): one worker,
                     two, and a local Ray head with two CPUs (--ways: some of them); each
                     output kept in --keep DIR, and those kept there compared

Run: .venv/bin/python bench/bench_validate.py --cells --boards 200 [--timeout S] [--out F]
Each run is `cellengine validate ... --format json` in a fresh process, interpreter start
included; --timeout is validate's own (a plan past it is reported, its worker stopped).
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from bench.boards import make_board  # noqa: E402
from bench.ray_head import ray_head  # noqa: E402

EXE = [sys.executable, "-m", "cellengine", "validate"]


def _timed(args: list[str], cwd: Path) -> tuple[float, subprocess.CompletedProcess[str]]:
    t0 = time.perf_counter()
    run = subprocess.run(EXE + args, cwd=cwd, capture_output=True, text=True)
    return time.perf_counter() - t0, run


def cells(runs: int) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for name, extra in (("one_worker", ["-j", "1"]), ("one_per_core", [])):
        times = [_timed(["cells/", "--no-cache", *extra], ROOT)[0] for _ in range(runs)]
        out[name] = times
        print(f"validate cells/ --no-cache {' '.join(extra)}: {_show(times)}", flush=True)
    with tempfile.TemporaryDirectory() as cache:
        first, run = _timed(["cells/", "--cache-dir", cache], ROOT)
        assert run.returncode == 0, run.stdout + run.stderr
        times = [_timed(["cells/", "--cache-dir", cache], ROOT)[0] for _ in range(runs)]
    out["cache_filling"], out["cached"] = first, times
    print(f"validate cells/ filling the cache: {first:.2f} s; cached: {_show(times)}")
    return out


WAYS = {"one_worker": ["-j", "1"], "two_workers": ["-j", "2"], "ray": []}


def boards(
    n: int, seed: int, timeout: float | None, ways: list[str], keep: Path | None
) -> dict[str, Any]:
    """``ways`` of validating the boards, each output kept in ``keep`` (if given) as soon as
    it is there, and compared with the outputs already kept there (a run in parts)."""
    with tempfile.TemporaryDirectory() as tmp:
        top = Path(tmp)
        for s in range(seed, seed + n):
            make_board(s, top / "boards" / f"board_{s}")
        args = ["boards/", "--no-cache", "--format", "json"]
        args += [] if timeout is None else ["--timeout", f"{timeout:g}"]
        walls: dict[str, float] = {}
        for way in ways:
            if way == "ray":
                with ray_head(cpus=2) as address:
                    walls[way], run = _timed([*args, "--cluster", address], top)
            else:
                walls[way], run = _timed([*args, *WAYS[way]], top)
            print(f"{n} boards, {way}: {walls[way]:.1f} s", flush=True)
            if keep is not None:
                keep.mkdir(parents=True, exist_ok=True)
                (keep / f"{way}.json").write_text(run.stdout)
                (keep / f"{way}.stderr").write_text(run.stderr)
    outputs = {p.stem: p.read_text() for p in sorted(keep.glob("*.json"))} if keep else {}
    same = len(set(outputs.values())) == 1
    report = json.loads(next(iter(outputs.values())) if outputs else run.stdout)
    plans = [f for f in report["files"] if f["file"].endswith("plan.yaml")]
    timed_out = [f["file"] for f in plans if _past_time(f)]
    # A plan near the limit can end inside it one way and past it another: the rest compared.
    files = [json.loads(text)["files"] for text in outputs.values()]
    late = {f["file"] for way in files for f in way if _past_time(f)}
    rest = [[f for f in way if f["file"] not in late] for way in files]
    same_in_time = all(way == rest[0] for way in rest)
    failed = [f["file"] for f in plans if not f["ok"]]
    print(
        f"outputs kept: {sorted(outputs)}, identical: {same}, identical but for the "
        f"{len(late)} plans past the time limit in any: {same_in_time}; plans {len(plans)}, "
        f"compiled {len(plans) - len(failed)}, refused {len(failed) - len(timed_out)}, "
        f"past the timeout {len(timed_out)}"
    )
    return {
        "boards": n,
        "seed": seed,
        "timeout_s": timeout,
        "wall_s": walls,
        "identical": {"ways": sorted(outputs), "same": same, "past_time_in_any": sorted(late)},
        "identical_in_time": same_in_time,
        "plans": len(plans),
        "failed": failed,
        "timed_out": timed_out,
    }


def _past_time(f: dict[str, Any]) -> bool:
    return any("s allowed" in p["message"] for p in f["problems"])


def _show(times: list[float]) -> str:
    return f"median {statistics.median(times):.2f} s (min {min(times):.2f}, max {max(times):.2f})"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--cells", action="store_true")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--boards", type=int, default=0)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--timeout", type=float)
    ap.add_argument("--ways", default=",".join(WAYS), help=f"some of {','.join(WAYS)}")
    ap.add_argument("--keep", type=Path, help="keep each way's output here, and compare")
    ap.add_argument("--out", type=Path)
    args = ap.parse_args()
    results: dict[str, Any] = {}
    if args.cells:
        results["cells"] = cells(args.runs)
    if args.boards:
        ways = args.ways.split(",")
        if unknown := [w for w in ways if w not in WAYS]:
            ap.error(f"--ways: unknown {', '.join(unknown)}; choose from {', '.join(WAYS)}")
        results["boards"] = boards(args.boards, args.seed, args.timeout, ways, args.keep)
    if args.out:
        args.out.write_text(json.dumps(results, indent=1) + "\n")


if __name__ == "__main__":
    main()
