"""What a cable plan means on its board, checked before any motion: the mistakes a harness
engineer makes in a plan or a board (a guide turned across the route, a connector guide
facing away from it, guides listed out of order, a connector placed into a U guide) are
named in board terms at the plan's line, instead of surfacing as an arm's collision.

Each check is geometry of the files alone (keypoints and the elements' bounds); none
plans a motion. Thresholds are what the cable can physically do, not tuning: a slot holds
the cable along its length, so a cable arriving more than half a right angle off it is
across it; a connector guide's exit notch lets the cable leave to the side, never back
through the guide.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

import numpy as np

from cellengine import geometry as g
from cellengine.arrays import Vec
from cellengine.info.platform import Element
from cellengine.skill import Skill
from cellengine.skills import cable_geometry as cg
from cellengine.skills import cable_group_meaning
from cellengine.skills.cable import PickCable, PlaceConnector, RouteCable
from cellengine.world import World

Loc = tuple[str | int, ...]
Finding = tuple[Loc, str]

ACROSS = math.radians(45.0)  # a slot's line against the cable's arrival: more is across it
BACKWARDS = math.radians(90.0)  # a connector guide's exit axis against the cable's way out
SEAT_PLAY = 0.001  # m: the connector's play in a pocket; material nearer its faces is no wall


def check(world: World, steps: Sequence[Skill]) -> list[Finding]:
    """Every meaning mistake of the cable steps, in plan order."""
    out: list[Finding] = []
    came_from: dict[str, _Seat] = {}  # cable -> the keypoint it last went into
    for i, step in enumerate(steps):
        cable = str(getattr(step, "cable", ""))
        branch = world.objects.branch_of(cable)
        if branch is not None and not isinstance(step, RouteCable):
            what = f"{step.skill} takes the whole harness (cable: {branch[0]})"
            out.append(
                (("steps", i, "cable"), f"{cable} is a branch of harness {branch[0]}: {what}")
            )
            continue
        if isinstance(step, PickCable):
            out += _span(world, step, ("steps", i, "from"))
        elif isinstance(step, PlaceConnector):
            out += _seat(world, step, ("steps", i, "guide"))
            came_from[step.cable] = _Seat(step.guide, ("steps", i, "guide"), connector=True)
        elif isinstance(step, RouteCable):
            for j, ref in enumerate(step.guides):
                here = _Seat(ref, ("steps", i, "guides", j), connector=False)
                # a branch's first leg leaves its harness's connector
                before = came_from.get(step.cable) or came_from.get(branch_harness(world, step))
                if before is not None:
                    out += _leg(world, before, here, step.guides[j + 1 :])
                came_from[step.cable] = here
    return out + cable_group_meaning.group_findings(world, steps)


def branch_harness(world: World, step: RouteCable) -> str:
    """The harness ``step``'s cable is a branch of ("" when it is none)."""
    found = world.objects.branch_of(step.cable)
    return "" if found is None else found[0]


@dataclass(frozen=True)
class _Seat:
    ref: str  # keypoint reference
    loc: Loc  # its place in the plan file
    connector: bool  # a PlaceConnector's guide (else a routed guide)


def _leg(world: World, start: _Seat, end: _Seat, later: Sequence[str]) -> Iterator[Finding]:
    """The straight cable from ``start`` into ``end``: it leaves a connector guide forwards,
    enters a slot along it and runs through no other element."""
    a, a_loc, b, b_loc = start.ref, start.loc, end.ref, end.loc
    up = cg.platform_up(world, b)
    p, q = cg.position(world, a), cg.position(world, b)
    chord = q - p - float((q - p) @ up) * up
    if float(np.linalg.norm(chord)) < 1e-6:
        return  # one spot: the cell's own check says so
    chord = g.unit(chord)
    if start.connector:
        off = _angle(cg.horizontal(cg.keypoint_x(world, a), up), chord)
        if off > BACKWARDS:
            yield (
                a_loc,
                (
                    f"{a} faces away from the route: the cable would leave it "
                    f"{math.degrees(off):.0f} deg off its exit axis (its keypoint's x, from the "
                    f"connector to its cable) to reach {b}; is the connector guide turned round?"
                ),
            )
    off = _slot_angle(world, b, chord, up)
    if off > ACROSS:
        if not start.connector and _slot_angle(world, a, chord, up) <= ACROSS:
            yield (
                b_loc,
                (
                    f"{b}'s slot runs across the route: the cable leaves {a} along its slot and "
                    f"would turn {math.degrees(off):.0f} deg into {b}'s (a cable turns round the "
                    "guide it leaves, not into the next); are the guides listed in reverse (they "
                    f"are listed from the connector on), or is {b} turned?"
                ),
            )
        else:
            yield (
                b_loc,
                (
                    f"{b}'s slot runs across the route: the cable comes from {a} at "
                    f"{math.degrees(off):.0f} deg to the slot (its keypoint's x), and a slot takes "
                    f"it along, at most {math.degrees(ACROSS):.0f} deg off; is the guide turned?"
                ),
            )
    crossed = _crossed(world, a, b, up)
    if crossed:
        ahead = [c for c in crossed if any(cg.element_of(r) == c for r in later)]
        names = " and ".join(crossed)
        if ahead:
            yield (
                b_loc,
                (
                    f"the cable from {a} to {b} would run through {names}, which the route "
                    "lists later: guides are listed in the order the cable runs through them "
                    "from the connector; is the route reversed?"
                ),
            )
        else:
            yield (
                b_loc,
                (
                    f"the cable from {a} to {b} would run through {names}: a cable runs straight "
                    "between guides; route it through a guide beside it, or move it"
                ),
            )


