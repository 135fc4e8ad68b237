"""A separation guide (issue #15, REMODEL's J<n>S, HARNESS.md 1.8 case A1, 2.3, 2.4): a
harness's bottom branch is routed first after the cables above it, still to be routed, are
laid aside in a guide near the connector; a later branch of those is taken back from there.

Laying aside (``RouteCable`` with ``separate_into``): the hand separates the cables above the
branch at the connector (its fingertips at the middle of the lowest of them, as for a top
branch, cable_group), lifts them straight up over the separation guide's top, carries them
over the guide to beyond its far face, closes, and swings down on a circle about the
connector's rear face so that the cables between the connector and the hand drop into the
guide's slot; it lets go and leaves upwards. The branch is then the bottom of what is left
at the connector, and is grasped there as the rest of a harness is.

Taking back (a later RouteCable of cables laid aside): the hand grasps them just before the
separation guide (between it and the connector), lifts them out of its slot and brings them
to where the placing held the bundle, a little higher: the route starts as any group's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from cellengine import geometry as g
from cellengine.arrays import Mat, Vec
from cellengine.program import GripperEvent, Segment
from cellengine.skills import cable as c
from cellengine.skills import cable_geometry as cg
from cellengine.skills.cable_state import CableState, Placed

if TYPE_CHECKING:
    from cellengine.context import PlanningContext


@dataclass(frozen=True)
class Aside:
    """Cables of a harness laid aside in a separation guide."""

    guide: str
    cables: tuple[str, ...]


@dataclass(frozen=True)
class Laying:
    """Where a hand lays cables into the separation guide (cell frame, m)."""

    up: Vec
    along: Vec  # from the connector's rear face towards the guide, horizontal
    T_over: Mat  # the hand beyond the guide, the cables over its top
    T_end: Mat  # after the swing down: the cables in the slot
    angle: float  # the swing (rad, about cross(along, up); negative: down)
    T_before: Mat  # where a hand takes them back: just before the guide


def laying(ctx: PlanningContext, placed: Placed, guide: str, arm: str, where: str) -> Laying:
    world = ctx.world
    up = cg.platform_up(world, guide)
    rear = np.asarray(placed.rear, dtype=float)
    p_s = cg.position(world, guide)
    along = cg.horizontal(p_s - rear, up)
    dims = cg.GuideDims.of(world, guide, where)
    tool = world.cell.tools[world.tools[arm] or ""]
    hand = cg.Hand.from_tool(tool, world.tools[arm] or "", world.cell.work_clearance)
    beyond = dims.length / 2.0 + hand.keep + hand.half_length
    top = float(p_s @ up) + (cg.rise(world, guide, up) or 0.0)
    flat = p_s - up * float((p_s - rear) @ up)
    to_guide = float(np.linalg.norm(flat - rear))
    p_end = p_s + along * beyond
    reach = to_guide + beyond
    # the cables from the rear face to the hand clear the guide's top by Z_offset
    h_rear = float(rear @ up)
    h_over = h_rear + (top + cg.Z_OFFSET - h_rear) * reach / to_guide
    p_over = p_end + up * (h_over - float(p_end @ up))
    e_over = math.atan2(h_over - h_rear, reach)
    e_end = math.atan2(float(p_end @ up) - h_rear, reach)
    T_over = cg.tcp_frame(p_over, along, up)
    T_before = cg.tcp_frame(p_s - along * beyond, along, up)
    end = cg.arc(T_over, rear, g.cross(along, up), e_end - e_over, turn=False)[-1]
    return Laying(up, along, T_over, np.asarray(end), e_end - e_over, T_before)


def lay_aside(
    ctx: PlanningContext,
    state: CableState,
    placed: Placed,
    harness: str,
    above: tuple[str, ...],
    take: tuple[Mat, Mat],
    guide: str,
    arm: str,
    where: str,
) -> tuple[list[Segment], CableState]:
    """``arm`` (open, the other out of the way) takes ``above`` at the connector (``take``:
    over the take, the take), and lays them into ``guide``."""
    T_above, T_take = take
    lay = laying(ctx, placed, guide, arm, where)
    rear = np.asarray(placed.rear, dtype=float)
    element, connector = cg.element_of(guide), cg.element_of(placed.guide)
    label = f"RouteCable: {arm} lays {', '.join(above)} aside in {guide}"
    b = c._Builder(state)
    b.add(f"{label}: to them", [c._transit(arm, T_above)], before=b.mode_event(arm, c.OPEN, None))
    b.add(
        f"{label}: down, separating them",
        [c._cartesian(arm, cg.line(T_above, T_take))],
        after=[GripperEvent(arm, c.SLIDE, harness)],
        near=[(arm, connector)],
        facts={"aside": list(above), "guide": guide},
    )
    T_up = cg.at(
        T_take, T_take[:3, 3] + lay.up * float((lay.T_over[:3, 3] - T_take[:3, 3]) @ lay.up)
    )
    b.add(f"{label}: up", [c._cartesian(arm, cg.line(T_take, T_up))], near=[(arm, connector)])
    b.add(
        f"{label}: over the guide",
        [c._cartesian(arm, cg.line(T_up, lay.T_over))],
        after=[GripperEvent(arm, c.GRASP, harness)],
    )
    swing = cg.arc(lay.T_over, rear, g.cross(lay.along, lay.up), lay.angle, turn=False)
    b.add(f"{label}: into its slot", [c._cartesian(arm, swing)], near=[(arm, element)])
    b.add(
        f"{label}: lets go",
        [c._up(lay.T_end, arm, lay.up, cg.RETRACT_HEIGHT)],
        before=[GripperEvent(arm, c.OPEN)],
        near=[(arm, element)],
    )
    aside = {**state.aside, harness: Aside(guide, above)}
    return b.segments, replace(b.state.transited(arm), aside=aside, held={})


def take_back(
    ctx: PlanningContext,
    state: CableState,
    placed: Placed,
    branch: str,
    aside: Aside,
    arm: str,
    T_end: Mat,
    where: str,
) -> tuple[list[Segment], CableState]:
    """``arm`` (open, the other out of the way) takes ``branch``'s cables back out of the
    separation guide and holds them at ``T_end`` (where a group's route starts)."""
    lay = laying(ctx, placed, aside.guide, arm, where)
    over = (cg.rise(ctx.world, aside.guide, lay.up) or 0.0) + cg.Z_OFFSET
    T_above = cg.lifted(lay.T_before, lay.up, over + cg.APPROACH_HEIGHT)
    T_out = cg.lifted(lay.T_before, lay.up, over)
    element = cg.element_of(aside.guide)
    label = f"RouteCable {branch}: {arm} takes it back from {aside.guide}"
    b = c._Builder(state)
    b.add(f"{label}: to it", [c._transit(arm, T_above)], before=b.mode_event(arm, c.OPEN, None))
    b.add(
        f"{label}: down",
        [c._cartesian(arm, cg.line(T_above, lay.T_before))],
        after=[GripperEvent(arm, c.GRASP, branch)],
        near=[(arm, element)],
    )
    b.add(
        f"{label}: out of its slot",
        [c._cartesian(arm, cg.line(lay.T_before, T_out))],
        near=[(arm, element)],
    )
    b.add(f"{label}: to the connector", [c._cartesian(arm, cg.line(T_out, T_end))])
    group = set(ctx.world.objects.cables_of(branch))
    still = tuple(n for n in aside.cables if n not in group)  # what stays aside
    rest = {
        h: Aside(a.guide, still) if a is aside else a
        for h, a in state.aside.items()
        if a is not aside or still
    }
    return b.segments, replace(b.state, aside=rest)
