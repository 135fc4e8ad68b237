"""A lab plan to segments: the steps as allocation tasks, the allocator's mission, and each
robot's actions turned into motion primitives in the mission's order.

Each step is a sub-task on one object, made of motion primitives with the skill each needs
(skills/lab_robots.py) and where it starts and ends:

- ``Place``: pick where the object stands, place at ``to``;
- ``Pick``: pick where it stands (the robot keeps it);
- ``Handover``: pick where it stands, put it down at ``at`` (a handover place);
- ``Weigh``: pick, weigh (a load cell), put it back;
- ``Unscrew``: pick, hold at a cooperation place, turn the cap off (another robot, at the
  same time: cooperation mode 2), put it back;
- ``Pour``: pick, pour over ``into``, put it back.

Steps on the same object keep their order in the file (each comes after the previous one on
that object), besides the ``after`` the plan gives. An object chosen at run time
(``heavier_of``) is planned at every candidate's place for the allocation; its motion uses
the masses known (measured, or objects.yaml's until then).

The program runs the mission's actions one robot at a time in the mission's planned order,
so no two robots are ever in the shared zone together except when they cooperate.
"""

from __future__ import annotations

import itertools
import math
from collections import OrderedDict
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from cellengine import geometry as g
from cellengine.allocate import (
    AllocationError,
    AllocationProblem,
    AnyOf,
    Blocker,
    Mission,
    Primitive,
    Robot,
    Task,
    Zone,
    allocate,
)
from cellengine.allocation.options import Action, relocation_id
from cellengine.arrays import Mat
from cellengine.choices import candidates, known_masses, resolve
from cellengine.concurrency import Overlap, SharedZone
from cellengine.context import PlanningContext
from cellengine.errors import InputError, Problem, StepError, at_step
from cellengine.motion.collision import CollisionChecker
from cellengine.motion.robot import CellModel
from cellengine.motion.scene import rearranged, standing_container
from cellengine.program import Segment
from cellengine.skill import Skill
from cellengine.skills import lab_geometry as lg
from cellengine.skills import lab_motion as lm
from cellengine.skills.lab import BimanualCarry, Handover, Pick, Place, Pour, Unscrew, Weigh
from cellengine.skills.lab_blockers import blockers
from cellengine.skills.lab_robots import robot_skills
from cellengine.skills.lab_state import LabState
from cellengine.world import World

LabSkill = Pick | Place | Handover | Unscrew | Weigh | Pour | BimanualCarry
Point = tuple[float, float, float]
# Rough durations (s) of each primitive for the mission's schedule; the executor times the
# real motion.
FREE_RADIUS = 0.05  # m: a place with a container or cap closer than this is taken
SAME_PLACE = 1e-3  # m: a Pick 'from' this near where the object stands names that place
CAP_REACH = 0.02  # m: the reach test of a place for a cap, this high over it
KEPT_ARRANGEMENTS = 8  # reach checkers kept (_Reach): each is MBs
DURATION = {
    "carry": 8.0,
    "pick": 3.0,
    "place": 3.0,
    "weigh": 1.0,
    "hold": 3.0,
    "turn_cap": 8.0,
    "pour": 4.0,
}


@dataclass(frozen=True)
class LabPlan:
    problem: AllocationProblem
    mission: Mission
    segments: list[Segment]
    state: LabState

    def overlap(self, world: World) -> Overlap:
        """What lets both robots work at once (cellengine/concurrency.py): the mission's
        precedence, its cooperations kept in order, the cell's shared zones."""
        after = {
            t.id: frozenset(t.after) | {relocation_id(b.name) for b in t.blocked_by}
            for t in self.problem.tasks
        }
        together = {
            (task, j)
            for task, option in self.mission.options.items()
            for j, part in enumerate(option.segments)
            if part.inserted == "cooperation"
        }
        zones = tuple(
            SharedZone(name, tuple(z.min), tuple(z.max), frozenset(z.robots))
            for name, z in world.cell.zones.items()
            if len(z.robots) > 1
        )
        return Overlap("mission", after, frozenset(together), zones)


