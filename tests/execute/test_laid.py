"""Cables laid on the board are obstacles for the hands working on another harness: each
stretch between two anchors a capsule of the cable's diameter, a branch's from its harness's
connector on; the harness the hands hold last is no obstacle to them."""

from __future__ import annotations

import numpy as np

from cellengine.context import build_context
from cellengine.execute.compile import Compiler
from cellengine.execute.laid import stretches
from cellengine.info.load import load_world
from cellengine.program import Anchor, ArmPath, GripperEvent, Segment
from cellengine.skills import cable_geometry as cg
from cellengine.world import World
from tests.conftest import CELLS

CELL = CELLS / "harness"


def _point(world: World, ref: str) -> tuple[float, float, float]:
    x, y, z = (float(v) for v in cg.position(world, ref))
    return (x, y, z)


def test_a_branch_lies_from_its_harness_connector_through_its_guides() -> None:
    world = load_world(CELL / "cell.yaml", CELL / "objects.yaml")
    conn, g1, g2 = (_point(world, f"board.{r}") for r in ("connector", "guide1", "guide2"))
    anchors = [("WH1", conn), ("TOP", g1), ("TOP", g2), ("BOT", g1)]
    laid = stretches(world, anchors, "WH2")
    bundle = world.objects.cable("TOP")
    assert bundle is not None
    assert [(n, a, b) for n, a, b, _ in laid] == [
        ("TOP@laid", conn, g1),
        ("TOP@laid#2", g1, g2),
        ("BOT@laid", conn, g1),
    ]
    assert laid[0][3] == bundle.diameter / 2
    assert stretches(world, anchors, "WH1") == []  # the hands work among their own


def test_the_compiler_keeps_the_hands_clear_of_another_harness_laid_before() -> None:
    world = load_world(CELL / "cell.yaml", CELL / "objects.yaml")
    ctx = build_context(world)
    compiler = Compiler(world, ctx.cell, ctx.checker, ctx.home, tooled=ctx.tooled_parts)
    conn, g1 = _point(world, "board.connector"), _point(world, "board.guide1")
    here = ctx.tcp_home("left")
    stay = ArmPath("left", "transit", np.asarray(here)[None])
    compiler.add(
        Segment(0, "WH1 laid", (stay,), annotations=(Anchor("WH1", conn), Anchor("TOP", g1)))
    )
    names = {s.name for s in compiler.checker.scene.statics}
    assert "TOP@laid" in names  # no harness held yet: every cable laid is an obstacle
    compiler.add(Segment(1, "WH1 held", (stay,), after=(GripperEvent("left", "grasp", "WH1"),)))
    assert "TOP@laid" not in {s.name for s in compiler.checker.scene.statics}
    mark = compiler.mark()
    compiler.add(Segment(2, "WH2 held", (stay,), after=(GripperEvent("left", "grasp", "WH2"),)))
    assert "TOP@laid" in {s.name for s in compiler.checker.scene.statics}
    compiler.restore(mark)  # back to the hands on WH1
    assert "TOP@laid" not in {s.name for s in compiler.checker.scene.statics}
