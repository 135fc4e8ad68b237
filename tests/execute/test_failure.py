"""Where a segment failed, as data (execute/failure.py): what the solving and checking code
gives the compiler, and the compiler the error, on hand-made segments of the cable cell."""

from __future__ import annotations

import numpy as np
import pytest

from cellengine.errors import StepError
from cellengine.execute import Compiler
from cellengine.program import ArmPath, Segment
from tests.execute.scenes import LEFT_READY, cable_cell, home, line, pose, tcp


def _failed(*segments: Segment) -> StepError:
    """The error of compiling ``segments`` one after another (the last fails)."""
    world, cell, checker = cable_cell()
    compiler = Compiler(world, cell, checker, home(cell))
    for s in segments[:-1]:
        compiler.add(s)
    with pytest.raises(StepError) as e:
        compiler.add(segments[-1])
    return e.value


def test_a_transit_goal_out_of_reach_is_marked_and_the_arms_shown_where_they_were() -> None:
    _, cell, _ = cable_cell()
    far = Segment(0, "far", (ArmPath("left", "transit", pose((1.5, 0.35, 0.2))[None]),))
    e = _failed(far)
    f = e.failure
    assert f is not None and f.at is not None and f.before is not None
    assert (f.step, f.segment, f.before.segments) == (0, far, ())
    assert (f.at.kind, f.at.pair, f.at.time) == ("unreachable", None, None)
    np.testing.assert_allclose(f.at.q, home(cell), atol=1e-12)
    np.testing.assert_allclose(f.at.targets["left"], [1.5, 0.35, 0.2], atol=1e-12)


def test_a_cartesian_path_into_the_table_shows_the_colliding_configuration() -> None:
    """Down from above the platform through the table top (z = 0): the pose is the one
    where the left fingers meet the table, after the one segment compiled."""
    _, cell, _ = cable_cell()
    x, y, _ = LEFT_READY
    above = Segment(0, "above", (ArmPath("left", "transit", pose((x, y + 0.2, 0.1))[None]),))
    down = Segment(
        1, "down", (ArmPath("left", "cartesian", line((x, y + 0.2, 0.1), (x, y + 0.2, -0.05))),)
    )
    e = _failed(above, down)
    f = e.failure
    assert f is not None and f.at is not None and f.before is not None
    assert [s.segment.label for s in f.before.segments] == ["above"]
    assert f.at.kind == "collision" and f.at.pair is not None
    assert f.at.pair[0].startswith("left/tool") and f.at.pair[1] == "table"
    z = tcp(cell, "left", np.asarray(f.at.q)[None])[0, 2, 3]  # the fingertips at the table
    assert -0.005 < z < 0.005, z
