"""Where each arm is at any time, once a program's segments are given their own starts.

A segment moves only its own arms (its trajectory's columns of them); an arm between its
segments stands where its last one left it (at the start: where the program starts). The
held objects and contacts at any time are those of the gripper events before it
(:meth:`ArmTimeline.events`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from cellengine.arrays import Vec
from cellengine.execute.merge import _union
from cellengine.motion.robot import CellModel
from cellengine.motion.trajectory import Trajectory
from cellengine.program import CompiledSegment, GripperEvent, Segment


def segment_arms(segment: Segment) -> tuple[str, ...]:
    """The arms a segment acts on: those it moves, those whose grippers it changes, both
    of a closed chain."""
    arms = [p.arm for p in segment.paths]
    arms += [e.arm for e in (*segment.before, *segment.after)]
    arms += list(segment.closed_chain or ())
    return tuple(dict.fromkeys(arms))


@dataclass(frozen=True)
class Slot:
    index: int  # the segment's index in the program compiled one after another
    start: float  # s, when it starts now
    arms: tuple[str, ...]


class ArmTimeline:
    """The segments placed so far, each at its own start; ``add`` and ``pop`` (the last
    added) let a scheduler try a start."""

    def __init__(self, cell: CellModel, q0: Vec, segments: Sequence[CompiledSegment]) -> None:
        self.cell = cell
        self.q0 = np.asarray(q0, dtype=float)
        self.segments = segments
        self.slots: list[Slot] = []
        self.by_arm: dict[str, list[Slot]] = {arm: [] for arm in cell.arms}

    def add(self, index: int, start: float, arms: tuple[str, ...]) -> Slot:
        slot = Slot(index, start, arms)
        for arm in arms:
            mine = self.by_arm[arm]
            if mine and start < self.end(mine[-1]) - 1e-9:
                raise ValueError(f"segment {index} starts before the {arm} arm's last ends")
            mine.append(slot)
        self.slots.append(slot)
        return slot

    def pop(self) -> None:
        slot = self.slots.pop()
        for arm in slot.arms:
            self.by_arm[arm].pop()

    def trajectory_of(self, slot: Slot) -> Trajectory:
        return self.segments[slot.index].trajectory

    def offset(self, slot: Slot) -> float:
        """Its start now less its start as compiled."""
        return slot.start - self.trajectory_of(slot).start_time

    def end(self, slot: Slot) -> float:
        return slot.start + self.trajectory_of(slot).duration

    @property
    def makespan(self) -> float:
        return max((self.end(s) for s in self.slots), default=0.0)

    def free(self, arm: str) -> float:
        mine = self.by_arm[arm]
        return self.end(mine[-1]) if mine else 0.0

    def active(self, lo: float, hi: float) -> list[Slot]:
        """The slots running at some time in (lo, hi), in compile order."""
        out = [s for s in self.slots if s.start < hi - 1e-9 and self.end(s) > lo + 1e-9]
        return sorted(out, key=lambda s: s.index)

    def states(self, times: Vec) -> tuple[Vec, Vec, Vec]:
        """The whole cell's q, qd, qdd at ``times`` (increasing)."""
        n = len(times)
        Q = np.repeat(self.q0[None, :], n, axis=0)
        V, A = np.zeros_like(Q), np.zeros_like(Q)
        for arm, mine in self.by_arm.items():
            if not mine:
                continue
            cols = self.cell.slices[arm]
            starts = np.array([s.start for s in mine])
            k = np.searchsorted(starts, times + 1e-12, side="right") - 1
            # before its first segment an arm stands where that one starts
            k = np.maximum(k, 0)
            for j in np.unique(k):
                slot = mine[int(j)]
                at = k == j
                q, qd, qdd = self.trajectory_of(slot).sample(times[at] - self.offset(slot))
                Q[at, cols], V[at, cols], A[at, cols] = q[:, cols], qd[:, cols], qdd[:, cols]
        return Q, V, A

    def trajectory(self, lo: float, hi: float) -> Trajectory:
        """The whole cell from ``lo`` to ``hi``: knots where any running segment has one
        (the same polynomials: each arm's motion exactly as it was compiled)."""
        knots = [np.array([lo, hi])]
        for s in self.active(lo, hi):
            t = self.trajectory_of(s).t + self.offset(s)
            knots.append(t[(t > lo) & (t < hi)])
        times = _union(np.concatenate(knots))
        Q, V, A = self.states(times)
        if len(times) < 2:
            return Trajectory(self.cell.joint_names, times, Q, V, A)
        # each arm's own polynomials on the union of knots (not Hermite data again, which
        # two arms' knots microseconds apart would make noisy)
        coef = [np.zeros((len(times) - 1, self.cell.nq)) for _ in range(6)]
        coef[0][:] = Q[:-1]
        for s in self.active(lo, hi):
            own = self.trajectory_of(s).refined(times - self.offset(s))
            for arm in s.arms:
                cols = self.cell.slices[arm]
                for c, o in zip(coef, own, strict=True):
                    c[:, cols] = o[:, cols]
        return Trajectory.with_coefficients(self.cell.joint_names, times, Q, V, A, coef)

    def events(self) -> list[tuple[float, int, GripperEvent]]:
        """Every gripper event of the slots, in time order (a segment's ``before`` at its
        start, ``after`` at its end; at one instant in compile order)."""
        out: list[tuple[float, int, int, GripperEvent]] = []
        for s in self.slots:
            seg = self.segments[s.index].segment
            out += [(s.start, s.index, 0, e) for e in seg.before]
            out += [(self.end(s), s.index, 1, e) for e in seg.after]
        out.sort(key=lambda x: (round(x[0], 9), x[1], x[2]))
        return [(t, i, e) for t, i, _, e in out]
