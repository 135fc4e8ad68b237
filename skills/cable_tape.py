"""Tape (issue #15): a cable, harness or branch laid through guides is taped between two of
them (REMODEL's T operation, HARNESS.md 2.6).

One hand holds the bundle beside the hold guide, on the far side from the taped span: its
fingertips on the route, its fingers the cell's work clearance from the guide's face. The
other brings the taping gun down to the midpoint of the two guides' slots, its x along the
cable (either way round), and the gun tapes for its ``dwell`` with both arms standing still
(the segment's trigger: a driver output). Then the gun goes back up and the hand lets go.

Which arm tapes: the one whose base is nearer the taped span first, the other after it
(REMODEL picks by the slots' x in its torso frame). Each arm gets the tool the work needs
first (a taping gun, a gripper), through the tool changer, as a ChangeTool would.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Annotated, Literal

import numpy as np

from cellengine.arrays import Mat, Vec
from cellengine.errors import InputError
from cellengine.info.units import count
from cellengine.program import GripperEvent, Segment
from cellengine.skill import CableRef, GuideRef, Skill
from cellengine.skills import cable as c
from cellengine.skills import cable_geometry as cg
from cellengine.skills import cable_tools
from cellengine.skills.cable_state import CableState
from cellengine.world import World

if TYPE_CHECKING:
    from cellengine.context import PlanningContext

GUN = "taping_gun"
# how far each hand tips its flange away from the other's (rad): upright first
LEANS = (0.0, cg.LEAN, cg.PIVOT_LEAN)


class Tape(Skill):
    """Tape ``cable`` between two guides of its route, held beside ``hold``."""

    skill: Literal["Tape"]
    cable: CableRef
    between: Annotated[tuple[GuideRef, GuideRef], count(2, "guides [one, other]")]
    hold: GuideRef


@dataclass(frozen=True)
class Taping:
    """Where the work is (cell frame, m): the gun's TCP at the midpoint, along the cable
    (``along``, unit), the holding hand's fingertips, the platform's up."""

    mid: Vec
    along: Vec
    hold: Vec
    hold_along: Vec
    up: Vec
    face_gap: float  # m from the hold guide's face to the holding fingers


def taping(
    ctx: PlanningContext, step: Tape, finger: float, where: str, away: bool = True
) -> Taping:
    """The work's geometry for a holding hand whose fingers are ``finger`` thick along the
    cable, on the side of the hold guide away from the taped span (``away``) or towards
    it."""
    world = ctx.world
    a, b = (cg.position(world, ref) for ref in step.between)
    up = cg.platform_up(world, step.hold)
    mid = (a + b) / 2.0
    along = cg.horizontal(b - a, up)
    p_hold = cg.position(world, step.hold)
    x = cg.horizontal(cg.keypoint_x(world, step.hold), up)
    side = 1.0 if float((p_hold - mid) @ x) >= 0.0 else -1.0  # away from the taped span
    side = side if away else -side
    length = cg.GuideDims.of(world, step.hold, where).length
    gap = world.cell.work_clearance
    hold = p_hold + side * (length / 2.0 + gap + finger / 2.0) * x
    return Taping(mid, along, hold, x, up, gap)


def tape_ways(
    ctx: PlanningContext, step: Tape, state: CableState
) -> Iterator[tuple[list[Segment], CableState]]:
    """The ways to tape, best first: each arm taping (nearer the span first), each way round
    of the gun, after what the hands hold is let go and the tools changed."""
    where = f"steps[{state.step}] Tape {step.cable}"
    a, b = (cg.position(ctx.world, r) for r in step.between)
    mid = (a + b) / 2.0
    arms = sorted(state.arms, key=lambda a: _base_distance(ctx, a, mid))
    first: InputError | None = None
    found = False
    for taper in arms:
        holder = next(a for a in state.arms if a != taper)
        for released, after in c.release_ways(ctx, state):
            try:
                segments, ready = _tooled_for(
                    ctx, after, {taper: GUN, holder: cable_tools.GRIPPER}, where
                )
                tooled = ctx.tooled(ready.tools)
                for work, done in _work(tooled, step, ready, taper, holder, where):
                    found = True
                    yield [*released, *segments, *work], done
            except InputError as e:
                first = first or e
    if not found and first is not None:
        raise first


def _tooled_for(
    ctx: PlanningContext, state: CableState, need: dict[str, str], where: str
) -> tuple[list[Segment], CableState]:
    """The tool changes that give each arm of ``need`` its kind of tool, and the state after."""
    segments: list[Segment] = []
    for arm, tool in cable_tools.fitting(ctx, state, need, where).items():
        label = f"ChangeTool {arm} (for Tape)"
        more, state = cable_tools.change(ctx, state, arm, tool, where, label)
        segments += more
    return segments, state


def _work(
    ctx: PlanningContext, step: Tape, state: CableState, taper: str, holder: str, where: str
) -> Iterator[tuple[list[Segment], CableState]]:
    """The hand holding, the gun taping (each way round), both leaving."""
    fingers = ctx.cell.arms[holder].fingers
    finger = fingers.size[0] if fingers is not None else 0.0
    dwell = ctx.world.cell.tools[state.tools[taper] or ""].dwell or 0.0
    first: InputError | None = None
    for lean, away, along in itertools.product(LEANS, (True, False), (1.0, -1.0)):
        # each hand tipped away from the other (their wrists apart), upright first; the hand
        # outside the span, then inside; the gun either way round
        t = taping(ctx, step, finger, where, away)
        T_hold = cg.tcp_frame(t.hold, t.hold_along, t.up, t.hold - t.mid, lean)
        T_hold_above = cg.lifted(T_hold, t.up, _above(ctx, [step.hold], t.up))
        rise = _above(ctx, step.between, t.up)
        T_gun = cg.tcp_frame(t.mid, along * t.along, t.up, t.mid - t.hold, lean)
        T_gun_above = cg.lifted(T_gun, t.up, rise)
        try:
            hold = [("holding approach", T_hold_above), ("holding grasp", T_hold)]
            c._check_reach(ctx, holder, hold, where)
            gun = [("taping approach", T_gun_above), ("taping", T_gun)]
            c._check_reach(ctx, taper, gun, where)
        except InputError as e:
            first = first or e
            continue
        poses = (T_hold_above, T_hold), (T_gun_above, T_gun)
        yield _segments(step, state, taper, holder, *poses, dwell, t)
    if first is not None:
        raise first


def _segments(
    step: Tape,
    state: CableState,
    taper: str,
    holder: str,
    hold: tuple[Mat, Mat],
    gun: tuple[Mat, Mat],
    dwell: float,
    t: Taping,
) -> tuple[list[Segment], CableState]:
    a, b = step.between
    label = f"Tape {step.cable}"
    guide = cg.element_of(step.hold)
    taped = [(taper, cg.element_of(a)), (taper, cg.element_of(b))]
    bld = c._Builder(state)
    bld.add(
        f"{label}: {holder} over {step.hold}",
        [c._transit(holder, hold[0])],
        before=bld.mode_event(holder, c.OPEN, None),
    )
    bld.add(
        f"{label}: {holder} holds it beside {step.hold}",
        [c._cartesian(holder, cg.line(*hold))],
        after=[GripperEvent(holder, c.GRASP, step.cable)],
        near=[(holder, guide)],
    )
    beside = [(holder, guide)]  # the holding hand stays there until it lets go
    bld.add(f"{label}: {taper} over {a}-{b}", [c._transit(taper, gun[0])], near=beside)
    bld.add(f"{label}: gun down", [c._cartesian(taper, cg.line(*gun))], near=taped + beside)
    facts = {
        "tape_point": [float(v) for v in t.mid],
        "hold_point": [float(v) for v in t.hold],
        "hold_guide": step.hold,
        "hold_from_face_m": t.face_gap,
        "dwell_s": dwell,
    }
    bld.segments.append(
        Segment(
            step=state.step,
            label=f"{label}: tapes between {a} and {b}",
            hold=dwell,
            triggers=(taper,),
            near=(*taped, *beside),
            facts=facts,
        )
    )
    up = [c._cartesian(taper, cg.line(gun[1], gun[0]))]
    bld.add(f"{label}: gun up", up, near=taped + beside)
    bld.add(
        f"{label}: {holder} lets go",
        [c._cartesian(holder, cg.line(hold[1], hold[0]))],
        before=[GripperEvent(holder, c.OPEN)],
        near=[(holder, guide)],
    )
    done = bld.state.transited(taper, holder)
    return bld.segments, replace(done, held={})


def _above(ctx: PlanningContext, guides: Sequence[str], up: Vec) -> float:
    """How high over its work a hand starts down: the approach height over the tops of
    ``guides`` (over their slots)."""
    tops = [cg.rise(ctx.world, ref, up) for ref in guides]
    return max((h for h in tops if h is not None), default=0.0) + cg.APPROACH_HEIGHT


def _base_distance(ctx: PlanningContext, arm: str, p: Vec) -> float:
    """Horizontal distance (m) from ``arm``'s base to ``p``."""
    d = p - ctx.cell.arms[arm].T_cell_base[:3, 3]
    return float(np.hypot(d[0], d[1]))


