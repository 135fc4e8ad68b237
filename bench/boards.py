"""Random cable-routing boards for the cable skills' success-rate benchmark (issue #13, point 5).

``make_board(seed, dest)`` writes a complete cell folder: cell.yaml (two UR5e on the y axis,
``home`` and tool as in cells/cable_routing, bases 500-800 mm apart), a routing platform in
the native format of cells/cable_routing/routing (X3D as Blender exports it, models.xml,
map.csv), the reference holder with its two combs (copied), objects.yaml with one cable and
plan.yaml (PickCable from the combs, PlaceConnector into the connector guide, RouteCable
through every U-guide in route order). The same seed always writes the same files.

A board: a connector guide (pocket 2 mm larger than a connector of 20-45 x 15-35 x 8-18 mm,
walls 3.5-6 mm, a notch of 8-14 mm for the cable) in front of the robots (x 300-550 mm,
|y| <= 250 mm), then 3-8 U-guides along a walk: 35-150 mm from slot to slot (from the
connector's exit to the first guide), the heading changing at each guide by 0 (probability
0.4, straight runs as in the reference) or uniformly up to 90 deg either way. Each guide's x
is the direction the cable arrives from (as guide4 of the reference). U-guides are 15-60 mm
tall, 8-12 mm thick along the cable, with a slot 6-30 mm wide and 8-20 mm deep (less than
the height by 5 mm); 20-30 mm wide, or the gap plus two 4 mm posts when wider. Every guide
stands on a 10 mm pad. The cable's length is the route (connector slot to last slot) plus
150-300 mm; its diameter is 3-6 mm and at least 1 mm under the narrowest gap and the combs'
6.5 mm; the grippers' slide and grasp jaws follow it (diameter + 1, diameter - 2 mm).

Rejected (and the walk drawn again from the next draws of the same generator), exactly:
a guide's footprint (+2 mm) overlapping another guide's or the holder plate's; the straight
cable between two consecutive guides crossing the footprint of a third or of a holder comb
(cellengine refuses such a route); a guide more than 700 mm horizontally from either base
(out of that arm's reach: the dual-arm method works every guide with both hands, one holding
the pivot before it while the other lays the cable in) or within 150 mm of one (inside the
robot's base); a guide off the table (x -200..1200, |y| <= 700 mm).

``remodel_placements()`` are the 8 poses at which the REMODEL sample is imported instead:
yaw 0, 90, 180, 270 deg, its keypoints' centre at the nearest and the farthest x (10 mm
steps; y within 200 mm of 0 in 10 mm steps, the nearest to 0) where every keypoint is in
front of the bases (x >= 150 mm) and both arms reach it, as bench_boards.py's probe finds
with the import's robots: the tool coming down the keypoint's z, at it and 100 mm above it,
on an IK branch clear of the arm itself and of the other arm at home. (The sample is 507 mm
long: turned 0 or 180 deg it does not fit within 700 mm of both bases.)
"""

from __future__ import annotations

import itertools
import math
import random
import shutil
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from cellengine.arrays import Mat, Vec
from cellengine.geometry import rot_z

REFERENCE = Path(__file__).resolve().parent.parent / "cells" / "cable_routing"
REACH = 700.0  # mm, horizontally from a base
BASE_KEEP_OUT = 150.0  # mm: the robot's own base
CLEARANCE = 2.0  # mm between footprints
PAD = 10.0  # mm: thickness of the pad every guide stands on (as the reference plate)
HOLDER_BOX = (150.0, 250.0, -190.0, 30.0)  # the reference holder plate: x0, x1, y0, y1 (mm)
# its two combs (10..80 mm high: taller than any slot here, so a cable across one runs through it)
COMB_BOXES = ((195.0, 205.0, -167.0, -113.0), (195.0, 205.0, -47.0, 7.0))
TABLE_BOX = (-200.0, 1200.0, -700.0, 700.0)
COMB_GAP = 6.5  # mm: the reference combs' slots


