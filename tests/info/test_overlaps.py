"""Oriented boxes' overlap depth (the separating axis theorem) behind the cell's overlap
warnings; the warnings' texts are asserted by the bad-input corpus (cell_platform_sunk,
x3d_parts_one_spot)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cellengine import geometry as g
from cellengine.info.overlaps import Box, depth_of


def _box(
    xyz: tuple[float, float, float], size: tuple[float, float, float], yaw: float = 0.0
) -> Box:
    return Box(g.pose(xyz, (0.0, 0.0, yaw)), np.asarray(size) / 2.0)


def test_boxes_standing_on_one_another_do_not_overlap() -> None:
    table = _box((0.0, 0.0, -0.01), (1.0, 1.0, 0.02))
    plate = _box((0.0, 0.0, 0.005), (0.3, 0.2, 0.01))
    assert depth_of(table, plate) == pytest.approx(0.0, abs=1e-9)


def test_depth_is_the_least_overlap() -> None:
    table = _box((0.0, 0.0, -0.01), (1.0, 1.0, 0.02))
    sunk = _box((0.0, 0.0, -0.025), (0.3, 0.2, 0.1))  # from 75 mm under the top to 25 over
    # lifted 45 mm it stands on the table (pushed down 75 mm it would hang under it)
    assert depth_of(table, sunk) == pytest.approx(0.045, abs=1e-9)
    assert depth_of(sunk, table) == pytest.approx(0.045, abs=1e-9)


def test_turned_boxes_apart_on_an_edge_axis() -> None:
    # two cubes turned 45 deg, corner to corner along x: the face axes of the first overlap,
    # the second's separate them
    a = _box((0.0, 0.0, 0.0), (0.1, 0.1, 0.1), yaw=math.pi / 4)
    b = _box((0.15, 0.0, 0.0), (0.1, 0.1, 0.1), yaw=math.pi / 4)
    assert depth_of(a, b) == 0.0
    c = _box((0.13, 0.0, 0.0), (0.1, 0.1, 0.1), yaw=math.pi / 4)
    # corner to corner: 2 * 0.05 * sqrt(2) - 0.13 along x, seen on the turned faces' normals
    assert depth_of(a, c) == pytest.approx((0.1 * math.sqrt(2) - 0.13) / math.sqrt(2), abs=1e-9)
