"""Which transit goals can follow the arm's Cartesian paths ahead (execute/following.py), on
the reference cable-routing cell: the tool tipped 30 deg, 80 mm above the table, on an arc
180 mm around the left arm's base (where the tool meets the shoulder on some branches)."""

from __future__ import annotations

import math
import re

import numpy as np

from cellengine import geometry as g
from cellengine.execute import solve
from cellengine.execute.following import followable
from cellengine.execute.refused import Refused
from cellengine.motion.ik import arm_ik
from tests.execute.scenes import cable_cell, home


def arc_near_the_base(base: np.ndarray) -> np.ndarray:
    poses = []
    for a in np.linspace(-0.6, 0.6, 61):  # 1.2 deg and 3.6 mm apart
        p = base + np.array(
            [0.18 * math.cos(a - math.pi / 2), 0.18 * math.sin(a - math.pi / 2), 0.08]
        )
        poses.append(g.transform(g.rot_z(a) @ g.rot_x(math.pi) @ g.rot_y(math.radians(30)), p))
    return np.array(poses)


def stop_of(cell: object, checker: object, arm: str, poses: np.ndarray, start: np.ndarray) -> str:
    """Why the arm's Cartesian path along ``poses`` from ``start`` stops ("" when it runs)."""
    try:
        solve.cartesian(cell, checker, arm, poses, start)  # type: ignore[arg-type]
    except Refused as e:
        return str(e)
    return ""


def test_a_goal_follows_the_poses_ahead_unless_its_path_runs_into_the_arm_itself() -> None:
    """A goal that does not follow: its Cartesian path stops on the arm itself (two of its
    own parts, or out of its branch's reach). One that does: its path runs, or stops on
    something else (the table: the compiler's to find out)."""
    _, cell, checker = cable_cell()
    q = home(cell)
    arm = "left"
    poses = arc_near_the_base(cell.arms[arm].T_cell_base[:3, 3])
    sols = arm_ik(cell.arms[arm]).solve_all(poses[0])
    flags = followable(cell, checker, arm, sols, poses, q)
    assert True in flags and False in flags
    for sol, follows in zip(sols, flags, strict=True):
        start = q.copy()
        start[cell.slices[arm]] = sol
        why = stop_of(cell, checker, arm, poses, start)
        itself = re.search(r"between 'left/[^']*' and 'left/", why) or "IK" in why
        assert bool(itself) == (not follows), why


def test_without_poses_ahead_every_goal_follows() -> None:
    _, cell, checker = cable_cell()
    sols = arm_ik(cell.arms["left"]).solve_all(
        arc_near_the_base(cell.arms["left"].T_cell_base[:3, 3])[0]
    )
    assert followable(cell, checker, "left", sols, None, home(cell)) == [True] * len(sols)
