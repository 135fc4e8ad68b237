"""RouteCable's way for a guide that stands too close to the one before for the published
slide and pivot (paper 003, Fig. 4): laid over its top, then pushed in (REMODEL's
``route_top`` and ``RC_push_inserted``, HARNESS.md 2.5.2).

The routing hand, sliding on the cable, rises from where it inserted the last guide and
moves along the route over the guide's top to where the published lift ends: R_lift from
the push point, Z_offset over the guide's far top corner. It grasps there, so the cable
runs from the last guide over the guide's top, taut, above the slot. The other hand, its
fingers closed as a pusher, comes down behind the guide (REMODEL's ``top_back`` ->
``bottom_back``) and presses the cable down to the slot's level there; the routing hand
then comes down on the circle about the pusher's fingertips, laying the cable along the
slot, as the published insert does about the pivot. From there the routing goes on as
after any guide: the pusher stands where a pivot hand would, on the cable.

No sideways slide beside the guide (what the routing hand's fingers cannot do when the
guide before stands close) and no grasp between the two guides: the pusher's closed
fingers are narrower than a grasp's open ones coming down, and it may stand upright.

Every distance comes from the guides' and the hands' dimensions (cable_geometry): the push
point is A + half the pusher's length before the guide (the A of the published stops, or
centred in the room before the guide), the routing hand ends at least X_offset past it and
far enough for the circle to clear the guide's top by Z_offset (R_lift).
"""

from __future__ import annotations

import functools
import itertools
import math
from collections.abc import Callable, Iterator, Set
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from cellengine import geometry as g
from cellengine.arrays import Mat, Poses, Vec
from cellengine.errors import InputError
from cellengine.motion import interpolate as ip
from cellengine.program import Anchor, GripperEvent, Segment
from cellengine.skills import cable as c
from cellengine.skills import cable_geometry as cg
from cellengine.skills.cable_state import ANY_BRANCH, CableState

if TYPE_CHECKING:
    from cellengine.context import PlanningContext

GRASP, SLIDE = c.GRASP, c.SLIDE
# The pusher holds nothing between its closed fingers: it may press with them turned about
# the vertical, its fingers then along the cable rather than across it (beside a guide that
# stands at an angle, a corner may come nearer its fingers across than along): every eighth
# of a turn, across first.
PUSH_YAWS = tuple(math.radians(a) for a in (0.0, 90.0, 45.0, -45.0))
LABEL = "over the top"  # the way's name in its segments' facts (RouteCable's "way")


@dataclass(frozen=True)
class TopWay:
    """The free parameters: where the pusher stands, where the routing hand ends, how the
    pusher tips and turns."""

    push_gap: float  # the pusher's fingers end this far before the guide's near face
    after: float  # the routing hand's fingers begin this far past the far face (at least)
    push_lean: float  # the pusher's flange tipped back along the cable by this much
    towards_base: float  # and towards its base (1) or not (0)
    push_yaw: float  # its jaw axis turned about the vertical from across the cable


@dataclass(frozen=True)
class TopPlan:
    guide: str
    where: str
    up: Vec
    slot: Vec
    axis: Vec
    push_point: Vec  # the pusher's fingertips on the cable
    radius: float  # the pusher's fingertips to the routing hand's
    elevation: float  # of the laid cable over the guide, seen from the push point
    lay: Poses  # the routing hand: up from where it is, over the guide to the lift's end
    above: Mat  # the pusher over the cable behind the guide (REMODEL's top_back)
    push: Poses  # the pusher down onto the cable to the slot's level (bottom_back)
    insert: Poses  # the routing hand down on the circle about the pusher
    laid: float  # route length from the connector's rear face to the push point
    # the elements the hands work between (the cell's work_clearance from them)
    beside: tuple[str, ...]