@dataclass(frozen=True)
class Guide:
    """A guide on the board: slot centre (x, y in mm, cell frame), heading (rad: its x),
    footprint length (along x) and width, and the model's dimensions."""

    name: str
    x: float
    y: float
    heading: float
    length: float
    width: float
    height: float
    gap: float
    depth: float


@dataclass(frozen=True)
class Connector:
    length: float
    width: float
    height: float
    wall: float
    notch: float

    @property
    def outer(self) -> tuple[float, float, float]:
        """Outer length, width, height of the guide: pocket 2 mm over the connector."""
        return (self.length + 2 + 2 * self.wall, self.width + 2 + 2 * self.wall, 0.0)


@dataclass(frozen=True)
class Board:
    seed: int
    base_distance: float
    connector: Connector
    conn_guide: Guide  # the connector guide as a footprint (its slot: the connector's centre)
    guides: tuple[Guide, ...]
    cable_length: float
    cable_diameter: float
    attempts: int  # walks drawn before this one was accepted

    @property
    def route_length(self) -> float:
        pts = [(self.conn_guide.x, self.conn_guide.y)] + [(g.x, g.y) for g in self.guides]
        return sum(math.dist(a, b) for a, b in itertools.pairwise(pts))


# ------------------------------------------------------------------------------ drawing


def draw_board(seed: int) -> Board:
    """The board of ``seed``: walks are drawn until one passes the rejection rules."""
    rng = random.Random(seed)
    base_distance = rng.uniform(500.0, 800.0)
    for attempt in range(1, 10_000):
        conn, cg, guides = _draw_walk(rng)
        if not _rejected(cg, guides, base_distance):
            diameter = min(rng.uniform(3.0, 6.0), min(g.gap for g in guides) - 1.0, COMB_GAP - 1)
            board = Board(seed, base_distance, conn, cg, guides, 0.0, round(diameter, 1), attempt)
            length = board.route_length + rng.uniform(150.0, 300.0)
            return replace(board, cable_length=round(length, 1))
    raise RuntimeError(f"seed {seed}: no acceptable board in 10000 walks")


def _draw_connector(rng: random.Random) -> Connector:
    return Connector(
        length=round(rng.uniform(20.0, 45.0), 1),
        width=round(rng.uniform(15.0, 35.0), 1),
        height=round(rng.uniform(8.0, 18.0), 1),
        wall=round(rng.uniform(3.5, 6.0), 1),
        notch=round(rng.uniform(8.0, 14.0), 1),
    )


def _draw_walk(rng: random.Random) -> tuple[Connector, Guide, tuple[Guide, ...]]:
    conn = _draw_connector(rng)
    heading = rng.uniform(-math.pi, math.pi)
    x, y = rng.uniform(300.0, 550.0), rng.uniform(-250.0, 250.0)
    lo, wo, _ = conn.outer
    cg = Guide("connector", x, y, heading, lo, wo, 0.0, conn.notch, conn.height)
    # the first spacing is from the connector's exit (its +x wall)
    x, y = x + lo / 2 * math.cos(heading), y + lo / 2 * math.sin(heading)
    guides = []
    for i in range(rng.randint(3, 8)):
        if i > 0 and rng.random() >= 0.4:
            heading += math.radians(rng.uniform(-90.0, 90.0))
        step = rng.uniform(35.0, 150.0)
        x, y = x + step * math.cos(heading), y + step * math.sin(heading)
        guides.append(_draw_guide(rng, f"guide{i + 1}", x, y, heading))
    return conn, cg, tuple(guides)


def _draw_guide(rng: random.Random, name: str, x: float, y: float, heading: float) -> Guide:
    height = rng.uniform(15.0, 60.0)
    gap = rng.uniform(6.0, 30.0)
    depth = rng.uniform(8.0, min(20.0, height - 5.0))
    width = max(rng.uniform(20.0, 30.0), gap + 8.0)
    r = round
    return Guide(
        name, r(x, 1), r(y, 1), heading, r(rng.uniform(8.0, 12.0), 1), r(width, 1), r(height, 1),
        r(gap, 1), r(depth, 1),
    )  # fmt: skip


