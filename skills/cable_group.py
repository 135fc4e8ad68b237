"""RouteCable of a harness's branch (issue #15): the branch's cables are routed as one group,
a thicker cable, from the harness's placed connector; before its first guide the routing
hand takes the group there (REMODEL's implicit SC and GC operations, HARNESS.md 1.8, 2.3,
2.4).

Behind the connector the cables leave their pins in rows, the bottom row lowest: the stack
at the hold the placing ended with (cable_state.Placed) is taken as a column of the harness's
cables in row order, centred where the hand held the whole bundle. A group that is the whole
of what is left there is grasped at the centre of that column (GC). A group above the cables
left (the top rows, REMODEL's case A2) is separated from them: the open hand comes down with
its fingertips at the middle of the group's lowest cable, above every other one, closes to
slide and lifts the group off before it grasps (SC). :func:`separation_point` is the one place
that decides where; a vision service (REMODEL's grasp point determination) would replace it.
A group below cables still to be routed (case A1) needs them laid aside into a separation
guide first, which is not built: cable_group_meaning refuses such a plan before any motion,
saying which branch to route first, as it does a slot too narrow for a group beside the
cables laid in it before.

Whatever the hands held before (the placing's hold, or the last group's route) is released
first (release_ways), and the other arm goes where the placing left it (or home); the taking
hand ends holding the group a little over where the placing held the whole bundle. So every
group's route starts as a single cable's does after PlaceConnector.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from cellengine.arrays import Mat, Vec
from cellengine.errors import InputError
from cellengine.info.harness import Harness
from cellengine.program import GripperEvent, Segment
from cellengine.skills import cable as c
from cellengine.skills import cable_aside
from cellengine.skills import cable_geometry as cg
from cellengine.skills.cable_state import CableState, Placed

if TYPE_CHECKING:
    from cellengine.context import PlanningContext

LIFT = 0.0075  # m: a group lifted over where the bundle was held (REMODEL: z_offset / 2)


@dataclass(frozen=True)
class Separation:
    """Where the hand takes a group: its TCP's height over the hold's (m, along the
    platform's up), the group, the cables left below it, and each cable's place in the
    column (bottom, top heights over the hold, m)."""

    height: float
    group: tuple[str, ...]
    below: tuple[str, ...]
    column: dict[str, tuple[float, float]]

    @property
    def separates(self) -> bool:
        return bool(self.below)


def separation_point(harness: Harness, group: Sequence[str], left: Sequence[str]) -> Separation:
    """The column of all the harness's cables in row order centred on the hold; the group's
    take: at the middle of its lowest cable when cables left lie below it, else the middle
    of what is left (``left``: the cables not yet routed, the group's among them)."""
    order = harness.in_order(list(harness.cables))
    total = sum(harness.cables[n].diameter for n in order)
    column: dict[str, tuple[float, float]] = {}
    z = -total / 2.0
    for n in order:
        d = harness.cables[n].diameter
        column[n] = (z, z + d)
        z += d
    below = tuple(n for n in harness.in_order(left) if n not in group)
    lowest = harness.in_order(group)[0]
    if below:
        bottom, top = column[lowest]
        height = (bottom + top) / 2.0
    else:
        height = (column[harness.in_order(left)[0]][0] + column[harness.in_order(left)[-1]][1]) / 2
    return Separation(height, harness.in_order(group), below, column)


def group_ways(
    ctx: PlanningContext, step: c.RouteCable, state: CableState
) -> Iterator[tuple[list[Segment], CableState]] | None:
    """The ways to take ``step``'s group at its harness's connector (or back from the
    separation guide it was laid aside in; or, with ``separate_into``, after laying the
    cables above it aside), each with the state RouteCable's first guide starts from; None
    when ``step`` routes no branch, or routes on a branch it already holds."""
    world = ctx.world
    found = world.objects.branch_of(step.cable)
    if found is None or state.cable == step.cable:
        return None
    name, harness = found
    placed = state.placed.get(name)
    if placed is None:  # cable_group_meaning refuses such a plan before any motion
        raise c._error(f"steps[{state.step}] RouteCable {step.cable}: {name} is not placed")
    group = harness.branches[step.cable].cables
    aside = state.aside.get(name)
    away = set(aside.cables) if aside is not None else set()
    left = [n for n in harness.cables if n not in state.routed and n not in away]
    where = f"steps[{state.step}] RouteCable {step.cable}"
    up = cg.platform_up(ctx.world, placed.guide)
    T_end = _shifted(placed.T_hold, LIFT * up)
    if aside is not None and set(group) <= away:
        back = functools.partial(_back, ctx, step, placed, aside, T_end, where)
        return _ways(ctx, step, state, placed, back, cg.position(world, aside.guide), where)
    low = min(harness.cables[n].pin for n in group)
    above = tuple(
        n for n in harness.in_order(left) if n not in group and harness.cables[n].pin > low
    )
    if step.separate_into is not None and above:
        return _aside_then(ctx, step, state, placed, (name, harness), above, where)
    return _grasp_ways(ctx, step, state, placed, separation_point(harness, group, left), where)


def _grasp_ways(
    ctx: PlanningContext,
    step: c.RouteCable,
    state: CableState,
    placed: Placed,
    sep: Separation,
    where: str,
) -> Iterator[tuple[list[Segment], CableState]]:
    """The group separated from the cables below it, or grasped (cable_group's notes)."""
    up = cg.platform_up(ctx.world, placed.guide)
    T_take = _shifted(placed.T_hold, sep.height * up)
    T_above = _shifted(T_take, cg.APPROACH_HEIGHT * up)
    # every group then held where the placing held the bundle, a little higher: the route
    # starts as it does after the placing, whichever rows the group came from
    T_end = _shifted(placed.T_hold, LIFT * up)

    def take(state: CableState, arm: str) -> tuple[list[Segment], CableState]:
        what = "separating grasp" if sep.separates else "group's grasp"
        c._check_reach(ctx, arm, [(f"{what} approach", T_above), (what, T_take)], where)
        return _take(step, state, placed, sep, arm, (T_above, T_take, T_end))

    end = cg.position(ctx.world, step.guides[-1])
    return _ways(ctx, step, state, placed, take, end, where)


def _aside_then(
    ctx: PlanningContext,
    step: c.RouteCable,
    state: CableState,
    placed: Placed,
    owner: tuple[str, Harness],
    above: tuple[str, ...],
    where: str,
) -> Iterator[tuple[list[Segment], CableState]]:
    """The cables ``above`` the group laid aside in ``step.separate_into`` (cable_aside),
    then the group, the bottom of what is left, grasped."""
    name, harness = owner
    guide = step.separate_into
    assert guide is not None
    left = [n for n in harness.cables if n not in state.routed]
    sep = separation_point(harness, above, left)
    up = cg.platform_up(ctx.world, placed.guide)
    T_take = _shifted(placed.T_hold, sep.height * up)
    T_above = _shifted(T_take, cg.APPROACH_HEIGHT * up)

    def lay(state: CableState, arm: str) -> tuple[list[Segment], CableState]:
        c._check_reach(ctx, arm, [("separating grasp", T_take)], where)
        take = (T_above, T_take)
        return cable_aside.lay_aside(ctx, state, placed, name, above, take, guide, arm, where)

    group = harness.branches[step.cable].cables
    rest = [n for n in left if n not in above]
    at = cg.position(ctx.world, guide)
    for laid, after in _ways(ctx, step, state, placed, lay, at, where):
        for more, taken in _grasp_ways(
            ctx, step, after, placed, separation_point(harness, group, rest), where
        ):
            yield [*laid, *more], taken


def _back(
    ctx: PlanningContext,
    step: c.RouteCable,
    placed: Placed,
    aside: cable_aside.Aside,
    T_end: Mat,
    where: str,
    state: CableState,
    arm: str,
) -> tuple[list[Segment], CableState]:
    """The group taken back out of the separation guide by ``arm``, held at ``T_end``."""
    more, after = cable_aside.take_back(ctx, state, placed, step.cable, aside, arm, T_end, where)
    group = ctx.world.objects.cables_of(step.cable)
    return more, _holding(after, placed, tuple(group), arm, step.cable, T_end)


Act = Callable[[CableState, str], tuple[list[Segment], CableState]]


def _ways(
    ctx: PlanningContext,
    step: c.RouteCable,
    state: CableState,
    placed: Placed,
    act: Act,
    near: Vec,
    where: str,
) -> Iterator[tuple[list[Segment], CableState]]:
    """Release what the hands hold (each way of release_ways), move the other arm out of the
    way, then ``act`` with the arm whose base is nearer ``near`` (the route's end, the
    separation guide), else with the other."""
    first: InputError | None = None
    # the arm whose base is nearer first, as PlaceConnector's roles keep each arm on its
    # side: the other's is the search's next choice ("arms")
    arms = sorted(state.arms, key=lambda a: _base_distance(ctx, a, near))
    for released, after in c.release_ways(ctx, state):
        for arm in arms:
            other = next(a for a in after.arms if a != arm)
            # the other arm out of the way first: where the placing left it, when it is the
            # arm that stood there, else at home (a route's release leaves it over the board)
            T_idle = placed.T_other if other != placed.arm else ctx.tcp_home(other)
            idle = c._Builder(after)
            idle.add(
                f"RouteCable {step.cable}: {other} out of the way",
                [c._transit(other, T_idle)],
            )
            try:
                more, taken = act(idle.state.transited(other), arm)
            except InputError as e:
                first = first or e
                continue
            yield [*released, *idle.segments, *more], taken
    if first is not None:
        raise first


def _take(
    step: c.RouteCable,
    state: CableState,
    placed: Placed,
    sep: Separation,
    arm: str,
    poses: tuple[Mat, Mat, Mat],
) -> tuple[list[Segment], CableState]:
    T_above, T_take, T_end = poses
    branch, element = step.cable, cg.element_of(placed.guide)
    label = f"RouteCable {branch}: {arm} takes the group at {placed.guide}"
    b = c._Builder(state)
    b.add(f"{label}: to it", [c._transit(arm, T_above)], before=b.mode_event(arm, c.OPEN, None))
    facts = {
        "group": list(sep.group),
        "below": list(sep.below),
        "tcp_height": sep.height,
        "column": {n: list(z) for n, z in sep.column.items()},
    }
    b.add(
        f"{label}: down" + (", separating it" if sep.separates else ""),
        [c._cartesian(arm, cg.line(T_above, T_take))],
        after=[GripperEvent(arm, c.SLIDE if sep.separates else c.GRASP, branch)],
        near=[(arm, element)],
        facts=facts,
    )
    what = "lifts it off the others" if sep.separates else "lifts it"
    b.add(
        f"{label}: {what}",
        [c._cartesian(arm, cg.line(T_take, T_end))],
        after=[GripperEvent(arm, c.GRASP, branch)] if sep.separates else [],
        near=[(arm, element)],
    )
    return b.segments, _holding(b.state, placed, sep.group, arm, branch, T_end)


def _holding(
    state: CableState, placed: Placed, group: tuple[str, ...], arm: str, branch: str, T_end: Mat
) -> CableState:
    """The state a group's route starts from: ``arm`` holds ``branch`` at ``T_end``, over
    where the placing held the bundle; the other holds the connector end."""
    rear = np.asarray(placed.rear, dtype=float)
    more = float(np.linalg.norm(T_end[:3, 3] - rear) - np.linalg.norm(placed.T_hold[:3, 3] - rear))
    other = next(a for a in state.arms if a != arm)
    after = state.hold(arm, branch, placed.s_hold).transited(arm)
    return replace(
        after,
        cable=branch,
        routing_arm=arm,
        connector_arm=other,
        place_guide=None,
        guides=(placed.guide,),
        route=(placed.rear,),
        pull_distance=placed.pull_distance + more,
        routed=state.routed | set(group),
    )


def _base_distance(ctx: PlanningContext, arm: str, p: Vec) -> float:
    """Horizontal distance (m) from ``arm``'s base to ``p``."""
    d = np.asarray(p, dtype=float) - ctx.cell.arms[arm].T_cell_base[:3, 3]
    return float(np.hypot(d[0], d[1]))


def _shifted(T: Mat, by: Vec) -> Mat:
    out = np.array(T, dtype=float)
    out[:3, 3] += by
    return out
