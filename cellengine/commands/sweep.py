"""`cellengine sweep PLAN --vary KEY=[...] | --variants FILE`: compile variants of a plan's
files and write one table of feasibility, cycle time and least clearance per variant."""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path
from typing import Any

from cellengine.commands.plan import add_cache_options, cache_of
from cellengine.commands.validate import seconds
from cellengine.errors import EXIT_OK, Problem, UsageError, display_path


def add_parser(sub: Any, name: str) -> None:
    p = sub.add_parser(
        name,
        help="compile variants of a plan's files into one table",
        description="Compile every variant of PLAN's files (values set over them, none "
        "written) and write one row per variant: feasible or why not, cycle time, the least "
        "clearance between the arms and to the cell. Keys: PLATFORM.ELEMENT.xyz or .rpy "
        "(the element in its platform's frame), or cell:KEY, objects:KEY, plan:KEY (a "
        "dotted path into that file; list items by index), values in the file's units.",
    )
    p.add_argument("plan", type=Path, metavar="PLAN")
    given = p.add_mutually_exclusive_group(required=True)
    given.add_argument(
        "--vary",
        action="append",
        metavar="KEY=[V1,V2,...]",
        help="values of one key; several --vary: every combination",
    )
    given.add_argument(
        "--variants", type=Path, metavar="FILE", help="a YAML list of variants (maps of KEY: value)"
    )
    p.add_argument(
        "--out", type=Path, metavar="FILE", help="the table (.csv or .json; else CSV on stdout)"
    )
    p.add_argument(
        "--jobs", "-j", type=int, metavar="N", help="worker processes (default: one per core)"
    )
    p.add_argument("--cluster", metavar="ADDRESS", help="compile on a Ray cluster (as validate)")
    add_cache_options(p)
    p.add_argument(
        "--timeout",
        type=seconds,
        metavar="SECONDS",
        help="a variant not compiled within SECONDS is a row saying so",
    )
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from cellengine.info.load import load_plan
    from cellengine.sweep import from_file, from_vary, run_sweep, table_text
    from cellengine.workers import default_jobs

    if not os.path.lexists(args.plan):
        raise UsageError.at("no such plan file", args.plan)
    if args.jobs is not None and args.jobs < 1:
        raise UsageError(Problem(f"--jobs must be at least 1, got {args.jobs}"))
    fmt = "json" if args.out is not None and args.out.suffix == ".json" else "csv"
    if args.out is not None and args.out.suffix not in (".csv", ".json"):
        raise UsageError.at("the table is a .csv or a .json file", args.out)
    platforms = load_plan(args.plan).world.platforms
    variants = from_vary(args.vary, platforms) if args.vary else from_file(args.variants, platforms)
    cache = cache_of(args)
    jobs = args.jobs or default_jobs()
    rows = run_sweep(args.plan, variants, jobs, args.cluster, cache, timeout=args.timeout)
    text = table_text(rows, fmt)
    if args.out is None:
        sys.stdout.write(text)
    else:
        args.out.write_text(text)
    feasible = sum(1 for r in rows if r["feasible"])
    where = "" if args.out is None else f": {display_path(args.out)}"
    print(f"{len(rows)} variant(s), {feasible} feasible{where}", file=sys.stderr)
    return EXIT_OK
