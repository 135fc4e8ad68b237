"""An independent check of a compiled cable-routing program (issue #13, point 5).

Written without the skills' code: it reads only the compiled Program (segments' labels and
timed trajectories, the gripper events), the world's keypoints and dimensions, forward
kinematics (cellengine.motion.robot), the engine's trajectory gate and its grippers' state
(cellengine.execute.held: the jaws and what they hold). It checks:

- ``insert``: for each RouteCable guide, in plan order, a segment of that step labelled
  "RouteCable <guide>: insert"; at its end both hands hold what the step routes (a cable, or
  a harness's group of cables), the guide's slot lies
  on the segment between the two fingertips within the slot's gap / 2 and that segment is
  within 15 deg of the guide's x (the cable runs through the slot);
- ``order``: the inserts come in the plan's order;
- ``limits``: joint position, velocity and acceleration at 1 ms samples (the gate);
- the least distance between the two arms (every 10 ms), with the grippers' jaws as the
  program's gripper events leave them: reported, with ``below_target`` when under 10 mm,
  but not a failure (the reference plans came within 3.7 mm, at the pick, before issue #13).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np

from cellengine.arrays import Vec
from cellengine.execute.held import Holding
from cellengine.motion.collision import CollisionChecker
from cellengine.motion.gate import ArmDistance, check_trajectory
from cellengine.motion.robot import CellModel
from cellengine.motion.trajectory import concatenate
from cellengine.pipeline import Compiled
from cellengine.program import CompiledSegment, GripperEvent, Program
from cellengine.world import World

ANGLE_MAX = 15.0  # deg between the cable and the guide's x
DISTANCE_DT = 0.010  # s between the samples of the arms' distance
MIN_ARM_DISTANCE = 0.010  # m


@dataclass(frozen=True)
class Failure:
    kind: str  # insert | order | limits
    message: str


@dataclass(frozen=True)
class CheckResult:
    failures: tuple[Failure, ...]
    min_arm_distance: float | None  # m
    closest_pair: tuple[str, str] | None

    @property
    def ok(self) -> bool:
        return not self.failures

    @property
    def below_target(self) -> bool:
        """The arms come closer than the 10 mm target."""
        return self.min_arm_distance is not None and self.min_arm_distance < MIN_ARM_DISTANCE


Route = tuple[int, str, tuple[str, ...]]  # a RouteCable step: its index, cable, guides


def routes(compiled: Compiled) -> list[Route]:
    """The plan's RouteCable steps (from the plan, not a skill): what each routes where."""
    out: list[Route] = []
    for i, step in enumerate(compiled.loaded.plan.steps):
        if step.skill == "RouteCable":
            guides = tuple(str(g) for g in getattr(step, "guides"))  # noqa: B009 (plan field)
            out.append((i, str(getattr(step, "cable")), guides))  # noqa: B009
    return out


def route_guides(compiled: Compiled) -> list[str]:
    """The guides of the plan's RouteCable steps, in plan order."""
    return [g for _, _, guides in routes(compiled) for g in guides]


def check_compiled(compiled: Compiled, world: World | None = None) -> CheckResult:
    """Check ``compiled`` against ``world`` (default: its own; another one moves keypoints)."""
    cell = compiled.cell
    a, b = tuple(cell.arms)
    tooled = _jaw_checkers(compiled)

    def distance(k: int) -> ArmDistance:
        return lambda q: tooled[k][1].distance(q, (a, b))

    cells = [c for c, _ in tooled]
    return check_program(
        compiled.program, world or compiled.world, cell, routes(compiled), distance, cells
    )


def _jaw_checkers(compiled: Compiled) -> list[tuple[CellModel, CollisionChecker]]:
    """Each segment's robot models and collision checker: with the tools the arms carry then
    (a tool change switches both), the grippers' jaws (and what they hold) as the program's
    gripper events leave them: a closed gripper's fingers are not where an open one's are."""
    program = compiled.program
    kept: dict[tuple[tuple[str, str | None], ...], tuple[CellModel, Holding]] = {}
    last: tuple[tuple[str, str | None], ...] | None = None
    out = []
    for seg in program.segments:
        tools = program.tools_at(seg.trajectory.start_time) if program.changes else {}
        key = tuple(sorted(tools.items()))
        if key not in kept:
            ctx = compiled.context.tooled(tools)
            kept[key] = (ctx.cell, Holding(ctx.world, ctx.scene))
        cell, holding = kept[key]
        if last is not None and last != key:  # a tool change: what is held carries over
            state = kept[last][1].state
            changed = {a for a, t in tools.items() if dict(last).get(a) != t}
            jaw = {a: v for a, v in state.jaw.items() if a not in changed}
            holding.restore(replace(state, jaw=jaw))
        last = key
        _apply(cell, holding, seg.segment.before, seg.trajectory.q[0])
        out.append((cell, holding.checker))
        _apply(cell, holding, seg.segment.after, seg.trajectory.q[-1])
    return out


def _apply(cell: CellModel, holding: Holding, events: Sequence[GripperEvent], q: Vec) -> None:
    for e in events:
        T_cell_tcp = cell.arms[e.arm].fk(cell.split(q)[e.arm])
        holding.set(e.arm, e.holds, T_cell_tcp, e.mode)


