"""The published split rule, alone and in the executor."""

from __future__ import annotations

import numpy as np
import pytest

from cellengine.errors import InputError
from cellengine.execute import Compiler, compile_segments
from cellengine.execute.split import SPLIT_THRESHOLD, split_point
from cellengine.motion.gate import check_cell_trajectory
from tests.execute.scenes import cable_cell, crossing, home, tcp


def points(a: float, b: float, n: int) -> np.ndarray:
    """n poses along x from a to b (the other coordinates 0)."""
    W = np.repeat(np.eye(4)[None], n, axis=0)
    W[:, 0, 3] = np.linspace(a, b, n)
    return W


def test_split_where_a_waypoint_enters_the_others_neighbourhood() -> None:
    W = {"left": points(0.0, 1.0, 11), "right": points(5.0, 6.0, 21)}
    # left's waypoint 7 (x = 0.7) is the first within 0.35 of the right TCP at x = 1.0
    p = split_point(W, {"left": np.zeros(3), "right": np.array([1.0, 0, 0])}, 0.35)
    assert p is not None and p.trigger == "left"
    assert p.index == {"left": 7, "right": int(7 * 21 / 11)}  # the proportional index


def test_the_earlier_split_wins_and_none_when_no_one_comes_close() -> None:
    W = {"left": points(0.0, 1.0, 11), "right": points(0.0, -1.0, 11)}
    tcp = {"left": np.array([-0.5, 0, 0]), "right": np.array([0.95, 0, 0])}
    p = split_point(W, tcp, 0.1)  # right's waypoint 4 (x=-0.4) before left's 9 (x=0.9)
    assert p is not None and p.trigger == "right" and p.index == {"right": 4, "left": 4}
    assert split_point(W, {"left": np.array([9.0, 0, 0]), "right": np.array([9.0, 0, 0])}) is None


def test_no_split_at_the_start_when_the_arms_already_stand_close() -> None:
    """The published loop would split at waypoint 0 and never end."""
    W = {"left": points(0.0, 0.05, 6), "right": points(1.0, 2.0, 6)}
    tcp = {"left": np.zeros(3), "right": np.array([0.02, 0, 0])}
    assert split_point(W, tcp, SPLIT_THRESHOLD) is None


def test_split_really_splits_when_the_arms_come_close() -> None:
    world, cell, checker = cable_cell()
    ready, cross = crossing()
    program = compile_segments(world, cell, checker, [ready, cross], home(cell), "split")
    seg = program.segments[1]
    assert seg.report["parts"] == 2
    (at,) = seg.report["split_at"]
    # where the left hand's waypoint first comes within the threshold of the right TCP
    right_tcp = tcp(cell, "right", seg.trajectory.q[:1])[0, :3, 3]
    left = next(p.poses for p in cross.paths if p.arm == "left")
    right = next(p.poses for p in cross.paths if p.arm == "right")
    near = np.linalg.norm(left[:, :3, 3] - right_tcp, axis=1) <= SPLIT_THRESHOLD
    assert at["left"] == int(np.argmax(near)) > 0
    assert at["right"] == int(at["left"] * len(right) / len(left))
    # the arms stop together at the split: one rest in the middle of the segment
    traj = seg.trajectory
    resting = np.flatnonzero(np.abs(traj.qd).max(axis=1) < 1e-9)
    inner = traj.t[resting[(resting > 0) & (resting < len(traj) - 1)]]
    assert len(inner) >= 1
    q_mid, _, _ = traj.sample(inner[0])
    p_left = tcp(cell, "left", q_mid[None])[0, :3, 3]
    assert np.allclose(p_left, left[at["left"] - 1, :3, 3], atol=1e-6)
    assert check_cell_trajectory(traj, cell, checker).ok


def test_without_the_split_the_same_motion_is_refused() -> None:
    """Async plans each arm against the other standing at its start, in one piece: the left
    arm then runs into the right arm where it no longer is."""
    world, cell, checker = cable_cell()
    ready, cross = crossing()
    c = Compiler(world, cell, checker, home(cell), "async")
    c.add(ready)
    with pytest.raises(InputError, match=r"step 2 \(cross\): the left arm's Cartesian path"):
        c.add(cross)
