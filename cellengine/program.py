"""What a plan compiles to: pure data, no I/O, no driver.

Skills turn plan steps into :class:`Segment` s (fingertip poses in the cell frame, gripper
events, couplings between the arms); the executor turns segments into a :class:`Program`
(timed joint trajectories of both arms on one time axis, with gripper events); drivers
play a program; the report describes it.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, Literal

import numpy as np

from cellengine.arrays import FloatArray, Poses
from cellengine.motion.trajectory import Trajectory

SAME_INSTANT = 1e-9  # s: a segment ending this near a piece's end has ended with it


@dataclass(frozen=True)
class GripperEvent:
    """A gripper changes mode (a name in the tool's ``jaw`` table: open, slide, grasp...)
    and, with it, what it holds: ``holds`` names the object held from then on (None: nothing)."""

    arm: str
    mode: str
    holds: str | None = None


@dataclass(frozen=True)
class ToolChange:
    """At the end of its segment ``arm``'s tool changer takes ``tool`` (locks it) or, when
    ``tool`` is None, lets go of the tool it carries, seated in its slot (unlocks). From then
    on the arm's TCP, fingers and collision shape are those of what it carries."""

    arm: str
    tool: str | None


@dataclass(frozen=True)
class Measure:
    """At the end of its segment the runner reads ``arm``'s load cell: the mass (kg) of
    ``object``, which may change a runtime choice (``heavier_of``) and so the rest of the
    plan."""

    arm: str
    object: str


@dataclass(frozen=True)
class Anchor:
    """From the end of its segment ``object`` (a cable) is fixed at ``point`` (cell frame, m)
    by ``by`` (a keypoint: the guide holding it); the report draws a cable through its
    anchors so far, then the hands holding it."""

    object: str
    point: tuple[float, float, float]
    by: str | None = None


# What a skill says about a segment besides its motion: typed, so the runner and the report
# act on it without knowing the skill (a Measure is done at run time, an Anchor is drawn).
Annotation = Measure | Anchor


@dataclass(frozen=True)
class ArmPath:
    """One arm's motion in a segment.

    ``cartesian``: the TCP follows ``poses`` (k >= 2, already interpolated: linear or circular,
    within the skill's step sizes), starting where the arm is. ``transit``: a free-space move
    to ``poses[-1]`` (k = 1), any collision-free joint path.
    """

    arm: str
    kind: Literal["cartesian", "transit"]
    poses: Poses

    def __post_init__(self) -> None:
        p = np.array(self.poses, dtype=float)
        if p.ndim != 3 or p.shape[1:] != (4, 4) or len(p) == 0:
            raise ValueError(f"poses must have shape (k, 4, 4), got {p.shape}")
        if self.kind == "cartesian" and len(p) < 2:
            raise ValueError("a cartesian path needs at least 2 poses")
        if self.kind == "transit" and len(p) != 1:
            raise ValueError("a transit move has exactly 1 goal pose")
        p.setflags(write=False)
        object.__setattr__(self, "poses", p)


@dataclass(frozen=True)
class Segment:
    """A piece of one step during which the arms move together (or one arm alone).

    ``before`` events happen at the start of the segment, ``after`` events at its end.
    ``closed_chain`` = (leader, follower): the follower keeps its pose relative to the
    leader (both hands on one object). ``keep_distance`` = two arms whose fingertips must
    stay at a constant distance (a taut cable) throughout; the executor checks it.
    """

    step: int  # index of the plan step
    label: str  # what it does, in plan terms: "RouteCable guide2: lift"
    paths: tuple[ArmPath, ...] = ()
    before: tuple[GripperEvent, ...] = ()
    after: tuple[GripperEvent, ...] = ()
    closed_chain: tuple[str, str] | None = None
    keep_distance: tuple[str, str] | None = None
    # (arm, object): contacts this segment makes on purpose (a gripper closing on or letting
    # go of a container): that arm's tool is not checked against that object meanwhile
    contacts: tuple[tuple[str, str], ...] = ()
    # (arm, object): what this segment works closer to than the cell's clearance without
    # touching it (fingers beside the comb they grasp in, around the guide's slot they slide
    # past, over the connector guide they insert into): still checked for collision, but
    # that arm's tool against that object is not held to the clearance meanwhile
    near: tuple[tuple[str, str], ...] = ()
    # what the step promises at the end of this segment, for reports and tests, e.g.
    # {"guide": "routing.guide2", "slot": [x, y, z]}
    facts: Mapping[str, Any] = field(default_factory=lambda: MappingProxyType({}))
    annotations: tuple[Annotation, ...] = ()
    # (arm, IK branches): the skill checked this segment's poses of that arm on those of its
    # closed-form IK branches only (ArmIK.by_branch rows); a transit before it chooses a
    # goal on one of them where it can, and an arm on another is refused here
    branches: tuple[tuple[str, frozenset[int]], ...] = ()
    # (arm, other arm, pairs of their IK branches): the skill checked the two arms against
    # each other on those pairs only (``branches`` says which of each arm's it looked at,
    # not which go together); two arms on another pair are refused here
    paired: tuple[tuple[str, str, frozenset[tuple[int, int]]], ...] = ()
    # tool changers locking or unlocking at the segment's end, after its ``after`` events
    changes: tuple[ToolChange, ...] = ()
    # s the arms then stand still (a tool at work: ``triggers``)
    hold: float = 0.0
    # arms whose tool works (is triggered) from the segment's start to its end: a taping gun
    triggers: tuple[str, ...] = ()

    def arms(self) -> tuple[str, ...]:
        return tuple(p.arm for p in self.paths)

    def branches_of(self, arm: str) -> frozenset[int] | None:
        """The IK branches ``branches`` requires of ``arm`` (None: any)."""
        return next((b for a, b in self.branches if a == arm), None)


@dataclass(frozen=True)
class TimedEvent:
    time: float  # seconds from the program's start
    event: GripperEvent


@dataclass(frozen=True)
class TimedChange:
    """A tool change at ``time``: ``arm`` carries ``tool`` from then on, having carried
    ``was`` (None: a bare flange)."""

    time: float  # seconds from the program's start
    arm: str
    tool: str | None
    was: str | None


@dataclass(frozen=True)
class CompiledSegment:
    """A segment as timed joint motion of the whole cell (every arm's joints, cell order)."""

    segment: Segment
    strategy: str  # split | sync | async
    trajectory: Trajectory  # times from the program's start
    report: Mapping[str, Any]  # fraction, planning time, durations, min distance, checks


@dataclass(frozen=True)
class Scheduled:
    """A compiled segment's place in its arms' streams, when the arms work at once."""

    index: int  # in the program as compiled, one segment after another
    compiled: CompiledSegment  # as compiled (its trajectory on that program's time axis)
    arms: tuple[str, ...]
    start: float  # s from the program's start
    end: float
    ready: float  # when its order let it start (its arms free, what it comes after ended)
    why: str | None  # why it starts after ``ready`` (a shared zone, the clearance); else None
    part: tuple[str, int] | None  # (task, part) of the family's rules

    @property
    def segment(self) -> Segment:
        return self.compiled.segment

    @property
    def label(self) -> str:
        return self.segment.label

    @property
    def step(self) -> int:
        return self.segment.step

    @property
    def wait(self) -> float:
        return self.start - self.ready


@dataclass(frozen=True)
class Program:
    """``segments``: what a driver plays, one after another. When the arms work at once
    (execute/streams.py) they are the pieces between instants at which any arm's segment
    starts or ends, and ``streams`` places each segment as compiled on the time axis."""

    joint_names: tuple[str, ...]
    segments: tuple[CompiledSegment, ...]
    events: tuple[TimedEvent, ...]
    streams: tuple[Scheduled, ...] = ()
    # a run resumed (or replanned) part way: the segments (``Scheduled.index``) it finished
    # before this program's start, left out of ``streams``
    done: frozenset[int] = frozenset()
    # tool changes, in time order; a program with any runs its segments one after another
    changes: tuple[TimedChange, ...] = ()
    # the tool each arm carries at the program's start
    tools: Mapping[str, str | None] = field(default_factory=lambda: MappingProxyType({}))

    def tools_at(self, t: float) -> dict[str, str | None]:
        """The tool each arm carries at time ``t`` (a change at ``t`` done)."""
        out = dict(self.tools)
        for c in self.changes:
            if c.time <= t + SAME_INSTANT:
                out[c.arm] = c.tool
        return out

    @property
    def duration(self) -> float:
        return self.segments[-1].trajectory.end_time if self.segments else 0.0

    def streams_at(self, t: float) -> tuple[frozenset[int], frozenset[int], FloatArray]:
        """When the arms work at once: the segments of ``streams`` finished at time ``t``
        (those finished before, ``done``, too), those running then, and where the program
        has the arms then."""
        finished = self.done | {s.index for s in self.streams if s.end <= t + SAME_INSTANT}
        running = {s.index for s in self.streams if s.start < t - SAME_INSTANT < s.end}
        ends = [s.trajectory.end_time for s in self.segments]
        k = min(int(np.searchsorted(ends, t - SAME_INSTANT)), len(ends) - 1)
        q = np.asarray(self.segments[k].trajectory.sample(t)[0], dtype=float)
        return frozenset(finished), frozenset(running - finished), q
