"""From a plan file to a validated Program, and from a Program to a run directory.

`cellengine plan`, `cellengine run` and `cellengine validate` share this: load and check the
files, build the planning context (robot models, collision scene, IK, home), let the plan's
skill family offer candidates for its steps, and compile them (strategy, merges, the gate,
the next candidate where one cannot run) into a Program.
"""

from __future__ import annotations

import itertools
import json
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

from cellengine.arrays import Vec
from cellengine.concurrency import Overlap
from cellengine.context import PlanningContext, build_context
from cellengine.errors import InputError, Problem, StepError
from cellengine.execute.candidates import compile_candidates
from cellengine.execute.compile import Compiler
from cellengine.execute.home import return_home
from cellengine.execute.overlap import overlapped, resumed, streams_json
from cellengine.family import SkillFamily, families, skill_name
from cellengine.info.load import LoadedPlan, load_plan
from cellengine.info.plan import Plan
from cellengine.motion.robot import CellModel
from cellengine.motion.speed import resolve, speed_json
from cellengine.program import Program, Segment
from cellengine.skill import Skill
from cellengine.world import World

T = TypeVar("T")
Progress = Callable[[int, int, str], None]  # (step index, number of steps, skill)


@dataclass(frozen=True)
class Compiled:
    loaded: LoadedPlan
    context: PlanningContext
    program: Program
    strategy: str
    # report.json entries the family adds (a lab plan's "mission": which robots do each
    # step, when)
    report: Mapping[str, Any] = field(default_factory=dict)
    # what let the arms work at once (the program has streams): a resumed or replanned run
    # places what is left with it again
    overlap: Overlap | None = None
    # the containers' `at` as the camera found them (`run --locate`), in objects.yaml's terms:
    # set over the file for this program, journaled with the run, set again on resuming it
    located: Mapping[str, Any] | None = None

    def rest(self, done: frozenset[int], running: frozenset[int], q: Vec) -> Compiled:
        """The run from where it stopped: the segments ``done`` (of the program's streams)
        finished, those ``running`` stopped part way, the arms at ``q``; the rest placed
        again (execute/overlap.py). Refused when that fails the gate."""
        if self.overlap is None or not self.program.streams:
            raise ValueError("only a program whose arms work at once is resumed by segments")
        ctx = self.context
        program = resumed(
            self.program,
            self.overlap,
            ctx.world,
            ctx.cell,
            ctx.checker.scene,
            ctx.clearance,
            done,
            running,
            np.asarray(q, dtype=float),
        )
        return replace(self, program=program)

    @property
    def world(self) -> World:
        return self.loaded.world

    @property
    def cell(self) -> CellModel:
        return self.context.cell

    @property
    def mission(self) -> list[dict[str, Any]] | None:
        mission = self.report.get("mission")
        return None if mission is None else list(mission)


def family_of(steps: Sequence[Skill]) -> SkillFamily:
    """The one family every step belongs to (a plan is all of one family)."""
    of_skill = families().of_skill
    family = of_skill[steps[0].skill]
    for i, step in enumerate(steps):
        other = of_skill[step.skill]
        if other is not family:
            raise StepError(
                Problem(
                    f"steps[{i}]: {step.skill} cannot be compiled to motion in a plan with "
                    f"{family.name} skills (a plan's skills are all of one family: "
                    + "; ".join(
                        f"{f.name}: {', '.join(skill_name(m) for m in f.skills)}"
                        for f in families().by_name.values()
                    )
                    + ")"
                ),
                i,
            )
    return family


def compile_plan(
    path: Path,
    strategy: str | None = None,
    merge: str = "joint",
    progress: Progress | None = None,
    cell: Path | None = None,
    speed: float = 1.0,
) -> Compiled:
    """Load, check and compile ``path`` (in ``cell`` instead of the plan's cell when
    given; ``speed``: the command line's factor on the files' speeds); InputError (in plan
    terms) when it cannot run."""
    return compile_loaded(load_plan(path, cell=cell), strategy, merge, progress, speed=speed)


