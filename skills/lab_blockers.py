"""Which standing containers keep every robot from grasping a target (the cluttered table).

For each robot that can pick, every grasp of the target its tool allows is tried (the grasp
and its approach, each inverse kinematics solution, the other robots at home) in the scene
with every container where it stands; a collision with another container puts that
container in the grasp's way, and it is taken out of the scene to look for more behind it.
A grasp whose way is clear needs nothing moved. Otherwise the target is blocked by the
smallest set of containers that clears one grasp of one robot: those the allocator must
have moved first (to a free place, by the robot and in the order of least cost).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from cellengine.arrays import Mat
from cellengine.context import PlanningContext
from cellengine.motion.collision import CollisionChecker
from cellengine.motion.ik import ArmIK
from cellengine.motion.robot import CellModel, tool_parts
from cellengine.motion.scene import CollisionScene, pair_key, rearranged
from cellengine.skills import lab_geometry as lg

MAX_BLOCKERS = 3  # containers looked for behind one another in one grasp's way
# checkers by (arm, containers taken out), for one target: assembling a scene costs far more
# than checking in it
Checkers = dict[tuple[str, tuple[str, ...]], CollisionChecker]


def blockers(
    ctx: PlanningContext, target: str, T_at: Mat, robots: Sequence[str]
) -> tuple[str, ...]:
    """The containers to move before ``target`` (standing at ``T_at``) can be grasped by
    one of ``robots``; () when a grasp is clear, or when no grasp would be clear even with
    them moved (the planner then reports that grasp's own reason)."""
    world, cell, scene = ctx.world, ctx.cell, ctx.scene
    checkers: Checkers = {}  # per target: the tool's contact with it is allowed
    containers = set(world.objects.containers) - {target}
    body = lg.Body.of(world.container(target))
    home = ctx.home
    best: tuple[str, ...] | None = None
    for arm in robots:
        tool = world.cell.robots[arm].tool
        grasp = world.cell.tools[tool].grasp if tool is not None else "top"
        base = world.cell.robots[arm].base.matrix()[:3, 3]
        ik = ctx.iks[arm]
        # the tool may touch the target it closes on
        allow = {pair_key(part, target): "contact" for part in tool_parts(cell.arms[arm])}
        for T in lg.grasp_candidates(grasp, T_at, body, base):
            found = _in_the_way(
                cell, scene, ik, arm, home, (T, lg.approach_of(T)), containers, allow, checkers
            )
            if found == ():
                return ()
            if found is not None and (best is None or len(found) < len(best)):
                best = found
    return best or ()


def _in_the_way(
    cell: CellModel,
    scene: CollisionScene,
    ik: ArmIK,
    arm: str,
    home: np.ndarray,
    poses: Sequence[Mat],
    containers: set[str],
    allow: dict[tuple[str, str], str],
    checkers: Checkers,
) -> tuple[str, ...] | None:
    """The containers in the way of reaching every pose (one IK branch for all), or None when
    something else is (or no solution exists)."""
    removed: list[str] = []
    while len(removed) <= MAX_BLOCKERS:
        key = (arm, tuple(sorted(removed)))
        if key not in checkers:
            statics = [s for s in scene.statics if s.name not in removed]
            checkers[key] = CollisionChecker(rearranged(scene, statics, scene.held, allow))
        checker = checkers[key]
        hit = _first_hit(cell, checker, ik, arm, home, poses)
        if hit is None:
            return tuple(sorted(removed))
        if hit == "":
            return None
        if hit not in containers:
            return None
        removed.append(hit)
    return None


def _first_hit(
    cell: CellModel,
    checker: CollisionChecker,
    ik: ArmIK,
    arm: str,
    home: np.ndarray,
    poses: Sequence[Mat],
) -> str | None:
    """None when some IK solution reaches every pose free; else the container (or other
    object) the best solution hits; "" when a pose has no solution at all."""
    hits: list[str] = []
    for P in poses:
        sols = ik.solve_all(P)
        if len(sols) == 0:
            return ""
        free = False
        for sol in sols:
            q = np.array(home, dtype=float)
            q[cell.slices[arm]] = sol
            contact = checker.check(q)
            if contact is None:
                free = True
                break
            other = contact.b if contact.a.startswith(f"{arm}/") else contact.a
            hits.append(other)
        if not free:
            return hits[0]
    return None
