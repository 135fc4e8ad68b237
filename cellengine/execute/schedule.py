"""The asynchronous scheduler: each arm on its own timing, started as soon as it is safe.

Arms solved apart are each planned against the others standing where they start, so running
them at once can collide where both arms pass through one place at one time. The scheduler
takes the arms in order: the first starts at once; each next one's trajectory is checked
against those already scheduled, with the whole cell's state sampled every ``dt`` over the
time the new arm moves, and its start is pushed back by ``step`` until no sample collides.
The time before its start needs no check: the arms already running were planned with it
standing at its start.

Once every arm already running has stopped, a delay no longer changes anything: an arm that
still collides then collides with where the others end, and is refused.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np
from numpy.typing import NDArray

from cellengine.execute.merge import on_one_axis
from cellengine.execute.refused import Refused
from cellengine.motion.robot import CellModel
from cellengine.motion.trajectory import Trajectory

Vec = NDArray[np.float64]
CollidingRows = Callable[[Vec], NDArray[np.bool_]]  # whole-cell states (k, nq) -> (k,)

SCHEDULE_DT = 0.01  # s between the states checked for each candidate start
DELAY_STEP = 0.05  # s by which a colliding arm's start is pushed back


def schedule(
    cell: CellModel,
    q: Vec,
    alone: Mapping[str, Trajectory],
    colliding: CollidingRows,
    *,
    dt: float = SCHEDULE_DT,
    step: float = DELAY_STEP,
) -> dict[str, float]:
    """Each arm's start time (s from the part's start), in ``alone``'s order."""
    starts: dict[str, float] = {}
    for arm, traj in alone.items():
        if not starts:  # the first arm runs at once: nothing is running yet
            starts[arm] = 0.0
            continue
        scheduled = {a: alone[a] for a in starts}
        busy_until = max((starts[a] + alone[a].duration for a in starts), default=0.0)
        delay = 0.0
        while _collides(cell, q, scheduled, starts, arm, traj, delay, colliding, dt):
            if delay >= busy_until:
                raise Refused(
                    f"async: the {arm} arm's motion collides with where "
                    f"{' and '.join(starts)} stand(s) after moving"
                )
            delay = min(delay + step, busy_until)
        starts[arm] = delay
    return starts


def _collides(
    cell: CellModel,
    q: Vec,
    scheduled: Mapping[str, Trajectory],
    starts: Mapping[str, float],
    arm: str,
    traj: Trajectory,
    delay: float,
    colliding: CollidingRows,
    dt: float,
) -> bool:
    together = on_one_axis(cell, q, {**scheduled, arm: traj}, {**starts, arm: delay})
    t = np.append(np.arange(delay, delay + traj.duration, dt), delay + traj.duration)
    states, _, _ = together.sample(t)
    return bool(colliding(states).any())