def top_ways(
    ctx: PlanningContext,
    step: c.RouteCable,
    state: CableState,
    k: int,
    dead: Set[bytes] = frozenset(),
) -> Iterator[tuple[list[Segment], CableState]]:
    """The ways to route guide ``k`` over its top, best first, each with the state after it;
    the closest way's error when none passes the checks. None when the other hand's release
    of the last guide is ``dead`` (RouteCable.guide_plans)."""
    r_arm, o_arm = step.arms(ctx, state)
    up = cg.platform_up(ctx.world, step.guides[k])
    nxt = step.guides[k + 1] if k + 1 < len(step.guides) else None
    let_go = c._letting_go(ctx, state, (r_arm, o_arm), up, step.guides[k], nxt)
    released = let_go.get(c.DEFAULT_BACK)
    if isinstance(released, InputError):
        raise released  # every way lets go of the last guide so
    if o_arm in state.held and c._stand_back(state, o_arm, up, c.DEFAULT_BACK).tobytes() in dead:
        return  # the compiler could not run it
    # the branches the routing arm may be on, still while the other hand lets go
    may = state.branches_of(r_arm) & dict(released or ()).get(r_arm, ANY_BRANCH)
    o_may = state.branches_of(o_arm) & dict(released or ()).get(o_arm, ANY_BRANCH)
    closest: tuple[float, InputError] | None = None
    found = False
    memo: Memo = {}
    apart_memo: dict[tuple[object, ...], Apart | InputError] = {}
    # why the pusher cannot stand where a way puts it, or the routing hand end where it does:
    # the ways that share it are not built
    blocked: dict[tuple[object, ...], InputError] = {}
    for way in _ways(ctx, state, step, k, r_arm, o_arm):
        parts = {
            "pusher": (way.push_gap, way.push_yaw, way.push_lean, way.towards_base),
            "routing": (way.push_gap, way.after),
        }
        known = [blocked.get((part, key)) for part, key in parts.items()]
        why = next((e for e in known if e is not None), None)
        if why is None:
            try:
                tp = _plan(ctx, state, step, k, r_arm, o_arm, way)
            except InputError as e:
                why = e
            else:
                failed = _check(ctx, step.cable, tp, (r_arm, o_arm), memo, may)
                if failed is None:
                    apart = _arms_apart(ctx, state, tp, (r_arm, o_arm), (may, o_may), apart_memo)
                    if not isinstance(apart, InputError):
                        found = True
                        yield _emit(state, tp, r_arm, o_arm, step.cable, apart)
                        continue
                    failed = "hands", apart
                part, why = failed
                if part in parts:
                    blocked[(part, parts[part])] = why
        score = why.distance if isinstance(why, c._Blocked) else -math.inf
        if closest is None or score > closest[0]:
            closest = (score, why)
    if not found:
        where = f"steps[{state.step}] RouteCable {step.guides[k]}"
        raise closest[1] if closest is not None else c._error(f"{where}: no way over the top")


def _ways(
    ctx: PlanningContext, state: CableState, step: c.RouteCable, k: int, r_arm: str, o_arm: str
) -> Iterator[TopWay]:
    """The pusher's stops (the published A's, then centred in the room before the guide),
    the routing hand's ends (X_offset past, then centred in the room after, then the other
    stops), the pusher's turns (PUSH_YAWS) and tips (cg.PIVOT_LEANS), towards its base or
    not: in that order, the pusher's stop varying slowest."""
    world, guide = ctx.world, step.guides[k]
    b_o = c._basics(world, state, guide, o_arm)
    b_r = c._basics(world, state, guide, r_arm)
    pushes = (*cg.APPROACH_GAPS, *c._centred_gap(world, guide, b_o, after=False))
    afters = (cg.APPROACH_GAP, *c._centred_gap(world, guide, b_r, after=True))
    afters += tuple(a for a in (*cg.APPROACH_GAPS, *cg.INSERT_PASTS) if a not in afters)
    for push, after, yaw, lean, base in itertools.product(
        pushes, afters, PUSH_YAWS, cg.PIVOT_LEANS, (1.0, 0.0)
    ):
        yield TopWay(push, after, lean, base, yaw)


