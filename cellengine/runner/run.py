"""A run from its start to its end, or from where a stopped run left off: the driver
opened, the arms moved to where the run goes on, the program played, all journaled.

Resuming compiles the plan again (the same files give the same program; masses the load
cell had read are used again); it must begin with the segments the journal says were
finished, so that none is repeated. The journal is appended to; the run directory's
trajectory and report are the program's.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

from cellengine.errors import InputError, Problem, display_path, known, printable
from cellengine.journal import JOURNAL, Entry, append, refuse_unfinished
from cellengine.runfolder import open_append, using
from cellengine.runner.driver import DriverOptions, confirm, open_driver
from cellengine.runner.identity import differences, run_identity
from cellengine.runner.move import move_to
from cellengine.runner.outcome import journaled, timed
from cellengine.runner.play import play

if TYPE_CHECKING:
    from cellengine.drivers.base import Driver
    from cellengine.journal import Progress
    from cellengine.pipeline import Compiled


def run_plan(
    compiled: Compiled, out: Path, driver_options: DriverOptions, yes: bool, quiet: bool
) -> None:
    """Write the run directory ``out`` and play the program in it from the start."""
    from cellengine.pipeline import write_plan_outputs

    with using(out):
        if (replaced := refuse_unfinished(out)) is not None:
            print(printable(replaced), file=sys.stderr)
        paths = write_plan_outputs(compiled, out)
        driver = open_driver(compiled, driver_options)
        confirm(driver, yes)
        with open_append(out / JOURNAL) as journal, driver:
            plan, kind = str(compiled.loaded.plan.file), type(driver).__name__
            run = run_identity(compiled)
            append(journal, Entry.START, plan=plan, driver=kind, run=run)
            _drive(compiled, driver, journal, out, quiet)
    if not quiet:
        print(
            f"ran {len(compiled.program.segments)} segments, "
            f"{compiled.program.duration:.2f} s of motion ({compiled.strategy})"
        )
        print(f"report: {display_path(paths['html'])}")


def resume_run(
    run_dir: Path,
    compile_plan: Callable[[], Compiled],
    driver_options: DriverOptions,
    yes: bool,
    quiet: bool,
) -> None:
    """Go on with the run in ``run_dir`` from the last segment it finished, the plan compiled
    by ``compile_plan`` (only when there is something left to do)."""
    from cellengine.journal import drop_torn_tail, read_progress
    from cellengine.pipeline import write_plan_outputs

    journal_path = run_dir / JOURNAL
    with using(run_dir):
        progress = read_progress(journal_path)
        if progress.ended:
            if not quiet:
                print(f"the run in {printable(display_path(run_dir))} is complete: nothing to do")
            return
        compiled = _resumable(compile_plan(), progress, run_dir)
        _fits_cell(progress, compiled, journal_path)
        write_plan_outputs(compiled, run_dir)
        q0, grippers = _where_left(progress)
        driver = open_driver(compiled, driver_options, q0=q0, grippers=grippers)
        confirm(driver, yes)
        nxt = compiled.program.segments[progress.done].segment.label
        drop_torn_tail(journal_path)
        with open_append(journal_path) as journal, driver:
            append(journal, Entry.RESUME, from_segment=progress.done, label=nxt)
            _drive(compiled, driver, journal, run_dir, quiet, progress, q0)
    if not quiet:
        done = len(compiled.program.segments) - progress.done
        print(f"resumed at segment {progress.done} ('{printable(nxt)}'): ran {done} more")


def _drive(
    compiled: Compiled,
    driver: Driver,
    journal: IO[str],
    out: Path,
    quiet: bool,
    progress: Progress | None = None,
    left: Any = None,
) -> None:
    """The driver's life around the program, from the first segment ``progress`` did not
    finish (and from where the arms were ``left``), to the journal's end."""
    start, measured = (0, None) if progress is None else (progress.done, progress.measured)

    def go_on() -> None:
        play(compiled, driver, journal, quiet, out, start, measured)

    with timed(journal, driver, out, quiet, compiled):
        driver.configure()
        driver.activate()
        move_to(compiled, driver, journal, start, left)
        journaled(journal, driver, go_on)
        driver.deactivate()
    append(journal, Entry.END, duration=compiled.program.duration)