def plan_lab_steps(ctx: PlanningContext, steps: Sequence[Skill], overlap: bool = False) -> LabPlan:
    """The mission and its segments (see the module notes), with the masses measured so
    far (``ctx.masses``) over objects.yaml's. ``overlap``: the robots will work at once, so
    a robot goes back to its rest after its work only when it ends in a shared zone."""
    world, cell = ctx.world, ctx.cell
    known = known_masses(world, ctx.masses)
    reach = _Reach(ctx, dict)  # no container for the allocation's reach tests
    problem = build_problem(ctx, steps, reach)
    by_id = {_id(s, i): (i, s) for i, s in enumerate(steps)}
    needs = {b.name: t.id for t in problem.tasks for b in t.blocked_by}
    try:
        mission = allocate(problem)
    except AllocationError as e:  # at the line of the step whose task it is
        task = needs.get(e.task.split(":", 1)[1], "") if e.task and ":" in e.task else e.task
        index = by_id[task][0] if task in by_id else None
        raise StepError(Problem(str(e)), index) from None
    except ValueError as e:
        raise InputError(Problem(str(e))) from None
    tcp = {name: ctx.tcp_home(name) for name in cell.arms}
    kept = _kept(mission, lambda t: _object_of(by_id, t, known)) if overlap else frozenset()
    b = lm.Builder(LabState.start(world, tcp))
    reach.where = lambda: b.state.where
    for task in mission.order:
        if task not in by_id:  # a blocker moved out of the way ("clear:<name>")
            name = task.split(":", 1)[1]
            i = by_id[needs[name]][0]
            b.state = replace(b.state, step=i)
            b.tag = {"mission": (task, 0)}
            with at_step(i):
                _clear(b, world, reach, name, _actions(mission, task), f"steps[{i}] clear {name}")
            for arm in dict.fromkeys(a.robot for a in _actions(mission, task)):
                if not overlap or _in_shared(world, b.state.tcp[arm]):
                    b.add(f"steps[{i}] clear {name}: {arm} back", [lm.transit(arm, tcp[arm])])
            continue
        i, step = by_id[task]
        with at_step(i):
            _step(ctx, b, reach, mission, task, i, step, known, tcp, kept if overlap else None)
    if overlap:
        _all_back(b, tcp)
    b.tag = {}
    return LabPlan(problem, mission, b.segments, b.state)


def _kept(mission: Mission, object_of: Callable[[str], str | None]) -> frozenset[Action]:
    """The places a robot need not do when the robots work at once: those its own next
    action picks the same object up again after, with no task between them on it."""
    out: set[Action] = set()
    order = list(mission.order)
    for acts in mission.actions.values():
        for a, nxt in itertools.pairwise(acts):
            name = object_of(a.step)
            if a.kind != "place" or nxt.kind != "pick" or name is None:
                continue
            if object_of(nxt.step) != name or a.step == nxt.step:
                continue
            between = order[order.index(a.step) + 1 : order.index(nxt.step)]
            if all(object_of(t) != name for t in between):
                out.add(a)
    return frozenset(out)


def _object_of(
    by_id: Mapping[str, tuple[int, Skill]], task: str, known: Mapping[str, float]
) -> str | None:
    """The object a task works on (a relocation: its blocker)."""
    if task not in by_id:
        return task.split(":", 1)[1] if ":" in task else None
    step = by_id[task][1]
    obj = getattr(step, "object", None)
    return None if obj is None else resolve(obj, known)


def _all_back(b: lm.Builder, tcp: Mapping[str, Mat]) -> None:
    """Every robot not at its rest goes back, as part of the last task it worked in: the
    plan ends where it started, as when the robots work one after another."""
    for arm, T in tcp.items():
        if np.allclose(b.state.tcp[arm], T, atol=1e-9):
            continue
        last = next((s for s in reversed(b.segments) if arm in s.arms()), None)
        if last is None:
            continue
        b.state = replace(b.state, step=last.step)
        b.tag = {"mission": last.facts["mission"]}
        head = last.label.split(":", 1)[0]
        b.add(f"{head}: {arm} back to its rest", [lm.transit(arm, T)])


