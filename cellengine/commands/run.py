"""`cellengine run PLAN`: compile, write the run directory, and play it on the cell's driver
(the simulated cell by default), with an append-only journal flushed at every entry."""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

import numpy as np

from cellengine.commands.plan import add_common, compile_from_args
from cellengine.errors import EXIT_OK, UsageError, display_path

if TYPE_CHECKING:  # the motion stack and drivers are imported when the command runs
    from cellengine.drivers.base import Driver
    from cellengine.pipeline import Compiled


def add_parser(sub: Any, name: str) -> None:
    p = sub.add_parser(
        name,
        help="compile a plan and run it on the cell's driver",
        description="Compile PLAN, write the run directory, and execute it on "
        "the cell's driver (the simulated cell unless the cell says otherwise).",
    )
    add_common(p)
    p.add_argument("--driver", help="driver to use instead of the cell's (e.g. sim)")
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
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from cellengine.pipeline import write_plan_outputs

    if args.resume is not None:
        from cellengine.commands.resume import resume

        return resume(args)
    compiled = compile_from_args(args)
    paths = write_plan_outputs(compiled, args.out)
    driver = _driver(compiled, args)
    _confirm(driver, args.yes)
    with (args.out / "journal.jsonl").open("a") as journal, driver:
        _entry(journal, "start", plan=str(compiled.loaded.plan.file), driver=type(driver).__name__)
        with timed(journal, driver, args.out, args.quiet):
            driver.configure()
            driver.activate()
            move_to(compiled, driver, journal, 0)
            journaled(
                journal, driver, lambda: _play(compiled, driver, journal, args.quiet, args.out)
            )
            driver.deactivate()
        _entry(journal, "end", duration=compiled.program.duration)
    if not args.quiet:
        print(
            f"ran {len(compiled.program.segments)} segments, "
            f"{compiled.program.duration:.2f} s of motion ({compiled.strategy})"
        )
        print(f"report: {display_path(paths['html'])}")
    return EXIT_OK


def _confirm(driver: Driver, yes: bool) -> None:
    """Real arms move only when the user says so: --yes, or 'yes' typed at a terminal."""
    if driver.kind == "sim" or yes:
        return
    where = ", ".join(f"{arm} at {ip}" for arm, ip in getattr(driver, "addresses", {}).items())
    if not sys.stdin.isatty():
        raise UsageError.at(
            f"refusing to move real arms ({where}) without --yes: no terminal to ask", None
        )
    answer = input(f"This moves real arms: {where}. Type 'yes' to go on: ")
    if answer.strip().lower() != "yes":
        raise UsageError.at("not confirmed: nothing moved", None)


def move_to(
    compiled: Compiled, driver: Driver, journal: IO[str], index: int, left: Any = None
) -> None:
    """When the arms are not where segment ``index`` starts (real arms left elsewhere, or
    stopped by a fault), a planned, gated, collision-free move there first (journaled).
    Only from near where the run expects them: the segment's start, or ``left``, where
    the journal says an earlier run left them (a fault may stop them far into a segment)."""

    from cellengine.execute.recovery import recovery_segment

    segment = compiled.program.segments[index]
    q_now = driver.joint_state()
    target = segment.trajectory.q[0]
    if float(np.max(np.abs(q_now - target))) <= driver.start_tolerance:
        return
    label = segment.segment.label
    if left is None:
        _check_move_limit(driver, q_now, target[None, :], f"'{label}' starts")
    else:  # a killed run journals no stop: the arms may be anywhere along the segment
        near = np.vstack([np.asarray(left, dtype=float)[None, :], segment.trajectory.q])
        _check_move_limit(driver, q_now, near, f"the run left it (in or before '{label}')")
    holds = {arm: driver.gripper(arm).holds for arm in compiled.cell.arms}
    move = recovery_segment(
        compiled.world,
        compiled.cell,
        compiled.context.scene,
        q_now,
        target,
        holds,
        driver.start_tolerance,
        segment.segment.step,
    )
    if move is None:
        return
    _entry(journal, "recovery", label=move.segment.label, duration=move.trajectory.duration)

    def go() -> None:
        assert move is not None
        driver.execute(move)

    journaled(journal, driver, go)


def _check_move_limit(driver: Driver, q_now: Any, expected: Any, where: str) -> None:
    """Arms far from every place the run expects them (rows of ``expected``) were put there
    on purpose, or by someone who does not know this run: they are not moved on their own
    (the driver's ``start_move_limit``)."""
    from cellengine.drivers.fault import DriverRefused

    offs = np.abs(q_now[None, :] - expected)
    nearest = int(np.argmin(offs.max(axis=1)))
    target, off = expected[nearest], offs[nearest]
    j = int(np.argmax(off))
    if off[j] <= driver.start_move_limit:
        return
    arm, joint = driver.layout.arm_of(j), driver.joint_names[j]
    raise DriverRefused(
        driver.kind,
        f"arm '{arm}' joint '{joint}' is at {q_now[j]:.4f}, {off[j]:.4f} rad from where "
        f"{where} ({target[j]:.4f}): farther than start_move_limit "
        f"({driver.start_move_limit:g} rad), so the run does not move it there on its own; "
        "jog the arms closer, or raise the driver's start_move_limit in the cell file",
    )


