"""Cable-routing skills: the published dual-arm method (paper 003, Algorithm 1, Fig. 4).

Each skill's ``plan(ctx, state)`` turns its step into :class:`~cellengine.program.Segment` s
of fingertip (TCP) poses in the cell frame, gripper events and couplings, and returns them
with the :class:`~cellengine.skills.cable_state.CableState` after them.
:func:`plan_cable_steps` chains a plan's steps (it looks ahead so PickCable gives the
connector end to the arm that will place it) and ends each cable with
:func:`release_and_retract` (Algorithm 1, line 35).
Frames, symbols and offsets: :mod:`cellengine.skills.cable_geometry`.

Arms. PlaceConnector's ``arm`` places the connector; with ``auto`` the arm whose base is
nearer the connector guide does (or, without a look-ahead, the arm already holding the
connector end). PickCable gives that arm the connector end. The other arm routes: after the
connector is placed it holds the cable in its sliding jaws and carries it guide to guide; the
connector arm becomes the "other arm", which grasps the cable before each guide so the two
hands can swing it, taut, into the slot. When the route heads towards the connector arm's
side (the combs may force the connector end on the arm farther from the connector guide),
PlaceConnector first offers to hand the cable over once the connector is seated: the
connector arm then routes and the other one pivots, so the arms do not reach across each
other for the whole route.

A guide that stands too close to the one before for the published slide and pivot is laid
over its top by the routing hand and pushed into its slot by the other hand
(:mod:`cellengine.skills.cable_top`, REMODEL's route_top), a way offered after all the
published ones.

Feasibility comes first: each skill computes all its poses and checks them (cable length,
reach of every key pose by inverse kinematics, a sliding angle that clears the guide) before
it returns any segment, and raises :class:`~cellengine.errors.InputError` naming the step
and the guide.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Collection, Iterable, Iterator, Mapping, Sequence, Set
from dataclasses import dataclass, field, replace
from types import MappingProxyType
from typing import TYPE_CHECKING, Annotated, Any, Literal, TypeVar

import numpy as np
from numpy.typing import NDArray
from pydantic import Field

from cellengine import geometry as g
from cellengine.arrays import Mat, Poses, Vec
from cellengine.errors import InputError, Problem, StepError, at_step, known
from cellengine.info.units import count
from cellengine.motion import interpolate as ip
from cellengine.program import Anchor, Annotation, ArmPath, GripperEvent, Segment, ToolChange
from cellengine.skill import CableRef, GuideRef, KeypointRef, Skill
from cellengine.skills import cable_geometry as cg
from cellengine.skills.best_first import best_first
from cellengine.skills.cable_state import ANY_BRANCH, CableState, Placed
from cellengine.world import World

if TYPE_CHECKING:  # planning needs the motion stack; parsing a plan does not
    from cellengine.context import PlanningContext
    from cellengine.motion.probe import Nearest

OPEN, SLIDE, GRASP = "open", "slide", "grasp"  # jaw modes the method uses (the tool's table)
CENTRING_STEP = 0.001  # m: how finely the room after a guide is scanned for a centred hand
CENTRING_TOL = 1e-9  # m: and how finely the element that ends it is found


# =========================================================================== the skills


# PlaceConnector carries the pair to over the connector guide: turned to the guide where it
# is first (as published), turned while carried, or turned over the guide
PLACE_ORDERS = ("align first", "together", "approach first")
# PickCable: how much farther from the connector hand than placing needs (m) the far hand ends
# its slide: where PlaceConnector's other hand may hold the cable (cg.PLACE_HOLDS, carried
# without a regrasp). Hands picked at the edge of both arms' reach leave the wrists closer than
# the cell's clearance at the published spacing.
PICK_FARTHER = tuple(sorted({farther for _, farther in cg.PLACE_HOLDS}))
HAND_OVER_AWAY = 0.150  # m: the hand handing the cable over moves this far out of the way


class PickCable(Skill):
    """Grasp both ends of a cable from two combs, connector end first."""

    skill: Literal["PickCable"]
    cable: CableRef
    from_: Annotated[
        tuple[KeypointRef, KeypointRef], count(2, "keypoints [connector end, other end]")
    ] = Field(alias="from")

    def plan(self, ctx: PlanningContext, state: CableState) -> tuple[list[Segment], CableState]:
        """Algorithm 1, PICKCABLE: pick configuration; approach, grasp and retract both ends
        at once; turn both hands along the cable; the far hand goes down on a circle about
        the connector hand (the cable then slides back against gravity), slides up the
        cable to the connector hand and comes back up on a circle; both grippers' z aligned
        with the routing platform."""
        return next(self.ways(ctx, state))

    def ways(
        self,
        ctx: PlanningContext,
        state: CableState,
        either_arm: bool = False,
        then: tuple[str, str] | None = None,
    ) -> Iterator[tuple[list[Segment], CableState]]:
        """The ways to pick the cable, best first, each with the state after it: the arm
        the look-ahead chose takes the connector end (``either_arm``: the PlaceConnector
        that follows lets either arm place it, so then the other arm too), with each tip of
        the hands (cg.LEANS, the default first), the far hand grasping as published, then
        turned half a turn; all of those first as published, then with the hands meeting
        between the combs before the slide (cg.PICK_MEETS); all of those with the far hand
        sliding up to the connector hand as published, then ending its slide farther from it
        (PICK_FARTHER); then, where the cable must turn round between the combs and the
        connector guide (_asides), the far hand first taking the free end aside on its own
        (each farther and tip). Left out: a way on which no pair of the arms' IK branches keeps the
        cell's clearance (_pick_on). The first way's error when none reaches. ``then``:
        where the connector arm, and the routing arm, work after the pick
        (the connector guide, the route's last guide): with either arm, the arms not crossing
        there either first."""
        world = ctx.world
        where = f"steps[{state.step}] PickCable {self.cable}"
        arms = _two_arms(world, where)
        for arm in arms:
            _check_jaw(world, arm, where, self.cable)
        conn_ref, free_ref = self.from_
        chosen = state.connector_arm or _nearest_arm(world, arms, conn_ref)
        c_arms: tuple[str, ...] = (chosen,)
        if either_arm:  # the arms not crossing first: the shorter reach from the bases
            pairs = [(chosen, _other(arms, chosen)), (_other(arms, chosen), chosen)]
            c_at, f_at = (
                ((conn_ref,), (free_ref,))
                if then is None
                else ((conn_ref, then[0]), (free_ref, then[1]))
            )
            reach = [
                sum(_base_distance(ctx, a, r) for r in c_at)
                + sum(_base_distance(ctx, b, r) for r in f_at)
                for a, b in pairs
            ]
            c_arms = tuple(
                p[0] for _, p in sorted(zip(reach, pairs, strict=True), key=lambda r: r[0])
            )
        first: InputError | None = None
        found = False
        for c_arm in c_arms:
            f_arm = _other(arms, c_arm)
            asides = _asides(world, state, conn_ref, free_ref)
            ways = itertools.chain(
                itertools.product(PICK_FARTHER, cg.PICK_MEETS, cg.LEANS, (False, True), (0.0,)),
                itertools.product(PICK_FARTHER, ((0.0, 0.0),), cg.LEANS, (False,), asides),
            )
            for farther, meet, lean, flip, aside in ways:
                s = replace(state, lean=lean)
                geo = _pick_geometry(
                    world, s, self.cable, conn_ref, free_ref, c_arm, f_arm, lean, flip, meet,
                    farther, aside,
                )  # fmt: skip
                try:
                    _check_reach(ctx, c_arm, geo.reach(c_arm), where)
                    _check_reach(ctx, f_arm, geo.reach(f_arm), where)
                    _check_both_free(ctx, geo, c_arm, f_arm, where)
                    segments, after = _emit_pick(self, s, geo, c_arm, f_arm)
                    segments = _pick_on(ctx, geo, segments, where)
                except InputError as e:
                    first = first or e
                    continue
                found = True
                yield segments, after
        if not found:
            raise first or _error(f"{where}: no way to pick it")


class PlaceConnector(Skill):
    """Insert the cable's connector into a connector guide."""

    skill: Literal["PlaceConnector"]
    cable: CableRef
    guide: GuideRef

    def connector_arm(
        self, world: World, holder: str | None = None, step: int | None = None
    ) -> str:
        """The arm that places the connector: ``arm`` if it names one; with ``auto``,
        ``holder`` (the arm holding the connector end) if given, else the arm whose base is
        nearer the guide. ``step``: this step's index, so an error names it."""
        where = f"PlaceConnector {self.guide}"
        if step is not None:
            where = f"steps[{step}] {where}"
        arms = _two_arms(world, where)
        if self.arm in arms:
            return self.arm
        if self.arm != "auto":
            raise _error(
                f"{where}: arm must be one robot or 'auto', not '{self.arm}'" + known(arms)
            )
        return holder if holder is not None else _nearest_arm(world, arms, self.guide)

    def plan(self, ctx: PlanningContext, state: CableState) -> tuple[list[Segment], CableState]:
        """Algorithm 1, PLACECONNECTOR: align the held cable with the connector guide (both
        hands as one rigid pair); approach, insert and retract keypoints; release and retract
        the connector gripper; then pull_distance."""
        world = ctx.world
        where = f"steps[{state.step}] PlaceConnector {self.guide}"
        c_arm = self.connector_arm(world, state.connector_arm, state.step)
        arms = _two_arms(world, where)
        f_arm = _other(arms, c_arm)
        _require_hold(state, c_arm, self.cable, where, "the connector end (plan PickCable first)")
        _require_hold(state, f_arm, self.cable, where, "the cable (plan PickCable first)")
        return next(self.ways(ctx, state))

    def ways(
        self, ctx: PlanningContext, state: CableState, route_end: str | None = None
    ) -> Iterator[tuple[list[Segment], CableState]]:
        """The ways to place the connector, best first: the pair turned to the guide where
        it is, then carried over the slot (as published); or turned while carried; or carried
        first and turned over the slot; each with the connector hand retracting straight up,
        then along its tipped tool axis. Each way leaves the other arm to route, as
        published, or hands the cable over to the connector arm (_hand_over): first the
        roles that keep each arm on its side, the connector guide for the arm that stays by
        it and ``route_end`` (the route's last guide) for the routing arm. The first way's
        error when none reaches."""
        world = ctx.world
        where = f"steps[{state.step}] PlaceConnector {self.guide}"
        c_arm = self.connector_arm(world, state.connector_arm, state.step)
        f_arm = _other(_two_arms(world, where), c_arm)
        _require_hold(state, c_arm, self.cable, where, "the connector end (plan PickCable first)")
        _require_hold(state, f_arm, self.cable, where, "the cable (plan PickCable first)")
        first: InputError | None = None
        found = False
        swap_first = route_end is not None and _crossed(ctx, c_arm, f_arm, self.guide, route_end)
        carries = _Replayed(_place_carries(ctx, state, self, c_arm, f_arm, where))
        for swap in (swap_first, not swap_first):
            for (hold, order), along_tool in ((c, a) for c in carries for a in (False, True)):
                geo = _place_geometry(
                    world, state, self, c_arm, f_arm, where, order, along_tool, hold
                )
                try:
                    _check_reach(ctx, c_arm, geo.reach(c_arm), where)
                    _check_reach(ctx, f_arm, geo.reach(f_arm), where)
                    _check_insert(ctx, geo, c_arm, where)
                    segments, after = _emit_place(self, state, geo, c_arm, f_arm)
                    segments = _place_apart(ctx, state, segments, (c_arm, f_arm), where)
                    if swap:
                        more, after = _hand_over(ctx, after, geo, c_arm, f_arm, self.cable, where)
                        segments += more
                    after = _with_placed(after, self.cable, self.guide, geo.rear)
                except InputError as e:
                    first = first or e
                    continue
                found = True
                yield segments, after
        if not found:
            raise first or _error(f"{where}: no way to place it")


def _with_placed(state: CableState, cable: str, guide: str, rear: Vec) -> CableState:
    """``state`` remembering where ``cable``'s connector was placed and the hold behind it
    the placing ends with: a harness's later groups are taken from there (cable_group)."""
    arm = state.routing_arm
    assert arm is not None
    other = next(a for a in state.arms if a != arm)
    placed = Placed(
        guide,
        _point(rear),
        arm,
        state.tcp[arm],
        state.held[arm].s,
        state.pull_distance,
        state.tcp[other],
    )
    return replace(state, placed={**state.placed, cable: placed})


Carry = tuple[tuple[float, float], str]  # PlaceConnector's: (the other hand's hold, order)
_Item = TypeVar("_Item")


class _Replayed(Iterable[_Item]):
    """An iterator's items, taken from it as they are first asked for, again each time the
    object is iterated (``itertools.product`` takes them all first)."""

    def __init__(self, items: Iterator[_Item]) -> None:
        self._items, self._taken = items, list[_Item]()

    def __iter__(self) -> Iterator[_Item]:
        k = 0
        while True:
            if k == len(self._taken):
                try:
                    self._taken.append(next(self._items))
                except StopIteration:
                    return
            yield self._taken[k]
            k += 1


def _place_carries(
    ctx: PlanningContext,
    state: CableState,
    step: PlaceConnector,
    c_arm: str,
    f_arm: str,
    where: str,
) -> Iterator[Carry]:
    """The ways to carry the pair to the guide and insert the connector: how the other hand
    holds the cable meanwhile (cg.PLACE_HOLDS) and the order of the carry (PLACE_ORDERS).
    Left out: a way along which the other hand's tool comes within the cell's clearance of
    the cell, or no pair of the arms' IK branches stays free and the clearance apart (at
    poses along it, _pair_rooms). The published hold first (no regrasp: the shortest), then
    the most room between the arms: the others are measured only when the published ones
    are all taken. None at all: an error that blames the arms (the other arm might place
    it)."""
    kept: list[tuple[int, float, int, tuple[float, float], str]] = []
    clear = False  # some way keeps the other hand's tool clear of the cell
    closest: Nearest | None = None  # else the way whose tool came least near, and to what
    rolls = dict.fromkeys(roll for roll, _ in cg.PLACE_HOLDS)
    centred = [(roll, f) for f in _centred_hold(ctx.world, step, f_arm) for roll in rolls]
    holds = (*cg.PLACE_HOLDS, *centred)
    published = len(PLACE_ORDERS)  # the first carries: the published hold's
    found = False
    for k, (hold, order) in enumerate(itertools.product(holds, PLACE_ORDERS)):
        if k == published:  # then the rest, ranked
            found = found or bool(kept)
            yield from ((hold, order) for *_, hold, order in sorted(kept))
            kept = []
        geo = _place_geometry(ctx.world, state, step, c_arm, f_arm, where, order, hold=hold)
        poses = [pair for _, paths in geo.carry for pair in _samples(paths)]
        poses += _samples(geo.insert)
        T_fs = [T_f for _, T_f in poses]
        if ctx.probe.comes_within(f_arm, T_fs, GRASP, (), ctx.clearance):
            if not clear:
                near = ctx.probe.nearest(f_arm, T_fs, GRASP, (), ctx.clearance)
                if near is not None and (closest is None or near.distance > closest.distance):
                    closest = near
            continue
        clear = True
        room = max(_pair_rooms(ctx, c_arm, f_arm, poses, ctx.clearance).values())
        if room >= ctx.clearance:
            rank = 0 if hold == cg.PLACE_HOLDS[0] else 2 if hold in centred else 1
            kept.append((rank, -room if rank else 0.0, k, hold, order))
    yield from ((hold, order) for *_, hold, order in sorted(kept))
    if not (found or kept):
        what = "the arms cannot keep the cell's clearance from each other"
        if not clear and closest is not None:
            what = f"{closest.tool} {_passes(closest, ctx.clearance)}"
        error = _error(
            f"{where}: however the other arm ({f_arm}) holds the cable, {what} carrying the "
            f"connector to the guide (the cell's clearance is {_mm(ctx.clearance)} mm)"
        )
        error.blames = "arms"  # the other arm might place it: PickCable decides which
        raise error


def _centred_hold(world: World, step: PlaceConnector, f_arm: str) -> tuple[float, ...]:
    """How much farther than published (cg.PLACE_HOLDS) the other hand holds the cable
    centred in the room between the connector guide and the element next along the cable,
    when one stands within twice the farthest hold (the published one may be in it): none
    when none does, or when the room is too short for the hand."""
    cable = world.cable(step.cable)
    conn_len = cable.connector.length if cable.connector is not None else 0.0
    hand = _hand(world, f_arm)
    dims = world.dimensions(step.guide)
    up, slot = cg.platform_up(world, step.guide), cg.position(world, step.guide)
    axis = cg.horizontal(cg.keypoint_x(world, step.guide), up)
    half = max(dims.get("length", 0.0), conn_len) / 2.0
    published = _connector_spacing(world, step.guide, conn_len, hand)
    reach = 2.0 * (published - half + max(farther for _, farther in cg.PLACE_HOLDS))
    face = slot + half * axis
    height = dims.get("height", 0.0)
    room = _room(world, step.guide, slot, height, face, axis, up, hand, reach)
    if room is None or room / 2.0 < hand.half_length:
        return ()
    farther = half + room / 2.0 - published
    same = any(abs(farther - f) <= 1e-6 for _, f in cg.PLACE_HOLDS)  # 1 um: the same
    return () if same else (farther,)


def _check_insert(ctx: PlanningContext, geo: _PlaceGeometry, c_arm: str, where: str) -> None:
    """Along the insert the connector hand's tool, closed on the connector, stays out of the
    connector guide (its fingers go down beside it: the collision checker's margin) and the
    cell's clearance from everything else: else no carry or hold can place it so (a pocket
    as deep as the connector is tall takes the fingers in with it)."""
    from cellengine.motion.collision import DEFAULT_CLEARANCE  # the motion stack

    guide = (cg.element_of(geo.guide),)
    found = _env_near(ctx, c_arm, geo.insert[0], GRASP, guide, DEFAULT_CLEARANCE)
    if found is None:
        return
    near, limit, own = found
    fix = (
        f"the tool keeps {_mm(limit)} mm from the guide it inserts into"
        if own
        else _env_fix(ctx, near, own, limit)
    )
    raise _error(f"{where}: {near.tool} {_passes(near, limit)} inserting the connector; {fix}")


def _samples(paths: tuple[Poses, Poses], n: int = 4) -> list[tuple[Mat, Mat]]:
    """``n`` + 1 pose pairs evenly along two paths of the same length."""
    last = len(paths[0]) - 1
    return [(paths[0][i], paths[1][i]) for i in sorted({round(last * j / n) for j in range(n + 1)})]


class RouteCable(Skill):
    """Route the cable through guides, in order."""

    skill: Literal["RouteCable"]
    cable: CableRef
    guides: tuple[GuideRef, ...] = Field(min_length=1)
    # a harness's bottom branch: the cables above it still to be routed are laid aside in
    # this guide first (a separation guide, REMODEL's J<n>S)
    separate_into: GuideRef | None = None

    def plan(self, ctx: PlanningContext, state: CableState) -> tuple[list[Segment], CableState]:
        """Algorithm 1, ROUTECABLE, for each guide: the other arm lets go of the previous
        guide; the routing gripper turns to face the guide and approaches it sliding; slides
        R_cable more at the sliding angle theta; the other arm grasps the cable where the
        routing gripper stopped; the routing gripper pulls the cable taut, lifts it over the
        guide, swings it over the slot and inserts it on circles about the other hand."""
        plans: list[GuidePlan] = []
        sim = state
        for k in range(len(self.guides)):  # every guide's first way, checked before any motion
            gp = next(self.guide_plans(ctx, sim, k))
            sim = gp.after(sim, *self.arms(ctx, state), self.cable)
            plans.append(gp)
        segments: list[Segment] = []
        for gp in plans:
            more, state = _emit_guide(state, gp, *self.arms(ctx, state), self.cable)
            segments += more
        return segments, state

    def arms(self, ctx: PlanningContext, state: CableState) -> tuple[str, str]:
        """(routing arm, other arm), checked to hold the cable with the jaw modes needed."""
        where = f"steps[{state.step}] RouteCable"
        r_arm, o_arm = _routing_arms(ctx.world, state, self.cable, where)
        _check_jaw(ctx.world, r_arm, where, self.cable)
        _check_jaw(ctx.world, o_arm, where, self.cable)
        _check_gaps(ctx.world, self.guides, self.cable, where)
        return r_arm, o_arm

    def ways(
        self,
        ctx: PlanningContext,
        state: CableState,
        k: int,
        dead: Set[bytes] = frozenset(),
        shared: Shared | None = None,
    ) -> Iterator[tuple[list[Segment], CableState]]:
        """The ways to route guide ``k`` from ``state``, best first, with the state after
        (``dead``, ``shared``: see guide_plans)."""
        r_arm, o_arm = self.arms(ctx, state)
        for gp in self.guide_plans(ctx, state, k, dead, shared):
            yield _emit_guide(state, gp, r_arm, o_arm, self.cable)

    def guide_plans(
        self,
        ctx: PlanningContext,
        state: CableState,
        k: int,
        dead: Set[bytes] = frozenset(),
        shared: Shared | None = None,
    ) -> Iterator[GuidePlan]:
        """Guide ``k``'s plans that pass the checks (reach, cable length, a slide clear of
        the other elements), best first (:func:`guide_ways`); the first way's error when
        none does. ``dead``: the other hand's releases (their poses' bytes) the compiler
        could not run from ``state``; the ways that begin with one are left out, looked at
        as they come (the set may grow while the ways are drawn). ``shared``: the routing
        hand's screens of calls before whose states differ only in the other arm (the hand
        swaps before a guide: cable_swap), by _routing_state."""
        world, guide = ctx.world, self.guides[k]
        r_arm, o_arm = self.arms(ctx, state)
        # the error to give when no way passes: the way that came closest to keeping the
        # clearance, else the first way's
        closest: tuple[float, InputError] | None = None
        found = False
        # Where the other hand stands back to matters only to the arms' clearance while the
        # routing hand comes (_coming): ways that differ only in it are otherwise checked once.
        checked: dict[WayKey, GuidePlan | InputError] = {}
        up = cg.platform_up(world, guide)
        screen = _Screen(tuple(cg.footprints(world, guide, up)), up)
        heads, theta0 = _way_heads(world, state, guide, r_arm, self._clear_from(ctx, state, k))
        released: dict[Back, InputError | Release] = {}
        releases: dict[Back, bytes] = {}
        seen: set[InputError] = set()  # the ways' errors the loop has been given
        # the loop below: the ways it would refuse from what the screens found so far
        looking = False

        def refused(h: _Head, c: Coordinates) -> int | None:
            if not looking or (releases and all(r in dead for r in releases.values())):
                return None  # the loop ends at the next way it is given
            return _refused(screen, checked, released, seen, h, c)

        ways = _ranked(heads, theta0, refused)
        first = next(ways)  # a head has ways
        self._check_any_length(ctx, state, k, heads, first, r_arm, o_arm)
        nxt = self.guides[k + 1] if k + 1 < len(self.guides) else None
        released = _letting_go(ctx, state, (r_arm, o_arm), screen.up, guide, nxt)
        whys = [e for e in released.values() if isinstance(e, InputError)]
        if released and len(whys) == len(released):
            # no way's other hand lets go of the last guide: in the other roles the arms
            # stand elsewhere (PlaceConnector decides who routes, PickCable who holds what)
            why = max(whys, key=lambda e: e.distance if isinstance(e, _Blocked) else -math.inf)
            if not isinstance(why, _Standing):  # where it holds the cable decides that
                why.blames = "arms"
            raise why
        state = _still_on(state, r_arm, released)
        if shared is not None:  # the routing hand's screens of the same routing hand
            own = shared.setdefault(_routing_state(state, k, r_arm), screen)
            screen = replace(own, pivots={}, coming={})
        releases = {b: _stand_back(state, o_arm, up, b).tobytes() for b in released}
        looking = True
        for way in itertools.chain((first,), ways):
            back = _back_of(way)
            release = released.get(back, ())
            if isinstance(release, InputError):
                continue  # the stand-backs that work are among the ways too
            if releases and releases[back] in dead:
                if all(r in dead for r in releases.values()):
                    return  # the compiler ran none of them
                continue
            key = _backless_key(way)
            if key not in checked:
                checked[key] = self._checked(ctx, state, guide, way, r_arm, o_arm, screen)
            gp = checked[key]
            if not isinstance(gp, InputError):
                gp = replace(_with_back(gp, back), release=release)
                gp = _coming(ctx, state, gp, way, (r_arm, o_arm), screen, (back,))
            if isinstance(gp, InputError):
                seen.add(gp)
                score = gp.distance if isinstance(gp, _Blocked) else -math.inf
                if closest is None or score > closest[0]:
                    closest = (score, gp)
                continue
            found = True
            yield gp
        if not found:
            # too little room between two guides explains it better than any way's distance
            where = f"steps[{state.step}] RouteCable {guide}"
            before = state.guides[-1] if state.guides else None
            after = self.guides[k + 1] if k + 1 < len(self.guides) else None
            _check_room(world, where, _hand(world, o_arm), before, guide)
            _check_room(world, where, _hand(world, r_arm), guide, after)
            raise closest[1] if closest is not None else _error(f"{where}: no way to route it")

    def _check_any_length(
        self,
        ctx: PlanningContext,
        state: CableState,
        k: int,
        heads: Sequence[_Head],
        first: GuideWay,
        r_arm: str,
        o_arm: str,
    ) -> None:
        """The first way's error when the cable is too short for every way (the stop and
        the insert's end set how much it needs) and the first way is within reach, before
        any is built."""
        world, guide = ctx.world, self.guides[k]
        last = np.asarray(state.route[-1], dtype=float)
        need = math.inf
        for gap, after in {(h.gap, a) for h in heads for a in h.afters}:
            b = _basics(world, state, guide, r_arm, gap, after)
            need = min(need, float(np.linalg.norm(b.ap - last)) + b.r_cable + b.pull)
        hand = _hand(world, r_arm)
        if state.route_length() + need + hand.end_margin > world.cable(self.cable).length:
            gp = _guide_plan(world, state, self.cable, guide, r_arm, o_arm, first)
            try:
                _check_reach(ctx, r_arm, gp.reach_routing(), gp.where)
            except InputError:
                return  # out of reach says more: the ways are screened for it first
            _check_length(world, self.cable, hand, gp)

    def _clear_from(
        self, ctx: PlanningContext, state: CableState, k: int
    ) -> Callable[[_Basics, float, bool], float | None]:
        """The least sliding angle (to BISECT_TOL, by bisection) at which the routing hand's
        tool, sliding with the default tips, keeps the cell's work_clearance from guide ``k``,
        for a stop, side and turning first or not; None when not even THETA_MAX does. (The published
        minimum assumes a hand W_gripper wide that does not turn; the steps of THETA_STEP
        above it miss a narrow range of angles that clear the guide and the elements on
        the slide's side.)"""
        guide = self.guides[k]
        r_arm, _ = self.arms(ctx, state)
        own = {cg.element_of(guide)}

        def clear(b: _Basics, side: float, first: bool, theta: float) -> bool:
            way = GuideWay(theta, side, gap=b.gap, turn_first=first)
            slide = _slide(b, way, _approach_pose(ctx.world, state, b, r_arm, way))
            poses = [*slide[::2], slide[-1]]
            return not ctx.probe.comes_within(r_arm, poses, SLIDE, (), b.hand.keep, own)

        def least(b: _Basics, side: float, first: bool) -> float | None:
            lo, hi = b.theta_min + cg.THETA_MARGIN, cg.THETA_MAX
            if clear(b, side, first, lo):
                return lo
            if not clear(b, side, first, hi):
                return None
            while hi - lo > BISECT_TOL:
                mid = (lo + hi) / 2.0
                lo, hi = (lo, mid) if clear(b, side, first, mid) else (mid, hi)
            return hi

        return least

    def _checked(
        self,
        ctx: PlanningContext,
        state: CableState,
        guide: str,
        way: GuideWay,
        r_arm: str,
        o_arm: str,
        screen: _Screen,
    ) -> GuidePlan | InputError:
        """The plan of ``way`` if it passes the checks (reach, cable length, clearances),
        else why not. Each check is made once for the ways that share what it depends on
        (``screen``): the routing hand's approach, what the routing hand does, the other
        hand's descent."""
        world, arms = ctx.world, (r_arm, o_arm)
        r_key = _routing_key(way)
        p_key = (way.gap, way.pivot_lean, way.towards_base)
        a_key = (way.gap, way.lean, way.towards_base)
        approaches, routed, pivots = screen.approaches, screen.routed, screen.pivots
        backs = _stand_backs(state, o_arm)
        for seen in (
            approaches.get(a_key),
            routed.get(r_key),
            pivots.get(p_key),
            screen.came.get(_coming_key(way, DEFAULT_BACK)),
            _coming_blocked(screen, way, backs),
        ):
            if isinstance(seen, InputError):
                return seen
        try:
            gp = _guide_plan(world, state, self.cable, guide, r_arm, o_arm, way, screen.prints)
            if a_key not in approaches:
                approaches[a_key] = _approach_blocked(ctx, gp, r_arm)
            reached = approaches[a_key]
            if reached is not None:
                return reached
            k = self.guides.index(guide)
            after = (cg.element_of(self.guides[k + 1]),) if k + 1 < len(self.guides) else ()
            gp = replace(gp, beside=(*gp.beside, *after, *_under(ctx, gp.slot, gp.up)))
            if a_key not in screen.hows:
                how = _approach_how(ctx, state, self.cable, way, gp, arms, screen.prints)
                screen.hows[a_key] = how
            if screen.hows[a_key] != way.approach:
                way = replace(way, approach=screen.hows[a_key])
                r_key = _routing_key(way)
                built = _guide_plan(
                    world, state, self.cable, guide, r_arm, o_arm, way, screen.prints
                )
                gp = replace(built, beside=gp.beside)
            if r_key not in routed:
                c_key, may = _coming_key(way, DEFAULT_BACK), state.branches_of(r_arm)

                def came() -> InputError | frozenset[int]:
                    if c_key not in screen.came:
                        screen.came[c_key] = _coming_hand_blocked(ctx, gp, r_arm, may)
                    return screen.came[c_key]

                routed[r_key] = _routing_hand_blocked(ctx, world, self.cable, gp, r_arm, came)
            if p_key not in pivots:
                nxt = cg.platform_up(world, self.guides[k + 1]) if after else None
                pivots[p_key] = _pivot_blocked(ctx, state, guide, arms, way, nxt)
            found, pivoting = routed[r_key], pivots[p_key]
            if isinstance(found, InputError):
                return found
            if isinstance(pivoting, InputError):
                return pivoting
            coming = _coming(ctx, state, replace(gp, branches=found), way, arms, screen, backs)
            if isinstance(coming, InputError):
                return coming
            gp = coming
            try:
                _check_reach(ctx, o_arm, gp.reach_other(), gp.where)
            except InputError as e:
                e.blames = "arms"  # the routing arm might reach: PickCable decides which
                raise
            _check_hands(ctx, gp, r_arm, o_arm)
            kept, grasp, pairs = _check_pivot_free(ctx, gp, r_arm, o_arm, pivoting)
            gp = replace(gp, branches=kept, grasp=grasp, grasp_pairs=pairs)
        except InputError as e:
            return e
        return gp


# The screens' keys are tuples of a way's fields, not ways: a guide's screen looks up
# hundreds of thousands of ways, and building a way (a frozen dataclass) per lookup costs
# more than the lookups.
WayKey = tuple[Any, ...]


@dataclass
class _Screen:
    """What RouteCable.guide_plans found of one guide's ways so far, by what it depends on."""

    prints: tuple[cg.Footprint, ...]  # the other elements' (cg.footprints of the guide)
    up: Vec  # the guide's platform's
    approaches: dict[tuple[float, float, float], InputError | None] = field(default_factory=dict)
    # why not, or the routing arm's branches that can
    routed: dict[WayKey, InputError | frozenset[int]] = field(default_factory=dict)
    hows: dict[tuple[float, float, float], str] = field(default_factory=dict)  # APPROACHES
    # why not, or the other arm's branches that can
    pivots: dict[tuple[float, float, float], InputError | frozenset[int]] = field(
        default_factory=dict
    )
    # why the routing hand cannot come to the guide and slide, or its branches that can
    came: dict[WayKey, InputError | frozenset[int]] = field(default_factory=dict)
    # how far apart the arms stay per pair of branches (8 x 8, _pair_least; None: solved
    # numerically) while the routing hand comes and slides, and why not when no pair keeps
    # the clearance
    coming: dict[WayKey, tuple[NDArray[np.float64] | None, _Blocked | None]] = field(
        default_factory=dict
    )


Release = tuple[tuple[str, frozenset[int]], ...]  # Segment.branches of a release
Shared = dict[bytes, _Screen]  # RouteCable.guide_plans's


def _routing_state(state: CableState, k: int, r_arm: str) -> bytes:
    """What the routing hand's screens of guide ``k`` depend on in ``state`` (_Screen's
    approaches, hows, routed and came): where the routing hand is and may be, and the
    cable laid so far."""
    what = (
        k,
        r_arm,
        state.step,
        sorted(state.branches_of(r_arm)),
        state.route,
        state.guides,
        state.pull_distance,
        state.lean,
        state.wound.get(r_arm),
        state.mode.get(r_arm),
        state.held.get(r_arm),
    )
    return repr(what).encode() + np.asarray(state.tcp[r_arm]).tobytes()


def _letting_go(
    ctx: PlanningContext,
    state: CableState,
    arms: tuple[str, str],
    up: Vec,
    guide: str,
    after: str | None = None,
) -> dict[Back, InputError | Release]:
    """Per stand-back (when the other hand holds the cable at the last guide), why the other
    arm cannot let go and stand back, the routing hand holding still, on the IK branches the
    arms may be on without hitting itself or coming within the cell's clearance of the
    routing arm; else each arm's branches in a pair of them that can. It depends on the state
    alone: every way of the guide with that stand-back would be refused for it (_coming, or
    the compiler), and its release requires those branches (so a transit before it that
    chose others is compiled again looking ahead at them). Its open hand keeps the cell's
    clearance from all but the elements it may pass near (_standing_near; ``after``: the
    guide after ``guide``), as the compiler holds it."""
    from cellengine.execute.following import STRIDE, surviving  # the motion stack

    r_arm, o_arm = arms
    if o_arm not in state.held:
        return {}
    out: dict[Back, InputError | Release] = {}
    where = f"steps[{state.step}] RouteCable {guide}"
    what = f"the other arm ({o_arm}) lets go of {state.guides[-1]} and stands back"
    near = _standing_near(ctx, state, up, guide, after)
    for back in _stand_backs(state, o_arm):
        poses = _stand_back(state, o_arm, up, back)
        may = state.branches_of(o_arm)
        alive, nearest = surviving(ctx.cell, ctx.checker, o_arm, poses, ctx.home, may)
        how = _back_text(back)
        if not alive:
            out[back] = _error(
                f"{where}: {what} {how} on no IK branch it may be on without "
                f"hitting itself ({', '.join(nearest[1]) or 'out of reach'})"
            )
            continue
        found = _env_near(ctx, o_arm, poses, OPEN, near, _checker_clearance(), stride=1)
        if found is not None:
            tool, limit, own = found
            out[back] = _Standing.of(
                tool.distance - limit,
                f"{where}: {tool.tool} {_passes(tool, limit)} while {what} {how}; "
                + _env_fix(ctx, tool, own, limit),
            )
            continue
        T_r = state.tcp[r_arm]
        pairs = [(T_r, T) for T in (*poses[::STRIDE], poses[-1])]
        may_r, may_o, keep = state.branches_of(r_arm), frozenset(alive), ctx.clearance
        rooms = _pair_rooms(ctx, r_arm, o_arm, pairs, keep, may_r, may_o, False)
        room = max(rooms.values())
        if room < keep:
            out[back] = _Blocked.of(
                room - keep,
                f"{where}: however the two arms are posed, they "
                + ("collide" if room == -math.inf else f"come within {_mm(room)} mm of each other")
                + f" while {what} {how}, the routing arm ({r_arm}) still; the cell's "
                f"clearance is {_mm(keep)} mm",
            )
            continue
        swapped = [(T_o, T_r) for T_r, T_o in pairs]
        o_rooms = _pair_rooms(ctx, o_arm, r_arm, swapped, keep, may_o, may_r, False)
        out[back] = tuple(
            (arm, frozenset(k for k, v in found.items() if v >= keep))
            for arm, found in sorted(((r_arm, rooms), (o_arm, o_rooms)))
            if -1 not in found  # an arm solved numerically has no branches
        )
    return out


def _standing_near(
    ctx: PlanningContext, state: CableState, up: Vec, guide: str, after: str | None
) -> tuple[str, ...]:
    """What the other hand standing back from the last guide may pass near (the compiler
    holds it to the cell's clearance from all else): the last two guides' elements (the
    release's near), those the hands work between at ``guide`` and the one ``after`` it, and
    what lies under the cable at the last guide and at ``guide``."""
    slot = cg.position(ctx.world, guide)
    return tuple(
        sorted(
            {
                *map(cg.element_of, state.guides[-2:]),
                *_beside(state, guide),
                *((cg.element_of(after),) if after is not None else ()),
                *_under(ctx, np.asarray(state.route[-1], dtype=float), up),
                *_under(ctx, slot, up),
            }
        )
    )


def _checker_clearance() -> float:
    from cellengine.motion.collision import DEFAULT_CLEARANCE  # the motion stack: planning only

    return DEFAULT_CLEARANCE


def _still_on(
    state: CableState, r_arm: str, released: Mapping[Back, InputError | Release]
) -> CableState:
    """``state`` with the routing arm on only the IK branches on which, holding still, it
    lets the other hand go (some stand-back of ``released``): it routes the guide on from
    there in Cartesian paths, and the ways' checks need look at no other branch."""
    kept = [dict(r).get(r_arm, ANY_BRANCH) for r in released.values() if isinstance(r, tuple)]
    if not kept:
        return state
    on = state.branches_of(r_arm) & frozenset().union(*kept)
    return replace(state, branches={**state.branches, r_arm: on})


def _approach_blocked(ctx: PlanningContext, gp: GuidePlan, r_arm: str) -> InputError | None:
    """Why the routing arm cannot reach the approach pose of ``gp`` (it depends only on the
    stop and the hand's tip), or None."""
    try:
        _check_reach(ctx, r_arm, gp.reach_routing()[:1], gp.where)
    except InputError as e:
        e.blames = "arms"  # the other arm might reach: PickCable decides which
        return e
    return None


def _approach_how(
    ctx: PlanningContext,
    state: CableState,
    cable: str,
    way: GuideWay,
    gp: GuidePlan,
    arms: tuple[str, str],
    prints: Sequence[cg.Footprint],
) -> str:
    """The first of APPROACHES on which the routing hand keeps clear turning to face the
    guide and coming to the approach pose of ``way`` (``gp``, built with way.approach), as
    _check_clear holds it; the first when none does (_check_clear says why)."""
    from cellengine.motion.collision import DEFAULT_CLEARANCE  # the motion stack: planning only

    def clear(poses: Poses | None) -> bool:
        return poses is None or (
            _env_near(ctx, arms[0], poses, SLIDE, gp.beside, DEFAULT_CLEARANCE, 1) is None
        )

    turned: bool | None = None  # the others all turn in place, from the same pose
    came: str | None = None  # the first whose approach alone keeps clear
    for how in APPROACHES:
        if how != way.approach:
            built = _guide_plan(
                ctx.world, state, cable, gp.guide, *arms, replace(way, approach=how), prints
            )
            gp = replace(built, beside=gp.beside)
        if how == OVER_ALL:
            if clear(gp.reorient) and clear(gp.approach):
                return how
            break
        if not clear(gp.approach):
            continue
        turned = clear(gp.reorient) if turned is None else turned
        if turned:
            return how
        came = came or how
    return came or APPROACHES[0]


def _routing_hand_blocked(
    ctx: PlanningContext,
    world: World,
    cable: str,
    gp: GuidePlan,
    r_arm: str,
    came: Callable[[], InputError | frozenset[int]],
) -> InputError | frozenset[int]:
    """Why the routing hand alone cannot do ``gp`` (the cable's length, its reach, its
    clearances, its own links), or the branches on which it can; ``came``: how it comes to
    the guide and slides (_coming_hand_blocked, shared by many ways)."""
    try:
        try:
            _check_reach(ctx, r_arm, gp.reach_routing()[1:], gp.where)
        except InputError as e:
            e.blames = "arms"  # the other arm might reach: PickCable decides which
            raise
        _check_length(world, cable, _hand(world, r_arm), gp)
        alive = came()
        if isinstance(alive, InputError):
            return alive
        _check_clear(ctx, gp, r_arm, coming=False)
        return _check_self(ctx, gp, r_arm, alive, coming=False)
    except InputError as e:
        return e


def _coming_hand_blocked(
    ctx: PlanningContext, gp: GuidePlan, r_arm: str, may: frozenset[int]
) -> InputError | frozenset[int]:
    """Why the routing hand cannot come to the guide and slide (its clearances, its own
    links), or the branches of ``may`` on which it can."""
    try:
        _check_clear(ctx, gp, r_arm, coming=True)
        return _check_self(ctx, gp, r_arm, may, coming=True)
    except InputError as e:
        return e


CableSkill = PickCable | PlaceConnector | RouteCable


def plan_cable_steps(
    ctx: PlanningContext, steps: Sequence[Skill], state: CableState | None = None
) -> tuple[list[Segment], CableState]:
    """Every step's segments (each step's first way), chained through one state (from the
    arms' homes unless given); when the plan ends, the cable is released and the arms
    retract."""
    state = state if state is not None else CableState.at_home(ctx)
    segments: list[Segment] = []
    for i in range(len(steps)):
        more, state = next(step_ways(ctx, steps, i, state))
        segments += more
    more, state = release_and_retract(ctx, state)
    return segments + more, state


def step_ways(
    ctx: PlanningContext, steps: Sequence[Skill], i: int, state: CableState
) -> Iterator[tuple[list[Segment], CableState]]:
    """The ways to do ``steps[i]`` from ``state``, best first, each with the state after it
    (a RouteCable's: one, each guide's first way; the cable family offers each guide's
    ways as a choice of its own). Before a PickCable, the cable held is released (its last
    step is done) and the PlaceConnector of the same cable is looked up for its arm and
    guide. A step that cannot be done raises StepError with its index."""
    step = steps[i]
    if not isinstance(step, PickCable | PlaceConnector | RouteCable):
        raise TypeError(f"steps[{i}]: {step.skill} is not a cable skill")
    with at_step(i):
        if isinstance(step, PlaceConnector):
            yield from step.ways(
                ctx, replace(state, step=i), _route_end(steps[i + 1 :], step.cable)
            )
            return
        if isinstance(step, RouteCable):
            yield step.plan(ctx, replace(state, step=i))
            return
        segments: list[Segment] = []
        if state.held:
            segments, state = release_and_retract(ctx, state)
        state = _look_ahead(ctx.world, replace(state, step=i), step, steps[i + 1 :])
        either = _placed_by_either(steps[i + 1 :], step.cable)
        then = _works_at(steps[i + 1 :], step.cable)
        try:
            for more, after in step.ways(ctx, state, either, then):
                yield segments + more, after
        except InputError as e:
            if either:
                raise
            raise _named_arm_hint(ctx, state, step, steps, e) from None


def _named_arm_hint(
    ctx: PlanningContext,
    state: CableState,
    pick: PickCable,
    steps: Sequence[Skill],
    error: InputError,
) -> InputError:
    """``error`` (no way to pick ``pick``'s cable with the connector end in the arm its
    PlaceConnector names) saying so when the other arm could pick it: a plan written for
    another cell (a REMODEL sequence's L and R, its platforms turned) names the arm on the
    far side."""
    named = state.connector_arm
    if named is None or len(error.problems) != 1:
        return error
    other = _other(_two_arms(ctx.world, ""), named)
    try:
        next(pick.ways(ctx, replace(state, connector_arm=other)))
    except InputError:
        return error
    k = next(
        k for k, s in enumerate(steps)
        if k > state.step and isinstance(s, PlaceConnector) and s.cable == pick.cable
    )  # fmt: skip
    hint = (
        f"; the {other} arm can pick it, but steps[{k}] PlaceConnector names the {named} "
        f"arm to place the connector (arm: auto lets the engine choose)"
    )
    out = InputError(replace(error.problems[0], message=error.problems[0].message + hint))
    out.blames, out.failure = error.blames, error.failure
    return out


def release_and_retract(
    ctx: PlanningContext, state: CableState
) -> tuple[list[Segment], CableState]:
    """Algorithm 1, line 35: every gripper that holds the cable opens and goes up
    (_retracts' first way)."""
    return next(release_ways(ctx, state))


def release_ways(
    ctx: PlanningContext, state: CableState
) -> Iterator[tuple[list[Segment], CableState]]:
    """release_and_retract's ways, best first (_retracts): which arm's branch the route
    left it on decides which can run, and only the compiler knows it."""
    holding = [a for a in state.arms if a in state.held]
    if not holding:
        yield [], state
        return
    label = f"{state.cable}: release and retract"
    opened = [GripperEvent(a, OPEN) for a in holding]
    for retract in _retracts(ctx, state, holding):
        b = _Builder(state)
        for k, (what, paths, on, paired) in enumerate(retract):
            b.add(label + what, paths, before=opened if k == 0 else [], branches=on, paired=paired)
        done = replace(
            b.state, cable=None, connector_arm=None, routing_arm=None, place_guide=None, route=()
        )
        yield b.segments, replace(done, guides=(), pull_distance=0.0, lean=cg.LEAN)


# a segment's: its label's end, paths, branches, pairs of branches
Retract = tuple[str, list[ArmPath], Release, "Paired"]


def _retracts(
    ctx: PlanningContext, state: CableState, arms: Sequence[str]
) -> Iterator[list[Retract]]:
    """The retract's ways, each its segments: each arm's retract (of _retract_ways, its best
    first); for two arms, the pairs of ways on which some pair of the IK branches they may
    be on keeps the cell's clearance between them, the hands retracting at once (a strategy
    may move one after the other: either order), then one after the other (either first),
    with the branches of those pairs required (Segment.branches: the transits before look
    ahead at them); when none does, the best ways at once."""
    ways = [_retract_ways(ctx, state, a) for a in arms]
    if len(arms) != 2:
        yield [("", [w[0] for w in ways], (), ())]
        return
    a, b = arms
    on_a, on_b = state.branches_of(a), state.branches_of(b)
    found = False
    for first in (None, a, b):
        for way_a, way_b in itertools.product(*ways):
            if first is None:
                pairs = _along(way_a.poses, way_b.poses)
            elif first == a:
                pairs = _along(way_a.poses, way_b.poses[:1]) + _along(way_a.poses[-1:], way_b.poses)
            else:
                pairs = _along(way_a.poses[:1], way_b.poses) + _along(way_a.poses, way_b.poses[-1:])
            least = _pair_least(ctx, a, b, pairs, ctx.clearance, on_a, on_b, measure=False)
            if least is None:  # no branches: the compiler finds out
                yield [("", [way_a, way_b], (), ())]
                return
            if not (least >= ctx.clearance).any():
                continue
            found = True
            kept = least >= ctx.clearance
            on, paired = _kept_branches(kept, a, b), _kept_pairs(kept, a, b)
            if first is None:
                yield [("", [way_a, way_b], on, paired)]
                continue
            (one, one_way), (two, two_way) = (a, way_a), (b, way_b)
            if first == b:
                (one, one_way), (two, two_way) = (two, two_way), (one, one_way)
            yield [
                (f": {one} first", [one_way], on, paired),
                (f": then {two}", [two_way], on, paired),
            ]
    if not found:
        yield [("", [w[0] for w in ways], (), ())]


def _retract_ways(ctx: PlanningContext, state: CableState, arm: str) -> list[ArmPath]:
    """The open hand backing out RETRACT_HEIGHT along its tool axis (up, tipped by its lean),
    as published, and straight up (the last guide's platform's up); straight up first where,
    the tool tipped towards the arm's base, backing out along its axis brings the open
    fingers into the arm's own shoulder on a branch it may be on (a transit before looks
    ahead at these poses too: it would leave the arm on a branch the route was not checked
    on)."""
    from cellengine.execute.following import surviving  # the motion stack: planning only

    T, may = state.tcp[arm], state.branches_of(arm)
    up = cg.platform_up(ctx.world, state.guides[-1]) if state.guides else np.eye(3)[2]
    ways = [_up(T, arm, -T[:3, 2], cg.RETRACT_HEIGHT), _up(T, arm, up, cg.RETRACT_HEIGHT)]
    kept = [surviving(ctx.cell, ctx.checker, arm, w.poses, ctx.home, may)[0] for w in ways]
    order = sorted(range(len(ways)), key=lambda k: (kept[k] >= may, len(kept[k]), -k))
    return [ways[k] for k in reversed(order)]


# =========================================================================== building segments


class _Builder:
    """Appends segments for one step and keeps the state in step with them: each path's last
    pose becomes its arm's TCP, each event its gripper's mode."""

    def __init__(self, state: CableState) -> None:
        self.state = state
        self.segments: list[Segment] = []

    def add(
        self,
        label: str,
        paths: Iterable[ArmPath],
        *,
        before: Iterable[GripperEvent] = (),
        after: Iterable[GripperEvent] = (),
        closed_chain: tuple[str, str] | None = None,
        keep_distance: tuple[str, str] | None = None,
        near: Iterable[tuple[str, str]] = (),
        facts: Mapping[str, Any] | None = None,
        annotations: Iterable[Annotation] = (),
        branches: tuple[tuple[str, frozenset[int]], ...] = (),
        paired: Paired = (),
        contacts: Iterable[tuple[str, str]] = (),
        changes: Iterable[ToolChange] = (),
    ) -> None:
        seg = Segment(
            step=self.state.step,
            label=label,
            paths=tuple(paths),
            before=tuple(before),
            after=tuple(after),
            closed_chain=closed_chain,
            keep_distance=keep_distance,
            near=tuple(near),
            facts=MappingProxyType(dict(facts or {})),
            annotations=tuple(annotations),
            branches=branches,
            paired=paired,
            contacts=tuple(contacts),
            changes=tuple(changes),
        )
        state = self.state
        for event in seg.before:
            state = state.gripped(event)
        for path in seg.paths:
            state = state.moved_along(path.arm, path.poses)
        for event in seg.after:
            state = state.gripped(event)
        for change in seg.changes:
            state = state.changed(change)
        self.state = state
        self.segments.append(seg)

    def mode_event(self, arm: str, mode: str, holds: str | None) -> list[GripperEvent]:
        """The event that puts ``arm`` in ``mode``, or none if it is in it already."""
        return [] if self.state.mode.get(arm) == mode else [GripperEvent(arm, mode, holds)]


def _cartesian(arm: str, poses: Poses) -> ArmPath:
    return ArmPath(arm, "cartesian", poses)


def _transit(arm: str, T_cell_tcp: Mat) -> ArmPath:
    return ArmPath(arm, "transit", np.asarray(T_cell_tcp)[None])


def _up(T: Mat, arm: str, up: Vec, height: float) -> ArmPath:
    return _cartesian(arm, cg.line(T, cg.lifted(T, up, height)))


# A stand-back: how far the released pivot hand backs off (m), after rising how high (m), in
# which direction (rad about the vertical from back along the route; positive: to the left)
Back = tuple[float, float, float]
DEFAULT_BACK: Back = (cg.STAND_BACK, cg.RETRACT_HEIGHT, 0.0)


def _stand_back(state: CableState, arm: str, up: Vec, back: Back) -> Poses:
    """Up by ``back[1]``, then ``back[0]`` back along the route (its last two points: the
    pivot and the slot of the last guide), turned by ``back[2]``."""
    last = np.asarray(state.route[-2:], dtype=float)
    return _stand_back_from(state.tcp[arm], last[-1] - last[0], up, back)


def _stand_back_from(T: Mat, along: Vec, up: Vec, back: Back) -> Poses:
    """_stand_back from ``T``, the route going ``along`` at its end."""
    distance, lift, turn = back
    T_up = cg.lifted(T, up, lift)
    if distance == 0.0:
        return cg.line(T, T_up)
    away = g.axis_angle_to_matrix(up, turn) @ -cg.horizontal(along, up)
    return ip.concatenate(
        [cg.line(T, T_up), cg.line(T_up, cg.at(T_up, T_up[:3, 3] + distance * away))]
    )


def _back_of(way: GuideWay | GuidePlan) -> Back:
    return (way.stand_back, way.stand_lift, way.stand_turn)


_Backed = TypeVar("_Backed", "GuideWay", "GuidePlan")


def _with_back(way: _Backed, back: Back) -> _Backed:
    distance, lift, turn = back
    return replace(way, stand_back=distance, stand_lift=lift, stand_turn=turn)


def _back_text(back: Back) -> str:
    """How a stand-back reads in a message."""
    distance, lift, turn = back
    if distance == 0.0:
        return f"only up {_mm(lift)} mm"
    up = "" if lift == cg.RETRACT_HEIGHT else f" from {_mm(lift)} mm up"
    side = "" if turn == 0.0 else f" to the {'left' if turn > 0.0 else 'right'}"
    return f"{_mm(distance)} mm{side}{up}"


def _vec(v: Any) -> list[float]:
    return [float(x) for x in np.asarray(v, dtype=float).reshape(-1)]


# =========================================================================== PickCable


@dataclass(frozen=True)
class _PickGeometry:
    up: Vec
    grasp: Mapping[str, Mat]  # each hand's grasp pose
    retracted: Mapping[str, Mat]
    faced: Mapping[str, Poses]  # each hand turned along the cable
    meet: Mapping[str, Poses]  # then the hands that move to meet (cg.PICK_MEETS; {}: none)
    lower: Poses  # the far hand down on a circle about the connector hand
    slide: Poses  # then up the cable to it
    raise_: Poses  # and back up on a circle
    align: tuple[Poses, Poses] | None  # both hands: z along the routing platform's -z
    s: Mapping[str, float]  # where each hand holds the cable, at the grasp
    s_slid: float  # where the far hand holds it after the slide
    spacing: float  # connector hand to far hand after the slide (what placing holds)
    connector_arm: str
    far_arm: str
    # the far hand first takes the free end out of its comb on its own and away from the
    # connector, the way the cable leaves the connector guide (PickCable.ways): then the
    # connector hand picks; None: both at once, as published
    aside: Poses | None = None

    def reach(self, arm: str) -> list[tuple[str, Mat]]:
        out = [("pick approach", cg.lifted(self.grasp[arm], self.up, cg.APPROACH_HEIGHT))]
        out += [("pick grasp", self.grasp[arm]), ("pick retract", self.retracted[arm])]
        if arm == self.far_arm and self.aside is not None:
            out += [("free end aside", self.aside[-1])]
        out += [("turn along the cable", self.faced[arm][-1])]
        if arm in self.meet:
            out += [("met", self.meet[arm][-1])]
        if arm == self.far_arm:
            out += [("slide start", self.lower[-1]), ("slide end", self.slide[-1])]
            out += [("raised", self.raise_[-1])]
        if self.align is not None:
            out += [("aligned", self.align[0 if arm == self.connector_arm else 1][-1])]
        return out

    def end(self, arm: str) -> str:
        return "connector end" if arm == self.connector_arm else "free end"


def _pick_geometry(
    world: World,
    state: CableState,
    name: str,
    conn_ref: str,
    free_ref: str,
    c_arm: str,
    f_arm: str,
    lean: float,
    flip: bool = False,
    meet: tuple[float, float] = (0.0, 0.0),
    farther: float = 0.0,
    aside: float = 0.0,
) -> _PickGeometry:
    """The pick's poses (see PickCable.ways for the choices). ``aside`` (m, > 0): the far
    hand first takes the free end this far from the connector's retract pose, along the
    coming connector guide's cable (state.place_guide), and turns there along it."""
    cable = world.cable(name)
    up = cg.platform_up(world, conn_ref)
    hand_f = _hand(world, f_arm)
    conn_len = cable.connector.length if cable.connector is not None else 0.0
    # Combs: keypoint x runs along the cable towards its end. The connector rests against
    # the comb's outer face, so the connector hand holds its centre there; without a
    # connector it takes the cable end like the other hand. Both hold the cable with x
    # towards increasing s: from the connector end into the cable, from the cable to the
    # free end.
    K_a, K_b = world.pose(conn_ref), world.pose(free_ref)
    x_a, x_b = cg.horizontal(K_a[:3, 0], up), cg.horizontal(K_b[:3, 0], up)
    half_a = world.dimensions(conn_ref).get("length", 0.0) / 2.0
    half_b = world.dimensions(free_ref).get("length", 0.0) / 2.0
    hand_c = _hand(world, c_arm)
    reach_a = conn_len / 2.0 if cable.connector is not None else hand_c.x_offset
    # Tipped apart along the cable from the grasp on (the connector hand must keep its tip
    # relative to the connector until it lets go of it).
    T_c = cg.tcp_frame(K_a[:3, 3] + (half_a + reach_a) * x_a, -x_a, up, x_a, lean)
    T_f = cg.tcp_frame(K_b[:3, 3] + (half_b + hand_f.x_offset) * x_b, x_b, up, x_b, lean)
    if flip:
        # the same grasp with the far hand turned half a turn about its tool axis (the gripper
        # is symmetric and that hand holds only the cable): its wrist on the other side, where
        # the arms may not meet; it turns back with the turn along the cable
        T_f = T_f @ g.transform(g.axis_angle_to_matrix(np.array([0.0, 0.0, 1.0]), math.pi))
    T_c_up = cg.lifted(T_c, up, cg.RETRACT_HEIGHT)
    T_f_up = cg.lifted(T_f, up, cg.RETRACT_HEIGHT)
    chord = cg.horizontal(T_f_up[:3, 3] - T_c_up[:3, 3], up)
    away = None
    if aside > 0.0 and state.place_guide is not None:
        chord = cg.horizontal(cg.keypoint_x(world, state.place_guide), up)
        T_aside = cg.tcp_frame(T_c_up[:3, 3] + aside * chord, chord, up, chord, lean)
        away = cg.line(T_f_up, cg.nearer_turn(T_f_up, T_aside))  # it holds only the cable
    faced_c = cg.turn_in_place(T_c_up, cg.tcp_frame(T_c_up[:3, 3], chord, up, -chord, lean))
    faced_f = (
        away[-1:]
        if away is not None
        else cg.turn_in_place(T_f_up, cg.tcp_frame(T_f_up[:3, 3], chord, up, chord, lean))
    )
    bases = {a: world.cell.robots[a].base.matrix()[:3, 3] for a in (c_arm, f_arm)}
    hands = {c_arm: faced_c[-1], f_arm: faced_f[-1]}
    met, chord = _meet(hands, c_arm, chord, up, lean, meet, bases)
    T_c_last = met[c_arm][-1] if c_arm in met else faced_c[-1]
    T_f_last = met[f_arm][-1] if f_arm in met else faced_f[-1]
    # Down on a circle about the connector hand, turning with it (the hand leans away from
    # the connector hand, its x staying along the chord), so the cable slides back against
    # gravity when the hand then moves up the chord (paper, section III-B).
    centre = T_c_last[:3, 3]
    axis = g.cross(chord, up)
    down = cg.slide_down_angle(float(np.linalg.norm(T_f_last[:3, 3] - centre)))
    lower = cg.arc(T_f_last, centre, axis, -down, turn=True)
    spacing = _connector_spacing(world, state.place_guide, conn_len, hand_f) + farther
    towards = g.unit(lower[-1][:3, 3] - centre)
    slide = cg.line(lower[-1], cg.at(lower[-1], centre + spacing * towards))
    raise_ = cg.arc(slide[-1], centre, axis, down, turn=True)
    align = _align_z(world, state.place_guide, T_c_last, raise_[-1], up, lean)
    return _PickGeometry(
        up=up,
        grasp={c_arm: T_c, f_arm: T_f},
        retracted={c_arm: T_c_up, f_arm: T_f_up},
        faced={c_arm: faced_c, f_arm: faced_f},
        meet=met,
        lower=lower,
        slide=slide,
        raise_=raise_,
        align=align,
        # The holder is assumed to present the free end just long enough beyond the grasp for
        # the fingers (end_margin): where along the cable the far hand starts is a guess;
        # where it ends after the slide is not.
        s={c_arm: -conn_len / 2.0, f_arm: cable.length - hand_f.end_margin},
        s_slid=spacing - conn_len / 2.0,
        spacing=spacing,
        connector_arm=c_arm,
        far_arm=f_arm,
        aside=away,
    )


def _asides(world: World, state: CableState, conn_ref: str, free_ref: str) -> tuple[float, ...]:
    """How far from the connector (m) the far hand may take the free end first, when the
    cable must turn round between the combs and the coming connector guide (it runs from
    the connector towards the free end's comb more against the guide's cable than along
    it): as far as the combs are apart, then half as far again (_PickGeometry.aside); none
    otherwise, or with no connector guide to come."""
    if state.place_guide is None:
        return ()
    up = cg.platform_up(world, conn_ref)
    span = cg.horizontal(world.pose(free_ref)[:3, 3] - world.pose(conn_ref)[:3, 3], up)
    along = cg.horizontal(cg.keypoint_x(world, state.place_guide), up)
    if float(span @ along) >= 0.0:
        return ()
    apart = float(np.linalg.norm(world.pose(free_ref)[:3, 3] - world.pose(conn_ref)[:3, 3]))
    return (apart, 1.5 * apart)


def _meet(
    hands: Mapping[str, Mat],
    c_arm: str,
    chord: Vec,
    up: Vec,
    lean: float,
    meet: tuple[float, float],
    bases: Mapping[str, Vec],
) -> tuple[dict[str, Poses], Vec]:
    """The paths of the hands that move to where they meet, by arm, and the chord after:
    the connector hand (``c_arm``'s) carries its end ``meet[0]`` of the level span towards
    the far hand, and the far hand comes round to the rest of the span from it, the chord
    turned by ``meet[1]`` (rad) about ``up``; or, ``meet[1]`` cg.ACROSS, the hands as far
    apart, centred on the bisector of the arms' ``bases`` (cg.PICK_MEETS). The hands never
    end farther apart than they start: the cable only slackens."""
    fraction, swing = meet
    if fraction == 0.0 and swing == 0.0:
        return {}, chord
    (f_arm,) = set(hands) - {c_arm}
    T_c, T_f = hands[c_arm], hands[f_arm]
    span = float((T_f[:3, 3] - T_c[:3, 3]) @ chord)
    centre = T_c[:3, 3] + fraction * span * chord
    if swing == cg.ACROSS:
        turned = cg.horizontal(bases[f_arm] - bases[c_arm], up)
        mid = (T_c[:3, 3] + T_f[:3, 3]) / 2.0
        mid -= float((mid - (bases[c_arm] + bases[f_arm]) / 2.0) @ turned) * turned
        centre = mid - (1.0 - fraction) * span / 2.0 * turned
    else:
        turned = g.axis_angle_to_matrix(up, swing) @ chord
    T_c1 = cg.tcp_frame(centre, turned, up, -turned, lean)
    T_f1 = cg.tcp_frame(centre + (1.0 - fraction) * span * turned, turned, up, turned, lean)
    paths = {c_arm: cg.line(T_c, T_c1)}  # turning its connector with it
    if swing != 0.0:  # the far hand holds only the cable: either way along it
        paths[f_arm] = cg.line(T_f, cg.nearer_turn(T_f, T_f1))
    return paths, turned


def _connector_spacing(world: World, guide: str | None, conn_len: float, hand: cg.Hand) -> float:
    """Connector centre to the other hand's fingertips when placing: the connector guide's
    exit face (or the connector's rear face, if it sticks out), then X_offset."""
    guide_len = world.dimensions(guide).get("length", 0.0) if guide is not None else 0.0
    return max(guide_len, conn_len) / 2.0 + hand.x_offset


def _align_z(
    world: World, guide: str | None, T_c: Mat, T_f: Mat, up: Vec, lean: float
) -> tuple[Poses, Poses] | None:
    """Both hands turned as one pair about the connector hand until its z is the routing
    platform's down (tipped back by LEAN, as everywhere); None when it already is (a level
    platform: the circles above turned the far hand back)."""
    platform_up = cg.platform_up(world, guide) if guide is not None else up
    cable = cg.horizontal(T_c[:3, 0], platform_up)
    T_c1 = cg.tcp_frame(T_c[:3, 3], cable, platform_up, -cable, lean)
    if g.rotation_angle(T_c, T_c1) < cg.TINY_ANGLE:
        return None
    return cg.pair_line(T_c, T_c1, g.inverse(T_c) @ T_f)


def _pick_pairs(geo: _PickGeometry) -> list[tuple[Mat, Mat]]:
    """(connector hand, far hand) poses along the pick, from over the combs to aligned
    (_along each path)."""
    c, f = geo.connector_arm, geo.far_arm
    above = [cg.lifted(geo.grasp[a], geo.up, cg.APPROACH_HEIGHT) for a in (c, f)]
    if geo.aside is not None:  # the connector hand picks with the far one aside
        T_f = geo.aside[-1]
        out = _along(np.array([above[0], geo.grasp[c], geo.retracted[c]]), T_f[None])
        out += _along(geo.faced[c], T_f[None])
    else:
        out = [(above[0], above[1]), (geo.grasp[c], geo.grasp[f])]
        out += _along(geo.faced[c], geo.faced[f])
    if geo.meet:
        out += _along(geo.meet.get(c, geo.faced[c][-1:]), geo.meet.get(f, geo.faced[f][-1:]))
    T_c = geo.meet[c][-1] if c in geo.meet else geo.faced[c][-1]  # the far hand goes about it
    for path in (geo.lower, geo.slide, geo.raise_):
        out += _along(T_c[None], path)
    if geo.align is not None:
        out += _along(*geo.align, together=True)  # a closed chain
    return out


def _along(a: Poses, b: Poses, stride: int = 4, together: bool = False) -> list[tuple[Mat, Mat]]:
    """Pose pairs evenly along two paths, from start to end, at most ``stride`` poses apart
    on the longer (the skills' poses are at most 5 mm or 2 deg apart: a hand passing another
    arm is seen): the hands moving at once, and, when both move, each with the other at its
    path's start or end (a strategy may move one after the other), unless ``together`` (a
    closed chain)."""
    n = max(1, math.ceil((max(len(a), len(b)) - 1) / stride))
    a_s = [a[round((len(a) - 1) * j / n)] for j in range(n + 1)]
    b_s = [b[round((len(b) - 1) * j / n)] for j in range(n + 1)]
    out = list(zip(a_s, b_s, strict=True))
    if len(a) > 1 and len(b) > 1 and not together:  # or one after the other, either first
        out += [(T, b[k]) for T in a_s for k in (0, -1)] + [(a[k], T) for T in b_s for k in (0, -1)]
    return out


def _pick_on(
    ctx: PlanningContext, geo: _PickGeometry, segments: list[Segment], where: str
) -> list[Segment]:
    """The pick's segments from the pick configuration on, requiring of each arm
    (Segment.branches) the IK branches that follow its Cartesian paths within reach and
    clear of itself and, paired with one of the other arm's, keep the cell's clearance
    between the arms at every pose of _pick_pairs (a continuous motion keeps its branches).
    An error when no pair does: the hands meet where these combs and grasps put them."""
    from cellengine.execute.following import surviving  # the motion stack: planning only

    c, f = geo.connector_arm, geo.far_arm
    follow = {}
    for arm in (c, f):
        poses = [p.poses for s in segments for p in s.paths if p.arm == arm]
        follow[arm], _ = surviving(ctx.cell, ctx.checker, arm, np.concatenate(poses), ctx.home)
        follow[arm] = _clear_of_cell(ctx, arm, segments, follow[arm], where)
    least = _pair_least(
        ctx,
        c,
        f,
        _pick_pairs(geo),
        ctx.clearance,
        frozenset(follow[c]),
        frozenset(follow[f]),
        measure=False,
    )
    if least is None:
        return segments  # solved numerically: no branches, the compiler finds out
    alive = least >= ctx.clearance
    if not alive.any():
        best = float(least.max())
        how = f"{_mm(best)} mm at best" if best > -math.inf else "they collide"
        raise _error(
            f"{where}: no pair of the arms' inverse kinematics branches that follow this pick "
            f"keeps the cell's clearance ({_mm(ctx.clearance)} mm) between them all along it "
            f"({how}): the hands meet where these combs and grasps put them"
        )
    on = dict(_kept_branches(alive, c, f))
    # each arm's from the segment after its transit to the pick (where it was before, the
    # skill did not look at: the connector arm stands while the far hand goes first)
    out, started = [], set[str]()
    for seg in segments:
        out.append(replace(seg, branches=tuple((a, on[a]) for a in (c, f) if a in started)))
        started |= {p.arm for p in seg.paths if p.kind == "transit"}
    return out


def _clear_of_cell(
    ctx: PlanningContext,
    arm: str,
    segments: Sequence[Segment],
    on: set[int],
    where: str,
    what: str = "pick",
) -> set[int]:
    """Those of ``arm``'s IK branches ``on`` that keep the cell's clearance from the cell
    along its Cartesian paths away from what it works near (the combs it grasps in, the
    guide it inserts into: declared ``near``): a forearm swung over a fixture is refused
    here, with the way, not by the compiler after the transit to it. An error when none
    does, naming the step's ``what`` ("pick", "placing")."""
    from cellengine.execute.following import touching  # the motion stack: planning only

    paths = [
        p.poses
        for s in segments
        if not s.near
        for p in s.paths
        if p.arm == arm and p.kind == "cartesian"
    ]
    if not paths or not on:
        return on
    hit = touching(ctx.cell, ctx.checker, arm, np.concatenate(paths), ctx.home, on, ctx.clearance)
    if len(hit) < len(on):
        return on - set(hit)
    a, b = next(iter(hit.values()))
    raise _error(
        f"{where}: on every inverse kinematics branch that follows this {what} the {arm} arm "
        f"comes within the cell's clearance ({_mm(ctx.clearance)} mm) of the cell ({a}, {b})"
    )


def _emit_grasp(b: _Builder, step: PickCable, geo: _PickGeometry, arms: tuple[str, ...]) -> None:
    """``arms`` go over their combs, grasp and retract together; a far hand on its own then
    takes the free end aside (_PickGeometry.aside)."""
    name, label = step.cable, f"PickCable {step.cable}"
    refs = dict(zip((geo.connector_arm, geo.far_arm), step.from_, strict=True))
    above = {a: cg.lifted(geo.grasp[a], geo.up, cg.APPROACH_HEIGHT) for a in arms}
    alone = "" if len(arms) == 2 else f" ({geo.end(arms[0])})"
    b.add(
        f"{label}: pick configuration{alone}",
        [_transit(a, above[a]) for a in arms],
        before=[GripperEvent(a, OPEN) for a in arms],
    )
    # each hand's fingers go down beside the comb they grasp in
    combs = tuple((a, cg.element_of(refs[a])) for a in arms)
    b.add(
        f"{label}: approach and grasp{alone}",
        [_cartesian(a, cg.line(above[a], geo.grasp[a])) for a in arms],
        after=[GripperEvent(a, GRASP, name) for a in arms],
        near=combs,
        facts={
            "cable": name,
            "grasps": {a: {"from": refs[a], "end": geo.end(a), "s": geo.s[a]} for a in arms},
        },
    )
    for a in arms:
        b.state = b.state.hold(a, name, geo.s[a])
    # Both hands lift the cable out of the combs together: one object, moved rigidly.
    b.add(
        f"{label}: retract{alone}",
        [_cartesian(a, cg.line(geo.grasp[a], geo.retracted[a])) for a in arms],
        closed_chain=arms if len(arms) == 2 else None,
        near=combs,
    )
    if arms == (geo.far_arm,) and geo.aside is not None:
        b.add(f"{label}: take the free end aside", [_cartesian(geo.far_arm, geo.aside)])


def _emit_pick(
    step: PickCable, state: CableState, geo: _PickGeometry, c_arm: str, f_arm: str
) -> tuple[list[Segment], CableState]:
    name = step.cable
    label = f"PickCable {name}"
    b = _Builder(replace(state, cable=name, connector_arm=c_arm).transited(c_arm, f_arm))
    both = (c_arm, f_arm)
    # the far hand first, alone, when it takes the free end aside; else both hands at once
    for arms in ((f_arm,), (c_arm,)) if geo.aside is not None else (both,):
        _emit_grasp(b, step, geo, arms)
    turned = both if geo.aside is None else (c_arm,)  # the far hand turned going aside
    b.add(f"{label}: turn along the cable", [_cartesian(a, geo.faced[a]) for a in turned])
    if geo.meet:
        b.add(f"{label}: meet", [_cartesian(a, poses) for a, poses in geo.meet.items()])
    b.add(f"{label}: down", [_cartesian(f_arm, geo.lower)], keep_distance=(c_arm, f_arm))
    b.add(
        f"{label}: slide to the connector",
        [_cartesian(f_arm, geo.slide)],
        before=[GripperEvent(f_arm, SLIDE, name)],
        facts={"spacing": geo.spacing},
    )
    b.state = b.state.hold(f_arm, name, geo.s_slid)
    b.add(
        f"{label}: up",
        [_cartesian(f_arm, geo.raise_)],
        before=[GripperEvent(f_arm, GRASP, name)],
        keep_distance=(c_arm, f_arm),
    )
    if geo.align is not None:
        b.add(
            f"{label}: align with the routing platform",
            [_cartesian(c_arm, geo.align[0]), _cartesian(f_arm, geo.align[1])],
            closed_chain=(c_arm, f_arm),
            keep_distance=(c_arm, f_arm),
        )
    return b.segments, b.state


# =========================================================================== PlaceConnector


@dataclass(frozen=True)
class _PlaceGeometry:
    guide: str
    connector_arm: str
    up: Vec
    slot: Vec
    axis: Vec  # from the connector to its cable
    gap: float
    adjust: Poses | None  # the other hand slides to where the placing needs it
    T_c_f: Mat  # the other hand in the connector hand's TCP frame, while both carry
    carry: tuple[tuple[str, tuple[Poses, Poses]], ...]  # to over the slot, turned to the guide
    insert: tuple[Poses, Poses]
    retract: Poses
    rear: Vec  # the connector's rear face, seated
    pull_distance: float
    s_other: float

    def reach(self, arm: str) -> list[tuple[str, Mat]]:
        i = 0 if arm == self.connector_arm else 1
        out = [(what, paths[i][-1]) for what, paths in self.carry]
        out += [("connector insert", self.insert[i][-1])]
        if i == 0:
            out += [("connector retract", self.retract[-1])]
        return out


def _place_geometry(
    world: World,
    state: CableState,
    step: PlaceConnector,
    c_arm: str,
    f_arm: str,
    where: str,
    order: str = "align first",
    along_tool: bool = False,
    hold: tuple[float, float] = (0.0, 0.0),
) -> _PlaceGeometry:
    """The poses of placing the connector: the pair carried to over the slot in ``order``
    (PLACE_ORDERS), then inserted; the connector hand retracting straight up, or back along
    its tool axis (``along_tool``). ``hold``: how the other hand holds the cable meanwhile,
    (roll about the cable, m farther along it) than as published (cg.PLACE_HOLDS)."""
    cable = world.cable(step.cable)
    conn_len = cable.connector.length if cable.connector is not None else 0.0
    up = cg.platform_up(world, step.guide)
    slot = cg.position(world, step.guide)
    # The connector guide's keypoint x points from the connector to its cable (models.xml).
    axis = cg.horizontal(cg.keypoint_x(world, step.guide), up)
    dims = world.dimensions(step.guide)
    if "length" not in dims:
        raise _error(f"{where}: guide '{step.guide}' has no length dimension (along the cable)")
    hand_f = _hand(world, f_arm)
    roll, farther = hold
    spacing = _connector_spacing(world, step.guide, conn_len, hand_f) + farther
    T_c0, T_f0 = state.tcp[c_arm], state.tcp[f_arm]
    # Carrying, the other hand holds the cable `spacing` ahead of the connector's centre,
    # both hands leaning apart: that relative pose does not depend on where the pair is.
    T_c_f = _pair_pose(spacing, up, state.lean, roll)
    T_f_want = T_c0 @ T_c_f
    adjust = None
    if not _same_pose(T_f0, T_f_want):
        adjust = cg.line(T_f0, T_f_want)
    T_c_ins = cg.tcp_frame(slot, axis, up, -axis, state.lean)
    T_c_app = cg.lifted(T_c_ins, up, cg.APPROACH_HEIGHT)
    carry = _carry(
        T_c0, T_c_app, T_c_f, cg.tcp_frame(T_c0[:3, 3], axis, up, -axis, state.lean), order
    )
    insert = cg.pair_line(T_c_app, T_c_ins, T_c_f)
    back = -T_c_ins[:3, 2] if along_tool else up
    retract = cg.line(T_c_ins, cg.at(T_c_ins, T_c_ins[:3, 3] + cg.RETRACT_HEIGHT * back))
    # pull_distance: the cable from the seated connector's rear face to the routing
    # fingertips: the guide beyond the connector (its exit wall, and the connector's play in
    # the pocket) plus X_offset (the fingers' half-length and the gap A).
    pull = spacing - conn_len / 2.0
    return _PlaceGeometry(
        guide=step.guide,
        connector_arm=c_arm,
        up=up,
        slot=slot,
        axis=axis,
        gap=dims.get("gap", 0.0),
        adjust=adjust,
        T_c_f=T_c_f,
        carry=carry,
        insert=insert,
        retract=retract,
        rear=slot + conn_len / 2.0 * axis,
        pull_distance=pull,
        s_other=pull,
    )


def _carry(
    T_c0: Mat, T_c_app: Mat, T_c_f: Mat, T_c_aligned: Mat, order: str
) -> tuple[tuple[str, tuple[Poses, Poses]], ...]:
    """The pair's paths from the connector hand at ``T_c0`` to over the slot (``T_c_app``),
    turned to the guide: where it is first (``T_c_aligned``: there, turned), while carried,
    or over the slot."""
    if order == "align first":
        return (
            ("align with the guide", cg.pair_line(T_c0, T_c_aligned, T_c_f)),
            ("approach", cg.pair_line(T_c_aligned, T_c_app, T_c_f)),
        )
    if order == "together":
        return (("approach", cg.pair_line(T_c0, T_c_app, T_c_f)),)
    over = cg.at(T_c0, T_c_app[:3, 3])
    return (
        ("approach", cg.pair_line(T_c0, over, T_c_f)),
        ("align with the guide", cg.pair_line(over, T_c_app, T_c_f)),
    )


def _pair_pose(spacing: float, up: Vec, lean: float, roll: float = 0.0) -> Mat:
    """T_connector-hand_other-hand when both hold the cable ``spacing`` apart, leaning apart,
    the other hand turned by ``roll`` about the cable."""
    x = cg.horizontal(_any_normal(up), up)
    origin = np.zeros(3)
    T_c = cg.tcp_frame(origin, x, up, -x, lean)
    T_f = cg.tcp_frame(origin + spacing * x, x, up, x, lean)
    T_f[:3, :3] = g.axis_angle_to_matrix(x, roll) @ T_f[:3, :3]
    return g.inverse(T_c) @ T_f


def _any_normal(up: Vec) -> Vec:
    v = np.array([1.0, 0.0, 0.0]) if abs(up[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    out: Vec = v - up * float(v @ up)
    return out


def _same_pose(A: Mat, B: Mat, tol_m: float = 1e-3, tol_rad: float = math.radians(1.0)) -> bool:
    dp = float(np.linalg.norm(A[:3, 3] - B[:3, 3]))
    return (
        dp <= tol_m
        and g.angle_between(A[:3, 0], B[:3, 0]) <= tol_rad
        and (g.angle_between(A[:3, 2], B[:3, 2]) <= tol_rad)
    )


def _emit_place(
    step: PlaceConnector, state: CableState, geo: _PlaceGeometry, c_arm: str, f_arm: str
) -> tuple[list[Segment], CableState]:
    name = step.cable
    label = f"PlaceConnector {step.guide}"
    b = _Builder(replace(state, connector_arm=c_arm))
    pair = (c_arm, f_arm)
    if geo.adjust is not None:
        b.add(
            f"{label}: slide to the placing grasp",
            [_cartesian(f_arm, geo.adjust)],
            before=b.mode_event(f_arm, SLIDE, name),
            after=[GripperEvent(f_arm, GRASP, name)],
        )
    # The cable between the connector and the other hand is short and straight: both hands
    # carry it as one rigid piece, and its length between them stays what it is.
    for what, paths in geo.carry:
        if all(_same_pose(path[0], path[-1], 1e-9, cg.TINY_ANGLE) for path in paths):
            continue  # aligned already (the pick left the pair along the guide)
        b.add(
            f"{label}: {what}",
            [_cartesian(c_arm, paths[0]), _cartesian(f_arm, paths[1])],
            before=b.mode_event(f_arm, GRASP, name),
            closed_chain=pair,
            keep_distance=pair,
        )
    b.add(
        f"{label}: insert",
        [_cartesian(c_arm, geo.insert[0]), _cartesian(f_arm, geo.insert[1])],
        after=[GripperEvent(c_arm, OPEN)],
        closed_chain=pair,
        keep_distance=pair,
        near=[(c_arm, cg.element_of(step.guide))],  # the fingers either side of the guide
        annotations=[Anchor(name, _point(geo.slot), step.guide)],
        facts={
            "guide": step.guide,
            "slot": _vec(geo.slot),
            "axis": _vec(geo.axis),
            "gap": geo.gap,
            "connector_arm": c_arm,
            "tcp": _vec(geo.insert[0][-1][:3, 3]),
        },
    )
    b.add(
        f"{label}: retract",
        [_cartesian(c_arm, geo.retract)],
        near=[(c_arm, cg.element_of(step.guide))],
        facts={"pull_distance": geo.pull_distance},
    )
    s = b.state.hold(f_arm, name, geo.s_other)
    return b.segments, replace(
        s,
        routing_arm=f_arm,
        place_guide=None,
        guides=(step.guide,),
        route=(_point(geo.rear),),
        pull_distance=geo.pull_distance,
    )


def _place_apart(
    ctx: PlanningContext,
    state: CableState,
    segments: Sequence[Segment],
    arms: tuple[str, str],
    where: str,
) -> list[Segment]:
    """The placing's segments requiring of each arm (Segment.branches) the IK branches it may
    be on that follow the placing's Cartesian paths clear of the cell (_clear_of_cell) and,
    paired with one of the other arm's, keep the cell's clearance between them at poses
    along it (_along; the pair carried as one rigid piece moves together; an arm moving
    alone, as the connector hand retracting, with the other where it stands); an error
    (blaming the arms: PickCable decides which holds the connector) when no pair does: the
    hands' places cross the arms. Numerical IK, or an arm that follows on no branch (the
    family says so): not screened."""
    from cellengine.execute.following import surviving  # the motion stack: planning only

    follow: dict[str, frozenset[int]] = {}
    for arm in arms:
        poses = [p.poses for s in segments for p in s.paths if p.arm == arm]
        alive, _ = surviving(
            ctx.cell, ctx.checker, arm, np.concatenate(poses), ctx.home, state.branches_of(arm)
        )
        if not alive:
            return list(segments)
        try:  # kept clear of the cell too (the carry swings the arms over the combs)
            alive = _clear_of_cell(ctx, arm, segments, alive, where, "placing")
        except InputError as e:
            e.blames = "arms"  # the other arm might place it
            raise
        follow[arm] = frozenset(alive)
    a, b = arms
    pairs: list[tuple[Mat, Mat]] = []
    at = {arm: state.tcp[arm][None] for arm in arms}  # where each arm stands
    for s in segments:
        paths = {p.arm: p.poses for p in s.paths}
        if a in paths or b in paths:  # one arm moving (the retract) with the other standing
            moving = {arm: paths.get(arm, at[arm]) for arm in arms}
            pairs += _along(moving[a], moving[b], together=s.closed_chain is not None)
        at |= {arm: poses[-1:] for arm, poses in paths.items()}
    least = _pair_least(ctx, a, b, pairs, ctx.clearance, follow[a], follow[b], measure=False)
    if least is None:
        return list(segments)
    kept = least >= ctx.clearance
    if kept.any():
        on, paired = _kept_branches(kept, a, b), _kept_pairs(kept, a, b)
        return [replace(s, branches=on, paired=paired) for s in segments]
    best = float(least.max())
    how = f"{_mm(best)} mm at best" if best > -math.inf else "they collide"
    error = _error(
        f"{where}: no pair of the arms' inverse kinematics branches that follow this placing "
        f"keeps the cell's clearance ({_mm(ctx.clearance)} mm) between them all along it "
        f"({how}): with {a} holding the connector, the arms cross to place it"
    )
    error.blames = "arms"
    raise error


def _crossed(ctx: PlanningContext, c_arm: str, f_arm: str, place: str, route_end: str) -> bool:
    """Whether the arms reach less far, in all, with the connector arm routing to
    ``route_end`` and the other one staying by the connector guide ``place`` (the cable
    handed over) than in the published roles."""
    kept = _base_distance(ctx, c_arm, place) + _base_distance(ctx, f_arm, route_end)
    swapped = _base_distance(ctx, f_arm, place) + _base_distance(ctx, c_arm, route_end)
    return swapped < kept


def _hand_over(
    ctx: PlanningContext,
    state: CableState,
    geo: _PlaceGeometry,
    c_arm: str,
    f_arm: str,
    cable: str,
    where: str,
) -> tuple[list[Segment], CableState]:
    """The connector placed, the other hand lets go of the cable and moves up and out of the
    way (to the side of the cable its base is on, the other side, or ahead along it: the
    first where some pair of the arms' IK solutions keeps the cell's clearance); the
    connector hand, open, comes down and grasps the cable where that hand held it (the cable
    from the seated connector to there is short and straight), to route it. The other arm
    becomes the pivot arm. An error when the connector arm cannot reach there or no way out
    of the way leaves the arms free of each other."""
    from cellengine.execute.following import surviving  # the motion stack: planning only

    label = f"PlaceConnector {geo.guide}: hand the cable over"
    up, T_f = geo.up, state.tcp[f_arm]
    T_take = cg.nearer_turn(
        state.tcp[c_arm],
        cg.tcp_frame(T_f[:3, 3], geo.axis, up, geo.axis, state.lean),
        state.wound.get(c_arm, 0.0),
    )
    T_above = cg.lifted(T_take, up, cg.APPROACH_HEIGHT)
    _check_reach(ctx, c_arm, [("taking the cable over", T_take), ("above it", T_above)], where)
    T_up = cg.lifted(T_f, up, cg.RETRACT_HEIGHT)
    side = g.cross(up, geo.axis)
    if float(side @ _towards_base(ctx.world, f_arm, T_f[:3, 3], up)) < 0.0:
        side = -side
    why: str | None = None
    for away in (side, -side, geo.axis):
        T_away = cg.at(T_up, T_up[:3, 3] + HAND_OVER_AWAY * away)
        lets_go = np.concatenate([cg.line(T_f, T_up), cg.line(T_up, T_away)[1:]])
        # the branches the other arm can be on out of the way: it moves there in a line
        alive, _ = surviving(
            ctx.cell, ctx.checker, f_arm, lets_go, ctx.home, state.branches_of(f_arm)
        )
        if not alive:
            why = f"{f_arm} cannot move out of the way on a branch it may be on"
            continue
        on = {f_arm: frozenset(alive)}
        whys = (
            _pair_blocked(ctx, {c_arm: T, f_arm: T_away}, ctx.clearance, on)
            for T in (T_above, T_take)
        )
        why = next((w for w in whys if w is not None), None)
        if why is None:
            break
    if why is not None:
        raise _error(
            f"{where}: handing the cable over, no pair of the arms' inverse kinematics "
            f"solutions keeps the cell's clearance ({_mm(ctx.clearance)} mm) with the "
            "connector hand taking the cable and the other hand out of its way"
            + (f" ({why})" if why else "")
        )
    # the pairs that keep the clearance: the other arm lets go on one of its branches in
    # them, and the connector arm's transit goes to one of its own
    f_on, c_on, paired = _handing_branches(ctx, (c_arm, T_above, T_take), (f_arm, T_away), alive)
    element = cg.element_of(geo.guide)
    b = _Builder(state)
    b.add(
        f"{label}: {f_arm} lets go",
        [_cartesian(f_arm, lets_go)],
        before=[GripperEvent(f_arm, OPEN)],
        branches=f_on,
    )
    b.add(f"{label}: {c_arm} to the cable", [_transit(c_arm, T_above)])
    b.add(
        f"{label}: {c_arm} takes the cable",
        [_cartesian(c_arm, cg.line(T_above, T_take))],
        after=[GripperEvent(c_arm, GRASP, cable)],
        near=[(c_arm, element)],
        branches=c_on,
        paired=paired,
    )
    after = b.state.hold(c_arm, cable, geo.s_other).transited(c_arm)
    return b.segments, replace(after, routing_arm=c_arm)


def _handing_branches(
    ctx: PlanningContext,
    taking: tuple[str, Mat, Mat],
    away: tuple[str, Mat],
    alive: Collection[int],
) -> tuple[Release, Release, Paired]:
    """Segment.branches of the other arm out of the way (of ``alive``) and of the connector
    arm above the cable and taking it (``taking``: the arm and both poses), in some pair
    that keeps the cell's clearance at both, and those pairs; none when no pair does (the
    compiler finds out)."""
    c_arm, T_above, T_take = taking
    f_arm, T_away = away
    poses = [(T_above, T_away), (T_take, T_away)]
    least = _pair_least(
        ctx, c_arm, f_arm, poses, ctx.clearance, ANY_BRANCH, frozenset(alive), measure=False
    )
    kept = None if least is None else least >= ctx.clearance
    if kept is None or not kept.any():
        return (), (), ()
    c_on, f_on = _kept_branches(kept, c_arm, f_arm)
    return (f_on,), (c_on,), _kept_pairs(kept, c_arm, f_arm)


# =========================================================================== RouteCable


@dataclass(frozen=True)
class GuidePlan:
    """One guide of RouteCable: the published quantities and every pose (cell frame)."""

    guide: str
    where: str
    dims: cg.GuideDims
    up: Vec
    slot: Vec  # S: the slot keypoint
    axis: Vec  # u: the cable's direction through the guide, along the route
    side: float  # +1: slide to the left of u (up x u), -1: to the right
    x_offset: float
    a: float
    r_lift: float
    r_insert: float
    r_cable: float
    theta_min: float
    theta: float
    slide_turn: float  # the share of theta the hand turns as it slides
    pull: float  # pulled to tension after the other hand grasps
    elevation: float  # of the lift, seen from the pivot
    reorient: Poses | None
    approach: Poses  # to Ap: X_offset before the near face, facing the guide
    approached: str  # how (APPROACHES)
    slide: Poses  # R_cable from Ap at theta
    other_above: Mat
    pivot: Mat  # the other hand's grasp: Ap, where the routing hand stopped
    pull_path: Poses
    lift: Poses
    swing: Poses
    insert: Poses
    laid: float  # route length from the connector's rear face to Ap
    stand_back: float  # the other hand, released at the previous guide, backs off this far
    stand_lift: float  # after rising this high
    stand_turn: float  # turned from back along the route by this (Back)
    # the elements the hands work between (this guide, and the one the cable leaves before
    # the pivot) and, once screened, the next guide (the insert ends before it) and what
    # lies under the cable (_under): the cell's work_clearance from them, its clearance from
    # everything else
    beside: tuple[str, ...]
    # the routing arm's IK branches that can do it (of those it may be on), once screened
    branches: frozenset[int] = ANY_BRANCH
    # each arm's IK branches on which the other hand's release (the first segment) keeps the
    # arms the cell's clearance apart, the routing arm standing (_letting_go), once screened
    release: tuple[tuple[str, frozenset[int]], ...] = ()
    # the other arm's IK branches in a pair with one of ``branches`` that keeps the cell's
    # clearance from its descent to the pivot to the insert (_check_pair_along), once
    # screened: its transit to the cable goes to one of them
    grasp: frozenset[int] = ANY_BRANCH
    grasp_pairs: Paired = ()  # (routing arm, other arm) pairs of those, as Segment.paired
    # the (routing arm, other arm) pairs of branches that keep the cell's clearance while the
    # other hand stands back and the routing hand comes and slides (_coming), once screened
    # for this way's stand-back: the compiler holds the arms to them there
    coming_pairs: Paired = ()

    @property
    def radius(self) -> float:
        """Distance between the hands during lift and insert: R_cable + the pull."""
        return self.r_cable + self.pull

    def reach_routing(self) -> list[tuple[str, Mat]]:
        return [
            ("approach", self.approach[-1]),
            ("slide end", self.slide[-1]),
            ("pull", self.pull_path[-1]),
            ("lift", self.lift[-1]),
            ("above the slot", self.swing[-1]),
            ("insert", self.insert[-1]),
        ]

    def reach_other(self) -> list[tuple[str, Mat]]:
        return [("pivot approach", self.other_above), ("pivot grasp", self.pivot)]

    def after(self, state: CableState, r_arm: str, o_arm: str, cable: str) -> CableState:
        """The state once this guide holds the cable: both hands grasping, the routing hand
        R past the guide, the other at the pivot."""
        ap = self.pivot[:3, 3]
        route = (*state.route, _point(ap), _point(self.slot))
        s = replace(
            state,
            tcp={**state.tcp, r_arm: self.insert[-1], o_arm: self.pivot},
            mode={**state.mode, r_arm: GRASP, o_arm: GRASP},
            guides=(*state.guides, self.guide),
            route=route,
            pull_distance=self.radius - (self.dims.length / 2.0 + self.x_offset),
            # the other arm came to the pivot on a transit: on any branch
            branches={
                **{a: b for a, b in state.branches.items() if a != o_arm},
                r_arm: self.branches,
            },
        )
        s = s.hold(o_arm, cable, self.laid)
        return s.hold(r_arm, cable, self.laid + self.radius)


def _point(v: Vec) -> tuple[float, float, float]:
    return (float(v[0]), float(v[1]), float(v[2]))


@dataclass(frozen=True)
class GuideWay:
    """The free parameters of routing one guide: the sliding angle and side, and how far
    each hand tips its flange (see cg.LEAN, cg.PIVOT_LEAN)."""

    theta: float
    side: float  # +1: slide to the left of the axis (up x axis), -1: to the right
    lean: float = cg.LEAN
    pivot_lean: float = cg.PIVOT_LEAN
    stand_back: float = cg.STAND_BACK  # the other hand, released, backs off this far first
    gap: float = cg.APPROACH_GAP  # A: the routing hand stops this far before the guide
    # the routing hand's front ends this far past the guide's far face (None: A, as published)
    gap_after: float | None = None
    turn_first: bool = False  # the routing hand turns to the sliding angle, then slides
    # the hands tip along the cable and towards their bases (1), not (0) or away from them
    # (-1: near its base, an arm reaches a hand tipped towards it only with its wrist folded
    # back over the base)
    towards_base: float = 1.0
    slide_turn: float = 1.0  # the share of theta the routing hand turns as it slides
    approach: str = "direct"  # how the routing hand comes to the approach pose: APPROACHES
    stand_lift: float = cg.RETRACT_HEIGHT  # the other hand rises this high, then backs off
    stand_turn: float = 0.0  # back along the route turned by this (Back)


# How the routing hand comes to Ap, the first that keeps clear: straight from where it is;
# last along the guide's axis from X_offset before Ap; down onto Ap from over the guide's
# top. (Coming in at an angle, the hand turned to the guide sweeps its fingers over the
# guide's near corner.)
APPROACHES = ("direct", "along the axis", "from above", "over everything on the way")
# The last rises over the tallest element beside its path, not only over the guide (a comb
# by the guide before can stand taller), and turns to face the guide up there: the others
# turn in place where the hand inserted.
OVER_ALL = APPROACHES[-1]


@dataclass(frozen=True)
class _Basics:
    """What every way of routing a guide shares: the published quantities."""

    where: str
    dims: cg.GuideDims
    hand: cg.Hand
    gap: float  # A
    x_offset: float  # A and the hand's half length along the cable
    up: Vec
    slot: Vec
    axis: Vec
    ap: Vec  # the approach point, X_offset before the near face: the pivot
    rise: float  # H: the guide's top over the slot
    r_lift: float
    r_insert: float
    r_cable: float
    pull: float
    theta_min: float

    @property
    def reach(self) -> float:
        """How far the routing hand slides out from the pivot: R_cable and the pull."""
        return self.r_cable + self.pull


def _basics(
    world: World,
    state: CableState,
    guide: str,
    r_arm: str,
    gap: float = cg.APPROACH_GAP,
    gap_after: float | None = None,
) -> _Basics:
    where = f"steps[{state.step}] RouteCable {guide}"
    dims = cg.GuideDims.of(world, guide, where)
    hand = _hand(world, r_arm)
    up = cg.platform_up(world, guide)
    slot = cg.position(world, guide)
    last = np.asarray(state.route[-1], dtype=float)
    # The guide's cable axis is its keypoint x; the cable goes through it away from the
    # last point of the route.
    axis = cg.horizontal(cg.keypoint_x(world, guide), up)
    if float(axis @ (slot - last)) < 0.0:
        axis = -axis
    x_off = gap + hand.half_length
    rise = cg.rise(world, guide, up)
    rise = dims.height if rise is None else rise
    rl = cg.r_lift(dims.length, rise, x_off, cg.Z_OFFSET)
    # R_insert = L + 2 X_offset, as published, when the hand ends as far past the guide as it
    # stopped before it; else from X_offset before to its own offset past
    after = x_off if gap_after is None else gap_after + hand.half_length
    ri = cg.r_insert(dims.length, x_off) + (after - x_off)
    r_cable = max(rl, ri)
    ap = slot - (dims.length / 2.0 + x_off) * axis
    t_min = cg.theta_min(hand.width, dims.width, gap)
    pull = cg.tension_pull(r_cable)
    return _Basics(
        where, dims, hand, gap, x_off, up, slot, axis, ap, rise, rl, ri, r_cable, pull, t_min
    )


THETA_TOL = math.radians(0.5)  # angles closer than this are one
BISECT_TOL = math.radians(0.2)  # the least clear sliding angle, to this
LEAST_MORE = math.radians(1.0)  # also offered: this much steeper than the least clear angle


def guide_ways(
    world: World,
    state: CableState,
    guide: str,
    r_arm: str,
    clear_from: Callable[[_Basics, float, bool], float | None] | None = None,
) -> Iterator[GuideWay]:
    """The ways to route ``guide``, best first: the published sliding angle (its minimum plus
    THETA_MARGIN) on the side farther from the other elements, with the hands' default
    tips, first; then every angle up to THETA_MAX in THETA_STEP steps on each side whose
    slide clears the other elements, each stop before the guide (APPROACH_GAPS, and centred
    in the room there), insert end (as far past as the stop, centred in the room after the
    guide, or nearer), the other tips (LEANS, PIVOT_LEANS, only along the cable or away from
    the bases), turning before sliding and the stand-backs, ranked by how much longer the
    motion gets (a steeper slide swings farther). ``clear_from(basics, side, turn_first)``,
    when given, is the least angle at which the slide keeps its hand clear of the guide (None:
    none does); that angle is offered too (and LEAST_MORE steeper), the steps missing it by
    up to THETA_STEP. An error naming what blocks when no angle clears the guide."""
    heads, theta0 = _way_heads(world, state, guide, r_arm, clear_from)
    yield from _ranked(heads, theta0)


def _way_heads(
    world: World,
    state: CableState,
    guide: str,
    r_arm: str,
    clear_from: Callable[[_Basics, float, bool], float | None] | None,
) -> tuple[list[_Head], float]:
    """guide_ways' heads in their order, and the published sliding angle; the error when no
    angle clears the guide."""
    b0 = _basics(world, state, guide, r_arm)
    prints = cg.footprints(world, guide, b0.up)
    theta0 = b0.theta_min + cg.THETA_MARGIN
    if theta0 > cg.THETA_MAX:
        raise _error(
            f"{b0.where}: no sliding angle clears the guide: theta must exceed "
            f"atan((W_gripper + W_guide) / (2 A)) = atan(({_mm(b0.hand.width)} + "
            f"{_mm(b0.dims.width)}) / (2 * {_mm(cg.APPROACH_GAP)})) = "
            f"{math.degrees(b0.theta_min):.1f} deg, plus {math.degrees(cg.THETA_MARGIN):.0f} "
            f"deg margin, but beyond {math.degrees(cg.THETA_MAX):.0f} deg the slide would go "
            "back along the cable"
        )
    heads: list[_Head] = []
    first_blocked: list[str] = []
    centred_after = _centred_gap(world, guide, b0, after=True)  # the same for every A
    for gap in (*cg.APPROACH_GAPS, *_centred_gap(world, guide, b0, after=False)):
        b = _basics(world, state, guide, r_arm, gap)
        afters = (None, *centred_after)
        afters += tuple(a for a in (*cg.APPROACH_GAPS, *cg.INSERT_PASTS) if a != gap)
        start = b.theta_min + cg.THETA_MARGIN
        n = int((cg.THETA_MAX - start) / cg.THETA_STEP + 1e-9) + 1 if start <= cg.THETA_MAX else 0
        angles: list[tuple[float, tuple[float, bool] | None]]
        angles = [(start + k * cg.THETA_STEP, None) for k in range(n)]
        if n and start + (n - 1) * cg.THETA_STEP < cg.THETA_MAX - THETA_TOL:
            angles.append((cg.THETA_MAX, None))  # the steepest slide: the steps miss it
        for side, first in itertools.product((1.0, -1.0), (False, True)):
            least = None if clear_from is None or n == 0 else clear_from(b, side, first)
            if least is not None and least > start:
                # and a little steeper: the least angle is the default tips'; other tips
                # (LEANS, slide turns) need slightly more
                steeper = [a for a in (least, least + LEAST_MORE) if a <= cg.THETA_MAX]
                angles += [(a, (side, first)) for a in steeper]
        for theta, only in angles:
            clear, blocked = _slide_sides(prints, b, theta, _beside(state, guide))
            if not first_blocked:
                first_blocked = blocked
            for rank, side in enumerate(clear):
                if only is None or side == only[0]:
                    firsts = (False, True) if only is None else (only[1],)
                    heads.append(_Head(theta, side, rank, gap, afters, firsts))
    if not heads:
        raise _error(
            f"{b0.where}: no sliding angle clears the guide: sliding at theta = "
            f"{math.degrees(theta0):.1f} deg is blocked on the "
            + " and on the ".join(first_blocked)
            + f", and so is every angle up to {math.degrees(cg.THETA_MAX):.0f} deg with the "
            f"hand stopping {_mm(min(cg.APPROACH_GAPS))}-{_mm(cg.APPROACH_GAP)} mm before "
            "the guide: move the guides that block it farther from the slide, or use "
            "narrower fingers"
        )
    return heads, theta0


# A way's coordinates in _ranked, those that the screens' keys take first (the pivot's, then
# the approach's, then the routing hand's, then the stand-back): a way refused by a screen
# names the last one its key takes, and best_first leaves out the ways that agree with it up
# to there. Ties keep the order of their first listing: lean, pivot, back, after, first, base,
# share.
BASE_, PIVOT_, LEAN_, AFTER_, FIRST_, SHARE_, BACK_ = range(7)
TIES = (LEAN_, PIVOT_, BACK_, AFTER_, FIRST_, BASE_, SHARE_)
Coordinates = tuple[Any, ...]


def _ranked(
    heads: Sequence[_Head],
    theta0: float,
    dead: Callable[[_Head, Coordinates], int | None] | None = None,
) -> Iterator[GuideWay]:
    """Every way of ``heads`` (with the tips, stand-back, insert end, turning first,
    tipping towards the base and share of the turn in the slide), ranked by how much longer
    the motion gets, lazily; ``dead``: which are known to fail (best_first's prune, on a
    head and its way's coordinates)."""
    dims = [
        (BASES, cg.PIVOT_LEANS, cg.LEANS, h.afters, h.firsts, cg.SLIDE_TURNS, _all_backs())
        for h in heads
    ]

    # costs to COST_DIGITS: ways whose costs differ by rounding alone keep the order listed
    def cost(i: int, c: Coordinates) -> float:
        base, pivot, lean, after, first, share, back = c
        way_cost = _way_cost(heads[i], theta0, lean, pivot, back, after, first, base, share)
        return round(way_cost, COST_DIGITS)

    def part(i: int, dim: int, v: Any) -> float:  # a dim's share in the cost, to order it
        if dim == AFTER_:
            d = 0.0 if v is None else abs(v - heads[i].gap) + 0.5 * (v > heads[i].gap)
        elif dim == BACK_:
            d = _back_cost(v)
        else:
            best = {LEAN_: cg.LEAN, BASE_: 1.0, FIRST_: 0, SHARE_: 1.0, PIVOT_: cg.PIVOT_LEAN}
            d = abs(float(v) - best[dim])
        return round(d, COST_DIGITS)

    prune = None if dead is None else (lambda i, c: dead(heads[i], c))
    for i, c in best_first(dims, cost, part, prune, TIES):
        h = heads[i]
        base, pivot, lean, after, first, share, (distance, lift, turn) = c
        yield GuideWay(
            h.theta, h.side, lean, pivot, distance, h.gap, after, first, base, share,
            stand_lift=lift, stand_turn=turn,
        )  # fmt: skip


BASES = (1.0, 0.0, -1.0)  # GuideWay.towards_base's values, best first
COST_DIGITS = 9  # ways' costs (radians and metres, summed) are compared to 1e-9


@dataclass(frozen=True)
class _Head:
    """A sliding angle, side and stop before the guide, and the insert ends and turning
    first or not that go with them."""

    theta: float
    side: float
    rank: int  # 0: the side farther from the other elements
    gap: float
    afters: tuple[float | None, ...]
    firsts: tuple[bool, ...]


def _way_cost(
    h: _Head,
    theta0: float,
    lean: float,
    pivot: float,
    back: Back,
    after: float | None,
    first: bool,
    base: float,
    share: float,
) -> float:
    """How much longer the motion of a way gets than the published one's (a steeper slide
    swings farther), roughly: the ranking of ways."""
    cost = abs(h.theta - theta0) + 0.05 * h.rank + _back_cost(back)
    cost += 0.5 * (abs(lean - cg.LEAN) + abs(pivot - cg.PIVOT_LEAN))
    cost += (0.0 if after is None else abs(after - h.gap)) + 0.01 * first
    # ending farther past swings farther: only when nearer does not work
    cost += 0.5 if after is not None and after > h.gap else 0.0
    return cost + 0.3 * (1.0 - base) + 0.2 * (1.0 - share)


def _centred_gap(world: World, guide: str, b: _Basics, after: bool) -> tuple[float, ...]:
    """A, for a hand beside the guide (after it: the routing hand inserting; before it: the
    pivot, where the routing hand stops) centred between the guide and the element standing
    next to it along the cable (its fingers then as far as they can be from both); none
    when no element stands within the steps' largest A plus the hand's thickness, or when the
    gap is too short for the hand."""
    direction = b.axis if after else -b.axis
    face = b.slot + b.dims.length / 2.0 * direction
    reach = 2.0 * (max(cg.APPROACH_GAPS) + b.hand.half_length)
    room = _room(world, guide, b.slot, b.dims.height, face, direction, b.up, b.hand, reach)
    if room is None:
        return ()
    gap = room / 2.0 - b.hand.half_length
    near = min(cg.APPROACH_GAPS, key=lambda a: abs(a - gap))
    return (gap,) if gap > 0.0 and abs(near - gap) > 1e-6 else ()  # 1 um: the same


def _room(
    world: World,
    guide: str,
    slot: Vec,
    height: float,
    face: Vec,
    direction: Vec,
    up: Vec,
    hand: cg.Hand,
    reach: float,
) -> float | None:
    """How far from ``face`` (a face of ``guide``, ``height`` tall about its ``slot``) along
    ``direction`` the first element that stands in the way of a hand across the cable
    begins (to CENTRING_TOL), within ``reach``; None when none does."""
    # what stands up to the fingers going down to the slot, not the plates
    level = float(slot @ up) - height / 2.0
    elements = [f for f in cg.footprints(world, guide, up) if f.top > level]
    across = hand.width / 2.0 * g.cross(up, direction)
    # only what stands within the hand's half width of its line (most elements do not)
    end = face + reach * direction
    elements = [f for f in elements if f.distance(face, end, up) <= hand.width / 2.0]

    def touches(d: float) -> bool:  # the hand's line d from the face meets an element
        p = face + d * direction
        return any(f.distance(p - across, p + across, up) <= 0.0 for f in elements)

    for k in range(1, int(reach / CENTRING_STEP) + 1 if elements else 0):
        if touches(k * CENTRING_STEP):
            # then finely: a millimetre's step leaves the hand up to half of one
            # off centre, and 5 mm either side of an 8 mm finger is all an 18 mm room has
            lo, hi = (k - 1) * CENTRING_STEP, k * CENTRING_STEP
            while hi - lo > CENTRING_TOL:
                mid = 0.5 * (lo + hi)
                lo, hi = (lo, mid) if touches(mid) else (mid, hi)
            return lo
    return None


def _guide_plan(
    world: World,
    state: CableState,
    cable: str,
    guide: str,
    r_arm: str,
    o_arm: str,
    way: GuideWay,
    prints: Sequence[cg.Footprint] | None = None,
) -> GuidePlan:
    """The plan of ``way``; ``prints``: the other elements' footprints (cg.footprints of the
    guide), when the caller has them."""
    b = _basics(world, state, guide, r_arm, way.gap, way.gap_after)
    up, slot, axis, ap, theta, side = b.up, b.slot, b.axis, b.ap, way.theta, way.side
    x_off = b.x_offset
    last = np.asarray(state.route[-1], dtype=float)
    tip_o = g.unit(-axis + way.towards_base * _towards_base(world, o_arm, slot, up))
    T_r0 = state.tcp[r_arm]
    T_ap = _approach_pose(world, state, b, r_arm, way)
    T_pivot = _pivot(state, b, o_arm, tip_o, way)
    r_cable, pull_r = b.r_cable, b.pull
    d = _slide_direction(b, way)
    prints = cg.footprints(world, guide, up) if prints is None else prints
    over = b.rise + cg.Z_OFFSET  # over the slot, from above
    if way.approach == OVER_ALL:
        over = max(over, _over_all(b, T_r0, T_ap, prints, world.cell.clearance))
    reorient = None
    if g.rotation_angle(T_r0, T_ap) > cg.REORIENT_MIN:
        up_by = _rise(T_r0, b, over) if way.approach == OVER_ALL else 0.0
        reorient = cg.turn_in_place(T_r0, T_ap)
        if up_by > 0.0:
            T_up = cg.lifted(T_r0, up, up_by)
            reorient = np.concatenate([cg.line(T_r0, T_up), cg.turn_in_place(T_up, T_ap)[1:]])
        T_r0 = reorient[-1]
    approach = _approach_path(T_r0, T_ap, b, way.approach, over)
    slide = _slide(b, way, T_ap)
    pull_path = cg.line(slide[-1], cg.at(slide[-1], ap + (r_cable + pull_r) * d))
    # Lift: up on the circle about the pivot in the vertical plane of the slide, to the
    # elevation at which radius >= R_lift puts the hand over the guide's far face and
    # Z_offset over its top. The hand keeps its orientation: turning with the circle would
    # lean the tool back over the other hand.
    # Higher when a taller element stands in the sector the swing sweeps.
    dims = b.dims
    elevation = math.atan2(b.rise + cg.Z_OFFSET, dims.length + x_off)
    elevation = max(elevation, _swept_elevation(prints, b, theta, side))
    lift = cg.arc(pull_path[-1], ap, g.cross(d, up), elevation, turn=False)
    # Swing about the vertical through the pivot until the cable is over the slot, turning
    # the hand with it (a turn about the vertical keeps its z down).
    swing = cg.arc(lift[-1], ap, up, -side * theta, turn=way.slide_turn)
    # Insert: down on the circle until the cable lies along the axis through the slot.
    insert = cg.arc(swing[-1], ap, g.cross(axis, up), -elevation, turn=False)
    laid = state.route_length() + float(np.linalg.norm(ap - last))
    return GuidePlan(
        guide=guide,
        where=b.where,
        dims=dims,
        up=up,
        slot=slot,
        axis=axis,
        side=side,
        x_offset=x_off,
        a=b.gap,
        r_lift=b.r_lift,
        r_insert=b.r_insert,
        r_cable=r_cable,
        theta_min=b.theta_min,
        theta=theta,
        slide_turn=way.slide_turn,
        pull=pull_r,
        elevation=elevation,
        reorient=reorient,
        approach=approach,
        approached=way.approach,
        slide=slide,
        other_above=cg.lifted(T_pivot, up, cg.APPROACH_HEIGHT),
        pivot=T_pivot,
        pull_path=pull_path,
        lift=lift,
        swing=swing,
        insert=insert,
        laid=laid,
        stand_back=way.stand_back,
        stand_lift=way.stand_lift,
        stand_turn=way.stand_turn,
        beside=_beside(state, guide),
    )


def _approach_pose(world: World, state: CableState, b: _Basics, r_arm: str, way: GuideWay) -> Mat:
    """T_cell_tcp where the routing hand's slide starts. It tips forward and towards its base
    (the other hand back and towards its base, by more: cg.LEAN and cg.PIVOT_LEAN), or
    only along the cable: tipped sideways, open fingers dip towards the plate."""
    tip = g.unit(b.axis + way.towards_base * _towards_base(world, r_arm, b.slot, b.up))
    T_r0 = state.tcp[r_arm]
    frame = cg.tcp_frame(b.ap, b.axis, b.up, tip, way.lean)
    return cg.nearer_turn(T_r0, frame, state.wound.get(r_arm, 0.0))


def _slide_direction(b: _Basics, way: GuideWay) -> Vec:
    left = g.cross(b.up, b.axis)
    d: Vec = math.cos(way.theta) * b.axis + way.side * math.sin(way.theta) * left
    return d


def _slide(b: _Basics, way: GuideWay, T_ap: Mat) -> Poses:
    """The routing hand's slide from ``T_ap``, R_cable along the sliding direction. Sliding,
    the hand turns about the vertical to hold the cable along the slide (or by a share of
    it, see cg.SLIDE_TURNS); the swing over the slot turns it back, so it inserts in the
    approach orientation."""
    turned = g.axis_angle_to_matrix(b.up, way.side * way.theta * way.slide_turn)
    T_slid = g.transform(turned @ T_ap[:3, :3], b.ap + b.r_cable * _slide_direction(b, way))
    if not way.turn_first:
        return cg.line(T_ap, T_slid)
    # turned first, the hand is as wide across the slide as the published sliding angle
    # assumes (W_gripper); turning as it goes, its fingers' ends sweep towards the guide's
    # corner, but its body swings less near the other hand
    turn = cg.turn_in_place(T_ap, T_slid)
    return np.concatenate([turn, cg.line(turn[-1], T_slid)[1:]])


def _under(ctx: PlanningContext, slot: Vec, up: Vec) -> tuple[str, ...]:
    """What lies wholly under the cable held at ``slot`` (the table, a plate): fingers that
    take the cable where it lies come down towards it, so they keep the cell's
    work_clearance from it, as from the guides they work between."""
    return tuple(sorted(ctx.probe.under(float(slot @ up), up)))


def _beside(state: CableState, guide: str) -> tuple[str, ...]:
    """The elements a hand works between at ``guide``: its own and the one the cable leaves
    before the pivot (the last routed guide, or the connector guide)."""
    before = (cg.element_of(state.guides[-1]),) if state.guides else ()
    return (cg.element_of(guide), *before)


def _swept_elevation(
    prints: Sequence[cg.Footprint], b: _Basics, theta: float, side: float
) -> float:
    """The least elevation (seen from the pivot) at which the cable and the routing hand,
    swinging from the slide's direction back to the guide's axis, pass Z_offset over every
    other element standing within the sector they sweep (out to the hand's reach and its
    half width either side); 0 when none stands there."""
    up, axis, ap = b.up, b.axis, b.ap
    left = g.cross(up, axis)
    level = float(b.slot @ up)
    out = 0.0
    for f in prints:
        rise = f.top - level
        if rise <= 0.0:
            continue
        v = f.points - ap
        v = v - np.outer(v @ up, up)
        r = np.linalg.norm(v, axis=1)
        phi = np.arctan2(side * (v @ left), v @ axis)
        spread = np.arctan2(b.hand.width / 2.0 + b.hand.keep, r)
        inside = (r >= 1e-6) & (r <= b.reach + b.hand.width / 2.0)
        inside &= (-spread <= phi) & (phi <= theta + spread)
        if inside.any():
            out = max(out, float(np.arctan2(rise + cg.Z_OFFSET, r[inside].min())))
    return out


def _pivot(state: CableState, b: _Basics, o_arm: str, tip_o: Vec, way: GuideWay) -> Mat:
    """The other hand's grasp at the pivot, tipped back along the cable (and towards its base
    when ``tip_o`` says so)."""
    T = cg.tcp_frame(b.ap, b.axis, b.up, tip_o, way.pivot_lean)
    return cg.nearer_turn(state.tcp[o_arm], T, state.wound.get(o_arm, 0.0))


def _over_all(
    b: _Basics, T_r0: Mat, T_ap: Mat, prints: Sequence[cg.Footprint], clearance: float
) -> float:
    """How high over the slot the hand passes coming from ``T_r0`` to ``T_ap`` over every
    element whose footprint lies within the hand's reach of that path seen from above: its
    fingertips (the TCP) the cell's clearance over the tallest, and its work_clearance more
    for the corners of tipped fingers, which hang below the TCP."""
    reach = b.hand.width / 2.0 + b.hand.half_length + clearance
    level = float(b.slot @ b.up)
    tops = [f.top for f in prints if f.distance(T_r0[:3, 3], T_ap[:3, 3], b.up) <= reach]
    return max(tops, default=level) - level + clearance + b.hand.keep


def _rise(T_r0: Mat, b: _Basics, over: float) -> float:
    """How far the hand at ``T_r0`` rises to be ``over`` the slot (<= 0: it is)."""
    return float(np.dot(b.ap + over * b.up - T_r0[:3, 3], b.up))


def _approach_path(T_r0: Mat, T_ap: Mat, b: _Basics, how: str, over: float) -> Poses:
    """The routing hand's path from ``T_r0`` to ``T_ap``, ``how`` (APPROACHES); coming from
    above, it passes ``over`` the slot."""
    if how == "direct":
        return cg.line(T_r0, T_ap)
    if how == "along the axis":
        vias = [cg.at(T_ap, b.ap - b.x_offset * b.axis)]
    else:  # from above: up from where it is to over the guide's top, over and down
        up_by = _rise(T_r0, b, over)
        vias = [cg.lifted(T_r0, b.up, up_by)] if up_by > 0.0 else []
        vias.append(cg.lifted(T_ap, b.up, over))
    points = [T_r0, *vias, T_ap]
    legs = [cg.line(T0, T1) for T0, T1 in itertools.pairwise(points)]
    return np.concatenate([legs[0], *(leg[1:] for leg in legs[1:])])


def _pivot_blocked(
    ctx: PlanningContext,
    state: CableState,
    guide: str,
    arms: tuple[str, str],
    way: GuideWay,
    next_up: Vec | None,
) -> InputError | frozenset[int]:
    """Why the other hand cannot come down to the pivot of ``way`` keeping its clearances
    (what depends only on A, the pivot's tip and its direction: checked before the rest of
    the way is built), or, when a next guide's platform has ``next_up``, then let go and
    stand back from it (_leave_blocked); else the other arm's IK branches on which it can."""
    r_arm, o_arm = arms
    b = _basics(ctx.world, state, guide, r_arm, way.gap, way.gap_after)
    base = way.towards_base
    tip_o = g.unit(-b.axis + base * _towards_base(ctx.world, o_arm, b.slot, b.up))
    T_pivot = _pivot(state, b, o_arm, tip_o, way)
    poses = cg.line(cg.lifted(T_pivot, b.up, cg.APPROACH_HEIGHT), T_pivot)
    beside = (*_beside(state, guide), *_under(ctx, b.slot, b.up))
    # closed on the cable, a leaning hand's fingers reach back over the guide before
    found = _env_near(ctx, o_arm, poses, OPEN, beside) or _env_near(
        ctx, o_arm, T_pivot[None], GRASP, beside
    )
    if found is None:
        return _leave_blocked(ctx, b, o_arm, poses, next_up)
    near, limit, own = found
    return _Blocked.of(
        near.distance - limit,
        f"{b.where}: {near.tool} {_passes(near, limit)} "
        f"grasping at the pivot (stopping {_mm(b.gap)} mm before the guide); "
        + _env_fix(ctx, near, own),
    )


def _leave_blocked(
    ctx: PlanningContext, b: _Basics, o_arm: str, grasp: Poses, next_up: Vec | None
) -> InputError | frozenset[int]:
    """The other arm's IK branches on which it can come down to the pivot along ``grasp``
    (any branch: it comes on a transit) and, when a next guide's platform has ``next_up``,
    then let go and stand back from it at that guide (_stand_back, some stand-back), without
    hitting itself; why not when none can. (Found only at the next guide, it sends the
    search back through every way of this one; and the arms' pair checks at this guide
    must not count on a branch the other arm cannot be on.)"""
    from cellengine.execute.following import surviving, touching  # the motion stack

    can, nearest = surviving(ctx.cell, ctx.checker, o_arm, grasp, ctx.home)
    hit = touching(ctx.cell, ctx.checker, o_arm, grasp, ctx.home, can)
    can -= set(hit)
    if next_up is not None:
        down, can = can, set()
        for back in _all_backs():  # each branch that can come down, until one stand-back lets it
            poses = np.concatenate([grasp, _stand_back_from(grasp[-1], b.axis, next_up, back)])
            alive, near = surviving(ctx.cell, ctx.checker, o_arm, poses, ctx.home, down - can)
            can |= alive
            nearest = min(nearest, near)
            if can == down:
                break
    if can:
        return frozenset(can)
    then = "" if next_up is None else ", then let go and stand back from it at the next guide,"
    cell = " or the cell" if hit else ""
    pair = nearest[1] if any(nearest[1]) or not hit else hit[min(hit)]
    return _error(
        f"{b.where}: the other arm ({o_arm}) has no IK branch on which it can come down to "
        f"the pivot (stopping {_mm(b.gap)} mm before the guide){then} without hitting itself"
        f"{cell} ({', '.join(pair) or 'out of reach'})"
    )


def _slide_sides(
    prints: Sequence[cg.Footprint], b: _Basics, theta: float, beside: Collection[str] = ()
) -> tuple[list[float], list[str]]:
    """The sides the slide at ``theta`` may take, farthest from every other element that
    stands up to the hand's height first (a base plate does not count; +1, left of the axis,
    on a tie), and for each blocked side what blocks it: within the hand's and the element's
    radii plus the work clearance. The elements the hand starts ``beside`` (the guide before, which
    the slide starts next to) are left to the tool probe, which measures the hand itself:
    a round hand would stand in them. ``prints``: the footprints of the elements but the
    guide's (cg.footprints)."""
    up, axis, ap, hand = b.up, b.axis, b.ap, b.hand
    left = g.cross(up, axis)
    # the hand turns with the slide (its x along it): half its extent across the motion,
    # the collision checks' stand-in being square
    hand_radius = max(hand.width, 2.0 * hand.half_length) / 2.0
    height = float(ap @ up) - hand.keep
    elements = [f for f in prints if f.top > height and f.name not in beside]
    # nearest first by a bound that holds on both sides: the rest cannot come nearer (and
    # of those as near, the first listed names the side's nearest, as without the bound)
    bounds = sorted((f.least_distance(ap, b.reach, up), k) for k, f in enumerate(elements))
    clear: list[tuple[float, float]] = []
    blocked: list[str] = []
    for side in (1.0, -1.0):
        end = ap + b.reach * (math.cos(theta) * axis + side * math.sin(theta) * left)
        margin, first = math.inf, len(elements)
        for bound, k in bounds:
            if bound - hand_radius > margin:
                break
            m = elements[k].distance(ap, end, up) - hand_radius
            if m < margin or (m == margin and k < first):
                margin, first = m, k
        nearest = elements[first].name if first < len(elements) else ""
        name = "left" if side > 0 else "right"
        if margin < hand.keep:
            why = (
                f"its footprint and the sliding hand's overlap by {_mm(-margin)} mm"
                if margin < 0.0
                else f"{_mm(margin)} mm from the hand, {_mm(hand.keep)} mm needed"
            )
            blocked.append(f"{name} by {nearest} ({why})")
        else:
            clear.append((margin, side))
    # the larger margin first; a tie (within 1e-9 m) keeps the left
    best: tuple[float, float] | None = None
    for margin, side in clear:
        if best is None or margin > best[0] + 1e-9:
            best = (margin, side)
    ordered = [side for _, side in clear]
    if best is not None and ordered[0] != best[1]:
        ordered.reverse()
    return ordered, blocked


def _check_room(
    world: World, where: str, hand: cg.Hand, first: str | None, then: str | None
) -> None:
    """A hand works between two consecutive elements of the route (the other hand grasps the
    cable between the last one routed and the guide; the routing hand inserts between the
    guide and the next one): the cable between their footprints holds its fingers, with
    the cell's work_clearance either side. (Footprints are bounding boxes: an element's may
    be larger than what stands there, so this explains a failed search, and does not
    replace it.)"""
    if first is None or then is None:
        return
    up = cg.platform_up(world, then)
    room = cg.room_between(world, first, then, up)
    need = 2.0 * (hand.half_length + hand.keep)
    if room is not None and room < need - 1e-9:
        a, b = cg.element_of(first), cg.element_of(then)
        raise _error(
            f"{where}: the cable runs {_mm(room)} mm from {a} to {b} (footprint to "
            f"footprint); a hand works between them, its fingers {_mm(2.0 * hand.half_length)} "
            f"mm thick along it keeping {_mm(hand.keep)} mm from each (work_clearance in "
            f"cell.yaml): {_mm(need)} mm. Move {b} at least {_mm(need - room)} mm farther from "
            f"{a}, or use thinner fingers"
        )


def _check_length(world: World, name: str, hand: cg.Hand, gp: GuidePlan) -> None:
    """The cable must reach the routing hand when it is farthest out (after the pull) and
    leave the fingers enough beyond it to hold."""
    cable = world.cable(name)
    margin = hand.end_margin
    need = gp.laid + gp.radius + margin
    if need > cable.length + 1e-9:
        raise _error(
            f"{gp.where}: cable '{name}' is too short for the route: this guide needs "
            f"{_mm(need)} mm ({_mm(gp.laid)} mm laid from the connector's rear face to the "
            f"approach point, R_cable {_mm(gp.r_cable)} mm slid past it, {_mm(gp.pull)} mm "
            f"pulled to tension, {_mm(margin)} mm for the fingers to hold) but the cable is "
            f"{_mm(cable.length)} mm long"
        )


RELEASE = "release the previous guide"  # the label's end of a guide's first segment


def _add_release(
    b: _Builder,
    label: str,
    arms: tuple[str, str],
    poses: Poses,
    beside: Sequence[str],
    branches: Release = (),
) -> None:
    """The segment in which the other hand lets go of the cable at the last guide and stands
    back along ``poses``: near its pivot's guides and ``beside`` (the elements the hands work
    between next), the routing hand standing where it inserted; ``branches``: the arms'
    (_letting_go)."""
    r_arm, o_arm = arms
    elements = sorted({*map(cg.element_of, b.state.guides[-2:]), *beside})
    b.add(
        f"{label}: {RELEASE}",
        [_cartesian(o_arm, poses)],
        before=[GripperEvent(o_arm, OPEN)],
        near=[*((o_arm, e) for e in elements), *((r_arm, e) for e in beside)],
        branches=branches,
    )


def _emit_guide(
    state: CableState, gp: GuidePlan, r_arm: str, o_arm: str, cable: str
) -> tuple[list[Segment], CableState]:
    label = f"RouteCable {gp.guide}"
    b = _Builder(state)
    pair = (r_arm, o_arm)
    if o_arm in b.state.held:
        # The other hand lets go of the cable at the previous guide, moves up and then back
        # along the route: straight up, its wrist stays where the routing arm's forearm
        # passes on its way to the next guide (a collision on plan_one_turn).
        poses = _stand_back(b.state, o_arm, gp.up, _back_of(gp))
        _add_release(b, label, (r_arm, o_arm), poses, gp.beside, gp.release)
    near = [(r_arm, e) for e in gp.beside]  # the hands work between these (GuidePlan)
    # the other arm, standing while the routing hand comes, on a branch of the coming pairs:
    # so the transit that chose its branch (at the guide before) looked for one of them
    standing = tuple((o, frozenset(j for _, j in pairs)) for _, o, pairs in gp.coming_pairs)
    if gp.reorient is not None:  # turning in place where it inserted, by that guide
        b.add(
            f"{label}: face the guide",
            [_cartesian(r_arm, gp.reorient)],
            before=b.mode_event(r_arm, SLIDE, cable),
            near=near,
            branches=standing,
            paired=gp.coming_pairs,
        )
    b.add(
        f"{label}: approach sliding",
        [_cartesian(r_arm, gp.approach)],
        before=b.mode_event(r_arm, SLIDE, cable),
        near=near,
        facts={"approach": gp.approached},
        branches=standing,
        paired=gp.coming_pairs,
    )
    b.add(
        f"{label}: slide R_cable",
        [_cartesian(r_arm, gp.slide)],
        after=[GripperEvent(r_arm, GRASP, cable)],
        near=near,
        branches=standing,
        paired=gp.coming_pairs,
        facts={
            "guide": gp.guide,
            "R_lift": gp.r_lift,
            "R_insert": gp.r_insert,
            "R_cable": gp.r_cable,
            "theta_min": gp.theta_min,
            "theta": gp.theta,
            "A": gp.a,
            "X_offset": gp.x_offset,
            "Z_offset": cg.Z_OFFSET,
            "side": gp.side,
            "slide_turn": gp.slide_turn,
        },
    )
    b.add(
        f"{label}: other arm to the cable",
        [_transit(o_arm, gp.other_above)],
        before=b.mode_event(o_arm, OPEN, None),
        near=near,  # the routing hand stands at the slide's end
    )
    # From here the other hand works between the guides, the routing hand still standing
    # at the slide's end there.
    near = [*near, *((o_arm, e) for e in gp.beside)]
    b.add(
        f"{label}: other arm grasps",
        [_cartesian(o_arm, cg.line(gp.other_above, gp.pivot))],
        after=[GripperEvent(o_arm, GRASP, cable)],
        near=near,
        branches=((o_arm, gp.grasp),) if gp.grasp != ANY_BRANCH else (),
        paired=gp.grasp_pairs,
    )
    # The distance between the hands grows by the pull here, by design: no keep_distance.
    b.add(
        f"{label}: pull to tension",
        [_cartesian(r_arm, gp.pull_path)],
        facts={"pull": gp.pull},
        near=near,
    )
    b.add(f"{label}: lift", [_cartesian(r_arm, gp.lift)], keep_distance=pair, near=near)
    b.add(f"{label}: over the slot", [_cartesian(r_arm, gp.swing)], keep_distance=pair, near=near)
    b.add(
        f"{label}: insert",
        [_cartesian(r_arm, gp.insert)],
        keep_distance=pair,
        near=near,  # the fingers take the cable down by the slot
        annotations=[Anchor(cable, _point(gp.slot), gp.guide)],
        facts={
            "guide": gp.guide,
            "slot": _vec(gp.slot),
            "axis": _vec(gp.axis),
            "gap": gp.dims.gap,
            "routing_arm": r_arm,
            "other_arm": o_arm,
            "radius": gp.radius,
        },
    )
    return b.segments, gp.after(b.state, r_arm, o_arm, cable)


# =========================================================================== checks and arms


class _Blocked(InputError):
    """A way whose tool would come within the clearance of something; ``distance``: by how
    much it keeps more than the clearance (negative: by how much less)."""

    distance: float

    @classmethod
    def of(cls, distance: float, message: str) -> _Blocked:
        e = cls(Problem(message))
        e.distance = distance
        return e


class _Standing(_Blocked):
    """The other hand's fingers standing back from the last guide come too near something:
    where it holds the cable there (the last guide's way) decides it, not which arm routes."""


def _error(message: str) -> InputError:
    return InputError(Problem(message))


def _mm(x: float) -> str:
    return f"{x * 1000.0:.1f}"


def _mm_under(x: float, limit: float) -> str:
    """``x`` (m, under ``limit``) in mm: to 0.01 mm where it rounds to the limit itself (a
    9.96 mm that prints as the 10.0 mm clearance would not say why it is refused)."""
    return _mm(x) if _mm(x) != _mm(limit) else f"{x * 1e3:.2f}"


def _short(x: float) -> str:
    """A shortfall in mm: to 0.01 mm where it rounds to 0.0, and "less than 0.01" where that
    does too (it is not nothing)."""
    if _mm(x) != "0.0":
        return _mm(x)
    return f"{x * 1000.0:.2f}" if x >= 0.5e-5 else "less than 0.01"


def _two_arms(world: World, where: str) -> tuple[str, str]:
    arms = tuple(world.cell.robots)
    if len(arms) != 2:
        raise _error(
            f"{where}: the cable skills need a cell with two arms, this one has {len(arms)}"
        )
    return arms[0], arms[1]


def _other(arms: tuple[str, str], arm: str) -> str:
    return arms[1] if arm == arms[0] else arms[0]


def _nearest_arm(world: World, arms: tuple[str, str], ref: str) -> str:
    """The arm whose base is nearer the keypoint (the first on a tie)."""
    p = cg.position(world, ref)
    dist = [float(np.linalg.norm(world.cell.robots[a].base.matrix()[:3, 3] - p)) for a in arms]
    return arms[0] if dist[0] <= dist[1] else arms[1]


def _towards_base(world: World, arm: str, p: Vec, up: Vec) -> Vec:
    """Horizontal unit vector from ``p`` towards the arm's base."""
    return cg.horizontal(world.cell.robots[arm].base.matrix()[:3, 3] - p, up)


def _hand(world: World, arm: str) -> cg.Hand:
    robot = world.cell.robots[arm]
    if robot.tool is None or robot.tool not in world.cell.tools:
        raise _error(f"arm '{arm}' has no tool: the cable skills need a parallel gripper")
    return cg.Hand.from_tool(world.cell.tools[robot.tool], robot.tool, world.cell.work_clearance)


def _check_jaw(world: World, arm: str, where: str, cable: str) -> None:
    """The tool has the jaw modes the method uses, each wide enough for what it does to
    ``cable``: open around the connector (across its thinner side) and the cable, slide
    along the cable, grasp it tighter than it is thick."""
    robot = world.cell.robots[arm]
    _hand(world, arm)
    assert robot.tool is not None
    jaw = world.cell.tools[robot.tool].jaw
    missing = [m for m in (OPEN, SLIDE, GRASP) if m not in jaw]
    if missing:
        raise _error(
            f"{where}: tool '{robot.tool}' of arm '{arm}' has no jaw mode "
            + ", ".join(f"'{m}'" for m in missing)
            + " (the method opens, slides and grasps)"
            + known(jaw)
        )
    c = world.cable(cable)
    d = c.diameter
    across = min(c.connector.width, c.connector.height) if c.connector else d
    wrong = [
        (OPEN, "open around", "the connector" if c.connector else "the cable", across, "wider")
        if jaw[OPEN] <= across
        else None,
        (SLIDE, "slide along", "the cable", d, "wider") if jaw[SLIDE] <= d else None,
        (GRASP, "hold", "the cable", d, "narrower") if jaw[GRASP] >= d else None,
    ]
    for mode, does, what, size, must in filter(None, wrong):
        raise _error(
            f"{where}: tool '{robot.tool}' of arm '{arm}': jaw '{mode}' is {_mm(jaw[mode])} mm; "
            f"to {does} {what} of '{cable}' ({_mm(size)} mm) it must be {must}"
        )


def _check_gaps(world: World, guides: Sequence[str], cable: str, where: str) -> None:
    """Each guide's slot takes the cable: its gap is wider than the cable is thick."""
    d = world.cable(cable).diameter
    for ref in guides:
        gap = cg.GuideDims.of(world, ref, where).gap
        if gap <= d:
            raise _error(
                f"{where}: guide '{ref}' has a {_mm(gap)} mm slot (its gap); '{cable}' is "
                f"{_mm(d)} mm thick: it does not fit"
            )


def _require_hold(state: CableState, arm: str, cable: str, where: str, what: str) -> None:
    hold = state.held.get(arm)
    if hold is None or hold.cable != cable:
        raise _error(f"{where}: arm '{arm}' does not hold {what}")


def _routing_arms(world: World, state: CableState, cable: str, where: str) -> tuple[str, str]:
    r_arm = state.routing_arm
    if state.cable != cable or r_arm is None or not state.route:
        raise _error(
            f"{where}: cable '{cable}' has no placed connector (plan PlaceConnector first)"
        )
    _require_hold(state, r_arm, cable, where, f"cable '{cable}'")
    return r_arm, _other(_two_arms(world, where), r_arm)


def _check_reach(
    ctx: PlanningContext, arm: str, poses: Sequence[tuple[str, Mat]], where: str
) -> None:
    """Every key pose has an inverse kinematics solution within the arm's joint limits (the
    executor plans the paths between them; this rejects a guide the arm cannot get to)."""
    ik = ctx.iks[arm]
    for what, T in poses:
        if ik.solve(T) is None:
            x, y, z = (_mm(v) for v in T[:3, 3])
            raise _error(
                f"{where}: out of reach of arm '{arm}': the {what} pose at ({x}, {y}, {z}) "
                "mm has no inverse kinematics solution within its joint limits"
            )


def _base_distance(ctx: PlanningContext, arm: str, ref: str) -> float:
    """Horizontal distance (m) from ``arm``'s base to the keypoint ``ref``."""
    d = ctx.world.pose(ref)[:3, 3] - ctx.cell.arms[arm].T_cell_base[:3, 3]
    return float(np.hypot(d[0], d[1]))


def _check_both_free(
    ctx: PlanningContext, geo: _PickGeometry, c_arm: str, f_arm: str, where: str
) -> None:
    """At each of the pick's key configurations (over the combs, where both hands go first;
    turned along the cable; the far hand slid to the connector hand, and raised), some pair
    of the two arms' inverse kinematics solutions is free of collisions, between the arms
    and with the cell: else the way is not handed to the compiler."""
    above = {a: cg.lifted(geo.grasp[a], geo.up, cg.APPROACH_HEIGHT) for a in (c_arm, f_arm)}
    over = f"{f_arm} over {geo.end(f_arm)}"
    if geo.aside is not None:
        above[f_arm], over = geo.aside[-1], f"{f_arm} with the {geo.end(f_arm)} aside"
    turned = {a: geo.faced[a][-1] for a in (c_arm, f_arm)}
    met = {a: geo.meet[a][-1] if a in geo.meet else turned[a] for a in (c_arm, f_arm)}
    configurations = (
        (f"the pick configuration ({c_arm} over {geo.end(c_arm)}, {over})", above),
        ("both hands turned along the cable", turned),
        *((("the hands met between the combs", met),) if geo.meet else ()),
        (f"{f_arm} slid to the connector hand", {c_arm: met[c_arm], f_arm: geo.slide[-1]}),
        (f"{f_arm} raised beside the connector hand",
         {c_arm: met[c_arm], f_arm: geo.raise_[-1]}),
    )  # fmt: skip
    for what, poses in configurations:
        why = _pair_blocked(ctx, poses)
        if why is not None:
            raise _error(
                f"{where}: every inverse kinematics solution of {what} is in collision"
                + (f" ({why})" if why else "")
            )


def _pair_rooms(
    ctx: PlanningContext,
    a: str,
    b: str,
    poses: Sequence[tuple[Mat, Mat]],
    keep: float,
    a_on: frozenset[int] = ANY_BRANCH,
    b_on: frozenset[int] = ANY_BRANCH,
    measure: bool = True,
) -> dict[int, float]:
    """For each IK branch of ``a`` in ``a_on``, how far apart (m) the two arms can stay while
    their tools pass ``poses``: the most of _pair_least over ``b``'s branches. {-1: inf} for
    an arm solved numerically (it has no branches)."""
    least = _pair_least(ctx, a, b, poses, keep, a_on, b_on, measure)
    if least is None:
        return {-1: math.inf}  # no branches: the compiler finds out
    room = least.max(axis=1)
    return {k: float(room[k]) for k in sorted(a_on)}


def _pair_least(
    ctx: PlanningContext,
    a: str,
    b: str,
    poses: Sequence[tuple[Mat, Mat]],
    keep: float,
    a_on: frozenset[int] = ANY_BRANCH,
    b_on: frozenset[int] = ANY_BRANCH,
    measure: bool = True,
) -> NDArray[np.float64] | None:
    """For each pair of IK branches (``a``'s in ``a_on``, ``b``'s in ``b_on``; 8 x 8), how
    far apart (m) the two arms stay while their tools pass ``poses`` (T_cell_tcp of ``a``,
    of ``b``): their least distance there when it keeps ``keep`` at every pose (the arms
    against each other only: the tools' contacts with the cell are the skills' other
    checks); just ``keep`` when not ``measure`` (a yes/no per pose, cheaper: for callers
    that only compare with ``keep``). Below ``keep`` when the pair comes within it: how near
    it came then (measuring on would cost far more); -inf where the pair meets, has no
    solution or is not asked for. None for an arm solved numerically. A continuous motion
    keeps its branches."""
    on_a, on_b = np.isin(np.arange(8), sorted(a_on)), np.isin(np.arange(8), sorted(b_on))
    alive = np.outer(on_a, on_b).reshape(64)  # pair i: a's branch i // 8, b's i % 8
    least = np.where(alive, math.inf, -math.inf)
    for T_a, T_b in poses:
        q_a, q_b = ctx.iks[a].by_branch(T_a), ctx.iks[b].by_branch(T_b)
        if q_a is None or q_b is None:
            return None
        Q = _solution_pairs(ctx, a, q_a, b, q_b)
        ok: NDArray[np.bool_] = alive & ~np.isnan(Q).any(axis=1)
        least[alive & ~ok] = -math.inf  # no solution there
        for i in np.flatnonzero(ok):
            if not measure and ctx.checker.apart(Q[i], keep, (a, b)):
                least[i] = min(least[i], keep)
                continue
            d = ctx.checker.distance(Q[i], between=(a, b))[0]
            least[i] = min(least[i], d) if d > 0.0 else -math.inf
        alive = ok & (least >= keep)
        if not alive.any():
            break
    out: NDArray[np.float64] = least.reshape(8, 8)
    return out


def _kept_branches(
    kept: NDArray[np.bool_], a: str, b: str
) -> tuple[tuple[str, frozenset[int]], tuple[str, frozenset[int]]]:
    """(arm, IK branches) of ``a`` and of ``b`` in some pair of ``kept`` (8 x 8: _pair_least
    compared with a clearance), as Segment.branches."""
    return (
        (a, frozenset(int(k) for k in np.flatnonzero(kept.any(axis=1)))),
        (b, frozenset(int(k) for k in np.flatnonzero(kept.any(axis=0)))),
    )


Paired = tuple[tuple[str, str, frozenset[tuple[int, int]]], ...]  # Segment.paired


def _kept_pairs(kept: NDArray[np.bool_], a: str, b: str) -> Paired:
    """The pairs of ``a``'s and ``b``'s IK branches in ``kept`` (8 x 8: _pair_least compared
    with a clearance), as Segment.paired: each arm's branches in some pair (_kept_branches)
    do not say which go together."""
    return ((a, b, frozenset((int(i), int(j)) for i, j in np.argwhere(kept))),)


def _solutions(ctx: PlanningContext, arm: str, T: Mat, on: frozenset[int] | None) -> Vec:
    """``arm``'s inverse kinematics solutions at ``T``: those of the branches ``on`` when
    given (an arm solved numerically has none: all)."""
    rows = ctx.iks[arm].by_branch(T) if on is not None and on != ANY_BRANCH else None
    if rows is None:
        return ctx.iks[arm].solve_all(T)
    rows = rows[sorted(on or ())]
    return rows[~np.isnan(rows).any(axis=1)]


def _solution_pairs(ctx: PlanningContext, a: str, sols_a: Vec, b: str, sols_b: Vec) -> Vec:
    """Every pair of ``a``'s and ``b``'s joint solutions, as the cell's configurations (the
    other joints at home)."""
    Q = np.repeat(ctx.home[None, :], len(sols_a) * len(sols_b), axis=0)
    Q[:, ctx.cell.slices[a]] = np.repeat(sols_a, len(sols_b), axis=0)
    Q[:, ctx.cell.slices[b]] = np.tile(sols_b, (len(sols_a), 1))
    return Q


def _pair_blocked(
    ctx: PlanningContext,
    poses: Mapping[str, Mat],
    keep: float = 0.0,
    on: Mapping[str, frozenset[int]] = MappingProxyType({}),
) -> str | None:
    """None when some pair of the two arms' inverse kinematics solutions at ``poses``
    (T_cell_tcp per arm; of the branches ``on`` names for an arm) is free of collisions, and
    keeps ``keep`` (m) between the arms; else why none is ("" when an arm has no solution,
    else the first pair's contact or least distance)."""
    (a, T_a), (b, T_b) = poses.items()
    sols_a, sols_b = _solutions(ctx, a, T_a, on.get(a)), _solutions(ctx, b, T_b, on.get(b))
    if len(sols_a) == 0 or len(sols_b) == 0:
        return ""
    Q = _solution_pairs(ctx, a, sols_a, b, sols_b)
    free = np.flatnonzero(~ctx.checker.check_batch(Q))
    if len(free) == 0:
        return str(ctx.checker.check(Q[0]))
    if keep <= 0.0:
        return None
    nearest = (math.inf, ("", ""))
    for i in free:
        d, pair = ctx.checker.distance(Q[i], between=(a, b))
        if d >= keep:
            return None
        nearest = min(nearest, (d, pair))
    return f"the arms {_mm(nearest[0])} mm apart at best ({', '.join(nearest[1])})"


def _refused(
    screen: _Screen,
    checked: Mapping[WayKey, GuidePlan | InputError],
    released: Mapping[Back, InputError | Release],
    seen: Set[InputError],
    h: _Head,
    c: Coordinates,
) -> int | None:
    """Whether guide_plans would refuse the way of ``h`` and coordinates ``c`` (_ranked's)
    from what its screens found so far: None when not known, else the last coordinate the
    refusal depends on (best_first then leaves out the ways that agree with it up to
    there). The ways left out would each give guide_plans an error it has been given
    (``seen``), so the closest it keeps is as without them: _checked returns the first of
    the approach's, the routing hand's and the pivot's, and the first two are returned
    when found."""
    base, pivot, lean, after, first, share, back = c
    hand = (h.theta, h.side, lean, h.gap, after, first, base, share)
    known = checked.get((*hand, "direct", pivot))
    if isinstance(known, InputError):
        return SHARE_
    why = [
        (LEAN_, screen.approaches.get((h.gap, lean, base))),
        (SHARE_, screen.routed.get((*hand, "direct"))),
        (PIVOT_, screen.pivots.get((h.gap, pivot, base))),
    ]
    errors = [(at, e) for at, e in why if isinstance(e, InputError)]
    if errors and errors[0][1] in seen:
        return min(at for at, e in errors if e in seen)
    if isinstance(released.get(back), InputError):
        return BACK_
    return None


def _coming_key(way: GuideWay, back: Back) -> WayKey:
    """What _coming measures depends on: the routing hand's motion (its approach follows from
    the way; the insert's end sets R_cable, how far it slides) and where the other hand
    stands back to."""
    return (*_hand_key(way), *back)


def _routing_key(way: GuideWay) -> WayKey:
    """What the routing hand's checks depend on: not the other hand's tip or stand-back."""
    return (*_hand_key(way), way.approach)


def _backless_key(way: GuideWay) -> WayKey:
    """Every field of ``way`` but where the other hand stands back to."""
    return (*_hand_key(way), way.approach, way.pivot_lean)


def _hand_key(way: GuideWay) -> WayKey:
    """The fields of the routing hand's motion but its approach."""
    w = way
    return (w.theta, w.side, w.lean, w.gap, w.gap_after, w.turn_first, w.towards_base, w.slide_turn)


def _all_backs() -> tuple[Back, ...]:
    """Every stand-back, best first (_back_cost): up RETRACT_HEIGHT and back along the route
    each of STAND_BACKS; just clear of the cable and back STAND_BACK along the route or to
    either side (STAND_LOWS: where a routing arm reaches over the pivot hand, rising takes
    its forearm into it); only up RETRACT_HEIGHT (STAND_UP)."""
    backs = [(d, cg.RETRACT_HEIGHT, 0.0) for d in cg.STAND_BACKS]
    backs += [(cg.STAND_BACK, lift, turn) for lift, turn in cg.STAND_LOWS]
    backs.append(cg.STAND_UP)
    return tuple(sorted(backs, key=_back_cost))


def _back_cost(back: Back) -> float:
    """How much a stand-back adds to a way's cost (_way_cost): the farther, the longer."""
    distance, lift, turn = back
    return abs(distance - cg.STAND_BACK) + abs(lift - cg.RETRACT_HEIGHT) + 0.05 * abs(turn)


def _stand_backs(state: CableState, o_arm: str) -> tuple[Back, ...]:
    """Where the other hand may stand back to: only when it holds the cable at a guide."""
    return _all_backs() if o_arm in state.held else (DEFAULT_BACK,)


def _coming(
    ctx: PlanningContext,
    state: CableState,
    gp: GuidePlan,
    way: GuideWay,
    arms: tuple[str, str],
    screen: _Screen,
    backs: Sequence[Back],
) -> GuidePlan | InputError:
    """gp if, while the other hand stands back from the previous guide (when it holds the
    cable there, to one of ``backs``) and then the routing hand comes to the guide and slides
    (Cartesian paths: each arm keeps its IK branch, the other arm one of those it may be on),
    some pair of branches keeps the cell's clearance between the arms at poses along the way,
    with the routing arm's branches narrowed to those in such a pair; else why not, by how
    much it falls short. Measured once for the ways that share those motions."""
    kept: set[int] = set()
    best = -math.inf
    # the routing arm's branches that come and slide clear of itself (gp's are among them)
    came = screen.came.get(_coming_key(way, DEFAULT_BACK))
    on = came if isinstance(came, frozenset) and -1 not in came else ANY_BRANCH
    pairs = np.zeros((8, 8), dtype=bool)
    # the other arm's branches the state allows: the routing arm's are kept for a pair with
    # one of them; the pairs are measured with all 8 (the compiler may have put the other
    # arm on any that its segments allowed, and the pairs tell it which work here)
    may = np.isin(np.arange(8), sorted(state.branches_of(arms[1])))
    for back in backs:
        key = _coming_key(way, back)
        if key not in screen.coming:
            least = _coming_least(ctx, state, _with_back(gp, back), arms, on)
            room = -math.inf if least is None else float(least[:, may].max())
            blocked = least is not None and room < ctx.clearance
            screen.coming[key] = (
                least,
                _coming_error(ctx, state, gp, arms, room) if blocked else None,
            )
        least, _ = screen.coming[key]
        if least is None:
            return gp  # no branches: the compiler finds out
        rows = np.isin(np.arange(8), sorted(gp.branches))[:, None]
        pairs |= rows & (least >= ctx.clearance)
        kept |= {k for k in gp.branches if least[k, may].max() >= ctx.clearance}
        best = max(best, *(float(least[k, may].max()) for k in gp.branches))
        if kept == gp.branches:
            break  # the other stand-backs could keep no more branches
    if not kept:
        return _coming_error(ctx, state, gp, arms, best)
    # the pairs are the stand-back's: only for a way's own (one stand-back), of the routing
    # arm's branches kept
    pairs &= np.isin(np.arange(8), sorted(kept))[:, None]
    paired = _kept_pairs(pairs, *arms) if len(backs) == 1 else ()
    return replace(gp, branches=frozenset(kept), coming_pairs=paired)


def _coming_blocked(screen: _Screen, way: GuideWay, backs: Sequence[Back]) -> InputError | None:
    """_coming's error, known before the way is built, when no branch has the room whatever
    the stand-back."""
    known = [screen.coming.get(_coming_key(way, back)) for back in backs]
    whys = [k[1] for k in known if k is not None and k[1] is not None]
    return max(whys, key=lambda e: e.distance) if len(whys) == len(backs) else None


def _coming_error(
    ctx: PlanningContext, state: CableState, gp: GuidePlan, arms: tuple[str, str], room: float
) -> _Blocked:
    r_arm, o_arm = arms
    return _arms_blocked(
        ctx,
        gp,
        room,
        f"the routing arm ({r_arm}) comes to the guide and slides (at theta = "
        f"{math.degrees(gp.theta):.1f} deg, stopping {_mm(gp.a)} mm before it), the other arm "
        f"{'standing back from the previous guide' if o_arm in state.held else 'still'}",
    )


def _arms_blocked(ctx: PlanningContext, gp: GuidePlan, room: float, what: str) -> _Blocked:
    """A way refused because no pair of the arms' branches keeps the cell's clearance while
    ``what`` happens; ``room``: how near every pair comes (_pair_rooms)."""
    d = _mm_under(room, ctx.clearance)
    at_best = "collide" if room == -math.inf else f"come within {d} mm of each other"
    return _Blocked.of(
        room - ctx.clearance,
        f"{gp.where}: however the two arms are posed, they {at_best} while {what}; the cell's "
        f"clearance is {_mm(ctx.clearance)} mm",
    )


def _coming_least(
    ctx: PlanningContext,
    state: CableState,
    gp: GuidePlan,
    arms: tuple[str, str],
    on: frozenset[int],
) -> NDArray[np.float64] | None:
    """_pair_least of the routing arm's branches ``on`` and each of the other arm's over
    _coming's motions (every STRIDE-th pose), keeping the cell's clearance."""
    from cellengine.execute.following import STRIDE  # the motion stack: planning only

    r_arm, o_arm = arms
    T_r, T_o = state.tcp[r_arm], state.tcp[o_arm]
    poses: list[tuple[Mat, Mat]] = []
    if o_arm in state.held:
        back = _stand_back(state, o_arm, gp.up, _back_of(gp))
        poses += [(T_r, T) for T in (*back[::STRIDE], back[-1])]
        T_o = back[-1]
    coming = np.concatenate([p for p in (gp.reorient, gp.approach, gp.slide) if p is not None])
    poses += [(T, T_o) for T in (*coming[::STRIDE], coming[-1])]
    return _pair_least(ctx, r_arm, o_arm, poses, ctx.clearance, on, ANY_BRANCH, measure=False)


def _check_pivot_free(
    ctx: PlanningContext, gp: GuidePlan, r_arm: str, o_arm: str, o_on: frozenset[int]
) -> tuple[frozenset[int], frozenset[int], Paired]:
    """While the routing hand holds still at the slide's end, the other arm comes down to the
    pivot (on a branch of ``o_on``: those on which it can, _pivot_blocked): some pair of the
    arms' solutions is free there and above it, and keeps the cell's clearance between the
    arms, and on to the insert (:func:`_check_pair_along`). The routing arm's branches (of
    gp.branches) on which it is so, the other arm's in a pair with them, and those pairs."""
    for what, T in (("above the pivot", gp.other_above), ("at the pivot", gp.pivot)):
        poses = {r_arm: gp.slide[-1], o_arm: T}
        why = _pair_blocked(ctx, poses, ctx.clearance, {r_arm: gp.branches, o_arm: o_on})
        if why is not None:
            raise _error(
                f"{gp.where}: every inverse kinematics solution of the other arm {what} is in "
                f"collision with the routing arm at the slide's end, or within the cell's "
                f"clearance ({_mm(ctx.clearance)} mm) of it (sliding at theta = "
                f"{math.degrees(gp.theta):.1f} deg, stopping {_mm(gp.a)} mm before the guide)"
                + (f" ({why})" if why else "")
            )
    ends = (gp.other_above, gp.pivot)
    kept = frozenset(
        k
        for k in gp.branches
        if all(
            _pair_blocked(
                ctx,
                {r_arm: gp.slide[-1], o_arm: T},
                ctx.clearance,
                {r_arm: frozenset({k}), o_arm: o_on},
            )
            is None
            for T in ends
        )
    )
    return _check_pair_along(ctx, replace(gp, branches=kept or gp.branches), r_arm, o_arm, o_on)


def _check_pair_along(
    ctx: PlanningContext, gp: GuidePlan, r_arm: str, o_arm: str, o_on: frozenset[int]
) -> tuple[frozenset[int], frozenset[int], Paired]:
    """From the other arm coming down to the pivot to the insert (both arms on Cartesian
    paths, so each keeps its IK branch), some pair of branches keeps the cell's clearance
    between the arms at poses along the way (every STRIDE-th): near the pivot the routing
    arm's wrist passes over the other arm's forearm on some boards and under it on others.
    The routing arm's branches (of gp.branches) in such a pair, the other arm's (of ``o_on``)
    in a pair with them, and those pairs; else the way is refused, by how much it falls
    short."""
    from cellengine.execute.following import STRIDE  # the motion stack: planning only

    down = cg.line(gp.other_above, gp.pivot)
    held = np.concatenate((gp.pull_path, gp.lift, gp.swing, gp.insert))
    poses = [(gp.slide[-1], T) for T in (*down[::STRIDE], down[-1])]
    poses += [(T, gp.pivot) for T in (*held[::STRIDE], held[-1])]
    least = _pair_least(ctx, r_arm, o_arm, poses, ctx.clearance, gp.branches, o_on, measure=False)
    if least is None:
        return gp.branches, o_on, ()  # no branches: the compiler finds out
    room = float(least.max())
    if room < ctx.clearance:
        raise _arms_blocked(
            ctx,
            gp,
            room,
            f"the other arm holds the pivot and the routing arm ({r_arm}) lays the cable in "
            f"(sliding at theta = {math.degrees(gp.theta):.1f} deg, stopping {_mm(gp.a)} mm "
            "before the guide)",
        )
    pairs = least >= ctx.clearance
    (_, kept), (_, grasp) = _kept_branches(pairs, r_arm, o_arm)
    return kept, grasp, _kept_pairs(pairs, r_arm, o_arm)


def _check_clear(ctx: PlanningContext, gp: GuidePlan, r_arm: str, coming: bool) -> None:
    """The routing hand's tool keeps the cell's clearance from everything but the guide it
    works at, and the cell's work_clearance from that guide, along the way's Cartesian
    paths up to the slide's end (``coming``) or from there on (every other
    pose: the compiler checks them all, with the arms; leaving the guide before, every pose
    and the checker's clearance from the guides it works between, as the compiler holds
    it), so a way that cannot is not handed to the compiler. (The hand turning with the
    slide swings its fingers towards the guide by more than the published sliding angle
    allows for.)"""
    from cellengine.motion.collision import DEFAULT_CLEARANCE  # the motion stack: planning only

    # Leaving the guide it inserted at, the hand turns and moves off beside it: held, as
    # the compiler holds it (_emit_guide's near), clear of it by the checker's clearance.
    leave = DEFAULT_CLEARANCE, 1
    turn = () if gp.reorient is None else ((r_arm, "facing the guide", SLIDE, gp.reorient, leave),)
    work = ctx.world.cell.work_clearance, 2
    paths = (
        *turn,
        (r_arm, "approaching", SLIDE, gp.approach, leave),
        (r_arm, "sliding", SLIDE, gp.slide, work),
        (r_arm, "pulling", GRASP, gp.pull_path, work),
        (r_arm, "lifting", GRASP, gp.lift, work),
        (r_arm, "swinging over the slot", GRASP, gp.swing, work),
        (r_arm, "inserting", GRASP, gp.insert, work),
    )  # the other hand's descent to the pivot: _pivot_blocked, before the way is built
    n = len(turn) + 2
    for arm, what, mode, poses, (own_limit, stride) in paths[:n] if coming else paths[n:]:
        found = _env_near(ctx, arm, poses, mode, gp.beside, own_limit, stride)
        if found is not None:
            near, limit, own = found
            fix = _env_fix(ctx, near, own, limit)
            raise _Blocked.of(near.distance - limit, _blocked(gp, near, what, limit, fix))


def _check_hands(ctx: PlanningContext, gp: GuidePlan, r_arm: str, o_arm: str) -> None:
    """The two hands keep the cell's clearance from each other while the other one comes
    down to the pivot and holds it, the routing hand working."""
    descend = cg.line(gp.other_above, gp.pivot)
    hands = (
        (r_arm, "ending its slide", SLIDE, [gp.slide[-1]], o_arm, gp.pivot, OPEN),
        (o_arm, "grasping at the pivot", OPEN, descend, r_arm, gp.slide[-1], GRASP),
        (r_arm, "pulling", GRASP, gp.pull_path, o_arm, gp.pivot, GRASP),
        (r_arm, "lifting", GRASP, gp.lift, o_arm, gp.pivot, GRASP),
        (r_arm, "swinging over the slot", GRASP, gp.swing, o_arm, gp.pivot, GRASP),
        (r_arm, "inserting", GRASP, gp.insert, o_arm, gp.pivot, GRASP),
    )
    for arm, what, mode, path, other, T_other, other_mode in hands:
        pair = ctx.probe.between(arm, [*path[::2], path[-1]], mode, other, T_other, other_mode)
        if pair is not None and pair.distance < ctx.clearance:
            fix = (
                f"the cell's clearance is {_mm(ctx.clearance)} mm: the hands would need "
                f"{_short(ctx.clearance - pair.distance)} mm more between them (a longer span of "
                "cable between guides) or narrower tools"
            )
            raise _Blocked.of(
                pair.distance - ctx.clearance, _blocked(gp, pair, what, ctx.clearance, fix)
            )


def _check_self(
    ctx: PlanningContext, gp: GuidePlan, r_arm: str, may: frozenset[int], coming: bool
) -> frozenset[int]:
    """The IK branches of ``may`` (those the routing arm may be on: it does not change branch
    from its last transit on) on which it follows the way's paths, from turning to face the
    guide to the slide's end (``coming``), or from there to the insert, without its tool or
    links coming within the checker's clearance of its own links: near its base, the tool
    turned to a guide can meet the shoulder on every branch (_routing_follows)."""
    paths = (
        (gp.reorient, gp.approach, gp.slide)
        if coming
        else (gp.slide[-1:], gp.pull_path, gp.lift, gp.swing, gp.insert)
    )
    poses = np.concatenate([p for p in paths if p is not None])
    return _routing_follows(ctx, r_arm, poses, may, gp.where, gp.guide)


def _routing_follows(
    ctx: PlanningContext, r_arm: str, poses: Poses, may: frozenset[int], where: str, guide: str
) -> frozenset[int]:
    """The branches of ``may`` on which the routing arm follows ``poses`` (a guide's) clear
    of itself; none: an error that blames the arms (the other arm might route the guide)."""
    from cellengine.execute.following import surviving  # the motion stack: planning only

    alive, nearest = surviving(ctx.cell, ctx.checker, r_arm, poses, ctx.home, may)
    if not alive:
        which = "any of its IK branches" if may == ANY_BRANCH else "the IK branches it may be on"
        error = _error(
            f"{where}: the routing arm ({r_arm}) cannot follow this guide's paths on "
            f"{which} without hitting itself ({', '.join(nearest[1])}; the guide "
            f"is {_mm(_base_distance(ctx, r_arm, guide))} mm from its base)"
        )
        error.blames = "arms"  # the other arm might route it: PickCable decides which
        raise error
    return frozenset(alive)


def _env_near(
    ctx: PlanningContext,
    arm: str,
    poses: Poses,
    mode: str,
    beside: Collection[str],
    own_limit: float | None = None,
    stride: int = 2,
) -> tuple[Nearest, float, bool] | None:
    """The first object ``arm``'s tool comes too near along ``poses`` (every ``stride``-th
    pose and the last), the distance it had to keep and whether it is one of the elements it
    works ``beside``: the cell's clearance from everything else, ``own_limit`` from those
    (None: the cell's work_clearance); None when it keeps both."""
    sampled = [*poses[::stride], poses[-1]]
    own = set(beside)
    work = ctx.world.cell.work_clearance if own_limit is None else own_limit
    for skip, limit, only in ((own, ctx.clearance, None), ((), work, own)):
        near = ctx.probe.nearest(arm, sampled, mode, skip, limit, only)
        if near is not None:
            return near, limit, only is not None
    return None


def _env_fix(ctx: PlanningContext, near: Nearest, own: bool, limit: float | None = None) -> str:
    """What would clear ``near`` (found by :func:`_env_near` with ``limit``; None: the
    cell's work_clearance)."""
    if own:
        work = ctx.world.cell.work_clearance
        limit = work if limit is None else limit
        setting = " (work_clearance in cell.yaml)" if limit == work else ""
        return (
            f"a hand keeps {_mm(limit)} mm from the guides it works between{setting}: "
            f"{near.other} would have to stand {_short(limit - near.distance)} mm farther "
            "from the hand's path (more room between the guides), or the fingers be narrower"
        )
    return (
        f"the cell's clearance is {_mm(ctx.clearance)} mm: {near.other} would have to stand "
        f"{_short(ctx.clearance - near.distance)} mm farther from the hand's path, or the "
        "fingers be narrower"
    )


def _passes(near: Nearest, limit: float) -> str:
    """'would pass D mm from OTHER' (to 0.01 mm where D rounds to the ``limit`` it is
    under), or 'would run D mm into OTHER' where they overlap."""
    if near.distance < 0.0:
        return f"would run {_short(-near.distance)} mm into {near.other}"
    d = _mm_under(near.distance, limit)
    return f"would pass {d} mm from {near.other}"


def _blocked(gp: GuidePlan, near: Nearest, what: str, limit: float, fix: str) -> str:
    side = "left" if gp.side > 0 else "right"
    return (
        f"{gp.where}: {near.tool} {_passes(near, limit)} {what} "
        f"(sliding at theta = {math.degrees(gp.theta):.1f} deg on the {side}, stopping "
        f"{_mm(gp.a)} mm before the guide); {fix}"
    )


def _placed_by_either(rest: Sequence[Skill], cable: str) -> bool:
    """Whether the PlaceConnector of ``cable`` that follows (before the next PickCable)
    leaves the arm to the planner: then either arm may take the connector end."""
    for step in rest:
        if isinstance(step, PickCable):
            break
        if isinstance(step, PlaceConnector) and step.cable == cable:
            return step.arm == "auto"
    return False


def _route_end(rest: Sequence[Skill], cable: str) -> str | None:
    """The last guide ``cable`` is routed through (before the next PickCable), if any."""
    last: str | None = None
    for step in rest:
        if isinstance(step, PickCable):
            break
        if isinstance(step, RouteCable) and step.cable == cable:
            last = step.guides[-1]
    return last


def _works_at(rest: Sequence[Skill], cable: str) -> tuple[str, str] | None:
    """Where the arms work on ``cable`` after its PickCable: the connector guide, and the last
    guide it is routed through (the connector guide when none); None without a
    PlaceConnector (before the next PickCable)."""
    place: str | None = None
    for step in rest:
        if isinstance(step, PickCable):
            break
        if isinstance(step, PlaceConnector) and step.cable == cable:
            place = step.guide
    return None if place is None else (place, _route_end(rest, cable) or place)


def _look_ahead(
    world: World, state: CableState, pick: PickCable, rest: Sequence[Skill]
) -> CableState:
    """Before a PickCable: the arm and guide of the PlaceConnector that follows for the same
    cable (before the next PickCable), so the pick hands the connector end to that arm."""
    for k, step in enumerate(rest):
        if isinstance(step, PickCable):
            break
        if isinstance(step, PlaceConnector) and step.cable == pick.cable:
            try:
                arm = step.connector_arm(world, step=state.step + 1 + k)
            except InputError as e:  # the error is that step's
                raise StepError.wrap(state.step + 1 + k, e) from None
            return replace(state, connector_arm=arm, place_guide=step.guide)
    return replace(state, connector_arm=None, place_guide=None)
