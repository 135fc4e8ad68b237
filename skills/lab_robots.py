"""What each robot of a lab cell can do, derived from its tool and its kinematics.

Skills (names the allocator matches against the motion primitives' needs):

- ``pick``, ``place``: any robot with a parallel gripper;
- ``weigh``: its tool has a load cell (``load_cell: true``);
- ``hold``: it grasps from the side (``grasp: side``), leaving a container's cap free;
- ``turn_cap``: it grasps from above and its last joint turns about the tool's axis (the
  fingers can screw a cap off);
- ``pour``: it can tilt what it holds: six joints or more, or a last joint whose axis is
  horizontal (the published robot 1: a side gripper turning about x).

The kinematic tests are made at the robot's home configuration (or all joints at zero),
where the tool points as it works.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from cellengine.motion.robot import Arm, CellModel, home_configuration
from cellengine.world import World

PARALLEL = 0.99  # |cos| above which two axes count as parallel
LEVEL = 0.1  # |cos| with the vertical below which an axis counts as horizontal


def robot_skills(world: World, cell: CellModel) -> dict[str, frozenset[str]]:
    """Each robot's skills, by name (see the module notes)."""
    out: dict[str, frozenset[str]] = {}
    home = home_configuration(cell)
    for name, arm in cell.arms.items():
        robot = world.cell.robots[name]
        tool = world.cell.tools.get(robot.tool) if robot.tool is not None else None
        if tool is None:
            out[name] = frozenset()
            continue
        skills = {"pick", "place"}
        if tool.load_cell:
            skills.add("weigh")
        if tool.grasp == "side":
            skills.add("hold")
        axis, tool_z = _last_axis(arm, home[cell.slices[name]])
        if tool.grasp == "top" and abs(float(axis @ tool_z)) > PARALLEL:
            skills.add("turn_cap")
        if arm.nq >= 6 or abs(float(axis[2])) < LEVEL:
            skills.add("pour")
        out[name] = frozenset(skills)
    return out


def _last_axis(arm: Arm, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The last joint's axis and the tool's z at ``q``, unit vectors in the cell frame."""
    J = arm.jacobian(q)
    w = np.asarray(J[3:6, -1], dtype=float)
    n = float(np.linalg.norm(w))
    axis = w / n if n > 1e-9 else np.zeros(3)  # a prismatic last joint turns nothing
    return axis, np.asarray(arm.fk(q)[:3, 2], dtype=float)


def describe(skills: Mapping[str, frozenset[str]]) -> str:
    """``robot1: hold, pick, place, pour, weigh; robot2: ...`` for messages."""
    return "; ".join(f"{r}: {', '.join(sorted(s)) or 'none'}" for r, s in skills.items())
