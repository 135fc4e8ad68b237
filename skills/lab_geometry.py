"""Grasps of upright containers for the lab skills: where the fingertips go and from where.

TCP frame convention (``T_cell_tcp``, as in the cable skills): ``z_tcp`` points out of the
fingertips (the approach direction), ``y_tcp`` is the jaw axis (the fingers close along it),
``x_tcp = y_tcp x z_tcp``. A container stands at its ``at`` keypoint: the centre of its base,
z up (objects.yaml).

- **top** grasp (``grasp: top`` tools): ``z_tcp`` straight down, the fingertips round the top
  of the container (the cap, when it has one), the jaw axis horizontal at a chosen heading.
- **side** grasp (``grasp: side`` tools): ``z_tcp`` horizontal towards the container's axis,
  the jaw axis horizontal too (the fingers close across the body), two thirds up the body
  below the cap.

Either way the fingertip centre is on the container's axis, and the hand comes in along
``z_tcp`` from :data:`APPROACH` away and leaves upwards by :data:`LIFT`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from cellengine import geometry as g
from cellengine.arrays import Mat, Vec
from cellengine.info.objects import Container

Grasp = Literal["top", "side"]

APPROACH = 0.06  # m: the hand comes in along its z from this far
LIFT = 0.08  # m: and lifts the container this high before carrying it
# A cap's height when objects.yaml does not give one: the top of the container, at most
# this share of its height, at most CAP_HEIGHT.
CAP_HEIGHT = 0.015
CAP_SHARE = 0.25
SIDE_GRASP_SHARE = 2.0 / 3.0
# Side grasps come in from these headings (deg from the cell's x, every 15), tried nearest
# first to the heading away from the arm's base: a robot whose tool cannot turn about the
# vertical (the published robot 1 comes in along +x only) finds its one heading among them.
SIDE_HEADINGS_DEG = tuple(range(0, 360, 15))
UP = np.array([0.0, 0.0, 1.0])


@dataclass(frozen=True)
class Body:
    """The dimensions the grasps need (m): height, diameter (the box's smaller side for a
    box), the cap's height (0: no cap)."""

    height: float
    diameter: float
    cap_height: float

    @classmethod
    def of(cls, c: Container) -> Body:
        height = c.full_height
        if height is None:
            raise ValueError("a container needs a height (or a box size) to be grasped")
        if c.diameter is not None:
            width = c.diameter
        elif c.size is not None:
            width = min(c.size[0], c.size[1])
        else:
            raise ValueError("a container needs a diameter (or a box size) to be grasped")
        cap = min(CAP_HEIGHT, CAP_SHARE * height) if c.cap is not None else 0.0
        return cls(height, width, cap)

    def grasp_height(self, grasp: Grasp) -> float:
        """Height of the fingertip centre above the base."""
        if grasp == "top":
            # round the cap, or the top quarter of an open container
            return self.height - (self.cap_height / 2.0 if self.cap_height else CAP_HEIGHT)
        # two thirds up the body below the cap: the fingers clear of the bench and of a
        # rack's walls, and below the cap that the other hand may turn
        return (self.height - self.cap_height) * SIDE_GRASP_SHARE


def horizontal(v: Vec) -> Vec:
    h = np.asarray(v, dtype=float) - UP * float(np.asarray(v, dtype=float) @ UP)
    n = float(np.linalg.norm(h))
    if n < 1e-9:
        return np.array([1.0, 0.0, 0.0])
    out: Vec = h / n
    return out


def top_grasp(axis_point: Vec, heading: float) -> Mat:
    """T_cell_tcp of a top grasp at ``axis_point``: z down, the jaw axis at ``heading`` (rad
    about z from the cell's x)."""
    z = -UP
    y = np.array([math.cos(heading), math.sin(heading), 0.0])
    return g.transform(g.frame_yz(y, z), axis_point)


def side_grasp(axis_point: Vec, direction: Vec) -> Mat:
    """T_cell_tcp of a side grasp at ``axis_point`` coming in along the horizontal
    ``direction``: z along it, the jaw axis horizontal across it."""
    z = horizontal(direction)
    y = np.cross(UP, z)
    return g.transform(g.frame_yz(y, z), axis_point)


def approach_of(T_grasp: Mat, distance: float = APPROACH) -> Mat:
    """Where the hand is before it comes in: back along its own z."""
    out = np.array(T_grasp, dtype=float)
    out[:3, 3] -= distance * T_grasp[:3, 2]
    return out


def lifted(T: Mat, height: float = LIFT) -> Mat:
    out = np.array(T, dtype=float)
    out[:3, 3] += height * UP
    return out


def grasp_candidates(grasp: Grasp, T_at: Mat, body: Body, base: Vec, n_top: int = 8) -> list[Mat]:
    """The grasps to try, best first, for a container standing at ``T_at`` and an arm whose
    base is at ``base``: top grasps at ``n_top`` headings starting across the line to the
    base; side grasps coming in from the base's side first."""
    p = T_at[:3, 3] + body.grasp_height(grasp) * UP
    away = horizontal(p - base)
    if grasp == "top":
        start = math.atan2(float(away[1]), float(away[0])) + math.pi / 2.0
        return [top_grasp(p, start + k * math.pi / n_top) for k in range(n_top)]
    heading = math.atan2(float(away[1]), float(away[0]))

    def off(deg: float) -> float:
        return abs(math.remainder(math.radians(deg) - heading, 2.0 * math.pi))

    return [
        T
        for d in sorted(SIDE_HEADINGS_DEG, key=off)
        for T in both_ways(
            side_grasp(p, np.array([math.cos(math.radians(d)), math.sin(math.radians(d)), 0.0]))
        )
    ]


def both_ways(T: Mat) -> tuple[Mat, Mat]:
    """A grasp and the same grasp turned half a turn about the tool's axis: a parallel
    gripper is symmetric about it, and an arm may reach only one of the two (a tool whose
    fingertips are off the flange's axis)."""
    flipped = np.array(T, dtype=float)
    flipped[:3, :2] *= -1.0
    return T, flipped