# ---------------------------------------------------------------------------- rejection


def rejection(cg: Guide, guides: tuple[Guide, ...], base_distance: float) -> str | None:
    """Why the board is physically unreasonable (module docstring), or None."""
    every = (cg, *guides)
    bases = ((0.0, base_distance / 2), (0.0, -base_distance / 2))
    for g in every:
        d = [math.dist((g.x, g.y), b) for b in bases]
        if max(d) > REACH:  # the method works every guide with both hands
            return f"{g.name} out of an arm's reach"
        if min(d) < BASE_KEEP_OUT:
            return f"{g.name} inside a robot's base"
        if not _inside(_corners(g, 0.0), TABLE_BOX):
            return f"{g.name} off the table"
        if _overlap(_corners(g, CLEARANCE), _box_corners(HOLDER_BOX)):
            return f"{g.name} overlaps the holder"
    for i, a in enumerate(every):
        for b in every[i + 1 :]:
            if _overlap(_corners(a, CLEARANCE), _corners(b, CLEARANCE)):
                return f"{a.name} overlaps {b.name}"
    for i in range(len(every) - 1):
        p, q = (every[i].x, every[i].y), (every[i + 1].x, every[i + 1].y)
        for k, g in enumerate(every):
            if k not in (i, i + 1) and _segment_hits(p, q, _corners(g, 0.0)):
                return f"the cable from {every[i].name} to {every[i + 1].name} crosses {g.name}"
        if any(_segment_hits(p, q, _box_corners(box)) for box in COMB_BOXES):
            return f"the cable from {every[i].name} to {every[i + 1].name} crosses a comb"
    return None


def _rejected(cg: Guide, guides: tuple[Guide, ...], base_distance: float) -> bool:
    return rejection(cg, guides, base_distance) is not None


Pt = tuple[float, float]


def _corners(g: Guide, grow: float) -> list[Pt]:
    c, s = math.cos(g.heading), math.sin(g.heading)
    hl, hw = g.length / 2 + grow, g.width / 2 + grow
    return [(g.x + c * u - s * v, g.y + s * u + c * v) for u, v in _rect(hl, hw)]


def _rect(hl: float, hw: float) -> list[Pt]:
    return [(-hl, -hw), (hl, -hw), (hl, hw), (-hl, hw)]


def _box_corners(box: tuple[float, float, float, float]) -> list[Pt]:
    x0, x1, y0, y1 = box
    return [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]


def _inside(pts: list[Pt], box: tuple[float, float, float, float]) -> bool:
    x0, x1, y0, y1 = box
    return all(x0 <= x <= x1 and y0 <= y <= y1 for x, y in pts)


def _overlap(a: list[Pt], b: list[Pt]) -> bool:
    """Separating axis test of two convex polygons."""
    for poly in (a, b):
        for i in range(len(poly)):
            (x0, y0), (x1, y1) = poly[i], poly[(i + 1) % len(poly)]
            n = (y0 - y1, x1 - x0)
            pa = [n[0] * x + n[1] * y for x, y in a]
            pb = [n[0] * x + n[1] * y for x, y in b]
            if max(pa) < min(pb) or max(pb) < min(pa):
                return False
    return True


def _segment_hits(p: Pt, q: Pt, poly: list[Pt]) -> bool:
    """Does segment pq meet the convex polygon (a degenerate polygon of two points)?"""
    return _overlap([p, q, q], poly)


# ------------------------------------------------------------------------------ writing


def make_board(seed: int, dest: Path) -> Board:
    """Draw the board of ``seed`` and write its cell folder into ``dest``."""
    board = draw_board(seed)
    write_board(board, dest)
    return board


