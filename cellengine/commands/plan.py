"""`cellengine plan PLAN [--out DIR]`: compile a plan to a validated program (no driver)."""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

from cellengine.cache import CACHE_ENV, Cache, Hit, default_folder
from cellengine.errors import EXIT_OK, UsageError, display_path, printable
from cellengine.info.files import real, recording

if TYPE_CHECKING:  # the motion stack is imported when a command runs, not by `--help`
    from cellengine.pipeline import Compiled, Progress

EXECUTIONS = ("split", "sync", "async", "sequential")


def add_parser(sub: Any, name: str) -> None:
    p = sub.add_parser(
        name,
        help="compile a plan into trajectories and a report (no motion)",
        description="Compile PLAN: skills, motion planning, time parameterisation "
        "and the trajectory gate; write trajectory.json, report.json and "
        "report.html. Nothing is sent to a driver.",
    )
    add_common(p)
    add_cache_options(p)
    p.set_defaults(run=run)


def cache_of(args: argparse.Namespace) -> Cache | None:
    """The compile cache the options name (None with ``--no-cache``)."""
    return None if args.no_cache else Cache(args.cache_dir or default_folder())


def add_cache_options(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--no-cache",
        action="store_true",
        help="compile, neither using nor keeping the compile cache",
    )
    p.add_argument(
        "--cache-dir",
        type=Path,
        metavar="DIR",
        help=f"the compile cache's folder (default: ${CACHE_ENV}, else ~/.cache/cellengine)",
    )


def add_common(p: argparse.ArgumentParser) -> None:
    p.add_argument("plan", type=Path, metavar="PLAN")
    p.add_argument("--out", type=Path, default=Path("run"), help="run directory (default: run)")
    p.add_argument("--execution", choices=EXECUTIONS, help="override the plan's execution")
    p.add_argument(
        "--cell", type=Path, metavar="CELL", help="run the plan in this cell file instead"
    )
    p.add_argument("-q", "--quiet", action="store_true", help="no progress lines")
    p.add_argument(
        "--speed",
        type=_fraction,
        default=1.0,
        metavar="FRACTION",
        help="slow every motion to this fraction (0 < FRACTION <= 1) of the files' speeds "
        "(velocity, acceleration and TCP speed cap), e.g. 0.25 for a first run",
    )


def _fraction(text: str) -> float:
    """``--speed``'s value: a number in (0, 1] (argparse makes anything else exit 2)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: '{text}'") from None
    if not 0.0 < value <= 1.0:  # also refuses nan
        raise argparse.ArgumentTypeError(f"must be more than 0 and at most 1, got {text}")
    return value


def compile_from_args(args: argparse.Namespace) -> Compiled:
    from cellengine.pipeline import compile_plan

    # a path that is there but not a file (a FIFO, a loop of links) is the loader's to name
    if not os.path.lexists(args.plan):
        raise UsageError.at("no such plan file", args.plan)
    if args.cell is not None and not os.path.lexists(args.cell):
        raise UsageError.at("no such cell file", args.cell)
    progress = None if args.quiet else _progress()
    compiled = compile_plan(
        args.plan, args.execution, progress=progress, cell=args.cell, speed=args.speed
    )
    for w in compiled.world.warnings:
        print(w.warning(), file=sys.stderr)
    return compiled


def compile_reporting(args: argparse.Namespace) -> Compiled:
    """:func:`compile_from_args`; a plan that cannot run gets the report of its failure in
    ``--out`` (cellengine/failed.py), and every failure found is raised."""
    from cellengine.pipeline import CompileFailed

    try:
        return compile_from_args(args)
    except CompileFailed as e:
        from cellengine.failed import report_failure

        raise report_failure(e, args.out, args.quiet) from None


def _progress() -> Progress:
    t0 = time.perf_counter()

    def show(step: int, steps: int, skill: str) -> None:
        print(f"[{step + 1}/{steps}] {skill}  ({time.perf_counter() - t0:.1f} s)", file=sys.stderr)

    return show


def run(args: argparse.Namespace) -> int:
    from cellengine.journal import refuse_unfinished
    from cellengine.pipeline import write_plan_outputs
    from cellengine.runfolder import using

    cache = cache_of(args)
    request = _request(args)
    if cache is not None and (hit := cache.lookup(request, OUTPUTS)) is not None:
        return _from_cache(args, hit)
    with recording() as reads:
        compiled = compile_reporting(args)
    with using(args.out):
        if (replaced := refuse_unfinished(args.out)) is not None:
            print(printable(replaced), file=sys.stderr)
        paths = write_plan_outputs(compiled, args.out)
    summary = {
        "segments": len(compiled.program.streams) or len(compiled.program.segments),
        "duration": compiled.program.duration,
        "in_turn": in_turn(compiled),
        "strategy": compiled.strategy,
        "warnings": [w.warning() for w in compiled.world.warnings],
    }
    if cache is not None:
        written = (paths["trajectory"], paths["report"], paths["html"])
        cache.store(request, reads, summary, {p.name: p.read_bytes() for p in written})
    _said(args, summary, paths["html"])
    return EXIT_OK


# the files `plan` writes (cellengine.pipeline, cellengine.report.write), kept in the cache
OUTPUTS = ("trajectory.json", "report.json", "report.html")


def in_turn(compiled: Compiled) -> float | None:
    """Both robots at once: the same segments' cycle one after another (s); else None."""
    streams = compiled.report.get("streams") or {}
    return float(streams["one_after_another_s"]) if streams.get("at_once") else None


def at_once(in_turn: float | None) -> str:
    """What a summary line says of both robots at once, if they are."""
    return "" if in_turn is None else f" with both robots at once ({in_turn:.2f} s in turn)"


def _request(args: argparse.Namespace) -> dict[str, object]:
    """What decides the outputs besides the files: the paths as given (the reports name
    them) and the options."""
    cell = None if args.cell is None else [str(args.cell), str(real(args.cell))]
    return {
        "command": "plan",
        "plan": [str(args.plan), str(real(args.plan))],
        "cell": cell,
        "cwd": os.getcwd(),
        "execution": args.execution,
        "speed": args.speed,
    }


def _from_cache(args: argparse.Namespace, hit: Hit) -> int:
    """The outputs of the same files compiled before, written as a compile would."""
    from cellengine.journal import refuse_unfinished
    from cellengine.outfiles import write_files
    from cellengine.runfolder import using

    for warning in hit.result["warnings"]:
        print(warning, file=sys.stderr)
    with using(args.out):
        if (replaced := refuse_unfinished(args.out)) is not None:
            print(printable(replaced), file=sys.stderr)
        paths = write_files(args.out, {n: hit.blobs[n].decode() for n in OUTPUTS})
    _said(args, hit.result, paths["report.html"], " (from the compile cache)")
    return EXIT_OK


def _said(args: argparse.Namespace, summary: dict[str, Any], html: Path, how: str = "") -> None:
    if not args.quiet:
        print(
            f"compiled {summary['segments']} segments, {summary['duration']:.2f} s of motion"
            f"{at_once(summary.get('in_turn'))} ({summary['strategy']}){how}"
        )
        print(f"report: {display_path(html)}")