def _step(
    ctx: PlanningContext,
    b: lm.Builder,
    reach: _Reach,
    mission: Mission,
    task: str,
    i: int,
    step: Skill,
    known: Mapping[str, float],
    tcp: Mapping[str, Mat],
    kept: frozenset[Action] | None,
) -> None:
    """The segments of one step's task in the mission; ``kept``: the robots work at once,
    and these places are not done (the robot keeps the object for its next pick)."""
    world, cell = ctx.world, ctx.cell
    assert isinstance(step, LabSkill)  # _tasks refused any other
    b.state = replace(b.state, step=i)
    where = f"steps[{i}] {step.skill}"
    overlap = kept is not None
    actions = [a for a in _actions(mission, task) if a not in (kept or ())]
    for k, action in enumerate(actions):
        prev = actions[k - 1] if k else None
        b.tag = {"mission": (task, _part(mission, task, action))}
        if prev is not None and prev.robot != action.robot and prev.kind != "hold":
            # a robot that hands over (or is done) leaves before the other comes in
            b.add(
                f"{where}: {prev.robot} back to its rest",
                [lm.transit(prev.robot, tcp[prev.robot])],
            )
        _do(b, world, cell, reach, step, action, known, where, actions)
    # as the published platform does: each robot retracts after its work, so the next
    # task finds the shared zone clear (working at once, only one that ends in it); a
    # turner first puts the cap down, once the holder has gone
    turners = [a.robot for a in actions if a.kind == "turn_cap"]
    for arm in dict.fromkeys(a.robot for a in actions if a.robot not in turners):
        place = next((a for a in kept or () if a.step == task and a.robot == arm), None)
        _back(b, reach, world, cell, step, arm, tcp[arm], known, where, overlap, place)
    for arm in turners:
        name = resolve(step.object, known)
        T = _cap_place(world, b, reach, arm)
        lm.put_cap_down(b, reach, world, arm, name, T, where)
        _back(b, reach, world, cell, step, arm, tcp[arm], known, where, overlap)


def _back(
    b: lm.Builder,
    reach: _Reach,
    world: World,
    cell: CellModel,
    step: LabSkill,
    arm: str,
    rest: Mat,
    known: Mapping[str, float],
    where: str,
    overlap: bool,
    place: Action | None = None,
) -> None:
    """``arm`` back to its ``rest`` after its work in a step: always one after another;
    at once, only out of a shared zone. An arm keeping what it holds for its next pick
    (``place``: the place it left out) goes back with it as it holds it, or, where that
    is out of reach, puts it down after all."""
    if overlap and not _in_shared(world, b.state.tcp[arm]):
        return
    held = b.state.held.get(arm)
    if held is not None and place is not None:
        T = np.array(b.state.tcp[arm], dtype=float)
        T[:3, 3] = np.asarray(rest)[:3, 3]
        if reach(arm, T, (held.name,)):
            b.add(f"{where}: {arm} back to its rest", [lm.transit(arm, T)])
            return
        _do(b, world, cell, reach, step, place, known, where)
    b.add(f"{where}: {arm} back to its rest", [lm.transit(arm, rest)])


# ------------------------------------------------------------------------------ the problem


def build_problem(
    ctx: PlanningContext, steps: Sequence[Skill], reach: lm.Solver
) -> AllocationProblem:
    world, cell = ctx.world, ctx.cell
    skills = robot_skills(world, cell)
    robots = tuple(
        Robot(
            name,
            skills[name],
            _point(ctx.tcp_home(name)[:3, 3]),
            reach=_point_reach(world, name, reach),
        )
        for name in cell.arms
    )
    zones = tuple(Zone(n, z.min, z.max, frozenset(z.robots)) for n, z in world.cell.zones.items())
    handovers = tuple(
        _point(world.pose(ref)[:3, 3]) for z in world.cell.zones.values() for ref in z.handovers
    )
    tasks = tuple(_tasks(ctx, steps))
    return AllocationProblem(robots, tasks, zones, handovers, length_unit=world.cell.units.length)


