"""Building the problem: every way an alliance can do each task (no search here).

An option assigns each primitive to a robot of the alliance. Where the robot holding the
object changes between primitives, a handover (mode 1) is inserted at a handover position
both robots reach; primitives that run at once (``with_previous``) form a cooperation
(mode 2) by distinct robots. Blockers become relocation tasks, one option per free spot.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, replace
from graphlib import CycleError, TopologicalSorter

from cellengine.allocation.model import (
    AllocationError,
    AllocationProblem,
    Blocker,
    Inserted,
    Loc,
    Point,
    Primitive,
    Robot,
    Task,
    distance,
    fmt_loc,
    resolve,
)

HANDOVER_SKILL = "handover"  # any robot holding an object can put it down and pick it up


@dataclass(frozen=True)
class Action:
    """A primitive as one robot does it, locations resolved."""

    robot: str
    step: str
    kind: str
    skill: str
    start: Loc
    end: Loc
    duration: float
    inserted: Inserted


@dataclass(frozen=True)
class Stint:
    """Actions of one task that run as one schedule entry: one robot's run, a cooperation
    (several robots at once), or one side of a handover."""

    robots: tuple[str, ...]
    actions: tuple[Action, ...]
    inserted: Inserted
    zones: frozenset[str]  # the shared zones it works in

    @property
    def duration(self) -> float:
        return max(sum(a.duration for a in self.actions if a.robot == r) for r in self.robots)


@dataclass(frozen=True)
class Option:
    """One way to do a task: the alliance and its segments in order."""

    task: str
    alliance: tuple[str, ...]
    segments: tuple[Stint, ...]
    spot: Point | None = None  # a relocation's chosen free spot

    def actions(self, robot: str) -> tuple[Action, ...]:
        return tuple(a for s in self.segments for a in s.actions if a.robot == robot)

    def entry(self, robot: str) -> Loc:
        return self.actions(robot)[0].start

    def exit(self, robot: str) -> Loc:
        return self.actions(robot)[-1].end

    def internal(self, robot: str) -> float:
        """The distance the robot travels within the task."""
        acts = self.actions(robot)
        moves = sum(distance(a.start, a.end) for a in acts)
        return moves + sum(distance(a.end, b.start) for a, b in itertools.pairwise(acts))


@dataclass(frozen=True)
class Expanded:
    """The built problem: the plan's tasks (blocked ones now after their relocations), then
    one relocation task per blocker, and every option of each."""

    problem: AllocationProblem
    tasks: tuple[Task, ...]
    options: dict[str, tuple[Option, ...]]
    relocations: dict[str, Blocker]  # relocation task id -> its blocker


def relocation_id(blocker: str) -> str:
    return f"clear:{blocker}"


def expand(problem: AllocationProblem) -> Expanded:
    tasks, relocations = _with_relocations(problem)
    _check_graph(problem, tasks)
    options = {t.id: _options(problem, t, relocations.get(t.id)) for t in tasks}
    return Expanded(problem, tasks, options, relocations)


def _with_relocations(problem: AllocationProblem) -> tuple[tuple[Task, ...], dict[str, Blocker]]:
    """A blocker named by several tasks is moved once, before all of them."""
    blockers: dict[str, Blocker] = {}
    tasks = []
    for t in problem.tasks:
        for b in t.blocked_by:
            if blockers.setdefault(b.name, b) != b:
                raise ValueError(f"blocker '{b.name}' is described twice, differently")
        tasks.append(replace(t, after=t.after + tuple(relocation_id(b.name) for b in t.blocked_by)))
    relocations = {relocation_id(name): b for name, b in blockers.items()}
    for tid, b in relocations.items():
        pick = Primitive("pick", b.pick, b.at, b.at, b.duration)
        place = Primitive("place", b.place, None, None, b.duration, releases=True)
        tasks.append(Task(tid, (pick, place)))
    return tuple(tasks), relocations


def _check_graph(problem: AllocationProblem, tasks: Sequence[Task]) -> None:
    ids = [t.id for t in tasks]
    dup = sorted({i for i in ids if ids.count(i) > 1})
    if dup:
        raise ValueError(f"task ids used twice: {', '.join(dup)}")
    robots = [r.name for r in problem.robots]
    for t in tasks:
        for a in t.after:
            if a not in ids:
                raise AllocationError(f"task '{t.id}': after: unknown task '{a}'", t.id)
        for arm in t.arms or ():
            if arm not in robots:
                raise AllocationError(
                    f"task '{t.id}': arms: unknown robot '{arm}'; known: {', '.join(robots)}",
                    t.id,
                )
    try:
        tuple(TopologicalSorter({t.id: t.after for t in tasks}).static_order())
    except CycleError as e:
        raise ValueError(f"precedence cycle: {' -> '.join(e.args[1])}") from None


def _options(problem: AllocationProblem, task: Task, blocker: Blocker | None) -> tuple[Option, ...]:
    if blocker is not None and not blocker.spots:
        raise AllocationError(
            f"task '{task.id}': blocker '{blocker.name}' has no free spot", task.id
        )
    variants = (
        [(task, None)] if blocker is None else [(_to_spot(task, s), s) for s in blocker.spots]
    )
    found: list[Option] = []
    reasons: list[tuple[int, str]] = []
    for variant, spot in variants:
        walker = _Walker(problem, variant, "obstacle" if spot is not None else None)
        found += walker.options(spot)
        reasons += walker.reasons
    if not found:
        raise AllocationError(_diagnose(problem, variants[0][0], reasons), task.id)
    return _cheapest_per_signature(found)


def _to_spot(task: Task, spot: Point) -> Task:
    pick, place = task.primitives
    return replace(task, primitives=(pick, replace(place, end=spot)))


Block = tuple[tuple[str, ...], tuple[Action, ...], Inserted]


class _Walker:
    """Every assignment of a task's primitives to robots, group by group, with a handover
    wherever the robot holding the object changes. ``reasons`` keeps why branches died,
    with how far they got, for the error message."""

    def __init__(self, problem: AllocationProblem, task: Task, base: Inserted) -> None:
        self.problem, self.task, self.base = problem, task, base
        self.robots = _robots(problem, task)
        self.groups = _groups(task)
        self.reasons: list[tuple[int, str]] = []

    def options(self, spot: Point | None) -> list[Option]:
        found = []
        for blocks in self._walk(0, None, None):
            used = {r for rs, _, _ in blocks for r in rs}
            if self.task.arms is not None and used != set(self.task.arms):
                continue
            alliance = tuple(r.name for r in self.problem.robots if r.name in used)
            found.append(Option(self.task.id, alliance, _segments(self.problem, blocks), spot))
        return found

    def _walk(self, g: int, loc: Loc | None, holder: str | None) -> Iterator[list[Block]]:
        """The groups g.. given where the object is and who holds it (None: on the table)."""
        if g == len(self.groups):
            yield []
            return
        group = self.groups[g]
        if len(group) > len(self.robots):
            kinds = " and ".join(f"{i + 1} ({p.kind})" for i, p in group)
            self.reasons.append((g, f"primitives {kinds} run at once and need {len(group)} robots"))
        for team in itertools.permutations(self.robots, len(group)):
            if any(p.skill not in r.skills for r, (_, p) in zip(team, group, strict=True)):
                continue
            lead = team[0].name
            for pre, here in self._handovers(g, loc, holder, lead):
                done = self._group(g, team, here)
                if done is None:
                    continue
                end, block = done
                keeps = None if group[0][1].releases else lead
                for rest in self._walk(g + 1, end, keeps):
                    yield [*pre, block, *rest]

    def _handovers(
        self, g: int, loc: Loc | None, holder: str | None, lead: str
    ) -> Iterator[tuple[list[Block], Loc | None]]:
        """None needed when nobody holds the object or the lead does; else one per handover
        position both reach: the holder puts the object there, the lead picks it up."""
        if holder is None or holder == lead or loc is None:
            yield [], loc
            return
        p, step, dur = self.problem, self.task.id, self.problem.handover_duration
        a, b = p.robot(holder), p.robot(lead)
        spots = [h for h in p.handovers if p.reaches(a, (h,)) and p.reaches(b, (h,))]
        if not spots:
            self.reasons.append((g, f"no handover position reachable by both {holder} and {lead}"))
        for h in spots:
            at = (h,)
            put = Action(holder, step, "handover_place", HANDOVER_SKILL, loc, at, dur, "handover")
            take = Action(lead, step, "handover_pick", HANDOVER_SKILL, at, at, dur, "handover")
            yield [((holder,), (put,), "handover"), ((lead,), (take,), "handover")], at

    def _group(self, g: int, team: Sequence[Robot], loc: Loc | None) -> tuple[Loc, Block] | None:
        """The group's actions, locations resolved (a helper starts where the lead does), or
        None if a robot cannot reach them."""
        actions: list[Action] = []
        inserted: Inserted = "cooperation" if len(team) > 1 else self.base
        for robot, (i, p) in zip(team, self.groups[g], strict=True):
            here = actions[0].start if actions else loc
            if here is None and p.start is None:
                raise AllocationError(
                    f"task '{self.task.id}': primitive {i + 1} ({p.kind}) has no start location",
                    self.task.id,
                )
            start = resolve(p.start, here or ())
            end = resolve(p.end, start)
            for where in (start, end):
                if not self.problem.reaches(robot, where):
                    at = fmt_loc(where, self.problem.length_unit)
                    why = f"{robot.name} cannot reach {at} for primitive {i + 1} ({p.kind})"
                    self.reasons.append((g, why))
                    return None
            step = self.task.id
            actions.append(
                Action(robot.name, step, p.kind, p.skill, start, end, p.duration, inserted)
            )
        return actions[0].end, (tuple(r.name for r in team), tuple(actions), inserted)


def _robots(problem: AllocationProblem, task: Task) -> tuple[Robot, ...]:
    if task.arms is None:
        return problem.robots
    return tuple(r for r in problem.robots if r.name in task.arms)


def _groups(task: Task) -> list[list[tuple[int, Primitive]]]:
    if not task.primitives:
        raise AllocationError(f"task '{task.id}': no primitives", task.id)
    if task.primitives[0].with_previous:
        raise AllocationError(
            f"task '{task.id}': primitive 1 cannot run with a previous one", task.id
        )
    groups: list[list[tuple[int, Primitive]]] = []
    for i, p in enumerate(task.primitives):
        if p.with_previous:
            groups[-1].append((i, p))
        else:
            groups.append([(i, p)])
    return groups


def _segments(problem: AllocationProblem, blocks: Sequence[Block]) -> tuple[Stint, ...]:
    """Consecutive blocks of the same robots and kind become one segment."""
    merged: list[Block] = []
    for robots, acts, inserted in blocks:
        last = merged[-1] if merged else None
        if last and last[0] == robots and last[2] == inserted and inserted in (None, "obstacle"):
            merged[-1] = (robots, last[1] + acts, inserted)
        else:
            merged.append((robots, acts, inserted))
    return tuple(Stint(robots, acts, ins, _zones(problem, acts)) for robots, acts, ins in merged)


def _zones(problem: AllocationProblem, actions: Sequence[Action]) -> frozenset[str]:
    return frozenset().union(*(problem.shared_zones(a.start + a.end) for a in actions))


def _cheapest_per_signature(options: Sequence[Option]) -> tuple[Option, ...]:
    """Options alike for the search (alliance, where each robot enters and leaves, spot)
    differ only in internal travel: keep the cheapest, the first on ties."""
    best: dict[object, tuple[float, Option]] = {}
    for o in options:
        key = (o.alliance, tuple((o.entry(r), o.exit(r)) for r in o.alliance), o.spot)
        cost = sum(o.internal(r) for r in o.alliance)
        if key not in best or cost < best[key][0] - 1e-12:
            best[key] = (cost, o)
    return tuple(o for _, o in best.values())


def _diagnose(problem: AllocationProblem, task: Task, reasons: Sequence[tuple[int, str]]) -> str:
    """Why no alliance can do the task: a skill no robot has, a location no robot with the
    skill reaches, or why the assignments that got furthest stopped."""
    robots = _robots(problem, task)
    for i, p in enumerate(task.primitives):
        able = [r for r in robots if p.skill in r.skills]
        if not able:
            have = "; ".join(f"{r.name} has {', '.join(sorted(r.skills)) or '-'}" for r in robots)
            who = "no robot has" if task.arms is None else "its arms do not have"
            need = f"primitive {i + 1} ({p.kind}) needs skill '{p.skill}'"
            return f"task '{task.id}': {need}, which {who} ({have})"
        for where in (p.start, p.end):
            loc = resolve(where, ())
            if loc and not any(problem.reaches(r, loc) for r in able):
                lack = "; ".join(
                    f"{r.name} cannot reach it"
                    if r in able
                    else f"{r.name} lacks skill '{p.skill}'"
                    for r in robots
                )
                at = fmt_loc(loc, problem.length_unit)
                return f"task '{task.id}': primitive {i + 1} ({p.kind}) at {at}: {lack}"
    names = ", ".join(r.name for r in robots)
    furthest = max((g for g, _ in reasons), default=0)
    why = next((w for g, w in reasons if g == furthest), "no assignment found")
    return f"task '{task.id}': no alliance of {names} can do its primitives in order: {why}"