def check(world: World, steps: Sequence[Skill]) -> list[tuple[tuple[str | int, ...], str]]:
    """Each Tape step's cables are laid through both of its guides, next to each other on
    their route, and through its hold guide, by the steps before it (plan facts: checked
    before any motion)."""
    objects = world.objects

    def canon(ref: str) -> str:  # platform.element names its first keypoint
        try:
            _, element, keypoint = world.resolve(ref)
        except LookupError:
            return ref  # the plan's references are checked on their own
        return f"{ref.split('.')[0]}.{element.name}.{keypoint.name}"

    placed: dict[str, str] = {}  # cable, harness -> its connector guide
    routes: dict[str, list[str]] = {}  # single cable -> the guides it lies through
    out: list[tuple[tuple[str | int, ...], str]] = []
    for i, step in enumerate(steps):
        if isinstance(step, c.PlaceConnector):
            placed[step.cable] = canon(step.guide)
        elif isinstance(step, c.RouteCable):
            owner = objects.branch_of(step.cable)
            start = placed.get(owner[0] if owner is not None else step.cable)
            for n in objects.cables_of(step.cable):
                routes[n] = [*([start] if start else []), *map(canon, step.guides)]
        elif isinstance(step, Tape):
            refs = (canon(step.between[0]), canon(step.between[1]), canon(step.hold))
            out += _laid(objects.cables_of(step.cable), routes, step, refs, i)
    return out


