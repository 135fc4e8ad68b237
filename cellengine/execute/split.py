"""The published split rule (ExecuteDualTraj of the cable-routing paper, Algorithm 2).

Each arm's Cartesian path is planned on its own, with the other arm standing where it is; so
a waypoint that comes close to where the other arm stands now is planned against a pose the
other arm will have left by then. Where one arm's waypoint i comes within a threshold of the
other arm's current TCP, both waypoint lists are split, the other's at the proportional index
j = i * len(other) / len(own); the first parts are planned and run, the arms' positions are
updated, and the rest is split again from there.

Two changes make the rule terminate and keep its intent: a split is where an arm *enters* the
other's neighbourhood (waypoint i within the threshold, waypoint i - 1 not, i >= 1), never at
the start: when the arms already stand within the threshold a split at 0 would leave an empty
first part (the published loop would not end there). And when both arms enter, the earlier
split (in fraction of its path) wins, so neither arm runs past a place it had to stop at.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cellengine.arrays import Poses, Vec

# m between a waypoint and the other arm's TCP. The paper calls it collision_threshold and
# does not give its value; 10 cm is about a gripper's width plus the fingers' travel.
SPLIT_THRESHOLD = 0.10


@dataclass(frozen=True)
class SplitPoint:
    """Split both lists: waypoints before ``index[arm]`` go in the first part."""

    index: dict[str, int]
    trigger: str  # the arm whose waypoint came within the threshold


def split_point(
    waypoints: dict[str, Poses], tcp: dict[str, Vec], threshold: float = SPLIT_THRESHOLD
) -> SplitPoint | None:
    """Where to split two arms' waypoint lists (N, 4, 4), given each arm's current TCP
    position ``tcp[arm]`` (3,); None when no waypoint enters the other arm's neighbourhood."""
    if len(waypoints) != 2:
        return None
    a, b = waypoints
    best: tuple[float, str, int] | None = None
    for own, other in ((a, b), (b, a)):
        i = _entering(waypoints[own], tcp[other], threshold)
        if i is None:
            continue
        fraction = i / len(waypoints[own])
        if best is None or fraction < best[0]:
            best = (fraction, own, i)
    if best is None:
        return None
    _, own, i = best
    other = b if own == a else a
    j = int(i * len(waypoints[other]) / len(waypoints[own]))
    return SplitPoint({own: i, other: j}, own)


def _entering(W: Poses, p_other: Vec, threshold: float) -> int | None:
    near = np.linalg.norm(W[:, :3, 3] - p_other, axis=1) <= threshold
    entering = np.flatnonzero(near[1:] & ~near[:-1]) + 1
    return int(entering[0]) if len(entering) else None
