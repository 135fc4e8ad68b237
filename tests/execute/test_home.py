"""A plan's return home: the arms back at their homes in joint space, timed and gated as any
transit; nothing when they are there."""

from __future__ import annotations

import numpy as np

from cellengine.execute import Compiler
from cellengine.execute.home import return_home
from tests.execute.scenes import cable_cell, home, ready


def test_the_arms_go_back_to_their_homes_exactly() -> None:
    world, cell, checker = cable_cell()
    compiler = Compiler(world, cell, checker, home(cell))
    compiler.add(ready())
    away = compiler.q.copy()
    assert np.abs(away - home(cell)).max() > 0.1
    return_home(compiler, home(cell), 0)
    program = compiler.program()
    back = program.segments[-1]
    assert (back.segment.label, back.segment.step, back.segment.arms()) == (
        "return home",
        0,
        ("left", "right"),
    )
    assert np.array_equal(back.trajectory.q[0], away)
    assert np.abs(back.trajectory.q[-1] - home(cell)).max() < 1e-9
    assert back.report["checks"]["gate"] and back.trajectory.duration > 0.5
    assert back.trajectory.start_time == program.segments[0].trajectory.end_time


def test_nothing_is_added_when_the_arms_are_home() -> None:
    world, cell, checker = cable_cell()
    compiler = Compiler(world, cell, checker, home(cell))
    return_home(compiler, home(cell), 0)
    assert compiler.program().segments == ()