def write_board(board: Board, dest: Path) -> None:
    (dest / "routing").mkdir(parents=True, exist_ok=True)
    shutil.copytree(REFERENCE / "holder", dest / "holder", dirs_exist_ok=True)
    (dest / "cell.yaml").write_text(cell_yaml(board))
    (dest / "objects.yaml").write_text(objects_yaml(board))
    (dest / "plan.yaml").write_text(plan_yaml(board))
    (dest / "routing" / "routing.x3d").write_text(routing_x3d(board))
    (dest / "routing" / "models.xml").write_text(models_xml(board))
    (dest / "routing" / "map.csv").write_text(map_csv(board))


def cell_yaml(board: Board) -> str:
    half = board.base_distance / 2
    d = board.cable_diameter
    robot = "    tool: cable_gripper\n    home: [0, -90, 90, -90, -90, 0]\n"
    return (
        f"# Generated by bench/boards.py, seed {board.seed}.\n"
        f"name: board_{board.seed}\n"
        "units: {length: mm, angle: deg}\nrobots:\n"
        f"  left:\n    model: ur5e\n    base: {{xyz: [0, {half:.1f}, 0]}}\n{robot}"
        f"  right:\n    model: ur5e\n    base: {{xyz: [0, {-half:.1f}, 0]}}\n{robot}"
        "tools:\n  cable_gripper:\n    kind: parallel_gripper\n    tcp: {xyz: [0, 0, 200]}\n"
        "    finger_width: 20\n    finger_thickness: 8\n"
        f"    jaw: {{open: 60, slide: {d + 1:.1f}, grasp: {max(1.0, d - 2):.1f}}}\n"
        "    shape:\n      - {name: body, box: [50, 90, 110], pose: {xyz: [0, 0, 55]}}\n"
        "    fingers: {size: [8, 6, 90]}\n"
        "# the plates' axes along the cell's (see cells/cable_routing/cell.yaml); routing's\n"
        "# plate coordinates are the cell's\nplatforms:\n"
        "  holder:  {pose: {xyz: [150, -190, 0], rpy: [0, 0, 180]}, cad: holder/holder.x3d,\n"
        "            models: holder/models.xml, map: holder/map.csv}\n"
        "  routing: {pose: {xyz: [0, 0, 0], rpy: [0, 0, 180]}, cad: routing/routing.x3d,\n"
        "            models: routing/models.xml, map: routing/map.csv}\n"
        "obstacles:\n  table: {box: [1400, 1400, 20], pose: {xyz: [500, 0, -10]}}\n"
        "driver: {kind: sim}\n"
    )


def objects_yaml(board: Board) -> str:
    c = board.connector
    return (
        f"# Generated by bench/boards.py, seed {board.seed}; route {board.route_length:.1f} mm.\n"
        "units: {length: mm, mass: g}\ncables:\n  cable1:\n"
        f"    length: {board.cable_length}\n    diameter: {board.cable_diameter}\n"
        "    color: grey\n"
        f"    connector: {{type: VGA, length: {c.length}, width: {c.width}, height: {c.height}}}\n"
    )


def plan_yaml(board: Board) -> str:
    guides = ", ".join(f"routing.{g.name}" for g in board.guides)
    return (
        f"# Generated by bench/boards.py, seed {board.seed}.\n"
        "cell: cell.yaml\nobjects: objects.yaml\nexecution: split\nsteps:\n"
        "  - skill: PickCable\n    cable: cable1\n    from: [holder.comb_a, holder.comb_b]\n"
        "  - skill: PlaceConnector\n    cable: cable1\n    guide: routing.connector\n"
        f"  - skill: RouteCable\n    cable: cable1\n    guides: [{guides}]\n"
    )


def map_csv(board: Board) -> str:
    rows = ["cad_name,model,name", "Conn_Holder,connector_guide,connector"]
    rows += [f"Guide_U_{i:03d},{g.name}_u,{g.name}" for i, g in enumerate(board.guides)]
    rows.append("Routing_Plate,obstacle,plate")  # the plate: an obstacle, as it was unmapped
    return "\n".join(rows) + "\n"