def _plan(
    ctx: PlanningContext,
    state: CableState,
    step: c.RouteCable,
    k: int,
    r_arm: str,
    o_arm: str,
    way: TopWay,
) -> TopPlan:
    world, guide = ctx.world, step.guides[k]
    b = c._basics(world, state, guide, r_arm)
    hand_r, hand_o = c._hand(world, r_arm), c._hand(world, o_arm)
    up, slot, axis, dims = b.up, b.slot, b.axis, b.dims
    last = np.asarray(state.route[-1], dtype=float)
    # the closed fingers press on the cable's top: their tips half its diameter over the slot
    level = world.cable(step.cable).diameter / 2.0 * up
    p = way.push_gap + hand_o.half_length  # near face to the pusher's fingertip centre
    push_point = slot - (dims.length / 2.0 + p) * axis + level
    # past the far face by X_offset, and by what puts the circle R_lift over the top corner
    lift = cg.r_lift(dims.length, b.rise, p, cg.Z_OFFSET)
    x = max(way.after + hand_r.half_length, lift - dims.length - p)
    radius = dims.length + p + x
    elevation = math.atan2(b.rise + cg.Z_OFFSET, dims.length + p)
    over = push_point + radius * (math.cos(elevation) * axis + math.sin(elevation) * up)
    _check_straight(b.where, world.cable(step.cable).diameter, dims, (slot, axis, up), last, over)
    tip_r = g.unit(axis + c._towards_base(world, r_arm, slot, up))
    T_r0 = state.tcp[r_arm]
    T_top = cg.nearer_turn(
        T_r0, cg.tcp_frame(over, axis, up, tip_r, cg.LEAN), state.wound.get(r_arm, 0.0)
    )
    # up where it is (turning to the guide's axis), then along the route at that height
    rise = max(0.0, float((over - T_r0[:3, 3]) @ up))
    T_up = cg.at(T_top, T_r0[:3, 3] + rise * up)
    lay = ip.concatenate([cg.line(T_r0, T_up), cg.line(T_up, T_top)])
    insert = cg.arc(T_top, push_point, np.cross(axis, up), -elevation, turn=False)
    tip_o = g.unit(-axis + way.towards_base * c._towards_base(world, o_arm, slot, up))
    turned = g.axis_angle_to_matrix(up, way.push_yaw) @ axis
    T_push = cg.nearer_turn(
        state.tcp[o_arm],
        cg.tcp_frame(push_point, turned, up, tip_o, way.push_lean),
        state.wound.get(o_arm, 0.0),
    )
    # over the draped cable (it crosses the guide's near face at most at its top) and the
    # cell's clearance over the guides, where the transit leaves it
    above = cg.lifted(T_push, up, max(cg.APPROACH_HEIGHT, b.rise + cg.Z_OFFSET + ctx.clearance))
    after_k = (cg.element_of(step.guides[k + 1]),) if k + 1 < len(step.guides) else ()
    beside = (*c._beside(state, guide), *after_k, *c._under(ctx, slot, up))
    return TopPlan(
        guide=guide,
        where=b.where,
        up=up,
        slot=slot,
        axis=axis,
        push_point=push_point,
        radius=radius,
        elevation=elevation,
        lay=lay,
        above=above,
        push=cg.line(above, T_push),
        insert=insert,
        laid=state.route_length() + float(np.linalg.norm(push_point - level - last)),
        beside=beside,
    )


def _check_straight(
    where: str,
    diameter: float,
    dims: cg.GuideDims,
    frame: tuple[Vec, Vec, Vec],
    last: Vec,
    over: Vec,
) -> None:
    """Laid over the top, the cable runs (seen from above) straight from the last point of
    the route to the routing hand: it must cross both of the guide's faces over the slot,
    within the gap less the cable (the route arriving along the guide, as on a straight run;
    ``frame``: slot, axis, up)."""
    slot, axis, up = frame
    free = (dims.gap - diameter) / 2.0
    faces = (slot - dims.length / 2.0 * axis, slot + dims.length / 2.0 * axis)
    off = max(cg.segment_distance(f, last, over, up) for f in faces)
    if off > free + 1e-9:
        raise c._error(
            f"{where}: laid over the guide's top from the last point of the route, the cable "
            f"would cross a face of the guide {c._mm(off)} mm off the slot's middle (the slot "
            f"leaves {c._mm(free)} mm either side of the cable): over the top needs the "
            "route to arrive along the guide"
        )


# What a check found of the poses it was given (the ways share most of their paths): why not,
# or None
Memo = dict[tuple[object, ...], InputError | None]


