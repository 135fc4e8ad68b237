"""The async scheduler: an arm whose motion would meet the other's running one waits."""

from __future__ import annotations

import numpy as np
import pytest

from cellengine.errors import InputError
from cellengine.execute import Compiler
from cellengine.execute.merge import on_one_axis
from cellengine.execute.refused import Refused
from cellengine.execute.retime import timed
from cellengine.execute.schedule import schedule
from cellengine.execute.strategies import _apart, solve_segment
from cellengine.info.cell import DEFAULT_CLEARANCE
from cellengine.motion.gate import check_cell_trajectory
from cellengine.motion.trajectory import Trajectory
from cellengine.program import ArmPath, Segment
from tests.execute.scenes import LEFT_READY, RIGHT_HIGH, cable_cell, home, line, states, sweep


@pytest.fixture(scope="module")
def swept() -> tuple[Compiler, np.ndarray]:
    world, cell, checker = cable_cell()
    ready, up, seg = sweep()
    c = Compiler(world, cell, checker, home(cell), "async")
    c.add(ready)
    c.add(up)
    q = c.q.copy()
    c.add(seg)
    return c, q


def apart(q: np.ndarray) -> dict[str, Trajectory]:
    """The sweep's arms each solved and timed on their own, from q."""
    _, cell, checker = cable_cell()
    (part,) = solve_segment(cell, checker, sweep()[2], q, "async")
    return {
        a: timed(r, cell.arms[a].limits, cell.arms[a].joint_names) for a, r in part.rows.items()
    }


def test_run_at_once_the_arms_would_collide(swept: tuple[Compiler, np.ndarray]) -> None:
    _, cell, checker = cable_cell()
    _, q = swept
    alone = apart(q)
    at_once = on_one_axis(cell, q, alone)
    assert checker.check_batch(states(at_once, 0.01)).any()


def test_async_delays_the_right_arm_until_it_is_safe(swept: tuple[Compiler, np.ndarray]) -> None:
    c, _ = swept
    _, cell, checker = cable_cell()
    seg = c.segments[-1]
    (delays,) = seg.report["delays_s"]
    assert delays["left"] == 0.0 and delays["right"] > 0.2
    assert seg.report["merge"] == "async" and seg.report["solved"] == ["apart"]
    gate = check_cell_trajectory(seg.trajectory, cell, checker)
    assert gate.ok and gate.min_arm_distance is not None
    assert gate.min_arm_distance >= 0.5 * DEFAULT_CLEARANCE  # 10 ms samples, then 1 ms
    # the right arm stands until its start, then moves
    start = seg.trajectory.start_time
    _, qd, _ = seg.trajectory.sample(np.array([start + 0.5 * delays["right"]]))
    assert np.allclose(qd[0, cell.slices["right"]], 0.0)
    assert not np.allclose(qd[0, cell.slices["left"]], 0.0)
    # the right arm starts moving at its delay and the segment lasts until both arms stop
    ts = np.linspace(start, seg.trajectory.end_time, 4001)
    _, qd, _ = seg.trajectory.sample(ts)
    moving = np.flatnonzero(np.abs(qd[:, cell.slices["right"]]).max(axis=1) > 1e-9)
    step = ts[1] - ts[0]
    assert abs(ts[moving[0]] - (start + delays["right"])) <= step
    assert (
        ts[moving[-1]] >= seg.trajectory.end_time - 2 * step
        or np.abs(qd[-2, cell.slices["left"]]).max() > 1e-9
    )


def test_one_step_earlier_would_come_too_close(swept: tuple[Compiler, np.ndarray]) -> None:
    _, q = swept
    _, cell, checker = cable_cell()
    alone = apart(q)
    starts = schedule(cell, q, alone, checker)
    earlier = on_one_axis(cell, q, alone, {**starts, "right": starts["right"] - 0.05})
    t = np.arange(starts["right"] - 0.05, earlier.end_time, 0.01)
    s, _, _ = earlier.sample(t)
    closest = min(checker.distance(x, ("left", "right"))[0] for x in s)
    assert closest < DEFAULT_CLEARANCE


def _collide_at_the_end() -> Segment:
    """The right hand comes down onto where the left hand ends: no delay helps."""
    return Segment(
        1,
        "collide at the end",
        (
            ArmPath("left", "cartesian", line(LEFT_READY, (0.40, -0.02, 0.20))),
            ArmPath("right", "cartesian", line(RIGHT_HIGH, (0.40, -0.02, 0.27))),
        ),
    )


def test_async_plans_each_arm_against_where_the_earlier_ones_end() -> None:
    world, cell, checker = cable_cell()
    ready_seg, up, _ = sweep()
    c = Compiler(world, cell, checker, home(cell), "async")
    c.add(ready_seg)
    c.add(up)
    with pytest.raises(InputError) as e:
        c.add(_collide_at_the_end())
    message = str(e.value)
    assert message.startswith(
        "step 2 (collide at the end): the right arm's Cartesian path stops at "
    )
    assert "collision between 'left/" in message


def test_the_scheduler_refuses_an_arm_that_collides_where_the_other_ends() -> None:
    world, cell, checker = cable_cell()
    ready_seg, up, _ = sweep()
    c = Compiler(world, cell, checker, home(cell), "async")
    c.add(ready_seg)
    c.add(up)
    paths = {p.arm: p for p in _collide_at_the_end().paths}
    part = _apart(cell, checker, paths, c.q, "apart")  # both against the other's start
    own = {a: timed(r, cell.arms[a].limits, cell.arms[a].joint_names) for a, r in part.rows.items()}
    with pytest.raises(Refused) as e:
        schedule(cell, c.q, own, checker)
    assert (
        str(e.value) == "async: the right arm's motion collides with left even after it has stopped"
    )
