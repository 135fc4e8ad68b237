"""The kinematic bound behind the 'no robot reaches it' warning (bad case
cell_platform_out_of_reach asserts its text)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from cellengine.info.cell import Cell
from cellengine.info.far import arm_bound
from cellengine.info.load import load_world
from cellengine.motion.ur_ik import URKinematics

REFERENCE = Path(__file__).resolve().parents[2] / "cells" / "cable_routing" / "cell.yaml"


def test_the_bound_holds_over_random_configurations() -> None:
    """No configuration puts the flange farther from the shoulder than the bound (tool
    left out), and the bound is not loose by more than the wrist's offsets."""
    cell: Cell = load_world(REFERENCE).cell
    robot = cell.robots["left"].model_copy(update={"tool": None})
    shoulder, reach = arm_bound(cell, robot)  # type: ignore[misc]
    kin = URKinematics.from_name("ur5e")
    q = np.random.default_rng(7).uniform(-math.pi, math.pi, size=(20000, 6))
    T_base = robot.base.matrix()
    p = kin.fk_batch(q)[:, :3, 3] @ T_base[:3, :3].T + T_base[:3, 3]
    farthest = float(np.linalg.norm(p - shoulder, axis=1).max())
    assert farthest <= reach
    assert farthest > reach - 0.35  # d4 + d5 + d6 of a ur5e: 0.333 m


def test_the_reference_cells_platforms_are_in_reach() -> None:
    world = load_world(REFERENCE)
    assert not [w for w in world.warnings if "no robot reaches" in w.message]


@pytest.mark.parametrize("model", ["ur3e", "ur5e", "ur10e", "ur5"])
def test_every_builtin_model_is_bounded(model: str) -> None:
    cell = load_world(REFERENCE).cell
    robot = cell.robots["left"].model_copy(update={"model": model})
    assert arm_bound(cell, robot) is not None
