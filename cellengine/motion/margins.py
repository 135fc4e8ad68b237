"""Transits that keep the cell's clearance: a security margin per pair for the planner.

The pairs the clearance measurement measures (:func:`~cellengine.motion.clearance.measured_pairs`:
one arm against the other, arms against the environment; contacts, held and allowed pairs left
out) must stay the clearance apart in every state the planner accepts and along every segment
it returns; every other pair keeps the exact check (margin 0). coal does the work: a pair
closer than its security margin is a collision (:class:`~cellengine.motion.collision.Keeping`).

The measured pairs out of each other's reach are not checked at all (they cannot touch), but
their reach spheres may be a few millimetres apart: the checker here checks them too
(:func:`~cellengine.motion.scene.checking_too`).

The segment check refuses a pair it finds closer than its margin plus a resolution (and its
steps never fall below that resolution over the pair's motion bound): 0.1 mm over the margin
for the measured pairs (a path 10.1 mm from a vial keeps a 10 mm clearance), the default
1 mm for the others, whose check stays what it was.

Where a transit starts or ends closer than the clearance to something (a hand leaving a grasp
at a comb), no path could keep it: that pair's margin is lowered, for that transit only, to what
its ends allow, less the resolution (the end itself must pass the segment check) and as much
again.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from cellengine.motion.clearance import measured_pairs
from cellengine.motion.collision import DEFAULT_CLEARANCE, CollisionChecker, Keeping
from cellengine.motion.scene import CollisionScene, checking_too

RESOLUTION = 1e-4  # m: the segment check refuses a measured pair within margin + this
ROOM = 1e-4  # m: below an end's distance besides the resolution, so the end itself passes


def keeping_clearance(checker: CollisionChecker, clearance: float, ends: ArrayLike) -> Keeping:
    """A checker of ``checker``'s scene keeping ``clearance`` (m) between the measured pairs
    everywhere but where ``ends`` (cell configurations: a transit's start and goals) are
    closer: there, what the closest end allows."""
    wide, measured = _margin_checker(checker.scene)
    margins = np.where(measured, clearance, 0.0)
    # an end must pass the segment check: its distance above the margin by the resolution
    limits = np.where(measured, clearance + RESOLUTION + ROOM, 0.0)
    for q in np.atleast_2d(np.asarray(ends, dtype=float)):
        for p, d in wide.closer_than(q, limits).items():
            margins[p] = min(margins[p], max(0.0, d - RESOLUTION - ROOM))
    return Keeping(wide, margins, np.where(measured, RESOLUTION, DEFAULT_CLEARANCE))


def _margin_checker(scene: CollisionScene) -> tuple[CollisionChecker, NDArray[np.bool_]]:
    """The checker of ``scene`` with its measured pairs out of reach checked too, and which of
    its pairs are measured; kept on the scene (a compile comes back to the same held states)."""
    kept = scene.margin_checker
    if kept is None:
        pairs, _ = measured_pairs(scene)
        wide = CollisionChecker(checking_too(scene, pairs))
        measured = set(pairs)
        kept = (wide, np.array([p in measured for p in wide.scene.pairs], dtype=bool))
        object.__setattr__(scene, "margin_checker", kept)
    wide, mask = kept
    return wide, mask
