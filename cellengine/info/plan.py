"""plan.yaml (DESIGN 3.4): a sequence (or precedence graph) of skill steps."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import Field, Strict

from cellengine.errors import InputError, Problem, StepError, known
from cellengine.family import families
from cellengine.info.speed import SpeedScaling, SpeedSpec, scaling
from cellengine.info.units import Frozen, Length, Units
from cellengine.info.validation import validate
from cellengine.info.yamlio import YamlDoc
from cellengine.skill import Skill


class PlanFile(Frozen):
    cell: str = "cell.yaml"
    objects: str | None = None
    # how the arms work (split, sync, async: DESIGN 3); sequential: split, with the robots of
    # a lab cell one after another, as in the published platform
    execution: Literal["split", "sync", "async", "sequential"] = "split"
    units: Units = Units()
    # the cell's speed, replaced for this plan; a lower TCP speed cap than the cell's
    speed: SpeedSpec | None = None
    tcp_speed: Length | None = Field(None, gt=0)
    # after its last step, the arms go back to their homes: the plan ends where it starts
    # (so that `run --cycles N` can repeat it)
    return_home: Annotated[bool, Strict()] = False  # `yes` is a string in YAML 1.2
    steps: list[dict[str, Any]] = Field(min_length=1)


@dataclass(frozen=True)
class Plan:
    file: Path
    cell: str
    objects: str | None
    execution: str
    steps: tuple[Skill, ...]
    # where each step begins in the file (line, column), kept from loading it
    positions: tuple[tuple[int, int] | None, ...] = ()
    speed: SpeedScaling | None = None  # the plan's own speed, if it gives one
    tcp_speed: float | None = None  # m/s
    return_home: bool = False

    def locate(self, error: StepError) -> InputError:
        """``error`` at its step's place in the plan file (at the file's top when the step
        is not known)."""
        step = error.step
        at = self.positions[step] if step is not None and step < len(self.positions) else None
        line, col = at or (None, None)
        return error.located(self.file, line, col)


def parse_plan(doc: YamlDoc) -> Plan:
    units = Units()  # first: the plan's own lengths (tcp_speed) are in its unit
    if isinstance(doc.data, dict) and "units" in doc.data:
        units = validate(Units, doc, data=doc.data["units"], prefix=("units",))
    context = units.context()
    head = validate(PlanFile, doc, context)
    problems: list[Problem] = []
    steps: list[Skill] = []
    skills = families().skills
    for i, raw in enumerate(head.steps):
        name = raw.get("skill")
        if not isinstance(name, str) or name not in skills:
            if name is None:
                what = "missing required key 'skill'"
            elif not isinstance(name, str):
                kind = {"dict": "a mapping", "list": "a list"}.get(type(name).__name__)
                kind = kind or repr(name)
                what = f"skill must be a skill's name, got {kind}"
            else:
                what = f"unknown skill '{name}'"
            loc = ("steps", i) if name is None else ("steps", i, "skill")
            problems.append(doc.error(f"steps[{i}]: {what}" + known(skills), loc).problems[0])
            continue
        try:
            steps.append(validate(skills[name], doc, context, data=raw, prefix=("steps", i)))
        except InputError as e:
            problems.extend(e.problems)
    if problems:
        raise InputError(problems)
    problems = _check_graph(doc, steps)
    if problems:
        raise InputError(problems)
    positions = tuple(doc.where(("steps", i)) for i in range(len(steps)))
    return Plan(
        doc.file,
        head.cell,
        head.objects,
        head.execution,
        tuple(steps),
        positions,
        scaling(head.speed),
        head.tcp_speed,
        head.return_home,
    )


def _check_graph(doc: YamlDoc, steps: list[Skill]) -> list[Problem]:
    """Step ids unique, `after` names known ids, and no cycles."""
    out: list[Problem] = []
    first: dict[str, int] = {}
    for i, s in enumerate(steps):
        if s.id is None:
            continue
        if s.id in first:
            msg = f"steps[{i}].id: duplicate step id '{s.id}' (first used by steps[{first[s.id]}])"
            out.append(doc.error(msg, ("steps", i, "id")).problems[0])
        else:
            first[s.id] = i
    for i, s in enumerate(steps):
        for j, dep in enumerate(s.after):
            if dep not in first:
                msg = f"steps[{i}].after[{j}]: unknown step id '{dep}'" + known(first)
                out.append(doc.error(msg, ("steps", i, "after", j)).problems[0])
    if out:
        return out
    cycle = _find_cycle({s.id: s.after for s in steps if s.id is not None})
    if cycle:
        i = first[cycle[0]]
        shown = (
            cycle if len(cycle) <= 12 else [*cycle[:6], f"... ({len(cycle) - 9} more)", *cycle[-3:]]
        )
        msg = f"steps[{i}].after: steps wait for each other in a cycle: " + " -> ".join(shown)
        out.append(doc.error(msg, ("steps", i, "after")).problems[0])
    return out


def _find_cycle(graph: dict[str, tuple[str, ...]]) -> list[str] | None:
    """A cycle of ``after`` (ids from the one waited on first), or None; depth-first with a
    stack of its own (a chain of thousands of steps is deeper than Python recurses)."""
    state: dict[str, int] = {}  # 1 on the path, 2 done
    for root in graph:
        if root in state:
            continue
        path: list[str] = [root]
        todo: list[Iterator[str]] = [iter(graph.get(root, ()))]
        state[root] = 1
        while todo:
            m = next(todo[-1], None)
            if m is None:
                state[path.pop()] = 2
                todo.pop()
            elif state.get(m) == 1:
                return [*path[path.index(m) :], m]
            elif m not in state:
                state[m] = 1
                path.append(m)
                todo.append(iter(graph.get(m, ())))
    return None
