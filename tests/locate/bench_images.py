"""Synthetic pictures of cells/lab_bench for the localisation tests."""

from __future__ import annotations

import math
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from cellengine import geometry
from cellengine.emulate.camera import Lens, Shot, looking_down, render, solids, world_markers
from cellengine.info.load import load_world
from cellengine.world import World

CELL = Path(__file__).resolve().parents[2] / "cells/lab_bench"
# the camera's true pose, which the locator is not told: 12 mm and 2 deg off the nominal
T_CAMERA = looking_down(0.762, 0.641, 0.905, math.pi / 2 + math.radians(2.0))


def bench_world() -> World:
    return load_world(CELL / "cell.yaml", CELL / "objects.yaml")


@cache
def bench_lens() -> Lens:
    """The bench camera's lens, built once for the tests (a second each)."""
    camera = bench_world().cell.camera
    assert camera is not None
    return Lens.of(camera)


def moved(world: World) -> dict[str, np.ndarray]:
    """vial1 off its rack onto the table (turned 0.3 rad), vial3 2 mm and 1 mm off its slot."""
    vial3 = world.standing(world.container("vial3")).copy()
    vial3[:2, 3] += (0.002, -0.001)
    return {"vial1": geometry.pose((0.55, 0.23, 0.0), (0.0, 0.0, 0.3)), "vial3": vial3}


def picture(world: World, places: dict[str, np.ndarray], **spoil: Any) -> Any:
    camera = world.cell.camera
    assert camera is not None
    markers = spoil.pop("markers", world_markers(camera))
    shot = Shot(T_CAMERA, markers, solids(world, places), seed=7, **spoil)
    return render(camera, shot, bench_lens())