def _tasks(ctx: PlanningContext, steps: Sequence[Skill]) -> list[Task]:
    world = ctx.world
    last_on: dict[str, str] = {}  # object -> the id of the last step on it
    # where plan steps put things: not free for a blocker
    targets = {
        _point(world.pose(ref)[:3, 3])
        for s in steps
        for ref in (getattr(s, "to", None), getattr(s, "at", None))
        if isinstance(ref, str)
    }
    where: dict[str, Point] = {
        n: _point(world.standing(c)[:3, 3])
        for n, c in world.objects.containers.items()
        if c.at is not None
    }
    out = []
    for i in range(len(steps)):
        with at_step(i):
            out.append(_task(ctx, steps, i, where, targets, last_on))
    return out


def _task(
    ctx: PlanningContext,
    steps: Sequence[Skill],
    i: int,
    where: dict[str, Point],
    targets: set[Point],
    last_on: dict[str, str],
) -> Task:
    """Step ``i`` as an allocation task; ``where`` and ``last_on`` follow the plan so far."""
    world, step = ctx.world, steps[i]
    if not isinstance(step, LabSkill):
        raise InputError(Problem(f"steps[{i}]: {step.skill} is not a lab skill"))
    names = candidates(step.object)
    for n in names:
        if n not in where:
            raise InputError(
                Problem(
                    f"steps[{i}] {step.skill}: '{n}' stands nowhere: the lab skills move "
                    "containers, each given where it stands ('at') in objects.yaml"
                )
            )
    _check_parameters(world, step, i, names, where)
    loc: Point | AnyOf = (
        where[names[0]] if len(names) == 1 else AnyOf(tuple(where[n] for n in names))
    )
    prims = _primitives(world, step, loc, where)
    blocked = _blocked(ctx, step, names, where, targets) if len(names) == 1 else ()
    after = set(step.after) | {last_on[n] for n in names if n in last_on}
    arms = (
        None
        if step.arm == "auto"
        else (tuple(world.cell.robots) if step.arm == "both" else (step.arm,))
    )
    tid = _id(step, i)
    for n in names:
        last_on[n] = tid
    if isinstance(step, Place | Handover):
        target = step.to if isinstance(step, Place) else step.at
        if target is not None:
            for n in names:
                where[n] = _point(world.pose(target)[:3, 3])
    return Task(tid, prims, tuple(sorted(after)), arms, blocked)


def _check_parameters(
    world: World, step: LabSkill, i: int, names: Sequence[str], where: Mapping[str, Point]
) -> None:
    """The parameters a step gives are ones it can use: a Pick ``from`` where the object
    stands at that step, Unscrew ``turns`` that take the cap off and no more than a turn
    past."""
    what = f"steps[{i}] {step.skill}"
    if isinstance(step, Pick) and step.from_ is not None:
        at = _point(world.pose(step.from_)[:3, 3])
        for n in names:
            if math.dist(at, where[n]) > SAME_PLACE:
                x, y, z = (round(v * 1000.0, 1) for v in where[n])
                raise InputError(
                    Problem(
                        f"{what}: '{n}' stands at ({x}, {y}, {z}) mm at this step, not at "
                        f"'{step.from_}'; leave 'from' out (it is where the object stands)"
                    )
                )
    if isinstance(step, Unscrew) and step.turns is not None:
        for n in names:
            cap = world.container(n).cap
            if cap is not None and not cap.turns <= step.turns <= cap.turns + 1.0:
                raise InputError(
                    Problem(
                        f"{what}: turns {step.turns:g} for '{n}', whose cap comes off in "
                        f"{cap.turns:g}: give {cap.turns:g} to {cap.turns + 1.0:g} (fewer "
                        "leave it on; it is off after one more), or leave turns out"
                    )
                )