def models_xml(board: Board) -> str:
    c = board.connector
    lo, wo, _ = c.outer
    floor = _conn_floor(c)
    top = floor + c.height
    mid = floor + c.height / 2
    out = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        f"<!-- Generated by bench/boards.py, seed {board.seed}: x along the cable, z up. -->",
        '<elements units="mm" angles="deg">',
        '  <element model="connector_guide">',
        *_dims(length=lo, width=wo, height=top, pocket_length=c.length + 2,
               pocket_width=c.width + 2, pocket_depth=c.height, gap=c.notch),
        f'    <keypoint name="slot" xyz="0 0 {mid:.2f}" rpy="0 0 0"/>',
        f'    <keypoint name="exit" xyz="{lo / 2:.2f} 0 {mid:.2f}" rpy="0 0 0"/>',
        "  </element>",
    ]  # fmt: skip
    for g in board.guides:
        out += [
            f'  <element model="{g.name}_u">',
            *_dims(length=g.length, width=g.width, height=g.height, gap=g.gap, depth=g.depth),
            f'    <keypoint name="slot" xyz="0 0 {g.height - g.depth / 2:.2f}" rpy="0 0 0"/>',
            "  </element>",
        ]
    return "\n".join([*out, "</elements>"]) + "\n"


def _dims(**dims: float) -> list[str]:
    return [f'    <dimension name="{k}" value="{v:.2f}"/>' for k, v in dims.items()]


def _conn_floor(c: Connector) -> float:
    """The pocket floor's height: the connector's centre at 55 mm, as in the reference."""
    return 55.0 - c.height / 2


# X3D: as Blender exports it (see cells/cable_routing/routing/routing.x3d)
_HEAD = """<?xml version="1.0" encoding="UTF-8"?>
<!DOCTYPE X3D PUBLIC "ISO//Web3D//DTD X3D 3.0//EN" "http://www.web3d.org/specifications/x3d-3.0.dtd">
<X3D version="3.0" profile="Immersive">
\t<head>
\t\t<meta name="filename" content="routing.x3d" />
\t\t<meta name="generator" content="cellengine bench/boards.py" />
\t</head>
\t<Scene>
\t\t<Transform DEF="Routing_Plate" translation="0 0 0" scale="0.001000 0.001000 0.001000"
\t\t           rotation="0.000000 0.707107 0.707107 3.141593">
"""
_TAIL = "\t\t</Transform>\n\t</Scene>\n</X3D>\n"

Box = tuple[float, float, float, float, float, float]  # x0 x1 y0 y1 z0 z1


def routing_x3d(board: Board) -> str:
    pads = [_pad(g) for g in (board.conn_guide, *board.guides)]
    parts = [_HEAD, _shape(pads, "coords_ME_Plate", indent=3)]
    cg = board.conn_guide
    parts.append(_element("Conn_Holder", cg, _connector_boxes(board.connector)))
    for i, g in enumerate(board.guides):
        parts.append(_element(f"Guide_U_{i:03d}", g, _guide_boxes(g)))
    return "".join([*parts, _TAIL])


def _pad(g: Guide) -> list[Pt]:
    return _corners(g, 10.0)


def _element(cad: str, g: Guide, boxes: list[Box]) -> str:
    return (
        f'\t\t\t<Transform DEF="{cad}" translation="{g.x:.3f} {g.y:.3f} {PAD:.1f}" '
        f'scale="1 1 1" rotation="0 0 1 {g.heading:.6f}">\n'
        f"{_shape([_box_prism(b) for b in boxes], f'coords_{cad}', indent=4)}"
        "\t\t\t</Transform>\n"
    )


def _guide_boxes(g: Guide) -> list[Box]:
    hl, hw, hg = g.length / 2, g.width / 2, g.gap / 2
    floor = g.height - g.depth
    return [
        (-hl, hl, -hw, hw, 0.0, floor),
        (-hl, hl, -hw, -hg, floor, g.height),
        (-hl, hl, hg, hw, floor, g.height),
    ]


