"""Bodies that intersect where the cell starts: a platform sunk into the table, two parts at
one spot. A real cell cannot be built so; in the files it is a slip (a pose's sign, a part
copied and not moved) that the planner would take at its word.

Bodies are compared as oriented boxes (an element's bounds in its own frame, a collision
box, an obstacle's shape's bounds) by the separating axis theorem, which also gives how
deep they overlap: only overlaps deeper than TOUCH count, so parts standing on one another
(a plate on the table) do not.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from cellengine import geometry as g
from cellengine.arrays import Mat, Vec
from cellengine.errors import Problem
from cellengine.info.cell import Obstacle
from cellengine.info.mapcsv import OBSTACLE
from cellengine.info.platform import Element
from cellengine.info.yamlio import YamlDoc
from cellengine.world import World

TOUCH = 0.001  # m: an overlap shallower than this is bodies touching (and rounding)


@dataclass(frozen=True)
class Box:
    """An oriented box: ``T_cell_box`` at its centre, ``half`` its half sizes."""

    T_cell_box: Mat
    half: Vec


def overlaps(world: World, doc: YamlDoc) -> list[Problem]:
    """Warnings: a platform's part inside one of the cell's obstacles; two elements with
    keypoints (guides, combs...) inside one another."""
    return _in_obstacles(world, doc) + _elements_overlapping(world)


def _in_obstacles(world: World, doc: YamlDoc) -> list[Problem]:
    out = []
    for pname, platform in world.platforms.items():
        deepest: tuple[float, str, str] | None = None
        for element in platform.elements.values():
            boxes = _element_boxes(platform.T_cell_platform, element)
            for oname, obstacle in world.cell.obstacles.items():
                depth = max((depth_of(b, _obstacle_box(obstacle)) for b in boxes), default=0.0)
                if depth > TOUCH and (deepest is None or depth > deepest[0]):
                    deepest = (depth, element.name, oname)
        if deepest is not None:
            depth, ename, oname = deepest
            message = (
                f"platforms.{pname}: its {ename} is {depth * 1000:.0f} mm inside obstacles."
                f"{oname}: is the platform sunk into it? (check its pose)"
            )
            out.append(doc.error(message, ("platforms", pname, "pose")).problems[0])
    return out


def _elements_overlapping(world: World) -> list[Problem]:
    named = [
        (f"{pname}.{e.name}", e, _element_boxes(p.T_cell_platform, e))
        for pname, p in world.platforms.items()
        for e in p.elements.values()
        if e.model != OBSTACLE and e.keypoints
    ]
    out = []
    for (a, _, boxes_a), (b, element, boxes_b) in itertools.combinations(named, 2):
        depth = max((depth_of(x, y) for x in boxes_a for y in boxes_b), default=0.0)
        if depth > TOUCH:
            source = element.source
            out.append(
                Problem(
                    f"{b} is {depth * 1000:.0f} mm inside {a}: two parts at one spot? "
                    "(a part copied and not moved, or placed twice)",
                    source.file if source else None,
                    source.line if source else None,
                )
            )
    return out


def _element_boxes(T_cell_platform: Mat, element: Element) -> list[Box]:
    """The element's bounds: its mesh's box in its frame, else its collision boxes."""
    T = T_cell_platform @ element.T_platform_element
    if element.mesh is not None:
        lo, hi = np.asarray(element.mesh.bounds, dtype=float)
        return [Box(T @ g.transform(t=(lo + hi) / 2.0), (hi - lo) / 2.0)]
    return [Box(T @ b.T_element_box, np.asarray(b.size) / 2.0) for b in element.boxes]


def _obstacle_box(obstacle: Obstacle) -> Box:
    T = obstacle.pose.matrix()
    if obstacle.box is not None:
        return Box(T, np.asarray(obstacle.box) / 2.0)
    if obstacle.cylinder is not None:  # along its z
        r, h = obstacle.cylinder.radius, obstacle.cylinder.length
        return Box(T, np.array([r, r, h / 2.0]))
    assert obstacle.sphere is not None
    return Box(T, np.full(3, obstacle.sphere.radius))


def depth_of(a: Box, b: Box) -> float:
    """How deep two oriented boxes overlap: the least overlap of their projections on the
    separating axis theorem's 15 axes (0 when an axis separates them)."""
    Ra, Rb = a.T_cell_box[:3, :3], b.T_cell_box[:3, :3]
    axes = [*Ra.T, *Rb.T]
    axes += [g.cross(u, v) for u in Ra.T for v in Rb.T]
    d = b.T_cell_box[:3, 3] - a.T_cell_box[:3, 3]
    least = np.inf
    for axis in axes:
        n = float(np.linalg.norm(axis))
        if n < 1e-9:
            continue  # parallel edges: the face axes cover them
        L = axis / n
        ra = float(np.abs(Ra.T @ L) @ a.half)
        rb = float(np.abs(Rb.T @ L) @ b.half)
        overlap = ra + rb - abs(float(d @ L))
        if overlap <= 0.0:
            return 0.0
        least = min(least, overlap)
    return float(least)
