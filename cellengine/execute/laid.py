"""Cables laid on the board, as obstacles for the hands working on other cables.

A segment's :class:`~cellengine.program.Anchor` annotations say where a cable is fixed from
its end on (the connector in its guide, each guide's slot). A cable lies straight between
its anchors, a harness's branch from its harness's connector on: each stretch is a capsule of
the cable's (or bundle's) diameter. The hands work among the cables of the harness (or cable)
they hold last, pushing a group into a slot another lies in: those are no obstacles. Every
other cable laid is, kept the cell's clearance from like the board itself.
"""

from __future__ import annotations

from collections.abc import Sequence

from cellengine.world import World

Point = tuple[float, float, float]
Anchored = tuple[str, Point]  # (cable, harness or branch; where it is fixed)
# (name, one end, the other, radius): a stretch of laid cable, m
Stretch = tuple[str, Point, Point, float]

SUFFIX = "@laid"  # a stretch's scene name: <cable>@laid, #2, #3... for its others


def root(world: World, name: str) -> str:
    """The harness a branch belongs to; any other cable or harness itself."""
    found = world.objects.branch_of(name)
    return found[0] if found is not None else name


def stretches(world: World, anchors: Sequence[Anchored], working: str | None) -> list[Stretch]:
    """The laid cables not of ``working``'s harness (None: all of them), stretch by stretch."""
    last: dict[str, Point] = {}
    count: dict[str, int] = {}
    out: list[Stretch] = []
    for name, point in anchors:
        start = last.get(name) or last.get(root(world, name))
        last[name] = point
        if start is None or root(world, name) == working:
            continue
        cable = world.objects.cable(name)
        radius = float(cable.diameter) / 2.0 if cable is not None else 0.0
        if radius <= 0.0 or start == point:
            continue
        k = count[name] = count.get(name, 0) + 1
        out.append((name + SUFFIX + (f"#{k}" if k > 1 else ""), start, point, radius))
    return out
