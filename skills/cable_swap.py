"""RouteCable's hand swap before a guide: the hand that held the last pivot takes the cable
over and routes on, and the routing hand becomes the pivot hand. Which hand leads is then
decided per guide, not once for the route (PlaceConnector's hand-over decides it for the
first guide): a route that runs past one arm's base or across to the other arm's side has
guides only the other arm can route, as a person routing with two hands swaps them.

After a guide the routing hand holds the cable along that guide's axis just past it, and
the other hand holds the pivot before it. The other hand lets go and stands back (as before
any guide); the routing hand lets go and moves up and out of the way (to the side its base
is on, the other side or on along the cable, AWAYS far: each that keeps the cell's
clearance is a swap of its own, in that order); then the same with the routing hand going
first (where the routing arm reaches across over the other, the other arm cannot stand back
from under it);
the other hand comes down and grasps the cable where the routing hand held it (the cable
from the guide's slot to there is short and straight, as where PlaceConnector's hand-over
takes it), tipped along the cable and towards its base, or only along it, or away (the
first it reaches); then it routes the guide from there, its approach sliding along the
cable as any routing hand's.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterator, Sequence, Set
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from cellengine import geometry as g
from cellengine.arrays import Mat
from cellengine.errors import InputError
from cellengine.motion import interpolate as ip
from cellengine.program import GripperEvent, Segment
from cellengine.skills import cable as c
from cellengine.skills import cable_geometry as cg
from cellengine.skills.cable_state import CableState

if TYPE_CHECKING:
    from cellengine.context import PlanningContext

SWAP = "the other hand takes the cable over"  # in the label of the swap's segments
# how far the routing hand, letting go, moves out of the other's way (after going up)
AWAYS = (c.HAND_OVER_AWAY, 2.0 * c.HAND_OVER_AWAY)


def hand_swaps(
    ctx: PlanningContext, step: c.RouteCable, state: CableState, k: int, dead: Set[bytes]
) -> Iterator[tuple[list[Segment], CableState]]:
    """The ways to swap the hands before guide ``k`` (k >= 1: a routed guide before it),
    each with the state after, the other arm routing: the routing hand out of the way to the
    side its base is on, the other side or on along the cable, AWAYS far, with the other
    hand taking the cable (_take), those the screens pass in that order; the first error
    when none does (``dead``: the other hand's releases the compiler could not run, see
    RouteCable.guide_plans)."""
    world = ctx.world
    r_arm, o_arm = step.arms(ctx, state)
    up = cg.platform_up(world, state.guides[-1])
    slot = np.asarray(state.route[-1], dtype=float)
    along = cg.horizontal(state.tcp[r_arm][:3, 3] - slot, up)  # the laid cable, out
    side = g.cross(up, along)
    if float(side @ c._towards_base(world, r_arm, state.tcp[r_arm][:3, 3], up)) < 0.0:
        side = -side
    aways = [d * a for d, a in itertools.product(AWAYS, (side, -side, along))]
    first: InputError | None = None
    found = False
    # with the other hand not at the last guide, the orders are one
    for routing_first in (False, True) if o_arm in state.held else (False,):
        try:
            for way in _swaps(ctx, step, state, k, dead, (up, slot, along), aways, routing_first):
                found = True
                yield way
        except InputError as e:
            first = first or e
    if not found and first is not None:
        raise first


def _swaps(
    ctx: PlanningContext,
    step: c.RouteCable,
    state: CableState,
    k: int,
    dead: Set[bytes],
    laid: tuple[np.ndarray, np.ndarray, np.ndarray],
    aways: Sequence[np.ndarray],
    routing_first: bool,
) -> Iterator[tuple[list[Segment], CableState]]:
    """The swaps with the routing hand moving by each of ``aways`` out of the way, after the
    other hand lets go of the last guide, or before it (``routing_first``: where the routing
    arm reaches over the other, the other's arm cannot stand back from under it); the first
    error when none passes the screens. ``laid``: the last guide's platform's up, its slot
    and the laid cable's direction from it."""
    up, slot, along = laid
    guide = step.guides[k]
    nxt = step.guides[k + 1] if k + 1 < len(step.guides) else None
    where = f"steps[{state.step}] RouteCable {guide}"
    arms = r_arm, o_arm = step.arms(ctx, state)
    T_r = state.tcp[r_arm]
    beside = (*c._beside(state, guide), *c._under(ctx, slot, up))
    label = f"RouteCable {guide}: {SWAP}"
    held = float((T_r[:3, 3] - slot) @ along)  # cable from slot to fingertips
    released = c._Builder(state)
    if o_arm in state.held and not routing_first:  # as before any guide
        _release(ctx, released, state, arms, up, (guide, nxt), dead, beside)
    first: InputError | None = None
    found = False
    for away in aways:
        try:
            b = c._Builder(released.state)
            path, r_on = _away(ctx, arms, b.state, (away, up), beside, where)
            # the other hand, when it lets go after, stands at its pivot by the last guides
            standing = {*map(cg.element_of, state.guides[-2:]), *beside}
            holding = sorted(standing) if o_arm in b.state.held else []
            b.add(
                f"{label}: {r_arm} lets go",
                [c._cartesian(r_arm, path)],
                before=[GripperEvent(r_arm, c.OPEN)],
                near=[*((r_arm, e) for e in beside), *((o_arm, e) for e in holding)],
            )
            if o_arm in b.state.held:
                # a segment of the swap: the compiler failing it fails this swap
                _release(ctx, b, b.state, arms, up, (guide, nxt), dead, beside, label)
            T_above, T_take = _take(ctx, arms, b.state, r_on, T_r, along, up, where)
        except InputError as e:
            first = first or e
            continue
        b.add(f"{label}: {o_arm} to the cable", [c._transit(o_arm, T_above)])
        b.add(
            f"{label}: {o_arm} grasps",
            [c._cartesian(o_arm, cg.line(T_above, T_take))],
            after=[GripperEvent(o_arm, c.GRASP, step.cable)],
            near=[(o_arm, e) for e in beside],
        )
        after = b.state.hold(o_arm, step.cable, state.route_length() + held)
        yield (
            [*released.segments, *b.segments],
            replace(after.transited(o_arm), routing_arm=o_arm, pull_distance=held),
        )
        found = True
    if not found and first is not None:
        raise first


def key(segments: Sequence[Segment]) -> bytes:
    """What tells one swap from another in a guide's dead releases: its routing hand's path
    out of the way, and whether the other hand let go before it (b"" when ``segments`` have
    no swap)."""
    for j, s in enumerate(segments):
        if SWAP in s.label:
            return bytes([j]) + np.asarray(s.paths[0].poses).tobytes()
    return b""


def _release(
    ctx: PlanningContext,
    b: c._Builder,
    state: CableState,
    arms: tuple[str, str],
    up: np.ndarray,
    guides: tuple[str, str | None],
    dead: Set[bytes],
    beside: tuple[str, ...],
    label: str = "",
) -> None:
    """The other hand lets go of the last guide and stands back, as before any guide: the
    first stand-back the arms can do (c._letting_go) that the compiler did not fail; in the
    swap (``label``) after the routing hand went out of the way, the first the arms can do
    (the compiler failing it fails the swap: key). ``guides``: the guide and the one after
    it (None after the last)."""
    o_arm, guide = arms[1], guides[0]
    released = c._letting_go(ctx, state, arms, up, *guides)
    first: InputError | None = None
    for back, release in released.items():
        poses = c._stand_back(state, o_arm, up, back)
        if isinstance(release, InputError) or (not label and poses.tobytes() in dead):
            first = first or (release if isinstance(release, InputError) else None)
            continue
        c._add_release(b, label or f"RouteCable {guide}", arms, poses, beside, release)
        return
    raise first or c._error(f"steps[{state.step}] RouteCable {guide}: no release was compiled")


def _take(
    ctx: PlanningContext,
    arms: tuple[str, str],
    state: CableState,
    r_on: frozenset[int],
    T_r: Mat,
    along: np.ndarray,
    up: np.ndarray,
    where: str,
) -> tuple[Mat, Mat]:
    """The other hand's grasp where the routing hand held the cable (at ``T_r``), and over
    it: tipped as a routing hand tips, along the cable and towards its base, or along it
    only, or away from the base (near its base an arm reaches a hand tipped towards it only
    with its wrist folded back), the first that some pair of the arms' IK solutions reaches
    keeping the cell's clearance, the routing hand out of the way (where ``state`` has it, on
    a branch of ``r_on``)."""
    r_arm, o_arm = arms
    p = T_r[:3, 3]
    towards = c._towards_base(ctx.world, o_arm, p, up)
    why = ""
    for base in c.BASES:
        tip = along + base * towards
        if float(np.linalg.norm(tip)) < 0.5:
            continue  # the base straight ahead: "towards it" is no tip
        frame = cg.tcp_frame(p, along, up, g.unit(tip), state.lean)
        T_take = cg.nearer_turn(state.tcp[o_arm], frame, state.wound.get(o_arm, 0.0))
        T_above = cg.lifted(T_take, up, cg.APPROACH_HEIGHT)
        T_away = state.tcp[r_arm]
        whys = (
            c._pair_blocked(ctx, {r_arm: T_away, o_arm: T}, ctx.clearance, {r_arm: r_on})
            for T in (T_above, T_take)
        )
        found = next((w for w in whys if w is not None), None)
        if found is None:
            return T_above, T_take
        why = why or found
    raise c._error(
        f"{where}: handing the cable over to the other arm ({o_arm}), no pair of the arms' "
        f"inverse kinematics solutions keeps the cell's clearance ({c._mm(ctx.clearance)} mm) "
        f"with the other hand taking the cable where the routing hand ({r_arm}) held it"
        + (f" ({why})" if why else " (out of reach)")
    )


def _away(
    ctx: PlanningContext,
    arms: tuple[str, str],
    state: CableState,
    way: tuple[np.ndarray, np.ndarray],
    beside: Sequence[str],
    where: str,
) -> tuple[np.ndarray, frozenset[int]]:
    """The routing hand's path up RETRACT_HEIGHT and by ``away`` (m, horizontal; ``way``:
    it and the platform's up) out of the other's way, and the IK branches the routing arm
    can be on there (it moves in lines, on one it may be on in ``state``), when its open
    fingers keep clear of the elements it let go ``beside`` (they close on the cable by the
    slot: opened, they may meet its walls) and the cell's clearance from the rest, and some
    pair of the arms' IK solutions on branches they can be on keeps the cell's clearance
    there, the other hand where ``state`` has it."""
    from cellengine.execute.following import surviving  # the motion stack: planning only
    from cellengine.motion.collision import DEFAULT_CLEARANCE

    r_arm, o_arm = arms
    away, up = way
    T_r, T_o = state.tcp[r_arm], state.tcp[o_arm]
    T_up = cg.lifted(T_r, up, cg.RETRACT_HEIGHT)
    T_away = cg.at(T_up, T_up[:3, 3] + away)
    path = ip.concatenate([cg.line(T_r, T_up), cg.line(T_up, T_away)])
    found = c._env_near(ctx, r_arm, path, c.OPEN, beside, DEFAULT_CLEARANCE)
    if found is not None:
        near, limit, own = found
        raise c._Blocked.of(
            near.distance - limit,
            f"{where}: handing the cable over to the other arm ({o_arm}), "
            f"{near.tool} {c._passes(near, limit)} as the routing hand opens and moves out of "
            "the way; " + c._env_fix(ctx, near, own, limit),
        )
    alive, _ = surviving(ctx.cell, ctx.checker, r_arm, path, ctx.home, state.branches_of(r_arm))
    on = {r_arm: frozenset(alive), o_arm: state.branches_of(o_arm)}
    whys = (c._pair_blocked(ctx, {o_arm: T_o, r_arm: T}, ctx.clearance, on) for T in (T_up, T_away))
    why = next((w for w in whys if w is not None), None) if alive else ""
    if why is None:
        return path, frozenset(alive)
    raise c._error(
        f"{where}: handing the cable over to the other arm ({o_arm}), no pair of the arms' "
        f"inverse kinematics solutions keeps the cell's clearance ({c._mm(ctx.clearance)} mm) "
        f"with the routing hand ({r_arm}) letting go and out of the way"
        + (f" ({why})" if why else "")
    )
