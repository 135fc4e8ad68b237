"""ChangeTool (issue #15): an arm puts the tool it carries back in its slot of the automatic
tool changer and takes another from its slot (REMODEL's ATC.changeTool, HARNESS.md 2.6).

A slot (cell.yaml ``tools.<name>.slot``) gives where the flange is when the tool is seated
(``at``), the offsets the seated tool leaves the slot through on the arm (``exit``) and those
the bare flange leaves the seated tool through (``retreat``), all in the slot's frame. So:

1. whatever the hands hold is let go (release_ways), the changing arm goes over its tool's
   slot (the last ``exit`` offset) and seats the tool, back along ``exit``; the changer
   unlocks (a ToolChange to None at that segment's end);
2. the bare flange backs off along ``retreat``, goes to the new tool's slot at its last
   ``retreat`` offset and comes down on the tool along ``retreat`` reversed; the changer
   locks (a ToolChange to the new tool);
3. the tool leaves its slot along ``exit``.

From each change on the compiler plans on the cell model and the scene of the new tools
(the tool left behind is an obstacle in its slot); the fingers touching the tool they leave or
take, and the tool touching its station (the element of ``at``'s keypoint), are the
segments' declared contacts. An arm that carries the tool asked for already does nothing.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterator, Sequence
from dataclasses import replace
from typing import TYPE_CHECKING, Literal

import numpy as np
from pydantic import model_validator

from cellengine import geometry as g
from cellengine.arrays import Mat, Poses
from cellengine.info.pose import Pose
from cellengine.motion.robot import parked_name
from cellengine.program import Segment, ToolChange
from cellengine.skill import Skill, ToolRef
from cellengine.skills import cable as c
from cellengine.skills import cable_geometry as cg
from cellengine.skills.cable_state import CableState

if TYPE_CHECKING:
    from cellengine.context import PlanningContext


class ChangeTool(Skill):
    """The arm leaves its tool in its slot of the tool changer and takes ``tool``."""

    skill: Literal["ChangeTool"]
    tool: ToolRef

    @model_validator(mode="after")
    def _one_arm(self) -> ChangeTool:
        if self.arm in ("auto", "both"):
            raise ValueError("arm: name the arm that changes its tool (a robot of the cell)")
        return self


def change_ways(
    ctx: PlanningContext, step: ChangeTool, state: CableState
) -> Iterator[tuple[list[Segment], CableState]]:
    """The ways to change ``step.arm``'s tool from ``state`` (each release's of what the
    hands hold, then the change); one way with no segments when it carries the tool."""
    arm, where = step.arm, f"steps[{state.step}] ChangeTool"
    if state.tools[arm] == step.tool:
        yield [], state
        return
    yield from released_change(ctx, state, arm, step.tool, where, f"ChangeTool {arm}")


def released_change(
    ctx: PlanningContext, state: CableState, arm: str, tool: str, where: str, label: str
) -> Iterator[tuple[list[Segment], CableState]]:
    """Each way of letting go of what the hands hold (release_ways), then the change."""
    for released, after in c.release_ways(ctx, state):
        segments, changed = change(ctx, after, arm, tool, where, label)
        yield [*released, *segments], changed


def change(
    ctx: PlanningContext,
    state: CableState,
    arm: str,
    tool: str | None,
    where: str,
    label: str,
) -> tuple[list[Segment], CableState]:
    """``arm`` (holding nothing) leaves its tool in its slot and takes ``tool`` (None: stays
    bare): the segments (labelled ``label: ...``) and the state after them, the arm's TCP
    the new tool's."""
    world = ctx.world
    b = c._Builder(state)
    was = state.tools[arm]
    T_flange = state.tcp[arm] @ g.inverse(_T_flange_tcp(ctx, was))
    if was is not None:
        spec = world.cell.tools[was].slot
        if spec is None:
            raise c._error(
                f"{where}: the {arm} arm carries '{was}', which has no slot in the tool "
                f"changer to be left in (cell.yaml tools.{was}.slot)"
            )
        T_slot, T_tcp = world.slot(was), _T_flange_tcp(ctx, was)
        exit_ = _offsets(T_slot, spec.exit, T_tcp)
        b.add(f"{label}: over {was}'s slot", [c._transit(arm, exit_[-1])])
        seat = _through([exit_[-1], *exit_[-2::-1], T_slot @ T_tcp])
        b.add(
            f"{label}: seats {was}",
            [c._cartesian(arm, seat)],
            contacts=_station(spec.at, arm),
            changes=[ToolChange(arm, None)],
        )
        back = _through([T_slot, *_offsets(T_slot, spec.retreat, np.eye(4))])
        b.add(
            f"{label}: leaves {was}", [c._cartesian(arm, back)], contacts=[(arm, parked_name(was))]
        )
        T_flange = back[-1]
    if tool is not None:
        spec = world.cell.tools[tool].slot
        assert spec is not None  # the step's reference is to a tool with a slot
        T_slot, T_tcp = world.slot(tool), _T_flange_tcp(ctx, tool)
        retreat = _offsets(T_slot, spec.retreat, np.eye(4))
        b.add(f"{label}: over {tool}", [c._transit(arm, retreat[-1])])
        down = _through([retreat[-1], *retreat[-2::-1], T_slot])
        b.add(
            f"{label}: takes {tool}",
            [c._cartesian(arm, down)],
            contacts=[(arm, parked_name(tool))],
            changes=[ToolChange(arm, tool)],
        )
        out = _through([T_slot @ T_tcp, *_offsets(T_slot, spec.exit, T_tcp)])
        b.add(
            f"{label}: {tool} out of its slot",
            [c._cartesian(arm, out)],
            contacts=_station(spec.at, arm),
        )
        T_flange = out[-1] @ g.inverse(T_tcp)
    # the builder moved the TCP along each path as given: after the last, the arm's TCP is
    # that of what it carries now
    after = b.state.moved(arm, T_flange @ _T_flange_tcp(ctx, tool))
    return b.segments, replace(after.transited(arm), tools={**after.tools, arm: tool})


