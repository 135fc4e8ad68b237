"""What report.html draws: the cell's static meshes, every arm link's shape and both TCPs
sampled along the program, joint positions and velocities, the step timeline, gripper events,
and the cables: which hands hold each when, and the slots it has been placed in.

Everything is in the cell frame, metres and radians. Per sample arrays are flat lists, one per
link (``stride`` numbers per sample), so the page indexes them without nesting:

- ``capsule`` and ``cylinder``: the two end points of the axis (6 numbers) and ``radius``;
- ``sphere``: the centre (3) and ``radius``;
- ``box``: the centre and the three half-axis vectors (12); any other shape is drawn as its
  local bounding box.

A link fixed in the cell (an arm's base) has one sample (``fixed``).
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from typing import Any

import coal
import numpy as np
import pinocchio as pin

from cellengine import geometry as g
from cellengine.arrays import IntArray, Vec
from cellengine.info import primitives
from cellengine.info.cell import Obstacle
from cellengine.info.mesh import Mesh
from cellengine.motion.robot import CellModel, home_configuration, is_tool
from cellengine.motion.scene import place_fingers
from cellengine.program import Anchor, Program, TimedEvent
from cellengine.report.data import event_entry, step_names
from cellengine.report.distance import ArmDistance
from cellengine.report.joints import joint_kinds
from cellengine.report.names import part_names, segment_name, step_title
from cellengine.report.objects import containers, zones
from cellengine.report.sampling import joint_order, program_span, sample_program, sample_times
from cellengine.report.tools import PREFIX, changes_tools, tool_links, tool_timeline
from cellengine.world import World

REPLAY_FORMAT = "cellengine.replay/1"
REPLAY_RATE = 25.0  # Hz: link shapes, TCPs, joint states
MAX_SAMPLES = 6000  # the rate is lowered for programs longer than 4 min at 25 Hz
MESH_TRIANGLES = 2000  # a static mesh with more triangles is decimated to at most this
DECIMALS = 4  # positions rounded to 0.1 mm
JOINT_DECIMALS = 5  # rad, rad/s (or m, m/s)
CYLINDER_SECTIONS = 24


def replay_data(
    program: Program,
    cell: CellModel,
    world: World,
    *,
    rate: float = REPLAY_RATE,
    max_samples: int = MAX_SAMPLES,
    step_labels: Mapping[int, str] | None = None,
) -> dict[str, Any]:
    """The replay embedded in report.html (see the module's notes for the layout)."""
    times = sample_times(program, rate, max_samples)
    if program.segments:
        q, qd = sample_program(program, times, joint_order(program, cell.joint_names))
    else:  # nothing moves: the cell at home
        q, qd = home_configuration(cell)[None], np.zeros((1, cell.nq))
    geometry, tcp = placements(cell, q, jaw_openings(program, cell, times))
    distance = ArmDistance(cell).series(q)
    start, end = program_span(program)
    limits = cell.limits
    return {
        "format": REPLAY_FORMAT,
        "start": start,
        "duration": end - start,
        "times": _round(times, DECIMALS),
        "arms": list(cell.arms),
        "joint_names": list(cell.joint_names),
        "joint_kinds": joint_kinds(cell),
        "arm_joints": {a: list(range(s.start, s.stop)) for a, s in cell.slices.items()},
        "limits": {
            "lower": limits.lower.tolist(),
            "upper": limits.upper.tolist(),
            "velocity": limits.velocity.tolist(),
        },
        "q": _round(q.T, JOINT_DECIMALS),
        "qd": _round(qd.T, JOINT_DECIMALS),
        "links": _links(program, cell, world, geometry, q, times),
        "tools": tool_timeline(program),
        "tcp": {arm: _round(p.ravel(), DECIMALS) for arm, p in tcp.items()},
        "arm_distance": None if distance is None else _round(distance[0], DECIMALS),
        "static": static_meshes(world),
        "keypoints": [
            {"name": name, "p": _round(T[:3, 3], DECIMALS)} for name, T in world.keypoints().items()
        ],
        **timeline(program, step_labels or {}),
        "events": [event_entry(e) for e in program.events],
        "cables": cables(program, world),
        "objects": containers(world, cell, program.events, times, q),
        "zones": zones(world),
        "part_names": part_names(_collision_names(cell, world), _tools(world)),
    }


def _links(
    program: Program, cell: CellModel, world: World, M: Vec, Q: Vec, times: Vec
) -> list[dict[str, Any]]:
    """The arms' links; in a cell with a tool changer, every tool drawn on its own where it
    is (report/tools.py) instead of the arms' own tool objects."""
    links = link_shapes(cell, M)
    if not changes_tools(world.cell.tools):
        return links
    arms = [link for link in links if not is_tool(link["name"], link["arm"])]
    tools = [
        _link(name, PREFIX, shape, P, False)
        for name, shape, P in tool_links(program, cell, world, Q, times)
    ]
    return arms + tools


def _tools(world: World) -> dict[str, str]:
    return {arm: robot.tool for arm, robot in world.cell.robots.items() if robot.tool}


def _collision_names(cell: CellModel, world: World) -> list[str]:
    """The names a closest pair may give: the arms' shapes, the obstacles."""
    return [str(o.name) for o in cell.collision.geometryObjects] + list(world.cell.obstacles)


def _round(a: Any, decimals: int) -> Any:
    return np.round(np.asarray(a, dtype=float), decimals).tolist()


# ---------------------------------------------------------------------------------- arms


def jaw_openings(program: Program, cell: CellModel, times: Vec) -> list[dict[str, float]]:
    """Per sample, each fingered arm's opening (m) in its last gripper mode (the widest before
    its first event)."""
    out: list[dict[str, float]] = []
    events = sorted(program.events, key=lambda e: e.time)
    state = {a: arm.fingers.widest for a, arm in cell.arms.items() if arm.fingers is not None}
    k = 0
    for t in times:
        while k < len(events) and events[k].time <= t:
            e = events[k].event
            fingers = cell.arms[e.arm].fingers if e.arm in cell.arms else None
            if fingers is not None:
                state[e.arm] = fingers.opening(e.mode)
            k += 1
        out.append(dict(state))
    return out


def placements(
    cell: CellModel, Q: Vec, jaw: Sequence[Mapping[str, float]] | None = None
) -> tuple[Vec, dict[str, Vec]]:
    """Every collision object's placement (S, G, 4, 4) and each arm's TCP position (S, 3) at
    the rows of Q, by pinocchio's forward kinematics; the fingers at ``jaw[s]``'s openings
    (else at their widest)."""
    model, geometry = cell.model, cell.collision.copy()
    data, gdata = model.createData(), pin.GeometryData(geometry)
    n = int(geometry.ngeoms)
    M = np.empty((len(Q), n, 4, 4))
    tcp = {arm: np.empty((len(Q), 3)) for arm in cell.arms}
    for s, q in enumerate(Q):
        if jaw is not None and (s == 0 or jaw[s] != jaw[s - 1]):  # else placed already
            place_fingers(cell, geometry, jaw[s])
        pin.framesForwardKinematics(model, data, q)
        pin.updateGeometryPlacements(model, data, geometry, gdata)
        for i in range(n):
            M[s, i] = gdata.oMg[i].homogeneous
        for arm, frame in cell.tcp.items():
            tcp[arm][s] = data.oMf[frame].translation
    return M, tcp


def link_shapes(cell: CellModel, M: Vec) -> list[dict[str, Any]]:
    """Each collision object of the cell's arms with its points per sample (M from
    :func:`placements`)."""
    out = []
    for i, obj in enumerate(cell.collision.geometryObjects):
        fixed = int(obj.parentJoint) == 0
        name = str(obj.name)
        out.append(_link(name, name.split("/", 1)[0], obj.geometry, M[:, i], fixed))
    return out


def _link(name: str, arm: str, shape: Any, M: Vec, fixed: bool) -> dict[str, Any]:
    kind, radius, points = shape_points(shape, M[:1] if fixed else M)
    return {
        "name": name,
        "arm": arm,
        "kind": kind,
        "radius": radius,
        "fixed": fixed,
        "stride": points.shape[1],
        "points": _round(points.ravel(), DECIMALS),
    }


def shape_points(shape: Any, M: Vec) -> tuple[str, float, Vec]:
    """Kind, radius and the (S, stride) points of a coal shape at placements M (S, 4, 4)."""
    R, p = M[:, :3, :3], M[:, :3, 3]
    if isinstance(shape, coal.Capsule | coal.Cylinder):
        axis = R[:, :, 2] * float(shape.halfLength)
        kind = "capsule" if isinstance(shape, coal.Capsule) else "cylinder"
        return kind, float(shape.radius), np.hstack([p - axis, p + axis])
    if isinstance(shape, coal.Sphere):
        return "sphere", float(shape.radius), p
    if isinstance(shape, coal.Box):
        centre, half = p, np.asarray(shape.halfSide, dtype=float)
    else:
        shape.computeLocalAABB()
        lo, hi = np.asarray(shape.aabb_local.min_), np.asarray(shape.aabb_local.max_)
        centre, half = p + R @ ((lo + hi) / 2), (hi - lo) / 2
    axes = [R[:, :, k] * half[k] for k in range(3)]
    return "box", 0.0, np.hstack([centre, *axes])


# ---------------------------------------------------------------------------------- statics


def static_meshes(world: World, max_triangles: int = MESH_TRIANGLES) -> list[dict[str, Any]]:
    """Platform elements (their mesh, else their collision boxes) and obstacles as triangle
    meshes in the cell frame. ``ground``: an obstacle nothing else reaches below the top of
    (the table), which the page draws first."""
    items: list[tuple[str, str, str, Vec, IntArray]] = []
    for pname, platform in world.platforms.items():
        for ename, element in platform.elements.items():
            T = platform.T_cell_platform @ element.T_platform_element
            mesh = _element_mesh(element.mesh, [(b.size, b.T_element_box) for b in element.boxes])
            if mesh is not None:
                items.append((f"{pname}.{ename}", pname, "element", *_placed(mesh, T)))
    for oname, obstacle in world.cell.obstacles.items():
        mesh = obstacle_mesh(obstacle)
        items.append((oname, "obstacles", "obstacle", *_placed(mesh, obstacle.pose.matrix())))
    lowest = [float(v[:, 2].min()) for *_, v, _ in items]
    out = []
    for k, (name, group, kind, v, f) in enumerate(items):
        others = [z for j, z in enumerate(lowest) if j != k]
        ground = kind == "obstacle" and float(v[:, 2].max()) <= min(others, default=0.0) + 1e-3
        v, f = decimate(v, f, max_triangles)
        out.append(
            {
                "name": name,
                "group": group,
                "kind": kind,
                "ground": ground,
                "vertices": _round(v.ravel(), DECIMALS),
                "triangles": f.ravel().tolist(),
            }
        )
    return out


def _element_mesh(mesh: Mesh | None, boxes: Sequence[tuple[Sequence[float], Vec]]) -> Mesh | None:
    if mesh is not None and len(mesh.faces) > 0:
        return mesh
    if not boxes:
        return None
    return Mesh.concatenate([primitives.box(size).transformed(T) for size, T in boxes])


def obstacle_mesh(o: Obstacle) -> Mesh:
    """An obstacle's shape in its own frame (a cylinder along z, as coal's)."""
    if o.box is not None:
        return primitives.box(o.box)
    if o.cylinder is not None:
        return primitives.cylinder(o.cylinder.radius, o.cylinder.length, CYLINDER_SECTIONS)
    assert o.sphere is not None  # the model validator guarantees exactly one shape
    return primitives.sphere(o.sphere.radius)


def _placed(mesh: Mesh, T: Vec) -> tuple[Vec, IntArray]:
    return g.transform_points(T, mesh.vertices), mesh.faces


def decimate(vertices: Vec, faces: IntArray, max_faces: int) -> tuple[Vec, IntArray]:
    """At most ``max_faces`` triangles by vertex clustering: vertices in one cell of a grid
    merge to their mean, collapsed and repeated triangles go; the grid coarsens until few
    enough remain. Small meshes come back unchanged."""
    if len(faces) <= max_faces:
        return vertices, faces
    lo = vertices.min(axis=0)
    size = float(np.linalg.norm(vertices.max(axis=0) - lo)) / 128 or 1.0
    while True:
        keys = np.floor((vertices - lo) / size).astype(np.int64)
        _, cluster, counts = np.unique(keys, axis=0, return_inverse=True, return_counts=True)
        cluster = cluster.ravel()
        merged = np.zeros((len(counts), 3))
        np.add.at(merged, cluster, vertices)
        merged /= counts[:, None]
        f = cluster[faces]
        f = f[(f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 0] != f[:, 2])]
        f = np.unique(f, axis=0) if len(f) else f
        if len(f) <= max_faces:
            used, f = np.unique(f, return_inverse=True)
            return merged[used], f.reshape(-1, 3).astype(np.int64)
        size *= 1.5