def compile_loaded(
    loaded: LoadedPlan,
    strategy: str | None = None,
    merge: str = "joint",
    progress: Progress | None = None,
    context: PlanningContext | None = None,
    masses: Mapping[str, float] | None = None,
    speed: float | None = None,
) -> Compiled:
    """Compile a loaded plan. ``context``: one already built for this plan's world (a
    caller compiling several plans of one cell builds it once); ``masses``: measured masses
    (kg) for runtime choices (else objects.yaml's); ``speed``: the command line's factor on
    the files' speeds (default: the context's, else none)."""
    plan = loaded.plan
    ctx = context if context is not None else build_context(loaded.world)
    factor = ctx.speed.factor if speed is None else speed
    ctx = ctx.with_speed(resolve(loaded.world.cell, plan, factor))
    if masses is not None:
        ctx = ctx.with_masses(masses)
    chosen = strategy or plan.execution
    ctx = ctx.with_execution(chosen)
    compiler = Compiler(
        ctx.world,
        ctx.cell,
        ctx.checker,
        ctx.home,
        "split" if chosen == "sequential" else chosen,  # type: ignore[arg-type]
        merge=merge,  # type: ignore[arg-type]
        clearance=ctx.clearance,
        tooled=ctx.tooled_parts,
    )
    shown: set[int] = set()

    def before_each(segment: Segment) -> None:
        if progress is not None and segment.step not in shown:
            shown.add(segment.step)
            progress(segment.step, len(plan.steps), plan.steps[segment.step].skill)

    def search() -> Compiled:
        family = family_of(plan.steps)
        taken = compile_candidates(compiler, family.plan(ctx, plan.steps), before_each)
        if plan.return_home:
            return_home(compiler, ctx.home, len(plan.steps) - 1)
        program = compiler.program()
        report: dict[str, Any] = {}
        rules = next((c.overlap for c in taken if c.overlap is not None), None)
        if rules is not None and program.changes:
            rules = None  # each stream's segments would run on another arm's tools
        if rules is not None:
            alone = program.duration
            program, why = overlapped(
                program, rules, ctx.world, ctx.cell, ctx.checker.scene, ctx.clearance
            )
            report["streams"] = streams_json(program, alone, why)
        if not program.streams:
            rules = None
        for candidate in taken:
            if candidate.report is not None:
                report.update(candidate.report(program))
        return Compiled(loaded, ctx, program, chosen, report, rules)

    try:
        return _in_plan(plan, search)
    except InputError as e:
        raise CompileFailed(e, loaded, ctx, chosen) from None


class CompileFailed(InputError):
    """A loaded plan that cannot run: ``error``'s problems (as printed), with what a report
    of the failure needs (the loaded plan, its planning context, the execution)."""

    def __init__(
        self, error: InputError, loaded: LoadedPlan, context: PlanningContext, strategy: str
    ) -> None:
        super().__init__(error.problems)
        self.blames = error.blames
        self.failure = error.failure
        self.loaded = loaded
        self.context = context
        self.strategy = strategy


def _in_plan(plan: Plan, make: Callable[[], T]) -> T:
    """Errors of a step at that step's place in the plan file; other errors in the file."""
    try:
        return make()
    except StepError as e:
        raise plan.locate(e) from None
    except InputError as e:
        raise InputError(
            p if p.file else Problem(p.message, str(plan.file), p.line, p.col) for p in e.problems
        ) from None


# trajectory.json numbers to 1e-9 (rad, rad/s, rad/s^2, s): far below what any arm resolves
# (and knots are >= 0.5 ms apart), and half the text and the writing time of full precision.
TRAJECTORY_DECIMALS = 9
TRAJECTORY_JSON = "trajectory.json"
TEXT_KNOTS = 4096  # knots turned to text at a time


def trajectory_json(program: Program) -> dict[str, Any]:
    """trajectory.json (DESIGN 3.5): one time axis for both arms, gripper events."""
    from cellengine.motion.trajectory import concatenate

    traj = concatenate([s.trajectory for s in program.segments])
    out = traj.to_json(decimals=TRAJECTORY_DECIMALS)
    out["events"] = _events_json(program)
    return out


def trajectory_text(program: Program, knots: int = TEXT_KNOTS) -> str:
    """``json.dumps(trajectory_json(program))``."""
    return "".join(trajectory_chunks(program, knots))