@contextlib.contextmanager
def timed(journal: IO[str], driver: Driver, out: Path, quiet: bool) -> Iterator[None]:
    """Whatever happens inside, afterwards: how the driver's real-time loop kept its period
    (a real driver's), journaled, printed, and in report.json's ``run``."""
    outcome = "fault"
    try:
        yield
        outcome = "completed"
    finally:
        timing = driver.timing()
        if timing is not None:
            from cellengine.drivers.servo_timing import describe
            from cellengine.outfiles import write_files
            from cellengine.report.write import REPORT_JSON

            _entry(journal, "timing", servo=timing)
            report = json.loads((out / REPORT_JSON).read_text())
            report["run"] = {"driver": driver.kind, "outcome": outcome, "servo": timing}
            write_files(out, {REPORT_JSON: json.dumps(report) + "\n"})
            if not quiet:
                print(describe(timing))


def journaled(journal: IO[str], driver: Driver, play: Callable[[], None]) -> None:
    """``play()``; a driver fault is journaled (what, where, when, the controller's safety
    bits, where the arms stopped) before it ends the run, so that ``--resume`` knows."""
    from cellengine.drivers.fault import DriverFault
    from cellengine.drivers.record import FaultRecord

    try:
        play()
    except DriverFault as e:
        record = next(
            (r for r in reversed(driver.recorder.entries) if isinstance(r, FaultRecord)), None
        )
        stopped = record.to_json() if record is not None else {}
        stopped.pop("entry", None)
        _entry(journal, "fault", fault={**e.fault.to_json(), **stopped})
        raise


def _driver(
    compiled: Compiled,
    args: argparse.Namespace,
    q0: Any = None,
    grippers: dict[str, Any] | None = None,
) -> Driver:
    """The cell's driver (or --driver's). The simulated cell starts where the program does,
    or at ``q0`` with ``grippers`` (where a journal left it)."""
    from cellengine.drivers.registry import make_driver

    world, cell = compiled.world, compiled.cell
    joints = {name: arm.joint_names for name, arm in cell.arms.items()}
    options: dict[str, Any] = {}
    if (args.driver or world.cell.driver.kind) == "sim":
        start = compiled.program.segments[0].trajectory.q[0] if q0 is None else q0
        options = {"realtime": args.realtime, "q0": start}
        if grippers is not None:
            options["grippers"] = grippers
    return make_driver(world.cell, joints, objects=world.objects, kind=args.driver, **options)


def _play(
    compiled: Compiled,
    driver: Driver,
    journal: IO[str],
    quiet: bool,
    out: Path,
    start: int = 0,
    measured: dict[str, float] | None = None,
) -> None:
    """Send every segment; after a segment that weighs (``facts["measure"] == "mass"``),
    read the load cell. When a measured mass changes what a runtime choice (``heavier_of``)
    picks, the plan is compiled again with the masses measured and the run goes on with the
    new program from the first segment that differs (the ones before are the same), its
    trajectory and report written over the first ones."""
    from cellengine.drivers.play import segment_events
    from cellengine.pipeline import write_plan_outputs

    program = compiled.program
    events_of = segment_events(program)
    measured = dict(measured or {})
    planned = dict(measured)  # the masses the program was planned with
    i = start
    while i < len(program.segments):
        segment, events = program.segments[i], events_of[i]
        seg = segment.segment
        _entry(journal, "sent", step=seg.step, segment=i, label=seg.label)
        driver.execute(segment, events)
        grippers = {arm: list(driver.gripper(arm)) for arm in compiled.cell.arms}
        _entry(
            journal,
            "finished",
            step=seg.step,
            segment=i,
            label=seg.label,
            q=[round(float(v), 6) for v in driver.joint_state()],
            grippers=grippers,
        )
        if seg.facts.get("measure") == "mass":
            name, arm = str(seg.facts["object"]), str(seg.facts["arm"])
            measured[name] = driver.read_mass(arm)
            _entry(journal, "measured", step=seg.step, object=name, arm=arm, mass_kg=measured[name])
            again = _recompiled(compiled, planned, measured, i + 1)
            if again is not None:
                compiled, program, planned = again, again.program, dict(measured)
                events_of = segment_events(program)
                write_plan_outputs(compiled, out)
                _entry(journal, "replanned", reason="measured masses changed a choice")
                if not quiet:
                    print("measured masses changed a runtime choice: replanned")
        i += 1


def _recompiled(
    compiled: Compiled, planned: dict[str, float], measured: dict[str, float], done: int
) -> Compiled | None:
    """The plan compiled again with the masses measured, if a runtime choice whose every
    candidate has now been weighed picks otherwise than the program (planned with
    ``planned`` over objects.yaml's masses) does; the segments already run must be the same
    in it."""
    from cellengine.choices import choices
    from cellengine.pipeline import compile_loaded

    world, steps = compiled.world, compiled.loaded.plan.steps
    now = choices(world, steps, measured, measured_only=True)
    then = choices(world, steps, planned)
    if all(then.get(k) == v for k, v in now.items()):
        return None
    again = compile_loaded(
        compiled.loaded, compiled.strategy, context=compiled.context, masses=measured
    )
    before = [s.segment.label for s in compiled.program.segments[:done]]
    if [s.segment.label for s in again.program.segments[:done]] != before:
        raise RuntimeError("replanning changed segments already run")  # a bug, not input
    return again


def _entry(journal: IO[str], kind: str, **fields: Any) -> None:
    """One journal line, on disk before the next thing happens."""
    journal.write(json.dumps({"time": time.time(), "entry": kind, **fields}) + "\n")
    journal.flush()
    os.fsync(journal.fileno())