# ---------------------------------------------------------------------------------- timeline


def timeline(program: Program, step_labels: Mapping[int, str]) -> dict[str, Any]:
    """Segments and steps with their start and end times."""
    names = step_names(program, step_labels)
    segments: list[dict[str, Any]] = [
        {
            "index": i,
            "step": int(cs.segment.step),
            "label": cs.segment.label,
            "name": segment_name(cs.segment.label, names[int(cs.segment.step)]),
            "strategy": cs.strategy,
            "start": cs.trajectory.start_time,
            "end": cs.trajectory.end_time,
        }
        for i, cs in enumerate(program.segments)
    ]
    steps: dict[int, dict[str, Any]] = {}
    for s in segments:
        step = steps.setdefault(
            s["step"],
            {
                "step": s["step"],
                "label": names[s["step"]],
                "title": step_title(s["step"], names[s["step"]]),
                "start": s["start"],
                "end": s["end"],
            },
        )
        step["start"], step["end"] = min(step["start"], s["start"]), max(step["end"], s["end"])
    return {"segments": segments, "steps": [steps[k] for k in sorted(steps)]}


def cables(program: Program, world: World) -> list[dict[str, Any]]:
    """Each cable some gripper holds: when which arms hold it (``held``: intervals with the
    same non-empty set of arms) and where it is fixed (``anchors``: a segment's
    :class:`~cellengine.program.Anchor`, e.g. the slot of a guide it was inserted into, from
    that segment's end). The page draws a cable through its anchors so far and then the
    hands holding it."""
    names = set(world.objects.cable_names())
    events = sorted(program.events, key=lambda e: e.time)
    held = _held_spans(events, names, program_span(program)[1])
    anchors: dict[str, list[dict[str, Any]]] = {}
    for cs in program.segments:
        end = cs.trajectory.end_time
        held_now = set(_holding(events, names, end).values())
        for a in cs.segment.annotations:
            # a cable no hand holds is not being laid (nothing to draw)
            if isinstance(a, Anchor) and a.object in names and a.object in held_now:
                anchors.setdefault(a.object, []).append(
                    {"time": end, "guide": a.by, "p": _round(a.point, DECIMALS)}
                )
    objects = world.objects
    out = []
    for c in sorted(set(held) | set(anchors)):
        mine = anchors.get(c, [])
        branch = objects.branch_of(c)
        if branch is not None:  # a group leaves its harness's connector
            mine = [*anchors.get(branch[0], []), *mine]
        members = [
            {"name": n, "color": _css(getattr(objects.single(n), "color", None))}
            for n in objects.cables_of(c)
        ]
        out.append({"name": c, "held": held.get(c, []), "anchors": mine, "members": members})
    return out


