"""Playing a program segment by segment, journaled, and planning the rest again when a
measurement changes what the plan chooses at run time."""

from __future__ import annotations

from collections.abc import Collection, Sequence
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

from cellengine.drivers.fault import DriverFault
from cellengine.journal import Entry, append
from cellengine.program import Measure

if TYPE_CHECKING:
    from cellengine.drivers.base import Driver
    from cellengine.pipeline import Compiled
    from cellengine.program import Program, Segment, TimedEvent
    from cellengine.runner.live import Live


def play(
    compiled: Compiled,
    driver: Driver,
    journal: IO[str],
    quiet: bool,
    out: Path,
    start: int = 0,
    measured: dict[str, float] | None = None,
    shown: Live | None = None,
) -> None:
    """Send every segment from ``start``; after a segment that measures, read the load cell.
    When the masses measured (and ``measured``, read by an earlier run) change what a runtime
    choice picks, the plan is compiled again with them and the run goes on with the new
    program from the first segment that differs (the ones before are the same; both robots
    at once: what is left of both streams, placed again from where they are), its
    trajectory and report written over the first ones. ``shown``: told of each segment
    before it is sent."""
    from cellengine.drivers.play import segment_events
    from cellengine.pipeline import write_plan_outputs

    program = compiled.program
    events_of = segment_events(program)
    measured = dict(measured or {})
    planned = dict(measured)  # the masses the program was planned with
    i = start
    while i < len(program.segments):
        if shown is not None:
            shown.segment(compiled, i)
        _send(driver, journal, program, i, events_of[i], compiled.cell.arms)
        i += 1
        if not _weigh(driver, journal, program.segments[i - 1].segment, measured):
            continue
        again = _recompiled(compiled, planned, measured, i)
        if again is None:
            continue
        planned = dict(measured)
        write_plan_outputs(again, out)  # the whole plan as it now is
        if program.streams:  # both robots at once: what is left, from where they are
            t = program.segments[i - 1].trajectory.end_time
            again = again.rest(*program.streams_at(t))
            i = 0
        compiled, program = again, again.program
        events_of = segment_events(program)
        append(journal, Entry.REPLANNED, reason="measured masses changed a choice")
        _still_running(compiled, driver, out)
        if not quiet:
            print("measured masses changed a runtime choice: replanned")


def _still_running(compiled: Compiled, driver: Driver, out: Path) -> None:
    """The new program's report says, as the first one did, that the run goes on."""
    from cellengine.report.outcome import write_run
    from cellengine.runner.ran import run_summary

    write_run(out, run_summary(compiled, driver.kind, out, running=True))


def _send(
    driver: Driver,
    journal: IO[str],
    program: Program,
    index: int,
    events: Sequence[TimedEvent],
    arms: Collection[str],
) -> None:
    """Segment ``index`` played, journaled before (sent) and after (finished, with where the
    arms and grippers are: where ``--resume`` starts from)."""
    segment = program.segments[index]
    seg = segment.segment
    append(journal, Entry.SENT, step=seg.step, segment=index, label=seg.label)
    carried = dict(driver.tools)
    try:
        driver.execute(segment, events)
    except DriverFault as e:
        if program.streams and e.fault.time is not None:  # the fault entry says it too
            e.streams = streams_entry(program, e.fault.time)
        raise
    for change in seg.changes:  # the driver changed tools at the segment's end
        append(
            journal,
            Entry.TOOL,
            step=seg.step,
            segment=index,
            arm=change.arm,
            tool=change.tool,
            was=carried[change.arm],
        )
        carried[change.arm] = change.tool
    grippers = {arm: list(driver.gripper(arm)) for arm in arms}
    more: dict[str, Any] = {}
    if program.streams:  # what --resume goes on from: each robot's segments
        more["streams"] = streams_entry(program, segment.trajectory.end_time)
    append(
        journal,
        Entry.FINISHED,
        step=seg.step,
        segment=index,
        label=seg.label,
        q=[round(float(v), 6) for v in driver.joint_state()],
        grippers=grippers,
        **more,
    )


def streams_entry(program: Program, t: float) -> dict[str, Any]:
    """Both robots at once: the segments of their streams finished and running at program
    time ``t``, and where the program has the arms then (what ``--resume`` goes on from)."""
    done, running, q = program.streams_at(t)
    return {
        "done": sorted(done),
        "running": sorted(running),
        "q": [round(float(v), 9) for v in q],
    }


def _weigh(driver: Driver, journal: IO[str], seg: Segment, measured: dict[str, float]) -> bool:
    """After a segment with a :class:`Measure`: each load cell read into ``measured``,
    journaled. Whether anything was measured."""
    measures = [a for a in seg.annotations if isinstance(a, Measure)]
    for m in measures:
        measured[m.object] = driver.read_mass(m.arm, of=m.object)
        mass = measured[m.object]
        append(journal, Entry.MEASURED, step=seg.step, object=m.object, arm=m.arm, mass_kg=mass)
    return bool(measures)


def _recompiled(
    compiled: Compiled, planned: dict[str, float], measured: dict[str, float], done: int
) -> Compiled | None:
    """The plan compiled again with the masses measured, if they change a runtime choice;
    the first ``done`` segments, already run, must be the same in it (the arms at once:
    the segments of the streams finished or running)."""
    from cellengine.pipeline import compile_loaded

    if not _choices_changed(compiled, planned, measured):
        return None
    again = compile_loaded(
        compiled.loaded, compiled.strategy, context=compiled.context, masses=measured
    )
    program = compiled.program
    if program.streams:
        finished, running, _ = program.streams_at(program.segments[done - 1].trajectory.end_time)
        new = {s.index: s.label for s in again.program.streams}
        old = {s.index: s.label for s in program.streams}
        same = all(new.get(k) == old[k] for k in running | (finished & set(old)))
        same = same and all(k in new for k in finished)
    else:
        before = [s.segment.label for s in program.segments[:done]]
        same = [s.segment.label for s in again.program.segments[:done]] == before
    if not same:
        raise RuntimeError("replanning changed segments already run")  # a bug, not input
    return again


def _choices_changed(
    compiled: Compiled, planned: dict[str, float], measured: dict[str, float]
) -> bool:
    """Whether a runtime choice whose every candidate has now been weighed picks otherwise
    than the program (planned with ``planned`` over objects.yaml's masses) does."""
    from cellengine.choices import choices

    world, steps = compiled.world, compiled.loaded.plan.steps
    now = choices(world, steps, measured, measured_only=True)
    then = choices(world, steps, planned)
    return not all(then.get(k) == v for k, v in now.items())
