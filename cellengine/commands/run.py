"""`cellengine run PLAN`: compile, write the run directory, and play it on the cell's driver
(the simulated cell by default), with an append-only journal flushed at every entry;
`--resume RUN_DIR` goes on with a stopped run (cellengine/runner/ does both)."""

from __future__ import annotations

import argparse
import json
import os
import sys
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from cellengine.commands.plan import add_common, compile_from_args, compile_reporting
from cellengine.errors import EXIT_OK, UsageError, known

if TYPE_CHECKING:
    from cellengine.pipeline import Compiled

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
    p.add_argument(
        "--locate",
        type=Path,
        metavar="IMAGE",
        help="before planning, locate the containers in this picture from the cell's camera "
        "(as `cellengine locate`) and plan with them where they were found",
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
    if args.resume is not None and args.locate is not None:
        raise UsageError.at(
            "--locate with --resume: a resumed run keeps the places located at its start", None
        )
    if args.resume is not None:  # compiled only if the run has something left to do
        resume_run(
            args.resume,
            lambda: at_places(args, journaled_places(args.resume), compile_from_args),
            options,
            args.yes,
            args.quiet,
        )
    else:
        places = located_places(args) if args.locate is not None else None
        compiled = at_places(args, places, compile_reporting)
        run_plan(compiled, args.out, options, args.yes, args.quiet, args.cycles)
    return EXIT_OK


def located_places(args: argparse.Namespace) -> dict[str, Any]:
    """The containers' `at` where the camera finds them in ``--locate``'s picture; what it
    found printed (to stderr: stdout is the run's)."""
    from cellengine.info.load import load_plan
    from cellengine.locate.session import at_settings, located, table

    if not os.path.lexists(args.plan):
        raise UsageError.at("no such plan file", args.plan)
    world = load_plan(args.plan, cell=args.cell).world
    found = located(world, args.locate, None)
    if not args.quiet:
        print("\n".join(table(world, found)), file=sys.stderr)
    return at_settings(world, found)


def journaled_places(run_dir: Path) -> dict[str, Any] | None:
    """The places a run located at its start (its journaled identity's), if it did."""
    from cellengine.journal import JOURNAL, read_progress

    run = read_progress(run_dir / JOURNAL).run or {}
    located = run.get("located")
    return json.loads(located) if isinstance(located, str) else None


def at_places(
    args: argparse.Namespace,
    places: dict[str, Any] | None,
    compile_with: Callable[[argparse.Namespace], Compiled],
) -> Compiled:
    """The plan compiled with the containers' `at` set to ``places`` (none: as the files
    say)."""
    from cellengine.info.settings import settings

    if not places:
        return compile_with(args)
    values = [("objects", ("containers", name, "at"), v) for name, v in places.items()]
    with settings(values):
        compiled = compile_with(args)
    return replace(compiled, located=places)
