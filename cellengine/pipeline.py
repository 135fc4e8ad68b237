"""From a plan file to a validated Program, and from a Program to a run directory.

`cellengine plan`, `cellengine run` and `cellengine validate` share this: load and check the
files, build the cell's robot models and collision scene, turn the steps into segments with
the skills, compile the segments (strategy, merges, the gate) into a Program.
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

from cellengine.errors import InputError, Problem
from cellengine.execute.compile import Compiler, home_configuration
from cellengine.info.load import LoadedPlan, load_plan
from cellengine.info.yamlio import load_yaml
from cellengine.motion.collision import CollisionChecker
from cellengine.motion.robot import CellModel, build_cell_model
from cellengine.motion.scene import build_scene
from cellengine.program import Program, Segment
from cellengine.skill import Skill
from cellengine.world import World

if TYPE_CHECKING:
    from cellengine.allocate import Mission

T = TypeVar("T")
Progress = Callable[[int, int, str], None]  # (step index, number of steps, skill)


@dataclass(frozen=True)
class Compiled:
    loaded: LoadedPlan
    cell: CellModel
    program: Program
    strategy: str
    # a lab plan's mission: which robots do each step, when (report.json's "mission")
    mission: list[dict[str, Any]] | None = None

    @property
    def world(self) -> World:
        return self.loaded.world


def plan_segments(
    world: World,
    cell: CellModel,
    steps: Sequence[Skill],
    masses: Mapping[str, float] | None = None,
) -> tuple[list[Segment], Mission | None]:
    """Every step's segments, and a lab plan's mission. A plan is all cable skills (they
    share one state through the whole plan) or all lab skills (the allocator decides which
    robots do what; ``masses``: measured masses that choose ``heavier_of`` objects)."""
    from cellengine.skills.cable import CableSkill, plan_cable_steps
    from cellengine.skills.lab_plan import LabSkill, plan_lab_steps

    if all(isinstance(s, LabSkill) for s in steps):
        lab = plan_lab_steps(world, cell, steps, masses)
        return lab.segments, lab.mission
    for i, step in enumerate(steps):
        if not isinstance(step, CableSkill):
            raise InputError(
                Problem(
                    f"steps[{i}]: {step.skill} cannot be compiled to motion in a plan with "
                    "cable skills (a plan is all cable skills, or all lab skills)"
                )
            )
    return plan_cable_steps(world, steps)[0], None


def compile_plan(
    path: Path,
    strategy: str | None = None,
    merge: str = "joint",
    progress: Progress | None = None,
    cell: Path | None = None,
) -> Compiled:
    """Load, check and compile ``path`` (in ``cell`` instead of the plan's cell when
    given); InputError (in plan terms) when it cannot run."""
    return compile_loaded(load_plan(path, cell=cell), strategy, merge, progress)


Models = tuple[CellModel, CollisionChecker]


def cell_models(world: World) -> Models:
    """The robots and the collision checker of ``world``'s cell."""
    cell = build_cell_model(world)
    return cell, CollisionChecker(build_scene(cell, world))


def compile_loaded(
    loaded: LoadedPlan,
    strategy: str | None = None,
    merge: str = "joint",
    progress: Progress | None = None,
    models: Callable[[World], Models] = cell_models,
    masses: Mapping[str, float] | None = None,
) -> Compiled:
    """Compile a loaded plan; ``models`` lets a caller reuse one cell's models across plans;
    ``masses``: measured masses (kg) for runtime choices (else objects.yaml's)."""
    world, plan = loaded.world, loaded.plan
    cell, checker = models(world)
    chosen = strategy or plan.execution
    segments, mission = _with_file(
        plan.file, lambda: plan_segments(world, cell, plan.steps, masses)
    )
    compiler = Compiler(
        world,
        cell,
        checker,
        home_configuration(cell),
        chosen,  # type: ignore[arg-type]
        merge=merge,  # type: ignore[arg-type]
        plan_file=plan.file,
    )
    shown: set[int] = set()

    def before_each(segment: Segment) -> None:
        if progress is not None and segment.step not in shown:
            shown.add(segment.step)
            progress(segment.step, len(plan.steps), plan.steps[segment.step].skill)

    # add_all looks ahead from each transit and comes back to it when a later segment fails
    program = compiler.add_all(segments, before_each)
    mission_json = None
    if mission is not None:
        from cellengine.skills.lab_plan import mission_json as to_json

        spans = [
            (s.segment, s.trajectory.start_time, s.trajectory.end_time) for s in program.segments
        ]
        mission_json = to_json(mission, spans)
    return Compiled(loaded, cell, program, chosen, mission_json)


def _with_file(plan_file: Path, make: Callable[[], T]) -> T:
    """Skill errors begin with the step (``steps[2] RouteCable guide3: ...``): put them at
    that step's line in the plan file."""
    try:
        return make()
    except InputError as e:
        doc = load_yaml(plan_file)
        problems = []
        for p in e.problems:
            if p.file:
                problems.append(p)
                continue
            m = re.match(r"steps\[(\d+)\]", p.message)
            line, col = (doc.where(("steps", int(m.group(1)))) if m else None) or (None, None)
            problems.append(Problem(p.message, str(plan_file), line, col))
        raise InputError(problems) from None


# trajectory.json numbers to 1e-9 (rad, rad/s, rad/s^2, s): far below what any arm resolves
# (and knots are >= 0.5 ms apart), and half the text and the writing time of full precision.
TRAJECTORY_DECIMALS = 9
TRAJECTORY_JSON = "trajectory.json"


def trajectory_json(program: Program) -> dict[str, Any]:
    """trajectory.json (DESIGN 3.5): one time axis for both arms, gripper events."""
    from cellengine.motion.trajectory import concatenate

    traj = concatenate([s.trajectory for s in program.segments])
    out = traj.to_json(decimals=TRAJECTORY_DECIMALS)
    out["events"] = [
        {
            "time_from_start": e.time,
            "arm": e.event.arm,
            "kind": "gripper",
            "mode": e.event.mode,
            "holds": e.event.holds,
        }
        for e in program.events
    ]
    return out


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
    }
    if compiled.mission is not None:
        extra["mission"] = compiled.mission
    labels = {i: step_label(step) for i, step in enumerate(plan.steps)}
    texts = {
        TRAJECTORY_JSON: json.dumps(trajectory_json(compiled.program)) + "\n",
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
