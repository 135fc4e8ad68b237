"""cable_geometry's frames: which way round a hand holding only the cable turns."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cellengine import geometry as g
from cellengine.skills import cable_geometry as cg

UP = np.array([0.0, 0.0, 1.0])


def frame(yaw_deg: float) -> np.ndarray:
    """A top grasp whose TCP x points ``yaw_deg`` from the cell's x, seen from above."""
    a = math.radians(yaw_deg)
    x = np.array([math.cos(a), math.sin(a), 0.0])
    return cg.tcp_frame(np.zeros(3), x, UP, x, 0.0)


def yaw(T: np.ndarray) -> float:
    return math.degrees(math.atan2(T[1, 0], T[0, 0]))


def test_turn_about_vertical_is_signed_and_the_shorter_way() -> None:
    assert math.degrees(cg.turn_about_vertical(frame(10), frame(40))) == pytest.approx(30.0)
    assert math.degrees(cg.turn_about_vertical(frame(170), frame(-170))) == pytest.approx(20.0)
    assert math.degrees(cg.turn_about_vertical(frame(-170), frame(170))) == pytest.approx(-20.0)


def test_nearer_turn_takes_the_smaller_rotation_unless_the_wrist_is_wound_up() -> None:
    """From yaw 0 to a frame at 120 deg: its flip (-60 deg) is nearer. Wound -150 deg
    already, turning -60 more would leave the hand wound 210 deg (over WIND_LIMIT, 180):
    it turns +120 deg instead, unwinding to -30 deg."""
    assert yaw(cg.nearer_turn(frame(0), frame(120))) == pytest.approx(-60.0)
    assert yaw(cg.nearer_turn(frame(0), frame(120), math.radians(-100))) == pytest.approx(-60.0)
    wound = cg.nearer_turn(frame(0), frame(120), math.radians(-150))
    assert yaw(wound) == pytest.approx(120.0)
    # z (the tool's axis) is the same either way
    assert g.angle_between(wound[:3, 2], -UP) == pytest.approx(0.0, abs=1e-9)


def test_a_footprints_bound_is_never_above_its_distance() -> None:
    """_slide_sides leaves out the elements whose bound is past the nearest found: the bound
    must hold for every segment of the reach from the point, on a tilted platform too, and
    come within the reach of the distance for a segment pointing at the element."""
    rng = np.random.default_rng(7)
    for _ in range(300):
        up = g.unit(np.array([0.0, 0.0, 1.0]) + 0.3 * rng.normal(size=3))
        corners = rng.normal(size=(8, 3)) * 0.03 + rng.normal(size=3) * 0.2
        flat = corners - np.outer(corners @ up, up)
        foot = cg.Footprint("e", cg._convex(flat, up), 0.0)
        a, reach = rng.normal(size=3) * 0.2, float(rng.uniform(0.0, 0.1))
        direction = g.unit(np.cross(up, rng.normal(size=3)))
        bound = foot.least_distance(a, reach, up)
        assert bound <= foot.distance(a, a + reach * direction, up)
        centre, radius = foot.circle
        towards = centre - a - ((centre - a) @ up) * up
        if np.linalg.norm(towards) > 1e-6:
            end = a + reach * g.unit(towards)
            assert foot.distance(a, end, up) <= bound + 2.0 * radius + 1e-9