def _blocked(
    ctx: PlanningContext,
    step: LabSkill,
    names: Sequence[str],
    where: Mapping[str, Point],
    targets: set[Point],
) -> tuple[Blocker, ...]:
    """The containers in the way of every grasp of the step's object (skills/lab_blockers),
    each with the zones' free places it may go to."""
    world, name = ctx.world, names[0]
    if world.container(name).at is None:
        return ()
    robots = [r for r in ctx.cell.arms if step.arm in ("auto", "both", r)]
    found = blockers(ctx, name, _pose_at(where[name]), robots)
    if not found:
        return ()
    taken = set(where.values()) | targets
    spots = tuple(
        p
        for p in (_point(world.pose(r)[:3, 3]) for z in world.cell.zones.values() for r in z.free)
        if all(np.linalg.norm(np.subtract(p, q)) > FREE_RADIUS for q in taken)
    )
    return tuple(Blocker(b, where[b], spots, duration=DURATION["pick"]) for b in found)


def _primitives(
    world: World, step: LabSkill, loc: Point | AnyOf, where: Mapping[str, Point]
) -> tuple[Primitive, ...]:
    """A start of None is where the object is at that moment (in a hand, or where the last
    primitive left it): the allocator inserts a handover when another robot takes over."""

    def p(
        kind: str, start: Point | AnyOf | None, end: Point | AnyOf | None = None, **kw: bool
    ) -> Primitive:
        return Primitive(kind, kind, start, end, DURATION[kind], **kw)

    pick = p("pick", loc)
    back = p("place", None, loc, releases=True)  # where it was picked
    if isinstance(step, Place):
        return (pick, p("place", None, _point(world.pose(step.to)[:3, 3]), releases=True))
    if isinstance(step, Pick):
        return (pick,)
    if isinstance(step, Handover):
        if step.at is None:
            return (pick,)
        return (pick, p("place", None, _point(world.pose(step.at)[:3, 3]), releases=True))
    if isinstance(step, Weigh):
        return (pick, p("weigh", None), back)
    if isinstance(step, Unscrew):
        meet = _cooperation(world)
        return (pick, p("hold", meet, meet), p("turn_cap", meet, meet, with_previous=True), back)
    if isinstance(step, BimanualCarry):
        # two hands at once: a cooperation of any two robots with grippers
        to = _point(world.pose(step.to)[:3, 3])
        return (
            Primitive("carry", "pick", loc, to, DURATION["carry"]),
            Primitive("carry", "pick", loc, to, DURATION["carry"], with_previous=True),
        )
    assert isinstance(step, Pour)
    targets = candidates(step.into)
    into: Point | AnyOf = (
        where[targets[0]] if len(targets) == 1 else AnyOf(tuple(where[n] for n in targets))
    )
    return (pick, p("pour", into, into), back)


# ------------------------------------------------------------------------------- the motion


def _actions(mission: Mission, task: str) -> list[Action]:
    return [a for seg in mission.options[task].segments for a in seg.actions]


def _part(mission: Mission, task: str, action: Action) -> int:
    """The index of the mission part (schedule entry) of ``task`` that ``action`` is in."""
    return next(j for j, seg in enumerate(mission.options[task].segments) if action in seg.actions)


def mission_json(
    mission: Mission, segments: Sequence[tuple[Any, float, float]]
) -> list[dict[str, Any]]:
    """report.json's ``mission``: each part of each step (one robot's run, a handover side,
    a cooperation, an obstacle moved), its robots, its start and end in the program (s)
    and the allocator's estimate of them; ``segments``: each compiled segment's mission
    part (task, index; None: none) with its start and end."""
    spans: dict[tuple[str, int], tuple[float, float]] = {}
    for key, t0, t1 in segments:
        if key is not None:
            k = (str(key[0]), int(key[1]))
            lo, hi = spans.get(k, (t0, t1))
            spans[k] = (min(lo, t0), max(hi, t1))
    out = []
    for (task, j), (lo, hi) in spans.items():
        part = mission.options[task].segments[j]
        # a task's parts follow one another: its schedule entries in time order are its parts
        est = [e for e in mission.schedule if e.step == task][j]
        out.append(
            {
                "step": task,
                "arms": list(part.robots),
                "start": round(lo, 6),
                "end": round(hi, 6),
                "inserted": part.inserted,
                "estimate": [round(est.start, 6), round(est.end, 6)],
            }
        )
    return sorted(out, key=lambda e: (float(e["start"]), float(e["end"])))