def _resumable(compiled: Compiled, progress: Progress, run_dir: Path) -> Compiled:
    """``compiled`` again with the masses the run measured; an error unless it begins with
    the segments the run finished and has more."""
    from cellengine.pipeline import compile_loaded

    _same_run(compiled, progress, run_dir)
    if progress.measured:
        compiled = compile_loaded(
            compiled.loaded, compiled.strategy, context=compiled.context, masses=progress.measured
        )
    labels = tuple(s.segment.label for s in compiled.program.segments)
    if labels[: progress.done] != progress.labels:
        pairs = enumerate(zip(labels, progress.labels, strict=False))
        k = next((i for i, (a, b) in pairs if a != b), len(labels))
        now = f"'{labels[k]}'" if k < len(labels) else "missing (the plan is shorter)"
        raise InputError(
            Problem(
                f"the plan no longer compiles to the segments the run in {run_dir} did: "
                f"segment {k} is now {now}, the run did '{progress.labels[k]}'",
                str(compiled.loaded.plan.file),
            )
        )
    if progress.done >= len(labels):
        raise InputError(Problem("every segment was finished; only the end was not journaled"))
    return compiled


def _same_run(compiled: Compiled, progress: Progress, run_dir: Path) -> None:
    """An error unless the run in ``run_dir`` was compiled from the same files, with the same
    execution, by the same engine (its journaled identity)."""
    journal = str(run_dir / JOURNAL)
    if progress.run is None:
        raise InputError(
            Problem(
                "the journal records no run identity (its start entry is missing, or an older "
                "cellengine wrote it): the run cannot be resumed safely; start a new run in "
                "another folder",
                journal,
            )
        )
    changed = differences(progress.run, run_identity(compiled))
    if changed:
        raise InputError(
            Problem(
                f"the run in {display_path(run_dir)} started from other inputs: "
                + "; ".join(changed)
                + ". Resume it with the files and options it started with, or start a new "
                "run in another folder",
                str(compiled.loaded.plan.file),
            )
        )


def _fits_cell(progress: Progress, compiled: Compiled, journal: Path) -> None:
    """The joints, arms, jaw modes and objects the journal gives are the cell's: the
    simulated cell starts where the journal left the arms, and the plan weighs with its
    masses."""
    cell, objects = compiled.world.cell, compiled.world.objects.names()
    joints = len(compiled.cell.joint_names)
    fault = progress.fault or {}
    problems: list[str] = []
    for where, q in (("finished", progress.q), ("fault", fault.get("q"))):
        if q is not None and len(q) != joints:
            problems.append(
                f"the last '{where}' entry gives {len(q)} joint values; the cell has {joints}"
            )
    states = [(arm, mode, holds) for arm, (mode, holds) in progress.grippers.items()]
    states += [(g["arm"], g.get("mode"), g.get("holds")) for g in fault.get("grippers", [])]
    for arm, mode, holds in states:
        robot = cell.robots.get(arm)
        tool = cell.tools.get(robot.tool) if robot is not None and robot.tool else None
        modes = list(tool.jaw) if tool is not None else []
        if robot is None:
            problems.append(f"unknown arm '{arm}'" + known(cell.robots))
        elif mode is not None and mode not in modes:
            problems.append(f"arm '{arm}': unknown jaw mode '{mode}'" + known(modes))
        elif holds is not None and holds not in objects:
            problems.append(f"arm '{arm}' holds unknown object '{holds}'" + known(objects))
    for name in progress.measured:
        if name not in objects:
            problems.append(f"a mass measured for unknown object '{name}'" + known(objects))
    if problems:
        raise InputError(Problem(p, str(journal)) for p in dict.fromkeys(problems))


def _where_left(progress: Progress) -> tuple[Any, dict[str, Any] | None]:
    """Where the run left the arms and grippers (the simulated cell starts there): where a
    fault stopped them, else where the last finished segment left them."""
    stopped = progress.fault or {}
    q0 = stopped.get("q", progress.q)
    grippers: dict[str, Any] | None = dict(progress.grippers) or None
    if stopped.get("grippers"):
        grippers = {g["arm"]: (g["mode"], g["holds"]) for g in stopped["grippers"]}
    return q0, grippers
