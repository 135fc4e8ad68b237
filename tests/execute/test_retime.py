"""Timing joint rows (execute/retime.py): a path whose spline bulges past a joint's range is
refused as a motion failure the compiler reports at its segment, not a crash."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cellengine.execute.refused import Refused
from cellengine.execute.retime import fastest, timed
from tests.execute.scenes import cable_cell

READY = np.array([0.0, -1.57, 1.57, -1.57, -1.57, 0.0])


def along_the_limit() -> np.ndarray:
    """Wrist 1 up to a hair under its 2 pi limit and back down steeply: the cubic through
    the rows overshoots the limit by about 6 mrad between the third and fourth."""
    rows = np.repeat(READY[None], 5, axis=0)
    rows[:, 3] = [6.0, 6.27, 2.0 * math.pi - 1e-6, 6.2, 4.0]
    return rows


def test_a_spline_past_a_joint_limit_is_refused() -> None:
    _, cell, _ = cable_cell()
    arm = cell.arms["left"]
    with pytest.raises(Refused) as err:
        timed(along_the_limit(), arm.limits, arm.joint_names)
    assert str(err.value).startswith(
        "the path runs along a joint's limit: the spline through the waypoints leaves joint 3's "
        "range [-6.28319, 6.28319] between waypoints 2 and 3 (reaching 6.289"
    )
    with pytest.raises(Refused):
        fastest(along_the_limit(), arm.limits)
