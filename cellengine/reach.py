"""Which arms reach each keypoint of a cell, with their tools (`cellengine show CELL --html`
colours keypoints by it; `import remodel` warns of a plan's keypoints that no arm reaches).

A keypoint asks the tool to come in along its frame: the TCP's z down the keypoint's z (into the
guide, the comb, the place), its x along the keypoint's x (along the cable), which turns the
keypoint frame half a turn about its x (:func:`approach`). A parallel gripper is symmetric about
its axis, so the same pose turned half a turn about the TCP's z holds as well: an arm reaches the
keypoint when its IK (the motion layer's, cellengine/motion/ik.py) finds either within its joint
limits. Collisions are not checked: a screen of where each arm can go, not a plan.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from cellengine.arrays import Mat
from cellengine.motion.ik import arm_ik
from cellengine.motion.robot import CellModel
from cellengine.world import World

# the keypoint frame turned half a turn about its x: z down into it, x kept, y = z x x
_HALF_TURN_X = np.diag([1.0, -1.0, -1.0, 1.0])
_HALF_TURN_Z = np.diag([-1.0, -1.0, 1.0, 1.0])


def approach(T_cell_keypoint: Mat) -> tuple[Mat, Mat]:
    """The TCP poses (cell frame) that hold the keypoint: its frame turned half a turn about
    its x, and that turned half a turn about the TCP's z."""
    T = np.asarray(T_cell_keypoint, dtype=float) @ _HALF_TURN_X
    return T, T @ _HALF_TURN_Z


def keypoint_reach(
    world: World, cell: CellModel, names: Iterable[str] | None = None
) -> dict[str, tuple[str, ...]]:
    """Each keypoint (every one of the world, or ``names``) -> the arms that reach it, in the
    cell's order of arms."""
    poses = world.keypoints()
    wanted = list(poses) if names is None else list(names)
    iks = {name: arm_ik(arm) for name, arm in cell.arms.items()}
    out: dict[str, tuple[str, ...]] = {}
    for name in wanted:
        T = poses[name] if name in poses else world.pose(name)
        tcp = approach(T)
        out[name] = tuple(
            arm for arm, ik in iks.items() if any(ik.solve(t) is not None for t in tcp)
        )
    return out