def _slot_angle(world: World, ref: str, chord: Vec, up: Vec) -> float:
    """The angle between the cable's way and the slot at ``ref`` (a slot is open at both
    ends: 0 to 90 deg)."""
    off = _angle(cg.horizontal(cg.keypoint_x(world, ref), up), chord)
    return min(off, math.pi - off)


def _angle(u: Vec, v: Vec) -> float:
    return math.acos(max(-1.0, min(1.0, float(u @ v))))


def _crossed(world: World, a: str, b: str, up: Vec) -> list[str]:
    """The elements (other than ``a``'s and ``b``'s) the straight cable between them runs
    through, seen from above and taller than the cable there."""
    ends = {cg.element_of(a), cg.element_of(b)}
    p, q = cg.position(world, a), cg.position(world, b)
    low = min(float(p @ up), float(q @ up))
    return [
        f.name
        for f in cg.footprints(world, "", up)
        if f.name not in ends
        and f.top > low
        and f.distance(p, q, up) == 0.0
        # one standing where an end is: the cell's check of parts at one spot says so
        and f.distance(p, p, up) > 0.0
        and f.distance(q, q, up) > 0.0
    ]


def _span(world: World, step: PickCable, loc: Loc) -> Iterator[Finding]:
    """The cable lies in both keypoints it is picked from: they are no farther apart than
    its length."""
    a, b = step.from_
    apart = float(np.linalg.norm(cg.position(world, b) - cg.position(world, a)))
    length = world.cable(step.cable).length
    if apart > length:
        yield (
            loc,
            (
                f"{step.cable} ({length * 1000:.0f} mm long) cannot lie in both {a} and {b}: "
                f"they are {apart * 1000:.0f} mm apart"
            ),
        )


def _seat(world: World, step: PlaceConnector, loc: Loc) -> Iterator[Finding]:
    """The connector seated at the guide's keypoint (its centre there, its length along
    the keypoint's x) must not be inside the element's material."""
    conn = world.cable(step.cable).connector
    if conn is None:
        return
    platform, element, _ = world.resolve(step.guide)
    tris = _triangles(element)
    up = cg.platform_up(world, step.guide)
    x = cg.horizontal(cg.keypoint_x(world, step.guide), up)
    T_cell_seat = g.transform(g.frame_yz(np.cross(up, x), up), cg.position(world, step.guide))
    T_seat_element = g.inverse(T_cell_seat) @ platform.T_cell_platform @ element.T_platform_element
    tris = tris @ T_seat_element[:3, :3].T + T_seat_element[:3, 3]
    half = np.array([conn.length, conn.width, conn.height]) / 2.0 - SEAT_PLAY
    if not _box_meets_triangles(half, tris):
        return
    size = " x ".join(f"{v * 1000:.0f}" for v in (conn.length, conn.width, conn.height))
    gap = element.dimensions.get("gap")
    slot = f" (its slot is {gap * 1000:.0f} mm wide)" if gap is not None else ""
    yield (
        loc,
        (
            f"{step.guide} is no seat for {step.cable}'s connector: a {size} mm {conn.type} "
            f"connector centred at it would be inside the element{slot}; PlaceConnector needs a "
            "connector guide, whose pocket the connector fits"
        ),
    )


def _triangles(element: Element) -> Vec:
    """The element's surface in its frame (n, 3, 3): its mesh, else its collision boxes."""
    if element.mesh is not None:
        return np.asarray(element.mesh.vertices, dtype=float)[np.asarray(element.mesh.faces)]
    out = [
        g.transform_points(b.T_element_box, _UNIT_BOX * np.asarray(b.size)) for b in element.boxes
    ]
    return np.concatenate([c[_BOX_FACES] for c in out]) if out else np.zeros((0, 3, 3))


_UNIT_BOX = np.array([[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)])
# the 12 triangles of _UNIT_BOX's faces (corner index = 4 x + 2 y + z)
_BOX_FACES = np.array(
    [
        [0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
        [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3],
    ]
)  # fmt: skip


def _box_meets_triangles(half: Vec, tris: Vec) -> bool:
    """Does the box (centred at the origin, axis-aligned, half sizes ``half``) meet any of
    the triangles (n, 3, 3)? The separating axis theorem over the box's 3 face normals,
    each triangle's normal and the 9 edge-edge axes."""
    if len(tris) == 0:
        return False
    edges = np.roll(tris, -1, axis=1) - tris  # (n, 3, 3)
    axes = [np.broadcast_to(np.eye(3)[k], (len(tris), 3)) for k in range(3)]
    axes.append(np.cross(edges[:, 0], edges[:, 1]))
    axes += [np.cross(np.eye(3)[k], edges[:, j]) for k in range(3) for j in range(3)]
    apart = np.zeros(len(tris), dtype=bool)
    for axis in axes:
        p = np.einsum("nij,nj->ni", tris, axis)  # each vertex projected: (n, 3)
        r = np.abs(axis) @ half
        apart |= (p.min(axis=1) > r) | (p.max(axis=1) < -r)
    return not bool(apart.all())