def _connector_boxes(c: Connector) -> list[Box]:
    lo, wo, _ = c.outer
    hl, hw, w = lo / 2, wo / 2, c.wall
    floor, top, hn = _conn_floor(c), _conn_floor(c) + c.height, c.notch / 2
    return [
        (-hl, hl, -hw, hw, 0.0, floor),
        (-hl, -hl + w, -hw, hw, floor, top),  # back wall
        (-hl + w, hl - w, -hw, -hw + w, floor, top),  # side walls
        (-hl + w, hl - w, hw - w, hw, floor, top),
        (hl - w, hl, -hw, -hn, floor, top),  # front wall, notched for the cable
        (hl - w, hl, hn, hw, floor, top),
    ]


Prism = tuple[list[Pt], float, float]


def _box_prism(b: Box) -> Prism:
    x0, x1, y0, y1, z0, z1 = b
    return ([(x0, y0), (x1, y0), (x1, y1), (x0, y1)], z0, z1)


def _shape(prisms: list[Prism] | list[list[Pt]], name: str, indent: int) -> str:
    """One IndexedFaceSet of quadrilateral prisms (a footprint list: pads 0..PAD high, on
    the table, under the guides that stand at PAD)."""
    points: list[str] = []
    faces: list[str] = []
    for item in prisms:
        quad, z0, z1 = item if isinstance(item, tuple) else (item, 0.0, PAD)
        base = len(points)
        points += [f"{x:.3f} {y:.3f} {z:.3f}" for z in (z0, z1) for x, y in quad]
        faces += [" ".join(str(base + i) for i in f) + " -1" for f in _PRISM_FACES]
    t = "\t" * indent
    return (
        f'{t}<Shape><Appearance></Appearance>\n{t}<IndexedFaceSet solid="false" '
        f'coordIndex="{" ".join(faces)}">\n'
        f'{t}\t<Coordinate DEF="{name}" point="{" ".join(points)}"/>\n'
        f"{t}</IndexedFaceSet></Shape>\n"
    )


_PRISM_FACES = ((0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7))


# ------------------------------------------------------------------------------ REMODEL


def remodel_placements(
    keypoints: Sequence[Mat], reaches: Callable[[Mat], bool]
) -> list[tuple[str, str]]:
    """(name, --pose) of the 8 REMODEL placements, from its keypoints' poses (4x4, m) imported
    at the origin: yaw 0/90/180/270, the centre at the nearest and the farthest feasible x
    (module docstring); ``reaches(T_cell_keypoint)``: both arms reach it."""
    centre = np.mean([T[:3, 3] for T in keypoints], axis=0)
    out = []
    xs = range(0, 1000, 10)
    ys = sorted(range(-200, 201, 10), key=lambda y: (abs(y), y))  # nearest 0 first
    for yaw in (0, 90, 180, 270):
        turn = np.eye(4)
        turn[:3, :3] = rot_z(math.radians(yaw))
        turned = [turn @ T for T in keypoints]
        c = turn[:3, :3] @ centre

        def placed(x: int, y: int, c: Vec = c, turned: list[Mat] = turned) -> Mat | None:
            shift = np.eye(4)
            shift[:2, 3] = np.array([x, y]) / 1000 - c[:2]
            ok = all(
                (shift @ T)[0, 3] * 1000 >= BASE_KEEP_OUT and reaches(shift @ T) for T in turned
            )
            return shift if ok else None

        for tag, order in (("near", xs), ("far", reversed(xs))):
            found = next(
                ((x, s) for x in order for y in ys if (s := placed(x, y)) is not None), None
            )
            if found is None:
                continue
            t = found[1][:3, 3] * 1000
            out.append((f"remodel_{yaw}_{tag}", f"{t[0]:.1f} {t[1]:.1f} 0 0 0 {yaw}"))
    return out
