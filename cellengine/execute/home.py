"""A plan's return home (``return_home: true``): after its last step, the arms that are not
at their cell.yaml homes go back there, planned in joint space (to the home configuration
itself, not another of its IK solutions), timed and gated as any transit. A plan that does
so ends where it starts, so ``run --cycles N`` can repeat it."""

from __future__ import annotations

import numpy as np

from cellengine.arrays import Vec
from cellengine.execute.compile import Compiler
from cellengine.execute.refused import Refused, in_plan_terms
from cellengine.execute.solve import to_configuration
from cellengine.execute.strategies import Part
from cellengine.program import ArmPath, Segment

LABEL = "return home"
AT_HOME = 1e-6  # rad (m for a prismatic joint): an arm this close to home is there


def return_home(compiler: Compiler, home: Vec, step: int) -> None:
    """The move home of every arm not at ``home``, added to ``compiler`` as a segment of plan
    step ``step`` (its last); nothing when they all are; InputError when no safe move is
    found."""
    cell, q = compiler.cell, compiler.q
    off = tuple(
        a for a, s in cell.slices.items() if float(np.max(np.abs(q[s] - home[s]))) > AT_HOME
    )
    if not off:
        return
    goals = cell.split(home)
    paths = tuple(ArmPath(a, "transit", cell.arms[a].fk(goals[a])[None]) for a in off)
    segment = Segment(step, LABEL, paths)
    try:
        rows = to_configuration(cell, compiler.checker, off, q, home, compiler.transit_clearance)
    except Refused as e:
        raise in_plan_terms(segment, e) from None
    part = Part(q, {a: rows[:, cell.slices[a]] for a in off}, rows, {}, "together")
    compiler.add_parts(segment, [part])
