"""The asynchronous scheduler: each arm on its own timing, started as soon as it is safe.

Arms solved apart are each planned against the others standing where they start, so running
them at once can collide where both arms pass through one place at one time. The scheduler
takes the arms in order: the first starts at once; each next one's trajectory is checked
against those already scheduled, with the whole cell's state sampled every ``dt`` over the
time the new arm moves, and its start is pushed back by ``step`` until at no sample is it
closer than ``clearance`` to an arm already running. A margin rather than bare contact:
between samples the arms move, and a schedule that only just misses is one a small tracking
error turns into a collision. The time before its start needs no check: the arms already
running were planned with it standing at its start.

Once every arm already running has stopped, a delay no longer changes anything: the margin
is then the planner's (the others stand still), and an arm that still collides collides with
where the others end, and is refused. Arms solved apart for async are planned with the arms
before them standing where they end (strategies.py), so that does not happen to them.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Protocol

import numpy as np

from cellengine.arrays import Vec
from cellengine.execute.merge import on_one_axis
from cellengine.execute.refused import Refused
from cellengine.info.cell import DEFAULT_CLEARANCE
from cellengine.motion.robot import CellModel
from cellengine.motion.trajectory import Trajectory

SCHEDULE_DT = 0.01  # s between the states checked for each candidate start
DELAY_STEP = 0.05  # s by which an arm's start is pushed back


class ArmDistance(Protocol):
    def distance(self, q: Vec, between: tuple[str, str] | None = None) -> tuple[float, object]:
        """The least distance (m) between two arms' objects at the cell state q."""
        ...


def schedule(
    cell: CellModel,
    q: Vec,
    alone: Mapping[str, Trajectory],
    checker: ArmDistance,
    *,
    dt: float = SCHEDULE_DT,
    step: float = DELAY_STEP,
    clearance: float = DEFAULT_CLEARANCE,  # m: cell.yaml's, through the compiler
) -> dict[str, float]:
    """Each arm's start time (s from the part's start), in ``alone``'s order."""
    starts: dict[str, float] = {}
    for arm, traj in alone.items():
        if not starts:  # the first arm runs at once: nothing is running yet
            starts[arm] = 0.0
            continue
        running = {a: alone[a] for a in starts}
        busy_until = max(starts[a] + alone[a].duration for a in starts)
        delay = 0.0
        while True:
            together = on_one_axis(cell, q, {**running, arm: traj}, {**starts, arm: delay})
            t = np.append(np.arange(delay, delay + traj.duration, dt), delay + traj.duration)
            states, _, _ = together.sample(t)
            d = min(checker.distance(s, (arm, other))[0] for s in states for other in running)
            if d >= clearance:
                break
            if delay >= busy_until:
                # the others have stopped: what is left is the planner's own clearance
                if d > 0.0:
                    break
                raise Refused(
                    f"async: the {arm} arm's motion collides with {' and '.join(running)} "
                    "even after it has stopped"
                )
            delay = min(delay + step, busy_until)
        starts[arm] = delay
    return starts
