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
from dataclasses import replace
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

import numpy as np

from cellengine.errors import InputError, Problem, display_path, known, printable
from cellengine.journal import JOURNAL, Entry, append, refuse_unfinished
from cellengine.runfolder import open_append, using
from cellengine.runner.cycles import check_cycles
from cellengine.runner.driver import DriverOptions, confirm, open_driver
from cellengine.runner.hint import resumable, resume_command
from cellengine.runner.identity import differences, run_identity
from cellengine.runner.live import live
from cellengine.runner.move import move_to
from cellengine.runner.outcome import journaled, timed
from cellengine.runner.play import play
from cellengine.runner.summary import motion_summary

if TYPE_CHECKING:
    from cellengine.drivers.base import Driver
    from cellengine.journal import Progress
    from cellengine.pipeline import Compiled


def run_plan(
    compiled: Compiled,
    out: Path,
    driver_options: DriverOptions,
    yes: bool,
    quiet: bool,
    cycles: int = 1,
) -> None:
    """Write the run directory ``out`` and play the program in it from the start, ``cycles``
    times (an error before anything moves unless the plan ends where it starts)."""
    from cellengine.pipeline import write_plan_outputs

    check_cycles(compiled, cycles)
    with using(out):
        if (replaced := refuse_unfinished(out)) is not None:
            print(printable(replaced), file=sys.stderr)
        paths = write_plan_outputs(compiled, out)
        driver = open_driver(compiled, driver_options)
        confirm(driver, yes, lambda: motion_summary(compiled, cycles), quiet)
        with open_append(out / JOURNAL) as journal, driver, resumable(_resume(compiled, out)):
            plan, kind = str(compiled.loaded.plan.file), type(driver).__name__
            run = run_identity(compiled)
            append(journal, Entry.START, plan=plan, driver=kind, run=run, cycles=cycles)
            _drive(compiled, driver, journal, out, quiet, cycles=(1, cycles))
    if not quiet:
        times = f" x {cycles} cycles" if cycles > 1 else ""
        from cellengine.commands.plan import at_once, in_turn

        program = compiled.program
        print(
            f"ran {len(program.streams) or len(program.segments)} segments{times}, "
            f"{program.duration:.2f} s of motion{at_once(in_turn(compiled))} "
            f"({compiled.strategy})"
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
        progress = _unweighed(compiled, progress)
        _fits_cell(progress, compiled, journal_path)
        write_plan_outputs(compiled, run_dir)
        q0, grippers = _where_left(progress)
        driver = open_driver(
            compiled,
            driver_options,
            q0=q0,
            grippers=grippers,
            tares=progress.tares,
            at=progress.done,
        )
        left = progress.cycles - progress.cycle + 1
        confirm(driver, yes, lambda: motion_summary(compiled, left), quiet)
        start, cycle = progress.done, progress.cycle
        first = compiled  # the rest of this cycle; the next ones are the whole program
        if progress.streams is not None and compiled.program.streams:
            first = _rest(compiled, progress, run_dir)
            start = 0 if first.program.segments else len(compiled.program.segments)
            first = first if first.program.segments else compiled
        if start == len(compiled.program.segments):  # a cycle finished: the next begins
            start, cycle, first = 0, cycle + 1, compiled
        nxt = first.program.segments[start].segment.label
        drop_torn_tail(journal_path)
        with open_append(journal_path) as journal, driver, resumable(_resume(compiled, run_dir)):
            if cycle != progress.cycle:
                append(journal, Entry.CYCLE, cycle=cycle, of=progress.cycles)
                progress = replace(progress, labels=(), measured={}, cycle=cycle)
            append(journal, Entry.RESUME, from_segment=start, label=nxt)
            _drive(
                compiled,
                driver,
                journal,
                run_dir,
                quiet,
                replace(progress, labels=progress.labels[:start]),
                q0,
                (cycle, progress.cycles),
                first,
            )
    if not quiet:
        done = len(first.program.segments) - start
        print(f"resumed at segment {start} ('{printable(nxt)}'): ran {done} more")


def _drive(
    compiled: Compiled,
    driver: Driver,
    journal: IO[str],
    out: Path,
    quiet: bool,
    progress: Progress | None = None,
    left: Any = None,
    cycles: tuple[int, int] = (1, 1),
    resumed: Compiled | None = None,
) -> None:
    """The driver's life around the program, from the first segment ``progress`` did not
    finish (and from where the arms were ``left``), in cycle ``cycles[0]`` of ``cycles[1]``,
    to the journal's end; ``resumed``: what the first cycle plays instead (both robots at
    once: the rest of their streams)."""
    start, measured = (0, None) if progress is None else (progress.done, progress.measured)
    first, last = cycles
    now = resumed or compiled

    def go_on() -> None:
        shown = live(compiled, quiet)  # drawn while the program plays
        try:
            for cycle in range(first, last + 1):
                if cycle > first:  # the plan ends where it starts (check_cycles)
                    append(journal, Entry.CYCLE, cycle=cycle, of=last)
                shown.cycle(cycle, last)
                begin = start if cycle == first else 0
                again = measured if cycle == first else None
                play(
                    now if cycle == first else compiled,
                    driver,
                    journal,
                    quiet,
                    out,
                    begin,
                    again,
                    shown,
                )
        finally:
            shown.close()  # before anything else is printed

    driver.check_program(now.program)  # a tool it cannot change or work: before anything
    with timed(journal, driver, out, quiet, compiled):
        driver.configure()
        driver.activate()
        if progress is None and driver.tares():  # a resumed run's driver keeps the first's
            append(journal, Entry.TARED, load_cells=driver.tares())
        move_to(now, driver, journal, start, left)
        journaled(journal, driver, go_on)
        driver.deactivate()
    append(journal, Entry.END, duration=compiled.program.duration * (last - first + 1))


def _resume(compiled: Compiled, run_dir: Path) -> str:
    """The command that goes on with the run in ``run_dir``."""
    factor = compiled.context.speed.factor
    return resume_command(compiled.loaded, compiled.strategy, factor, run_dir)


def _rest(compiled: Compiled, progress: Progress, run_dir: Path) -> Compiled:
    """Both robots at once: the rest of their streams from where the journal's last
    finished segment left them (each robot's finished and running segments, the arms)."""
    from cellengine.execute.refused import Refused

    assert progress.streams is not None
    done, running, q = progress.streams
    n = len(compiled.program.streams)
    if len(done) >= n and progress.cycle >= progress.cycles:
        raise InputError(Problem("every segment was finished; only the end was not journaled"))
    if any(i >= n for i in done | running):
        raise InputError(
            Problem(
                f"the journal names segment {max(done | running)} finished or running; the "
                f"plan's streams have {n} segments",
                str(run_dir / JOURNAL),
            )
        )
    try:
        return compiled.rest(done, running, np.asarray(q, dtype=float))
    except Refused as e:
        raise InputError(
            Problem(
                f"the rest of the run cannot be placed from where it stopped: {e}",
                str(run_dir / JOURNAL),
            )
        ) from None


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
    if progress.streams is not None and compiled.program.streams:
        return compiled  # its rest is placed again from each robot's segments (_rest)
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
    if progress.done >= len(labels) and progress.cycle >= progress.cycles:
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


def _unweighed(compiled: Compiled, progress: Progress) -> Progress:
    """A run stopped by its load cell journaled the weighing segment finished but not its
    reading: that segment is taken as not finished, so the resumed run plays what is left
    of it and weighs again (and plans the rest again if the mass changes a choice)."""
    from cellengine.program import Measure

    if not progress.labels:
        return progress
    label = progress.labels[-1]
    seg = next((s.segment for s in compiled.program.segments if s.segment.label == label), None)
    if seg is None or all(
        a.object in progress.measured for a in seg.annotations if isinstance(a, Measure)
    ):
        return progress
    streams = progress.streams
    if streams is not None:
        done, running, q = streams
        k = next(s.index for s in compiled.program.streams if s.label == label)
        streams = (done - {k}, running | {k}, q)
    return replace(progress, labels=progress.labels[:-1], streams=streams)


def _where_left(progress: Progress) -> tuple[Any, dict[str, Any] | None]:
    """Where the run left the arms and grippers (the simulated cell starts there): where a
    fault stopped them, else where the last finished segment left them."""
    stopped = progress.fault or {}
    q0 = stopped.get("q", progress.q)
    grippers: dict[str, Any] | None = dict(progress.grippers) or None
    if stopped.get("grippers"):
        grippers = {g["arm"]: (g["mode"], g["holds"]) for g in stopped["grippers"]}
    return q0, grippers
