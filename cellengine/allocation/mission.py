"""The mission: alliances, each robot's actions in order, and a schedule that respects
precedence, one task per robot at a time, and one robot at a time in a shared zone unless
they cooperate there (a robot is in a zone only during a segment that works in it: it
retracts after each, as the published platform does)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

from cellengine.allocation.model import Inserted, Loc, distance
from cellengine.allocation.options import Action, Expanded, Option, Stint


@dataclass(frozen=True)
class Entry:
    """One schedule entry: a segment of a step, its robots and times (s)."""

    step: str
    arms: tuple[str, ...]
    start: float
    end: float
    inserted: Inserted
    zones: frozenset[str]  # the shared zones it works in

    def to_json(self) -> dict[str, object]:
        return {
            "step": self.step,
            "arms": list(self.arms),
            "start": round(self.start, 6),
            "end": round(self.end, 6),
            "inserted": self.inserted,
        }


@dataclass(frozen=True)
class Mission:
    order: tuple[str, ...]  # the tasks, relocations included, in the order they were planned
    options: dict[str, Option]  # per task: its alliance and segments
    actions: dict[str, tuple[Action, ...]]  # per robot, in order
    schedule: tuple[Entry, ...]
    cost: float  # metres, every robot's path summed
    optimal: bool
    method: Literal["exact", "heuristic"]

    def alliance(self, task: str) -> tuple[str, ...]:
        return self.options[task].alliance

    def to_json(self) -> list[dict[str, object]]:
        """What report.json stores as ``mission``."""
        return [e.to_json() for e in self.schedule]


def build_mission(
    ex: Expanded,
    order: Sequence[str],
    chosen: dict[str, Option],
    optimal: bool,
    method: Literal["exact", "heuristic"],
) -> Mission:
    robots = [r.name for r in ex.problem.robots]
    actions = {r: tuple(a for t in order for a in chosen[t].actions(r)) for r in robots}
    cost = sum(_path(ex, r, acts) for r, acts in actions.items())
    after = {t.id: t.after for t in ex.tasks}
    schedule = _schedule(order, chosen, after, robots)
    return Mission(tuple(order), dict(chosen), actions, schedule, cost, optimal, method)


def _path(ex: Expanded, robot: str, actions: Sequence[Action]) -> float:
    r = ex.problem.robot(robot)
    here: Loc = (r.start,)
    total = 0.0
    for a in actions:
        total += distance(here, a.start) + distance(a.start, a.end)
        here = a.end
    return total + (0.0 if r.end is None else distance(here, (r.end,)))


def _schedule(
    order: Sequence[str],
    chosen: dict[str, Option],
    after: dict[str, tuple[str, ...]],
    robots: Sequence[str],
) -> tuple[Entry, ...]:
    """List scheduling in the planned order: each segment as early as its task's previous
    segment, its robots and the tasks it comes after allow, then later until no other
    robot works in a shared zone it needs."""
    free = dict.fromkeys(robots, 0.0)
    ends: dict[str, float] = {}
    entries: list[Entry] = []
    for t in order:
        ready = max((ends[p] for p in after[t]), default=0.0)
        for seg in chosen[t].segments:
            start = _zone_fit(entries, seg, max(ready, *(free[r] for r in seg.robots)))
            entry = Entry(t, seg.robots, start, start + seg.duration, seg.inserted, seg.zones)
            entries.append(entry)
            for r in seg.robots:
                free[r] = entry.end
            ready = entry.end
        ends[t] = ready
    return tuple(sorted(entries, key=lambda e: (e.start, e.end)))


def _zone_fit(entries: Sequence[Entry], seg: Stint, start: float) -> float:
    """The earliest time from ``start`` when the segment's shared zones are free of others
    for its whole duration."""
    busy = sorted((e.start, e.end) for e in entries if e.zones & seg.zones)
    moved = True
    while moved:
        moved = False
        for s, e in busy:
            if s < start + seg.duration and start < e:
                start, moved = e, True
    return start
