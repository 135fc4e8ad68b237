"""RouteCable's hand swap before a guide: the hand that held the last pivot takes the cable
over and routes on, and the routing hand becomes the pivot hand. Which hand leads is then
decided per guide, not once for the route (PlaceConnector's hand-over decides it for the
first guide): a route that runs past one arm's base or across to the other arm's side has
guides only the other arm can route, as a person routing with two hands swaps them.

After a guide the routing hand holds the cable along that guide's axis just past it, and
the other hand holds the pivot before it. The other hand lets go and stands back (as before
any guide); the routing hand lets go and moves up and out of the way (to the side its base
is on, the other side or on along the cable, AWAYS far: each that keeps the cell's
clearance is a swap of its own, in that order);
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
    world, guide = ctx.world, step.guides[k]
    where = f"steps[{state.step}] RouteCable {guide}"
    r_arm, o_arm = step.arms(ctx, state)
    last = state.guides[-1]
    up = cg.platform_up(world, last)
    slot = np.asarray(state.route[-1], dtype=float)
    T_r = state.tcp[r_arm]
    along = cg.horizontal(T_r[:3, 3] - slot, up)  # the laid cable, from the slot out
    released = c._Builder(state)
    beside = (*c._beside(state, guide), *c._under(ctx, slot, up))
    if o_arm in state.held:
        _release(ctx, released, state, (r_arm, o_arm), up, guide, dead, beside)
    T_o = released.state.tcp[o_arm]
    label = f"RouteCable {guide}: {SWAP}"
    cable = step.cable
    held = float((T_r[:3, 3] - slot) @ along)  # cable from the slot to the fingertips
    side = g.cross(up, along)
    if float(side @ c._towards_base(world, r_arm, T_r[:3, 3], up)) < 0.0:
        side = -side
    first: InputError | None = None
    found = False
    for distance, away in itertools.product(AWAYS, (side, -side, along)):
        try:
            path = _away(ctx, (r_arm, o_arm), T_r, T_o, away * distance, up, where)
            b = c._Builder(released.state)
            b.add(
                f"{label}: {r_arm} lets go",
                [c._cartesian(r_arm, path)],
                before=[GripperEvent(r_arm, c.OPEN)],
                near=[(r_arm, e) for e in beside],
            )
            T_above, T_take = _take(ctx, (r_arm, o_arm), b.state, T_r, along, up, where)
        except InputError as e:
            first = first or e
            continue
        b.add(f"{label}: {o_arm} to the cable", [c._transit(o_arm, T_above)])
        b.add(
            f"{label}: {o_arm} grasps",
            [c._cartesian(o_arm, cg.line(T_above, T_take))],
            after=[GripperEvent(o_arm, c.GRASP, cable)],
            near=[(o_arm, e) for e in beside],
        )
        after = b.state.hold(o_arm, cable, state.route_length() + held).transited(o_arm)
        found = True
        yield (
            [*released.segments, *b.segments],
            replace(after, routing_arm=o_arm, pull_distance=held),
        )
    if not found and first is not None:
        raise first


def key(segments: Sequence[Segment]) -> bytes:
    """What tells one swap from another in a guide's dead releases: its routing hand's path
    out of the way (b"" when ``segments`` have no swap)."""
    for s in segments:
        if SWAP in s.label:
            return np.asarray(s.paths[0].poses).tobytes()
    return b""


def _release(
    ctx: PlanningContext,
    b: c._Builder,
    state: CableState,
    arms: tuple[str, str],
    up: np.ndarray,
    guide: str,
    dead: Set[bytes],
    beside: tuple[str, ...],
) -> None:
    """The other hand lets go of the last guide and stands back, as before any guide: the
    first stand-back the arms can do (c._letting_go) that the compiler did not fail."""
    o_arm = arms[1]
    released = c._letting_go(ctx, state, arms, up, guide)
    first: InputError | None = None
    for back, release in released.items():
        poses = c._stand_back(state, o_arm, up, back)
        if isinstance(release, InputError) or poses.tobytes() in dead:
            first = first or (release if isinstance(release, InputError) else None)
            continue
        c._add_release(b, f"RouteCable {guide}", arms, poses, beside, release)
        return
    raise first or c._error(f"steps[{state.step}] RouteCable {guide}: no release was compiled")


def _take(
    ctx: PlanningContext,
    arms: tuple[str, str],
    state: CableState,
    T_r: Mat,
    along: np.ndarray,
    up: np.ndarray,
    where: str,
) -> tuple[Mat, Mat]:
    """The other hand's grasp where the routing hand held the cable (at ``T_r``), and over
    it: tipped as a routing hand tips, along the cable and towards its base, or along it
    only, or away from the base (near its base an arm reaches a hand tipped towards it only
    with its wrist folded back), the first that some pair of the arms' IK solutions reaches
    keeping the cell's clearance, the routing hand out of the way (where ``state`` has it)."""
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
            c._pair_blocked(ctx, {r_arm: T_away, o_arm: T}, ctx.clearance)
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
    T_r: Mat,
    T_o: Mat,
    away: np.ndarray,
    up: np.ndarray,
    where: str,
) -> np.ndarray:
    """The routing hand's path up RETRACT_HEIGHT and by ``away`` (m, horizontal) out of the
    other's way, when some pair of the arms' IK solutions keeps the cell's clearance there,
    the other arm's hand at ``T_o``."""
    r_arm, o_arm = arms
    T_up = cg.lifted(T_r, up, cg.RETRACT_HEIGHT)
    T_away = cg.at(T_up, T_up[:3, 3] + away)
    whys = (c._pair_blocked(ctx, {o_arm: T_o, r_arm: T}, ctx.clearance) for T in (T_up, T_away))
    why = next((w for w in whys if w is not None), None)
    if why is None:
        return ip.concatenate([cg.line(T_r, T_up), cg.line(T_up, T_away)])
    raise c._error(
        f"{where}: handing the cable over to the other arm ({o_arm}), no pair of the arms' "
        f"inverse kinematics solutions keeps the cell's clearance ({c._mm(ctx.clearance)} mm) "
        f"with the routing hand ({r_arm}) letting go and out of the way"
        + (f" ({why})" if why else "")
    )