def _css(color: str | None) -> str | None:
    """A colour name as CSS takes it (objects.yaml's are words: grey, Yellow), else None."""
    if color is None or not re.fullmatch(r"[A-Za-z]{3,20}", color):
        return None
    return color.lower()


def _cable_of(name: str | None, cables: set[str]) -> str | None:
    if name is None:
        return None
    head = name.split(".", 1)[0]  # cable1.connector: cable1
    return name if name in cables else head if head in cables else None


def _holding(events: Sequence[TimedEvent], cables: set[str], until: float) -> dict[str, str]:
    """arm -> cable it holds after the events before ``until``."""
    out: dict[str, str | None] = {}
    for e in events:
        if e.time >= until:
            break
        out[e.event.arm] = _cable_of(e.event.holds, cables)
    return {arm: c for arm, c in out.items() if c is not None}


def _held_spans(
    events: Sequence[TimedEvent], cables: set[str], end: float
) -> dict[str, list[dict[str, Any]]]:
    """cable -> intervals during which the same arms (one or more) hold it."""
    spans: dict[str, list[dict[str, Any]]] = {}
    times = sorted({float(e.time) for e in events})
    for k, t in enumerate(times):
        arms_of: dict[str, list[str]] = {}
        for arm, cable in _holding(events, cables, t + 1e-9).items():
            arms_of.setdefault(cable, []).append(arm)
        until = times[k + 1] if k + 1 < len(times) else end
        for cable, arms in arms_of.items():
            mine = spans.setdefault(cable, [])
            if mine and mine[-1]["arms"] == sorted(arms) and mine[-1]["end"] == t:
                mine[-1]["end"] = until
            elif until > t:
                mine.append({"arms": sorted(arms), "start": t, "end": until})
    return spans
