"""A plan that failed to compile: every failure found without guessing where the arms would
be, and its report in the run folder.

Which failures: the compile's own (what ``plan`` and ``run`` always printed), and, when that
is a skill refusing a step, the first motion failure of the steps before it. The compiler grows
the plan's candidates to its end before compiling any, so a step the skills refuse hides every
motion failure before it; those steps start where the arms are at home and do not depend on
the refused one, so compiling them is sound. Nothing is compiled after a failed segment: each
segment starts from the whole cell's configuration and what the grippers hold where the one
before left them (both arms: each is the other's obstacle), and a failed segment leaves no
such state, so what comes after could be checked only from a guessed one. Nor can the skills
go past a step they refuse: a family offers a step's candidates from the candidate taken
before it.

The report (:mod:`cellengine.report.failure`) replaces report.json and report.html; a
trajectory.json there (an earlier plan's) is removed first, so nothing executable is left
beside the report of a plan that cannot run. A folder holding an unfinished run is left as it
is: its files are that run's, for ``--resume`` (:func:`~cellengine.journal.refuse_unfinished`).
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path

from cellengine.errors import InputError, Problem, StepError, display_path, printable
from cellengine.execute.compile import Compiler
from cellengine.execute.search import add_all
from cellengine.journal import refuse_unfinished
from cellengine.outfiles import write_files
from cellengine.pipeline import TRAJECTORY_JSON, CompileFailed, step_label
from cellengine.program import Program
from cellengine.report.failure import Found, failure_texts
from cellengine.report.write import REPORT_HTML
from cellengine.runfolder import using


@dataclass(frozen=True)
class FailedPlan:
    """``error`` examined: ``program``, what was compiled before the first failure; ``found``,
    every failure (the error's first); ``problems``, theirs as printed."""

    error: CompileFailed
    program: Program
    found: tuple[Found, ...]
    problems: tuple[Problem, ...]


def examine(error: CompileFailed) -> FailedPlan:
    """Every failure of ``error``'s plan that can be found (see the module's notes)."""
    first = Found(tuple(str(p) for p in error.problems), error.failure)
    failure, ctx = error.failure, error.context
    empty = Program(ctx.cell.joint_names, (), ())
    if failure is None or not failure.ahead:
        before = failure.before if failure is not None else None
        return FailedPlan(error, before or empty, (first,), error.problems)
    compiler = Compiler(
        ctx.world, ctx.cell, ctx.checker, ctx.home, error.strategy,  # type: ignore[arg-type]
        clearance=ctx.clearance, tooled=ctx.tooled_parts,
    )  # fmt: skip
    try:
        add_all(compiler, failure.ahead)
    except InputError as e:
        located = error.loaded.plan.locate(e) if isinstance(e, StepError) else e
        also = Found(tuple(str(p) for p in located.problems), e.failure)
        before = e.failure.before if e.failure is not None else None
        return FailedPlan(
            error, before or empty, (first, also), (*error.problems, *located.problems)
        )
    return FailedPlan(error, compiler.program(), (first,), error.problems)


def report_failure(error: CompileFailed, out: Path, quiet: bool) -> InputError:
    """Write the report of ``error``'s plan into ``out`` (see the module's notes); the error
    to raise: every failure's problems, the compile's first (as it always said), then why no
    report was written, if none was."""
    failed = examine(error)
    problems = failed.problems
    try:
        html = write_failure(failed, out)
    except InputError as e:  # a run folder that cannot be written, or holds a run to resume
        why = [
            Problem(f"no report written: {p.message}", p.file, p.line, p.col) for p in e.problems
        ]
        html, problems = None, (*problems, *why)
    if html is not None and not quiet:
        print(f"report: {display_path(html)}")
    raised = InputError(problems)
    raised.failure = error.failure
    return raised


def write_failure(failed: FailedPlan, out: Path) -> Path:
    """report.json and report.html of ``failed`` into ``out``, trajectory.json removed; the
    page's path. InputError, with nothing written, when ``out`` holds an unfinished run."""
    plan, ctx = failed.error.loaded.plan, failed.error.context
    with using(out):
        if (replaced := refuse_unfinished(out)) is not None:
            print(printable(replaced), file=sys.stderr)
        (out / TRAJECTORY_JSON).unlink(missing_ok=True)
        extra = {
            "plan": str(plan.file),
            "execution": failed.error.strategy,
            "duration": failed.program.duration,
            "clearance_m": ctx.clearance,
        }
        texts = failure_texts(
            failed.program,
            ctx.world,
            ctx.cell,
            failed.found,
            extra,
            step_labels={i: step_label(step) for i, step in enumerate(plan.steps)},
            title=f"{plan.file.name}: FAILED",
        )
        return write_files(out, texts)[REPORT_HTML]