def _check(
    ctx: PlanningContext,
    cable: str,
    tp: TopPlan,
    arms: tuple[str, str],
    memo: Memo,
    may: frozenset[int],
) -> tuple[str, InputError] | None:
    """Why not, and what it depends on ("pusher": where the pusher stands; "routing": where
    the routing hand ends; "hands": both): reach, the cable's length, each hand's
    clearances (the cell's work_clearance from the elements it works between, its clearance
    from everything else), the routing arm's from itself on a branch of ``may`` (it lays and
    inserts in lines) and the two hands' from each other; each check made once for the poses
    it looks at (``memo``)."""
    world, (r_arm, o_arm) = ctx.world, arms
    hand = c._hand(world, r_arm)
    need = tp.laid + tp.radius + hand.end_margin
    length = world.cable(cable).length
    if need > length + 1e-9:
        return "routing", c._error(
            f"{tp.where}: cable '{cable}' is too short to lay it over the guide's top: "
            f"{c._mm(need)} mm needed, {c._mm(length)} mm long"
        )
    Check = tuple[str, tuple[object, ...], Callable[[], InputError | None]]
    checks: list[Check] = [
        *(
            (part, (arm, what, T.tobytes()), functools.partial(_reach, ctx, arm, what, T, tp.where))
            for part, arm, what, T in (
                ("pusher", o_arm, "over the push", tp.above),
                ("pusher", o_arm, "push", tp.push[-1]),
                ("routing", r_arm, "over the top", tp.lay[-1]),
                ("routing", r_arm, "insert", tp.insert[-1]),
            )
        ),
        *(
            (
                part,
                (arm, what, poses.tobytes(), beside),
                functools.partial(_env, ctx, tp, arm, what, mode, poses, beside),
            )
            for part, arm, what, mode, poses, beside in (
                ("pusher", o_arm, "coming over the cable", GRASP, tp.push[:1], ()),  # transit end
                ("pusher", o_arm, "pushing the cable down", GRASP, tp.push, tp.beside),
                ("routing", r_arm, "laying the cable", SLIDE, tp.lay, tp.beside),
                ("routing", r_arm, "inserting", GRASP, tp.insert, tp.beside),
            )
        ),
        (
            "routing",
            (r_arm, "itself", tp.lay.tobytes(), tp.insert.tobytes()),
            functools.partial(_itself, ctx, tp, r_arm, may),
        ),
        *(
            (
                "hands",
                ("free", what, T_o.tobytes(), tp.lay[-1].tobytes()),
                functools.partial(_free, ctx, tp, arms, what, T_o, may),
            )
            for what, T_o in (("over the cable", tp.above), ("pushing it down", tp.push[-1]))
        ),
        *(
            (
                "hands",
                (arm, what, path.tobytes(), T_other.tobytes()),
                functools.partial(_hands, ctx, tp, (arm, other), what, path, T_other),
            )
            for arm, what, path, other, T_other in (
                (o_arm, "pushing the cable down", tp.push, r_arm, tp.lay[-1]),
                (r_arm, "inserting", tp.insert, o_arm, tp.push[-1]),
            )
        ),
    ]
    for part, key, check in checks:
        if key not in memo:
            memo[key] = check()
        if (why := memo[key]) is not None:
            return part, why
    return None


def _free(
    ctx: PlanningContext,
    tp: TopPlan,
    arms: tuple[str, str],
    what: str,
    T_o: Mat,
    may: frozenset[int],
) -> InputError | None:
    """Some pair of the arms' configurations is free of collisions with the cell and each
    other, the pusher at ``T_o`` and the routing hand over the top (on a branch of ``may``):
    the hands' checks see the tools only, and an upper arm can meet a guide or the holder
    where the hand is clear (the compiler would refuse the pusher's transit goal)."""
    r_arm, o_arm = arms
    why = c._pair_blocked(ctx, {r_arm: tp.lay[-1], o_arm: T_o}, on={r_arm: may})
    if why is None:
        return None
    return c._error(
        f"{tp.where}: every inverse kinematics solution of the pusher ({o_arm}) {what}, the "
        f"routing hand over the top, is in collision" + (f" ({why})" if why else "")
    )


def _reach(ctx: PlanningContext, arm: str, what: str, T: Mat, where: str) -> InputError | None:
    try:
        c._check_reach(ctx, arm, [(what, T)], where)
    except InputError as e:
        return e
    return None


def _env(
    ctx: PlanningContext,
    tp: TopPlan,
    arm: str,
    what: str,
    mode: str,
    poses: Poses,
    beside: tuple[str, ...],
) -> InputError | None:
    found = c._env_near(ctx, arm, poses, mode, beside)
    if found is None:
        return None
    near, limit, own = found
    return c._Blocked.of(
        near.distance - limit,
        f"{tp.where}: {near.tool} {c._passes(near, limit)} {what} over the top; "
        + c._env_fix(ctx, near, own, limit),
    )


