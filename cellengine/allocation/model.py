"""The allocation problem: robots with skills and reach, tasks made of motion primitives.

Pure data, no solving. Locations are points of the cell frame in metres. A location may be
a set of candidates (``AnyOf``) when a runtime choice (``heavier_of``) is not made yet: a
robot must then reach every candidate, and distances count the farthest pair, so the
mission holds and its cost is an upper bound whichever candidate it turns out to be.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Literal

Point = tuple[float, float, float]
Loc = tuple[Point, ...]  # a resolved location: its candidates, at least one
Inserted = Literal["handover", "cooperation", "obstacle"] | None
# lengths in messages: per metre, and the decimals of a millimetre
LENGTH_UNITS = {"m": (1.0, 3), "cm": (100.0, 1), "mm": (1000.0, 0)}


class AllocationError(ValueError):
    """No mission: ``task`` is the id of the task that cannot be done (None: not one task's)."""

    def __init__(self, message: str, task: str | None = None) -> None:
        super().__init__(message)
        self.task = task


@dataclass(frozen=True)
class AnyOf:
    """One of these points, not known until run time (e.g. the heavier of two vials)."""

    points: tuple[Point, ...]

    def __post_init__(self) -> None:
        if not self.points:
            raise ValueError("AnyOf needs at least one point")


Where = Point | AnyOf


@dataclass(frozen=True)
class Primitive:
    """One motion primitive of a task.

    ``start`` is where the robot begins it, ``end`` where it leaves the object; ``None``
    means where the object is (start) or the same as start (end). ``with_previous`` runs it
    at the same time as the previous primitive by another robot of the alliance (a
    cooperation: one holds while the other turns the cap). ``releases`` leaves the object
    on the table, so the next primitive needs no handover even if another robot does it.
    """

    kind: str
    skill: str
    start: Where | None = None
    end: Where | None = None
    duration: float = 1.0
    with_previous: bool = False
    releases: bool = False


@dataclass(frozen=True)
class Blocker:
    """An object in the way of a task's target: where it is and the free spots it may go to."""

    name: str
    at: Point
    spots: tuple[Point, ...]
    pick: str = "pick"  # the skills its relocation needs
    place: str = "place"
    duration: float = 1.0  # per primitive


@dataclass(frozen=True)
class Task:
    """One plan step: a sub-task on one object. ``arms`` None lets the allocator choose."""

    id: str
    primitives: tuple[Primitive, ...]
    after: tuple[str, ...] = ()
    arms: tuple[str, ...] | None = None
    blocked_by: tuple[Blocker, ...] = ()


@dataclass(frozen=True)
class Robot:
    """A robot's skills, where it starts, optionally where it must end (the paper's end
    vertex: the return counts in the cost; None: it stays) and a reach test for points."""

    name: str
    skills: frozenset[str]
    start: Point
    end: Point | None = None
    reach: Callable[[Point], bool] | None = field(default=None, compare=False)


@dataclass(frozen=True)
class Zone:
    """An axis-aligned box where only ``robots`` may work; shared when two or more may."""

    name: str
    lo: Point
    hi: Point
    robots: frozenset[str]

    def contains(self, p: Point) -> bool:
        return all(a <= v <= b for a, v, b in zip(self.lo, p, self.hi, strict=True))

    @property
    def shared(self) -> bool:
        return len(self.robots) >= 2


@dataclass(frozen=True)
class AllocationProblem:
    """Robots, tasks, zones and the handover positions of the cooperation area (mode 1)."""

    robots: tuple[Robot, ...]
    tasks: tuple[Task, ...]
    zones: tuple[Zone, ...] = ()
    handovers: tuple[Point, ...] = ()
    handover_duration: float = 1.0  # each of the place and the pick at a handover
    length_unit: str = "m"  # of locations in messages (LENGTH_UNITS): the cell file's

    def robot(self, name: str) -> Robot:
        return next(r for r in self.robots if r.name == name)

    def reaches(self, robot: Robot, loc: Loc) -> bool:
        """Every candidate point is inside a zone that admits the robot, or in no zone, and
        passes the robot's reach test if it has one."""
        return all(self._reaches_point(robot, p) for p in loc)

    def _reaches_point(self, robot: Robot, p: Point) -> bool:
        zones = [z for z in self.zones if z.contains(p)]
        if zones and not any(robot.name in z.robots for z in zones):
            return False
        return robot.reach is None or robot.reach(p)

    def shared_zones(self, loc: Loc) -> frozenset[str]:
        return frozenset(z.name for z in self.zones if z.shared for p in loc if z.contains(p))


def resolve(where: Where | None, default: Loc) -> Loc:
    if where is None:
        return default
    if isinstance(where, AnyOf):
        return where.points
    return (where,)


def distance(a: Loc, b: Loc) -> float:
    """The farthest pair of candidates: an upper bound whichever candidates they are. The
    same location is one choice (the same object), so no distance."""
    if a == b:
        return 0.0
    return max(math.dist(p, q) for p in a for q in b)


def fmt_loc(loc: Loc, unit: str = "m") -> str:
    """``(x, y, z) mm``, or ``any of (...), (...) mm``, in ``unit`` (LENGTH_UNITS)."""
    scale, decimals = LENGTH_UNITS[unit]
    points = ", ".join("(" + ", ".join(f"{v * scale:.{decimals}f}" for v in p) + ")" for p in loc)
    return (points if len(loc) == 1 else f"any of {points}") + f" {unit}"
