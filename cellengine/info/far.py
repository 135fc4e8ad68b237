"""A platform no robot can reach: usually a pose in the wrong unit or a sign slip, which
every plan using the platform would report as IK failures one keypoint at a time.

The bound is kinematic, not tuned: an arm's TCP is never farther from its shoulder (the
base frame raised by d1, where the upper arm turns) than the sum of its links and wrist
offsets plus the tool's TCP offset (the triangle inequality over the DH chain). Only the
built-in UR models have a DH table here; URDF robots are not bounded.
"""

from __future__ import annotations

import math

import numpy as np

from cellengine.errors import Problem
from cellengine.info.cell import Cell, Robot
from cellengine.info.yamlio import YamlDoc
from cellengine.motion.ur_ik import UR_DH
from cellengine.world import World


def out_of_reach(world: World, doc: YamlDoc) -> list[Problem]:
    """A warning per platform that has keypoints and none within any robot's bound."""
    arms = [(name, *b) for name, r in world.cell.robots.items() if (b := arm_bound(world.cell, r))]
    if not arms:
        return []
    out = []
    for pname in world.platforms:
        margins = [
            (float(np.linalg.norm(T[:3, 3] - shoulder)) - reach, ref, arm, reach)
            for ref, T in world.keypoints(pname).items()
            for arm, shoulder, reach in arms
        ]
        if not margins or min(margins)[0] <= 0.0:
            continue
        margin, ref, arm, reach = min(margins)
        message = (
            f"platforms.{pname}: no robot reaches it: its nearest keypoint {ref} is "
            f"{(margin + reach) * 1000:.0f} mm from {arm}'s shoulder, which reaches "
            f"{reach * 1000:.0f} mm at most with its tool (is its pose in the file's length "
            "unit?)"
        )
        out.append(doc.error(message, ("platforms", pname, "pose")).problems[0])
    return out


def arm_bound(cell: Cell, robot: Robot) -> tuple[np.ndarray, float] | None:
    """The robot's shoulder in the cell frame and how far its TCP can be from it."""
    if not isinstance(robot.model, str) or robot.model not in UR_DH:
        return None
    dh = UR_DH[robot.model]
    T_base = robot.base.matrix()
    shoulder = T_base[:3, 3] + dh.d[0] * T_base[:3, 2]
    tool = cell.tools.get(robot.tool) if robot.tool is not None else None
    tcp = math.dist(tool.tcp.xyz, (0.0, 0.0, 0.0)) if tool is not None else 0.0
    return shoulder, sum(abs(v) for v in (*dh.a, *dh.d[1:])) + tcp
