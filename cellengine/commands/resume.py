"""`cellengine run PLAN --resume RUN_DIR`: go on with a stopped run from the last segment it
finished, without repeating what was done.

The plan is compiled again (the same files give the same program; masses the load cell had
read are used again) and must begin with the segments the journal says were finished. The
arms must be where the next segment starts; when they are not (a protective stop
mid-segment), a safe move is planned there first (execute/recovery.py). The journal is
appended to; the run directory's trajectory and report are the program's.
"""

from __future__ import annotations

import argparse

from cellengine.commands.plan import compile_from_args
from cellengine.commands.run import (
    _confirm,
    _driver,
    _entry,
    _play,
    journaled,
    move_to,
    timed,
)
from cellengine.errors import EXIT_OK, InputError, Problem, display_path


def resume(args: argparse.Namespace) -> int:
    from cellengine.journal import drop_torn_tail, read_progress
    from cellengine.pipeline import compile_loaded, write_plan_outputs

    run_dir = args.resume
    journal_path = run_dir / "journal.jsonl"
    progress = read_progress(journal_path)
    if progress.ended:
        if not args.quiet:
            print(f"the run in {display_path(run_dir)} is complete: nothing to do")
        return EXIT_OK
    compiled = compile_from_args(args)
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
    write_plan_outputs(compiled, run_dir)
    # the simulated cell is where the run left it: where a fault stopped the arms, else
    # where the last finished segment left them
    stopped = progress.fault or {}
    q0 = stopped.get("q", progress.q)
    grippers = progress.grippers or None
    if stopped.get("grippers"):
        grippers = {g["arm"]: (g["mode"], g["holds"]) for g in stopped["grippers"]}
    driver = _driver(compiled, args, q0=q0, grippers=grippers)
    _confirm(driver, args.yes)
    nxt = compiled.program.segments[progress.done]
    drop_torn_tail(journal_path)
    with journal_path.open("a") as journal, driver:
        _entry(journal, "resume", from_segment=progress.done, label=nxt.segment.label)

        def go_on() -> None:
            _play(compiled, driver, journal, args.quiet, run_dir, progress.done, progress.measured)

        with timed(journal, driver, run_dir, args.quiet):
            driver.configure()
            driver.activate()
            move_to(compiled, driver, journal, progress.done, q0)
            journaled(journal, driver, go_on)
            driver.deactivate()
        _entry(journal, "end", duration=compiled.program.duration)
    if not args.quiet:
        done = len(labels) - progress.done
        print(f"resumed at segment {progress.done} ('{nxt.segment.label}'): ran {done} more")
    return EXIT_OK
