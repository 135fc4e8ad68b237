"""Looking ahead: can the next segments run from a configuration? Geometry only.

A transit can reach its goal pose in several configurations, and the choice decides what
comes after: an arm left on a branch that cannot follow its next Cartesian path, or with an
elbow where the other arm's next move passes. Before a transit commits to a goal, the
segments after it, up to the next transit (which chooses afresh) and at most
``PREVIEW_SEGMENTS`` of them, are solved from that goal as the published method solves them
(each arm's Cartesian path with the other arms standing where they are; a closed chain as
one), without timing, each with what the grippers hold and the contacts it expects then
(its events applied to the compiler's holding, which is put back after). A goal from which
one of them fails goes to the back of the transit's queue.

This is a cheap first filter (a few Cartesian paths per goal looked at); what it cannot see
(a failure further on, a timing or a gate failure) the compiler's search handles by coming
back to the transit (search.py).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from cellengine.arrays import Vec
from cellengine.execute import solve
from cellengine.execute.held import Holding
from cellengine.execute.refused import Refused
from cellengine.execute.solve import Accept
from cellengine.motion.collision import CollisionChecker
from cellengine.motion.robot import CellModel
from cellengine.program import Segment

PREVIEW_SEGMENTS = 6


def upcoming(following: Sequence[Segment]) -> list[Segment]:
    """The segments a transit's choice of goal decides: those before the next transit."""
    out = []
    for seg in following[:PREVIEW_SEGMENTS]:
        if any(p.kind == "transit" for p in seg.paths):
            break
        out.append(seg)
    return out


def preview(cell: CellModel, holding: Holding, following: Sequence[Segment]) -> Accept:
    """Whether ``upcoming(following)`` can be solved one after the other from a cell
    configuration, each with the grippers' jaws, held objects and contacts as the compiler
    will have them (a closed hand's fingers are elsewhere than an open one's)."""
    segments = upcoming(following)

    def accept(q: Vec) -> bool:
        here = np.array(q)
        now = holding.state
        try:
            for seg in segments:
                _hold(cell, holding, seg, here)
                here = _solved(cell, holding.checker, seg, here)
        except (Refused, ValueError, KeyError):  # held objects that cannot ride: as compiling
            return False
        finally:
            holding.restore(now)
        return True

    return accept


def _hold(cell: CellModel, holding: Holding, seg: Segment, q: Vec) -> None:
    """``holding`` as the compiler sets it when ``seg`` begins at ``q``."""
    for e in seg.before:
        T_cell_tcp = cell.arms[e.arm].fk(cell.split(q)[e.arm])
        holding.set(e.arm, e.holds, T_cell_tcp, e.mode)
    holding.touch(seg.contacts)


def _solved(cell: CellModel, checker: CollisionChecker, seg: Segment, q: Vec) -> Vec:
    """Where the arms are after ``seg``, solved the cheap way."""
    paths = {p.arm: p for p in seg.paths if p.arm in cell.arms}
    if seg.closed_chain is not None and seg.closed_chain[0] in paths:
        leader, follower = seg.closed_chain
        rows, _ = solve.closed_chain(cell, checker, leader, follower, paths[leader].poses, q)
        out: Vec = rows[-1].copy()
        return out
    here = q.copy()
    for arm, p in paths.items():
        rows, _ = solve.cartesian(cell, checker, arm, p.poses, q)
        here[cell.slices[arm]] = rows[-1]
    return here