def _do(
    b: lm.Builder,
    world: World,
    cell: CellModel,
    reach: lm.Solver,
    step: LabSkill,
    a: Action,
    masses: Mapping[str, float],
    where: str,
    actions: Sequence[Action] = (),
) -> None:
    """One action of a step; ``actions``: all the step's (a carry needs its partner's)."""
    name = resolve(step.object, masses)
    names = candidates(step.object)

    def at(loc: tuple[Point, ...]) -> Mat:
        # a location planned for every candidate object: the chosen one's
        return _pose_at(loc[names.index(name)] if len(loc) == len(names) else loc[0])

    arm = a.robot
    grasp = _grasp(world, arm)
    if a.kind in ("pick", "handover_pick"):
        if b.state.holder(name) != arm:
            lm.pick(b, reach, world, arm, name, grasp, where)
    elif a.kind in ("place", "handover_place"):
        lm.place(b, reach, arm, at(a.end), where)
    elif a.kind == "weigh":
        lm.weigh(b, arm, name, where)
    elif a.kind == "hold":
        lm.hold(b, reach, arm, at(a.start), where)
    elif a.kind == "turn_cap":
        assert isinstance(step, Unscrew)
        lm.unscrew(b, reach, world, arm, name, where, step.turns)
    elif a.kind == "carry":
        assert isinstance(step, BimanualCarry)
        pair = [x for x in actions if x.kind == "carry"]
        if a is pair[0]:  # the first carries for both; the second is the follower's part
            to = world.pose(step.to)
            lm.carry_together(b, reach, world, a.robot, pair[1].robot, name, to, where)
    elif a.kind == "pour":
        assert isinstance(step, Pour)
        lm.pour(b, reach, world, arm, name, resolve(step.into, masses), step.angle, where)
    else:
        raise InputError(Problem(f"{where}: no motion for '{a.kind}'"))


def _clear(
    b: lm.Builder, world: World, reach: lm.Solver, name: str, actions: list[Action], where: str
) -> None:
    """Move blocker ``name`` to the free place the allocator chose."""
    for a in actions:
        if a.kind in ("pick", "handover_pick"):
            lm.pick(b, reach, world, a.robot, name, _grasp(world, a.robot), where)
        elif a.kind in ("place", "handover_place"):
            lm.place(b, reach, a.robot, _pose_at(a.end[0]), where)
        else:
            raise InputError(Problem(f"{where}: no motion for '{a.kind}'"))


def _cap_place(world: World, b: lm.Builder, reach: lm.Solver, arm: str) -> Mat:
    """Where a cap goes: the zones' free places (then their handover places) with nothing
    on them, nearest the arm's fingertips first, the first the arm reaches."""
    refs = [r for z in world.cell.zones.values() for r in z.free]
    refs += [r for z in world.cell.zones.values() for r in z.handovers]
    taken = [T[:3, 3] for T in (*b.state.where.values(), *b.state.caps.values())]
    here = b.state.tcp[arm][:3, 3]
    places = sorted(
        (world.pose(r) for r in dict.fromkeys(refs)),
        key=lambda T: float(np.linalg.norm(T[:3, 3] - here)),
    )
    for T in places:
        free = all(np.linalg.norm(T[:3, 3] - p) > FREE_RADIUS for p in taken)
        if free and reach(arm, lg.top_grasp(T[:3, 3] + CAP_REACH * lg.UP, 0.0)):
            return T
    raise InputError(
        Problem(
            f"no free place within reach of arm '{arm}' to put a cap down: list some in a "
            "zone's 'free' (or 'handovers')"
        )
    )