def check_program(
    program: Program,
    world: World,
    cell: CellModel,
    steps: Sequence[Route],
    distance: Callable[[int], ArmDistance],
    cells: Sequence[CellModel] | None = None,
) -> CheckResult:
    """The checks; ``distance(k)``: the distance between the two arms during segment k;
    ``cells[k]``: the robot models with the tools the arms carry then (default ``cell``)."""
    failures = _inserts(program, world, cells or [cell] * len(program.segments), steps)
    report = check_trajectory(
        concatenate([s.trajectory for s in program.segments]), cell.joint_names, cell.limits
    )
    failures += [Failure("limits", f"{v.kind} limit: {v}") for v in report.violations]
    least, pair = _least_arm_distance(program, distance)
    return CheckResult(tuple(failures), least, pair)


def _least_arm_distance(
    program: Program, distance: Callable[[int], ArmDistance]
) -> tuple[float | None, tuple[str, str] | None]:
    """The least distance between the arms every DISTANCE_DT of every segment (and at its
    end), and the closest pair of their parts."""
    best: tuple[float, tuple[str, str]] | None = None
    for k, seg in enumerate(program.segments):
        traj, measure = seg.trajectory, distance(k)
        t = np.append(np.arange(traj.start_time, traj.end_time, DISTANCE_DT), traj.end_time)
        q, _, _ = traj.sample(t)
        for row in q:
            d = measure(row)
            if best is None or d[0] < best[0]:
                best = d
    return (None, None) if best is None else best


def _inserts(
    program: Program, world: World, cells: Sequence[CellModel], steps: Sequence[Route]
) -> list[Failure]:
    """Each RouteCable step's guides inserted by its own segments, in plan order, with what
    it routes (a cable, a harness or one of its branches) held through each slot."""
    out: list[Failure] = []
    last = -math.inf
    index = {id(s): k for k, s in enumerate(program.segments)}
    for i, cable, guides in steps:
        ends = _insert_ends(program, i)
        for guide in guides:
            times = ends.get(guide, [])
            if not times:
                out.append(Failure("insert", f"{guide}: no insert"))
                continue
            seg = times.pop(0)
            t = seg.trajectory.end_time
            if t <= last:
                msg = f"{guide}: inserted before the guide planned before it"
                out.append(Failure("order", msg))
            last = max(last, t)
            cell = cells[index[id(seg)]]
            problem = _through_slot(program, world, cell, guide, cable, seg)
            if problem:
                out.append(Failure("insert", f"{guide}: {problem}"))
    return out


def _insert_ends(program: Program, step: int) -> dict[str, list[CompiledSegment]]:
    """Step ``step``'s insert segments, by the guide named in the label."""
    ends: dict[str, list[CompiledSegment]] = {}
    for seg in program.segments:
        label = seg.segment.label
        if seg.segment.step != step:
            continue
        if label.startswith("RouteCable ") and label.endswith(": insert"):
            guide = label[len("RouteCable ") : -len(": insert")]
            ends.setdefault(guide, []).append(seg)
    return ends


def _through_slot(
    program: Program, world: World, cell: CellModel, guide: str, cable: str, seg: CompiledSegment
) -> str | None:
    """Why the cable between the fingertips does not run through ``guide``'s slot at the end
    of its insert ``seg``."""
    t = seg.trajectory.end_time
    not_holding = [a for a in cell.arms if _holds(program, a, t) != cable]
    if not_holding:
        return f"not held by {', '.join(not_holding)} at the end of the insert"
    pose = world.pose(guide)
    slot, axis = np.asarray(pose[:3, 3], dtype=float), np.asarray(pose[:3, 0], dtype=float)
    gap = float(world.dimensions(guide)["gap"])
    a, b = _tips(seg, cell)
    d = b - a
    lateral = _point_segment(slot, a, b)
    angle = math.degrees(math.acos(min(1.0, abs(float(d @ axis)) / float(np.linalg.norm(d)))))
    if lateral > gap / 2:
        return f"slot {lateral * 1000:.1f} mm off the cable (gap/2 {gap * 500:.1f} mm)"
    if angle > ANGLE_MAX:
        return f"cable {angle:.1f} deg off the guide's x"
    return None


def _holds(program: Program, arm: str, t: float) -> str | None:
    """What ``arm`` holds just before t, from the gripper events (a sliding hand holds)."""
    held: str | None = None
    for e in program.events:
        if e.event.arm == arm and e.time < t - 1e-9:
            held = e.event.holds if e.event.mode in ("grasp", "slide") else None
    return held


def _tips(seg: CompiledSegment, cell: CellModel) -> tuple[Vec, Vec]:
    """Both fingertips (cell frame, m) at the end of ``seg``."""
    parts = cell.split(seg.trajectory.q[-1])
    a, b = (np.asarray(cell.arms[arm].fk(parts[arm])[:3, 3], dtype=float) for arm in cell.arms)
    return a, b


def _point_segment(p: Vec, a: Vec, b: Vec) -> float:
    ab = b - a
    s = float(np.clip((p - a) @ ab / float(ab @ ab), 0.0, 1.0))
    return float(np.linalg.norm(p - (a + s * ab)))
