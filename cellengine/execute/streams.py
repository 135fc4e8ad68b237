"""Both arms at once: a program compiled one segment after another, its segments given their
own starts wherever the family's rules (cellengine/concurrency.py) and the cell's safety
allow.

Segments are placed in compile order. Each is *ready* when its arms' earlier segments, the
parts its part comes after and the earlier segments touching its objects have ended; a sync
point (a segment of no part, one that measures) waits for everything before it, and
everything after it waits for it. It is tried
at that time, then at each later time another segment ends. A start is checked from it to
the end of everything placed so far, since the segment changes what the cell looks like
from then on (where its arm stands, what its gripper let go), cut at every segment's start
and end and gripper event, each piece with the held objects and contacts of its moment:

- the gate (limits, collisions, the cell's clearance; ``dt`` apart: coarse while trying);
- two arms not working in the same together part keep ``max(clearance, DEFAULT_CLEARANCE)``
  apart, as the async scheduler's arms moving on their own do;
- a shared zone holds one arm's TCP at a time, but arms that came in for the same together
  part (a cooperation).

A start at the end of everything placed is always taken: every segment before it in compile
order has ended by then, so the cell is as it was when the segment was compiled and gated.
So the schedule is never longer than the compiled program, and a plan that compiles one
segment after another always gets one.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from itertools import pairwise

import numpy as np

from cellengine.concurrency import Overlap, Part, SharedZone
from cellengine.execute.checks import gate, near_pairs
from cellengine.execute.held import Holding
from cellengine.execute.refused import Refused
from cellengine.execute.timeline_arms import ArmTimeline, Slot, segment_arms
from cellengine.info.cell import DEFAULT_CLEARANCE
from cellengine.motion.gate import SAMPLE_DT, GateReport, Violation
from cellengine.motion.robot import CellModel
from cellengine.motion.scene import Pair
from cellengine.motion.trajectory import Trajectory
from cellengine.program import CompiledSegment, GripperEvent, Measure, Scheduled, Segment

SCHEDULE_DT = 0.01  # s between the states checked while trying starts
SAME = 1e-9  # s: starts and ends closer than this are one instant


@dataclass(frozen=True)
class Piece:
    """The cell between two instants at which a segment starts or ends or a gripper acts."""

    lo: float
    hi: float
    slots: tuple[Slot, ...]  # running in it, compile order
    trajectory: Trajectory
    report: GateReport


class Streams:
    """The scheduler: ``place`` every segment, then ``pieces`` (checked at the gate's 1 ms)."""

    def __init__(
        self,
        segments: Sequence[CompiledSegment],
        rules: Overlap,
        cell: CellModel,
        holding: Holding,
        q0: np.ndarray,
        clearance: float,
    ) -> None:
        self.segments = segments
        self.rules = rules
        self.cell = cell
        self.holding = holding
        self.start_state = holding.state
        self.clearance = clearance
        self.margin = max(clearance, DEFAULT_CLEARANCE)
        self.timeline = ArmTimeline(cell, q0, segments)
        self.parts: list[Part | None] = [rules.part(cs.segment.facts) for cs in segments]
        self.touches = _touches(segments)
        self.scheduled: list[Scheduled] = []

    # ---------------------------------------------------------------------------- placing

    def place_all(
        self, dt: float = SCHEDULE_DT, done: frozenset[int] = frozenset()
    ) -> tuple[Scheduled, ...]:
        """Every segment but those ``done`` already (a resumed run's)."""
        for i in range(len(self.segments)):
            if i not in done:
                self.place(i, dt)
        return tuple(self.scheduled)

    def place(self, i: int, dt: float) -> Scheduled:
        seg = self.segments[i].segment
        arms = segment_arms(seg) or tuple(self.cell.arms)
        ready = self.ready(i, arms)
        tl = self.timeline
        end = tl.makespan
        later = sorted({tl.end(s) for s in tl.slots if ready + SAME < tl.end(s) < end - SAME})
        why: str | None = None  # why the latest start tried could not be taken
        start = end
        for t in (ready, *later):
            if t >= end - SAME:
                break
            tl.add(i, t, arms)
            refused = self.check(t, max(tl.makespan, t), dt)
            tl.pop()
            if refused is None:
                start = t
                break
            why = refused
        start = max(start, ready)
        tl.add(i, start, arms)
        out = Scheduled(
            i,
            self.segments[i],
            arms,
            start,
            tl.end(tl.slots[-1]),
            ready,
            why if start > ready + SAME else None,
            self.parts[i],
        )
        self.scheduled.append(out)
        return out

    def ready(self, i: int, arms: tuple[str, ...]) -> float:
        """When segment ``i``'s order lets it start (see the module notes)."""
        tl = self.timeline
        part = self.parts[i]
        ends = [tl.free(a) for a in arms]
        if _measures(self.segments[i].segment):  # read at rest: nothing else running
            ends.append(tl.makespan)
        for s, placed in zip(tl.slots, self.scheduled, strict=True):
            j = s.index
            other = self.parts[j]
            seg = self.segments[j].segment
            if (
                part is None
                or other is None
                or _measures(seg)
                or (self.touches[i] & self.touches[j])
                or (other[0] in self.rules.after.get(part[0], ()))
                or (other[0] == part[0] and other[1] < part[1])
            ):
                ends.append(placed.end)
        return max(ends, default=0.0)

    # ---------------------------------------------------------------------------- checking

    def check(self, lo: float, hi: float, dt: float) -> str | None:
        """Why the cell placed as it is cannot run from ``lo`` to ``hi``; None if it can.
        The shared zones first: the rule a user wrote, and cheaper than the gate."""
        for lo_k, hi_k in self._bounds(lo, hi):
            why = self._zones(lo_k, hi_k, self.timeline.trajectory(lo_k, hi_k))
            if why is not None:
                return why
        for piece in self.pieces(lo, hi, dt, refuse=False):
            why = self.why_not(piece)
            if why is not None:
                return why
        return None

    def _bounds(self, lo: float, hi: float) -> list[tuple[float, float]]:
        """The instants from ``lo`` to ``hi`` at which a segment starts or ends or a
        gripper acts, as consecutive pairs."""
        tl = self.timeline
        cuts = {lo, hi} | {t for t, _, _ in tl.events()}
        for s in tl.slots:
            cuts |= {s.start, tl.end(s)}
        bounds = [t for t in sorted(cuts) if lo - SAME <= t <= hi + SAME]
        bounds = [b for k, b in enumerate(bounds) if k == 0 or b - bounds[k - 1] > SAME]
        return list(pairwise(bounds))

    def pieces(
        self, lo: float, hi: float, dt: float = SAMPLE_DT, refuse: bool = True
    ) -> list[Piece]:
        """The placed cell from ``lo`` to ``hi``, cut at every segment's start and end and
        every gripper event, each piece through the gate with what the grippers hold and the
        contacts at its time. ``refuse``: Refused at the first piece the gate refuses (else
        that piece's report has the violation, and the rest are not built)."""
        tl = self.timeline
        events = tl.events()
        hold = self.holding
        hold.restore(self.start_state)
        k = 0
        out: list[Piece] = []
        for u0, u1 in self._bounds(lo, hi):
            while k < len(events) and events[k][0] <= u0 + SAME:
                self._apply(events[k][2], events[k][0])
                k += 1
            running = tuple(tl.active(u0, u1))
            contacts = {c for s in running for c in self.segments[s.index].segment.contacts}
            hold.touch(contacts)
            near: frozenset[Pair] = frozenset()
            for s in running:
                near |= near_pairs(self.cell, hold.checker.scene, self.segments[s.index].segment)
            traj = tl.trajectory(u0, u1)
            try:
                report = gate(traj, self.cell, hold.checker, self.clearance, near, dt)
            except Refused as e:
                if refuse:
                    raise
                out.append(Piece(u0, u1, running, traj, _refused(e)))
                return out
            out.append(Piece(u0, u1, running, traj, report))
        return out

    def why_not(self, piece: Piece) -> str | None:
        """Why a piece cannot run at once as it is placed (None: it can)."""
        if piece.report.violations:
            return piece.report.violations[0].what
        arms = piece.report.clearance.arms if piece.report.clearance else None
        # closest where the piece starts: leaving (the gate's rule), checked before it
        leaving = arms is not None and arms.time <= piece.lo + 2 * SCHEDULE_DT
        short = arms is not None and arms.distance < self.margin - 1e-12 and not leaving
        if arms is not None and short and not self._together(piece):
            return (
                f"the arms would pass {arms.distance * 1000:.1f} mm apart "
                f"({arms.pair[0]}, {arms.pair[1]}); working apart they keep "
                f"{self.margin * 1000:.0f} mm"
            )
        return None

    def _together(self, piece: Piece) -> bool:
        """Whether every arm's latest segment is of one together part (a cooperation)."""
        parts = {self._part_now(arm, piece.hi) for arm in self.cell.arms}
        return len(parts) == 1 and parts.pop() in self.rules.together

    def _part_now(self, arm: str, t: float) -> Part | None:
        mine = [s for s in self.timeline.by_arm[arm] if s.start < t - SAME]
        return self.parts[mine[-1].index] if mine else None

    def _zones(self, lo: float, hi: float, trajectory: Trajectory) -> str | None:
        """Why two arms' TCPs would be in a shared zone at once from ``lo`` to ``hi`` (a
        piece), sampled every 10 ms; None if they would not, or came in for one
        cooperation."""
        if not self.rules.zones:
            return None
        times = np.append(np.arange(lo, hi, SCHEDULE_DT), hi)
        Q, _, _ = trajectory.sample(times)
        for zone in self.rules.zones:
            inside = {arm: zone.inside(self._tcps(arm, Q)) for arm in zone.arms}
            both = np.sum([v for v in inside.values()], axis=0) >= 2
            if not both.any():
                continue
            coop = [self._presence(arm, zone, lo) for arm in zone.arms]
            if not set.intersection(*coop):
                t = float(times[int(np.argmax(both))])
                return f"both arms would be in shared zone '{zone.name}' at t={t:.2f} s"
        return None

    def _tcps(self, arm: str, Q: np.ndarray) -> np.ndarray:
        model, cols = self.cell.arms[arm], self.cell.slices[arm]
        return np.array([model.fk(q[cols])[:3, 3] for q in Q])

    def _presence(self, arm: str, zone: SharedZone, t: float) -> set[Part]:
        """The together parts of ``arm``'s segments since its TCP last came into ``zone``
        (the zone's box), up to the one running at ``t``."""
        tl = self.timeline
        mine = [s for s in tl.by_arm[arm] if s.start < t + SCHEDULE_DT]
        out: set[Part] = set()
        for s in reversed(mine):
            part = self.parts[s.index]
            if part in self.rules.together and part is not None:
                out.add(part)
            q0 = tl.trajectory_of(s).q[0]
            if not zone.inside(self._tcps(arm, q0[None, :]))[0]:
                break  # it came in during this segment
        return out

    def _apply(self, event: GripperEvent, t: float) -> None:
        Q, _, _ = self.timeline.states(np.array([t]))
        arm = self.cell.arms[event.arm]
        T = arm.fk(Q[0][self.cell.slices[event.arm]])
        self.holding.set(event.arm, event.holds, T, event.mode)


def _measures(seg: Segment) -> bool:
    return any(isinstance(a, Measure) for a in seg.annotations)


def _refused(e: Refused) -> GateReport:
    return GateReport((Violation("collision", 0.0, str(e)),), 0)


def _touches(segments: Sequence[CompiledSegment]) -> list[frozenset[str]]:
    """The objects each segment touches: what its grippers take or let go, what its moving
    arms hold, its contacts."""
    holds: dict[str, str] = {}
    out: list[frozenset[str]] = []
    for cs in segments:
        seg = cs.segment
        names = {holds[p.arm] for p in seg.paths if p.arm in holds}
        names |= {obj for _, obj in seg.contacts}
        for e in (*seg.before, *seg.after):
            if e.arm in holds:
                names.add(holds.pop(e.arm))
            if e.holds is not None:
                holds[e.arm] = e.holds
                names.add(e.holds)
        out.append(frozenset(names))
    return out