def _laid(
    cables: Sequence[str],
    routes: dict[str, list[str]],
    step: Tape,
    refs: tuple[str, str, str],
    i: int,
) -> list[tuple[tuple[str | int, ...], str]]:
    """The cables of ``cables`` routed so far that run straight between the two guides are
    taped there (a harness's trunk, its branches that went on elsewhere not): at least one
    must, and each of those must lie in the hold guide."""
    a, b, hold = refs
    routed = [n for n in cables if n in routes]
    if not routed:
        what = (
            f"{step.cable} is not"
            if list(cables) == [step.cable]
            else f"none of {step.cable}'s cables is"
        )
        message = f"{what} routed before this step: tape it after the RouteCable that lays it"
        return [(("steps", i, "cable"), message)]

    def straight(route: list[str]) -> bool:
        return any({route[k], route[k + 1]} == {a, b} for k in range(len(route) - 1))

    laid = [n for n in routed if straight(routes[n])]
    if not laid:
        n = routed[0]
        what = step.cable if n == step.cable else f"{n} of {step.cable}"
        return [
            (
                ("steps", i, "between"),
                f"{what} does not run straight from {a} to {b}: its route is "
                f"{', '.join(routes[n])} (tape between two guides next to each other on it)",
            )
        ]
    for n in laid:
        if hold not in routes[n]:
            what = step.cable if n == step.cable else f"{n} of {step.cable}"
            return [
                (
                    ("steps", i, "hold"),
                    f"{what} does not lie in {hold}: its route is {', '.join(routes[n])} "
                    "(hold it beside a guide it lies in)",
                )
            ]
    return []