def trajectory_chunks(program: Program, knots: int = TEXT_KNOTS) -> Iterator[str]:
    """:func:`trajectory_text` in pieces, the points turned to text ``knots`` at a time, for
    a writer: the whole body as Python lists took ~7 times the text, and the text itself
    need never be whole (issue 19: 420 MB at the end of a 100-step compile)."""
    from cellengine.motion.trajectory import concatenate

    traj = concatenate([s.trajectory for s in program.segments])
    yield f'{{"joint_names": {json.dumps(list(traj.joint_names))}, "points": ['
    for k in range(0, len(traj.t), knots):
        points = json.dumps(traj.points_json(TRAJECTORY_DECIMALS, k, k + knots))[1:-1]
        yield (", " if k else "") + points
    yield f'], "events": {json.dumps(_events_json(program))}}}'


def _events_json(program: Program) -> list[dict[str, Any]]:
    """The gripper events, the tools' work (triggers: a taping gun) and the tool changes, in
    time order (a change after the others of its instant: it happens at its segment's very
    end)."""
    grippers = [
        {
            "time_from_start": e.time,
            "arm": e.event.arm,
            "kind": "gripper",
            "mode": e.event.mode,
            "holds": e.event.holds,
        }
        for e in program.events
    ]
    changes = [
        {"time_from_start": c.time, "arm": c.arm, "kind": "tool", "tool": c.tool, "was": c.was}
        for c in program.changes
    ]
    triggers = [
        {
            "time_from_start": cs.trajectory.start_time,
            "arm": arm,
            "kind": "trigger",
            "tool": program.tools_at(cs.trajectory.start_time)[arm],
            "duration": cs.trajectory.duration,
        }
        for cs in program.segments
        for arm in cs.segment.triggers
    ]
    order = {"gripper": 0, "trigger": 1, "tool": 2}
    return sorted(
        grippers + triggers + changes, key=lambda e: (e["time_from_start"], order[e["kind"]])
    )


def step_label(step: Skill) -> str:
    """A step as people read it: ``RouteCable cable1: routing.guide1, routing.guide2``; a
    runtime choice as ``Pour heavier of vial1/vial2: beaker``."""
    fields: dict[str, list[str]] = {}
    choice: dict[str, str] = {}
    for loc, _, name in step.refs():
        key = str(loc[0])
        fields.setdefault(key, []).append(name)
        if len(loc) > 1 and loc[1] in ("heavier_of", "lighter_of"):
            choice[key] = str(loc[1]).replace("_of", " of")
    names = [
        f"{choice[k]} {'/'.join(v)}" if k in choice else n
        for k, v in fields.items()
        for n in (v if k not in choice else v[:1])
    ]
    if not names:
        return step.skill
    head, rest = names[0], names[1:]
    return f"{step.skill} {head}" + (f": {', '.join(rest)}" if rest else "")


def write_plan_outputs(compiled: Compiled, out: Path) -> dict[str, Path]:
    """trajectory.json, report.json and report.html into ``out``, all or none: each is
    written to a temporary name and the three are moved into place together."""
    from cellengine.outfiles import write_files
    from cellengine.report.write import REPORT_HTML, REPORT_JSON, report_texts

    plan = compiled.loaded.plan
    extra: dict[str, Any] = {
        "plan": str(plan.file),
        "execution": compiled.strategy,
        "duration": compiled.program.duration,
        "clearance_m": compiled.context.clearance,
        "speed": speed_json(compiled.context.speed),
    }
    extra.update(compiled.report)
    labels = {i: step_label(step) for i, step in enumerate(plan.steps)}
    texts = {
        TRAJECTORY_JSON: itertools.chain(trajectory_chunks(compiled.program), ["\n"]),
        **report_texts(
            compiled.program,
            compiled.world,
            compiled.cell,
            extra,
            step_labels=labels,
            title=plan.file.name,
        ),
    }
    paths = write_files(out, texts)
    return {
        "trajectory": paths[TRAJECTORY_JSON],
        "report": paths[REPORT_JSON],
        "html": paths[REPORT_HTML],
    }