def _T_flange_tcp(ctx: PlanningContext, tool: str | None) -> Mat:
    return np.eye(4) if tool is None else ctx.world.cell.tools[tool].tcp.matrix()


def _offsets(T_slot: Mat, offsets: Sequence[Sequence[float]], T_flange_tcp: Mat) -> list[Mat]:
    """The TCP at each offset (slot frame) of the flange from its seated pose."""
    return [T_slot @ g.transform(np.eye(3), tuple(map(float, o))) @ T_flange_tcp for o in offsets]


def _through(poses: Sequence[Mat]) -> Poses:
    """Straight TCP lines through ``poses`` in order."""
    parts = [cg.line(a, b) for a, b in itertools.pairwise(poses)]
    return np.concatenate([parts[0], *(p[1:] for p in parts[1:])])


def _station(at: str | Pose, arm: str) -> list[tuple[str, str]]:
    """The slot's station (the element of its keypoint) as ``arm``'s contact: its tool goes
    into and out of it; none for a slot given as a pose."""
    return [(arm, cg.element_of(at))] if isinstance(at, str) else []


GRIPPER = "parallel_gripper"


def fitting(
    ctx: PlanningContext, state: CableState, need: dict[str, str], where: str
) -> dict[str, str]:
    """The tool changes (arm -> tool) that give each arm of ``need`` a tool of the kind it
    needs (REMODEL changes tools before any operation that needs another, HARNESS.md 2.6):
    the tool the arm started with if it is of that kind and free, else the free one of that
    kind whose slot is nearest the arm's base. A step no free tool can serve is refused."""
    tools = ctx.world.cell.tools
    carried = {t for t in state.tools.values() if t is not None}
    start = ctx.world.cell.robots
    out: dict[str, str] = {}
    for arm, kind in sorted(need.items()):
        now = state.tools[arm]
        if now is not None and tools[now].kind == kind:
            continue
        if now is not None and tools[now].slot is None:
            raise c._error(
                f"{where} needs a {kind} on the {arm} arm, which carries '{now}', and '{now}' "
                f"has no slot in the tool changer to be left in (cell.yaml tools.{now}.slot)"
            )
        free = [
            n
            for n, t in tools.items()
            if t.kind == kind and t.slot is not None and n not in carried
        ]
        base = start[arm].base.matrix()[:3, 3]
        free.sort(
            key=lambda n: (
                n != start[arm].tool,
                float(np.linalg.norm(ctx.world.slot(n)[:3, 3] - base)),
                n,
            )
        )
        if not free:
            what = f"carries '{now}'" if now is not None else "carries no tool"
            raise c._error(
                f"{where} needs a {kind} on the {arm} arm, which {what}, and no {kind} waits in "
                "the tool changer (a cell.yaml tool of that kind with a slot)"
            )
        out[arm] = free[0]
        carried.add(free[0])
    return out