def _itself(
    ctx: PlanningContext, tp: TopPlan, r_arm: str, may: frozenset[int]
) -> InputError | None:
    try:
        c._routing_follows(ctx, r_arm, np.concatenate([tp.lay, tp.insert]), may, tp.where, tp.guide)
    except InputError as e:
        return e
    return None


def _hands(
    ctx: PlanningContext, tp: TopPlan, arms: tuple[str, str], what: str, path: Poses, T_other: Mat
) -> InputError | None:
    """The hands' clearance from each other (both closed: the pusher and the routing hand)."""
    arm, other = arms
    pair = ctx.probe.between(arm, [*path[::2], path[-1]], GRASP, other, T_other, GRASP)
    if pair is None or pair.distance >= ctx.clearance:
        return None
    return c._Blocked.of(
        pair.distance - ctx.clearance,
        f"{tp.where}: {pair.tool} {c._passes(pair, ctx.clearance)} {what} over the top; the "
        f"cell's clearance is {c._mm(ctx.clearance)} mm between the hands",
    )


class Apart(NamedTuple):
    """The arms' IK branches on which they keep the cell's clearance from each other: the
    routing arm laying the cable with the other standing (``lay``: pairs), then the pusher
    pushing and the routing hand inserting (``push``: pairs)."""

    lay: c.Paired
    push: c.Paired


def _arms_apart(
    ctx: PlanningContext,
    state: CableState,
    tp: TopPlan,
    arms: tuple[str, str],
    may: tuple[frozenset[int], frozenset[int]],
    memo: dict[tuple[object, ...], Apart | InputError],
) -> Apart | InputError:
    """The arms, not only the hands, keep the cell's clearance from each other (a wrist
    passes over the other arm's upper arm on some boards): laying the cable, the other arm
    where it stands back to, on the branches ``may`` (routing arm's, other arm's); pushing
    and inserting, the pusher on any branch its transit over the cable can take, the routing
    arm on one it laid the cable on. Every STRIDE-th pose (the compiler checks them all)."""
    from cellengine.execute.following import STRIDE  # the motion stack: planning only

    (r_arm, o_arm), (r_may, o_may) = arms, may
    T_o = state.tcp[o_arm]
    if o_arm in state.held:
        T_o = c._stand_back(state, o_arm, tp.up, c.DEFAULT_BACK)[-1]
    lay = [(T, T_o) for T in (*tp.lay[::STRIDE], tp.lay[-1])]
    push = [(tp.lay[-1], T) for T in (*tp.push[::STRIDE], tp.push[-1])]
    push += [(T, tp.push[-1]) for T in (*tp.insert[::STRIDE], tp.insert[-1])]
    key = ("apart", T_o.tobytes(), tp.lay.tobytes(), tp.push.tobytes(), tp.insert.tobytes())
    if key not in memo:
        memo[key] = _apart(ctx, tp, (r_arm, o_arm), (r_may, o_may), lay, push)
    return memo[key]


def _apart(
    ctx: PlanningContext,
    tp: TopPlan,
    arms: tuple[str, str],
    may: tuple[frozenset[int], frozenset[int]],
    lay: list[tuple[Mat, Mat]],
    push: list[tuple[Mat, Mat]],
) -> Apart | InputError:
    (r_arm, o_arm), keep = arms, ctx.clearance
    least = c._pair_least(ctx, r_arm, o_arm, lay, keep, *may, measure=False)
    if least is None:  # an arm solved numerically: the compiler finds out
        return Apart((), ())
    laid = least >= keep
    if laid.any():
        on = frozenset(int(k) for k in np.flatnonzero(laid.any(axis=1)))
        least = c._pair_least(ctx, r_arm, o_arm, push, keep, on, ANY_BRANCH, measure=False)
        if least is not None and (least >= keep).any():
            pushed = least >= keep
            # the routing arm's branches that push and insert too; pushing it is the same
            laid &= np.isin(np.arange(8), np.flatnonzero(pushed.any(axis=1)))[:, None]
            return Apart(c._kept_pairs(laid, r_arm, o_arm), c._kept_pairs(pushed, r_arm, o_arm))
        what, poses, on_ = "pushing the cable down and inserting", push, (on, ANY_BRANCH)
    else:
        what, poses, on_ = "laying the cable over the top", lay, may
    measured = c._pair_least(ctx, r_arm, o_arm, poses, keep, *on_)
    room = -math.inf if measured is None else float(measured.max())
    return c._Blocked.of(
        room - keep,
        f"{tp.where}: however the two arms are posed, they come within "
        f"{c._mm(max(room, 0.0))} mm of each other {what}; the cell's clearance is "
        f"{c._mm(keep)} mm",
    )


