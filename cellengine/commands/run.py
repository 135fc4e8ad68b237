"""`cellengine run PLAN`: compile, write the run directory, and play it on the cell's driver
(the simulated cell by default), with an append-only journal flushed at every entry;
`--resume RUN_DIR` goes on with a stopped run (cellengine/runner/ does both)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from cellengine.commands.plan import add_common, compile_from_args, compile_reporting
from cellengine.errors import EXIT_OK, UsageError, known

# The drivers' names (cellengine/drivers/registry.py DRIVERS, which a test keeps equal): here so
# that `--driver foo` is a usage error before anything compiles, without importing the drivers
DRIVER_KINDS = ("sim", "ur_rtde", "lab")


def add_parser(sub: Any, name: str) -> None:
    p = sub.add_parser(
        name,
        help="compile a plan and run it on the cell's driver",
        description="Compile PLAN, write the run directory, and execute it on "
        "the cell's driver (the simulated cell unless the cell says otherwise).",
    )
    add_common(p)
    p.add_argument(
        "--driver",
        type=driver_kind,
        help="driver to use instead of the cell's: " + ", ".join(DRIVER_KINDS),
    )
    p.add_argument("--realtime", action="store_true", help="simulated cell: in real time")
    p.add_argument(
        "--yes", action="store_true", help="move real arms without asking for confirmation"
    )
    p.add_argument(
        "--resume",
        type=Path,
        metavar="RUN_DIR",
        help="go on with the run in RUN_DIR from the last segment it finished",
    )
    p.add_argument(
        "--cycles",
        type=_count,
        default=1,
        metavar="N",
        help="play the plan N times in a row (it must end where it starts: return_home: true)",
    )
    p.set_defaults(run=run)


def driver_kind(value: str) -> str:
    """A --driver value: one of DRIVER_KINDS."""
    if value not in DRIVER_KINDS:
        raise argparse.ArgumentTypeError(f"unknown driver '{value}'" + known(DRIVER_KINDS))
    return value


def _count(text: str) -> int:
    """``--cycles``' value: a whole number from 1 (argparse makes anything else exit 2)."""
    from cellengine.journal import MAX_CYCLES

    if not text.isdigit() or not 1 <= int(text) <= MAX_CYCLES:
        raise argparse.ArgumentTypeError(f"must be a whole number from 1 to {MAX_CYCLES}")
    return int(text)


def run(args: argparse.Namespace) -> int:
    # the runner brings the motion stack and drivers: imported when the command runs
    from cellengine.runner import DriverOptions, resume_run, run_plan

    options = DriverOptions(kind=args.driver, realtime=args.realtime)
    if args.resume is not None and args.cycles != 1:
        raise UsageError.at("--cycles with --resume: a resumed run goes on with its own", None)
    if args.resume is not None:  # compiled only if the run has something left to do
        resume_run(args.resume, lambda: compile_from_args(args), options, args.yes, args.quiet)
    else:
        run_plan(compile_reporting(args), args.out, options, args.yes, args.quiet, args.cycles)
    return EXIT_OK