# ------------------------------------------------------------------------------- helpers


class _Reach:
    """Reach tests (lm.Solver) in the scene as it is now: the containers standing where the
    plan has put them so far (``where()``), the held ones and those ignored left out; the
    other arms at home. Checkers are kept for the latest KEPT_ARRANGEMENTS arrangements (a
    plan comes back to a few again and again; all of a long plan's would grow its memory
    with its steps)."""

    def __init__(self, ctx: PlanningContext, where: Callable[[], Mapping[str, Mat]]) -> None:
        self.world, self.cell, self.where = ctx.world, ctx.cell, where
        self.iks = ctx.iks
        self.home = ctx.home
        self.scene = ctx.scene
        self.checkers: OrderedDict[tuple[object, ...], CollisionChecker] = OrderedDict()

    def __call__(self, arm: str, T_cell_tcp: Mat, ignore: Sequence[str] = ()) -> bool:
        checker = self._checker(ignore)
        q = np.array(self.home, dtype=float)
        for sol in self.iks[arm].solve_all(T_cell_tcp):
            q[self.cell.slices[arm]] = sol
            if checker.check(q) is None:
                return True
        return False

    def _checker(self, ignore: Sequence[str]) -> CollisionChecker:
        standing = {n: T for n, T in self.where().items() if n not in ignore}
        key = tuple(sorted((n, tuple(np.round(T[:3, 3], 6))) for n, T in standing.items()))
        checker = self.checkers.pop(key, None)
        if checker is None:
            containers = self.world.objects.containers
            statics = [s for s in self.scene.statics if s.name not in containers]
            statics += [standing_container(self.world, n, T) for n, T in sorted(standing.items())]
            checker = CollisionChecker(rearranged(self.scene, statics, {}, {}))
        self.checkers[key] = checker
        while len(self.checkers) > KEPT_ARRANGEMENTS:
            self.checkers.popitem(last=False)
        return checker


def _point_reach(world: World, arm: str, reach: lm.Solver) -> Callable[[Point], bool]:
    """Whether the arm can grasp something standing at a point (its tool's grasp, any
    heading), cached per point."""
    grasp = _grasp(world, arm)
    base = world.cell.robots[arm].base.matrix()[:3, 3]
    body = lg.Body(0.06, 0.028, 0.0)  # a typical vial: the reach test of a place
    seen: dict[Point, bool] = {}

    def test(p: Point) -> bool:
        if p not in seen:
            T_at = np.eye(4)
            T_at[:3, 3] = p
            seen[p] = any(
                reach(arm, T) and reach(arm, lg.lifted(T))
                for T in lg.grasp_candidates(grasp, T_at, body, base)
            )
        return seen[p]

    return test


def _grasp(world: World, arm: str) -> lg.Grasp:
    tool = world.cell.robots[arm].tool
    return world.cell.tools[tool].grasp if tool is not None else "top"


def _in_shared(world: World, T_cell_tcp: Mat) -> bool:
    """Whether a TCP is in a zone more than one robot works in."""
    p = np.asarray(T_cell_tcp)[:3, 3]
    return any(
        len(z.robots) > 1 and bool(np.all(p >= z.min) and np.all(p <= z.max))
        for z in world.cell.zones.values()
    )


def _cooperation(world: World) -> Point:
    for z in world.cell.zones.values():
        if z.cooperation:
            return _point(world.pose(z.cooperation[0])[:3, 3])
    raise InputError(
        Problem("Unscrew needs a cooperation place: give a shared zone 'cooperation: [keypoint]'")
    )


def _pose_at(p: Point) -> Mat:
    return g.transform(None, p)


def _point(v: Sequence[float] | np.ndarray) -> Point:
    return (float(v[0]), float(v[1]), float(v[2]))


def _id(step: Skill, i: int) -> str:
    return step.id if step.id is not None else f"step{i + 1}"