def _emit(
    state: CableState, tp: TopPlan, r_arm: str, o_arm: str, cable: str, apart: Apart
) -> tuple[list[Segment], CableState]:
    label = f"RouteCable {tp.guide}"
    b = c._Builder(state)
    pair = (r_arm, o_arm)
    if o_arm in b.state.held:  # as after any guide: it lets go and backs off along the route
        poses = c._stand_back(b.state, o_arm, tp.up, c.DEFAULT_BACK)
        c._add_release(b, label, pair, poses, tp.beside)
    near_r = [(r_arm, e) for e in tp.beside]
    b.add(
        f"{label}: lay the cable over the top",
        [c._cartesian(r_arm, tp.lay)],
        before=b.mode_event(r_arm, SLIDE, cable),
        after=[GripperEvent(r_arm, GRASP, cable)],  # held taut, above the slot
        near=near_r,
        branches=_branches(apart.lay),
        paired=apart.lay,
        facts={"way": LABEL, "guide": tp.guide, "elevation": tp.elevation},
    )
    # the fingers closed without the cable between them: a pusher (REMODEL's closed push)
    b.add(
        f"{label}: pusher over the cable",
        [c._transit(o_arm, tp.above)],
        before=[GripperEvent(o_arm, GRASP, None)] if b.state.mode.get(o_arm) != GRASP else [],
        near=near_r,
    )
    near = [*near_r, *((o_arm, e) for e in tp.beside)]
    b.add(
        f"{label}: push into the slot",
        [c._cartesian(o_arm, tp.push)],
        # from here the cable runs under the pusher's fingertips, fixed there as by a grasp
        after=[GripperEvent(o_arm, GRASP, cable)],
        near=near,  # the fingertips touch the cable beside the guide's slot
        branches=_branches(apart.push),
        paired=apart.push,
        facts={"way": LABEL, "push_point": c._vec(tp.push_point)},
    )
    b.add(
        f"{label}: insert",
        [c._cartesian(r_arm, tp.insert)],
        keep_distance=pair,
        near=near,
        branches=_branches(apart.push),
        paired=apart.push,
        annotations=[Anchor(cable, c._point(tp.slot), tp.guide)],
        facts={
            "way": LABEL,
            "guide": tp.guide,
            "slot": c._vec(tp.slot),
            "axis": c._vec(tp.axis),
            "routing_arm": r_arm,
            "other_arm": o_arm,
            "radius": tp.radius,
        },
    )
    return b.segments, _after(b.state, tp, r_arm, o_arm, cable, apart)


def _branches(paired: c.Paired) -> tuple[tuple[str, frozenset[int]], ...]:
    """Each arm's branches in some pair of ``paired`` (Segment.branches)."""
    return tuple(
        (arm, frozenset(p[k] for p in pairs))
        for a, b, pairs in paired
        for k, arm in enumerate((a, b))
    )


def _after(
    state: CableState, tp: TopPlan, r_arm: str, o_arm: str, cable: str, apart: Apart
) -> CableState:
    """Both hands on the cable, as after a published insert: the pusher where a pivot stands,
    the routing hand past the guide, on a branch it laid and inserted on."""
    level = float((tp.push_point - tp.slot) @ tp.up) * tp.up
    branches = {a: br for a, br in state.branches.items() if a != o_arm}
    laid = dict(_branches(apart.push)).get(r_arm)
    if laid is not None:
        branches[r_arm] = state.branches_of(r_arm) & laid
    s = replace(
        state,
        guides=(*state.guides, tp.guide),
        route=(*state.route, c._point(tp.push_point - level), c._point(tp.slot)),
        pull_distance=float(np.linalg.norm(tp.insert[-1][:3, 3] - level - tp.slot)),
        branches=branches,
    )
    s = s.hold(o_arm, cable, tp.laid)
    return s.hold(r_arm, cable, tp.laid + tp.radius)
