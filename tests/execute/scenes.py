"""Hand-made segments on the cable-routing cell, shared by the executor's tests and bench."""

from __future__ import annotations

from functools import cache
from pathlib import Path

import numpy as np

from cellengine.arrays import Vec
from cellengine.info.load import load_world
from cellengine.motion.collision import CollisionChecker
from cellengine.motion.robot import CellModel, build_cell_model
from cellengine.motion.scene import build_scene
from cellengine.motion.trajectory import Trajectory
from cellengine.program import ArmPath, GripperEvent, Segment
from cellengine.world import World

CELL = Path(__file__).resolve().parents[2] / "cells" / "cable_routing" / "cell.yaml"
DOWN = np.diag([1.0, -1.0, -1.0])  # TCP z pointing down, x along the cell's x
STEP = 0.005  # m between Cartesian waypoints (the skills' step)


@cache
def cable_cell() -> tuple[World, CellModel, CollisionChecker]:
    world = load_world(CELL, CELL.parent / "objects.yaml")
    cell = build_cell_model(world)
    return world, cell, CollisionChecker(build_scene(cell, world))


def home(cell: CellModel) -> Vec:
    return cell.join({n: a.home for n, a in cell.arms.items()})


def pose(xyz: tuple[float, float, float], R: Vec = DOWN) -> Vec:
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, xyz
    return T


def line(a: tuple[float, float, float], b: tuple[float, float, float], R: Vec = DOWN) -> Vec:
    """TCP poses from a to b, STEP apart, orientation R."""
    n = max(2, int(np.ceil(np.linalg.norm(np.subtract(b, a)) / STEP)) + 1)
    ps = np.add(a, np.linspace(0, 1, n)[:, None] * np.subtract(b, a))
    return np.array([pose(tuple(p), R) for p in ps])


def arc(start: tuple[float, float, float], centre: tuple[float, float, float], angle: float) -> Vec:
    """TCP poses turning ``start`` about the vertical axis through ``centre`` by ``angle``
    (rad), orientation fixed: the distance to the centre stays the same."""
    r = np.subtract(start, centre)
    n = max(2, int(np.ceil(abs(angle) * np.linalg.norm(r[:2]) / STEP)) + 1)
    out = []
    for a in np.linspace(0.0, angle, n):
        c, s = np.cos(a), np.sin(a)
        p = np.add(centre, [c * r[0] - s * r[1], s * r[0] + c * r[1], r[2]])
        out.append(pose(tuple(p)))
    return np.array(out)


def states(traj: Trajectory, dt: float = 0.001) -> Vec:
    """The trajectory's positions every ``dt`` from its start, its end included."""
    t = np.append(np.arange(traj.start_time, traj.end_time, dt), traj.end_time)
    q, _, _ = traj.sample(t)
    out: Vec = q
    return out


def tcp(cell: CellModel, arm: str, Q: Vec) -> Vec:
    """The arm's TCP poses (k, 4, 4) at whole-cell states (k, nq)."""
    return np.array([cell.arms[arm].fk(q[cell.slices[arm]]) for q in Q])


LEFT_READY = (0.40, 0.15, 0.20)
RIGHT_READY = (0.40, -0.15, 0.20)


def ready() -> Segment:
    """Both arms from home to above the routing platform, tools down (a transit)."""
    return Segment(
        0,
        "ready",
        (
            ArmPath("left", "transit", pose(LEFT_READY)[None]),
            ArmPath("right", "transit", pose(RIGHT_READY)[None]),
        ),
        before=(GripperEvent("left", "open"), GripperEvent("right", "open")),
    )


def reference_segments() -> list[Segment]:
    """A transit of both arms, a Cartesian line of one arm, a dual Cartesian move, a closed
    chain move, and a kept-distance arc about the other hand."""
    lx, ly, lz = LEFT_READY
    rx, ry, rz = RIGHT_READY
    return [
        ready(),
        Segment(
            1,
            "left line",
            (ArmPath("left", "cartesian", line(LEFT_READY, (lx + 0.1, ly, lz))),),
            after=(GripperEvent("left", "grasp", "cable1"),),
        ),
        Segment(
            1,
            "both down",
            (
                ArmPath("left", "cartesian", line((lx + 0.1, ly, lz), (lx + 0.1, ly, lz - 0.05))),
                ArmPath("right", "cartesian", line(RIGHT_READY, (rx, ry + 0.05, rz - 0.1))),
            ),
        ),
        Segment(
            2,
            "lift together",
            (
                ArmPath(
                    "right",
                    "cartesian",
                    line((rx, ry + 0.05, rz - 0.1), (rx, ry + 0.05, rz)),
                ),
            ),
            before=(GripperEvent("right", "grasp", "cable1"),),
            closed_chain=("right", "left"),
        ),
        Segment(
            2,
            "left arc about the right hand",
            (
                ArmPath(
                    "left",
                    "cartesian",
                    arc((lx + 0.1, ly, lz + 0.05), (rx, ry + 0.05, rz), -0.4),
                ),
            ),
            keep_distance=("left", "right"),
            after=(GripperEvent("left", "open"),),
        ),
    ]


def crossing() -> tuple[Segment, Segment]:
    """Where the published split matters: the left hand crosses towards where the right hand
    stands while the right hand moves away. Planned apart in one piece, the left arm's path
    runs into the right arm standing at its start; split, it is planned against the right
    arm where it has got to. (After ``ready``.)"""
    seg = Segment(
        1,
        "cross",
        (
            ArmPath("left", "cartesian", line(LEFT_READY, (0.40, -0.10, 0.20))),
            ArmPath("right", "cartesian", line(RIGHT_READY, (0.40, -0.35, 0.20))),
        ),
    )
    return ready(), seg


RIGHT_HIGH = (0.40, -0.15, 0.35)


def sweep() -> tuple[Segment, Segment, Segment]:
    """Where async waits: the left hand sweeps out to y = -5 cm and back while the right hand
    comes down through where the left is at the middle of its sweep. Each path is free with
    the other arm standing at its start; run at once they collide. (After ``ready``, a move
    of the right hand up.)"""
    out = line(LEFT_READY, (0.40, -0.05, 0.20))
    back = line((0.40, -0.05, 0.20), LEFT_READY)
    up = Segment(1, "right up", (ArmPath("right", "cartesian", line(RIGHT_READY, RIGHT_HIGH)),))
    seg = Segment(
        1,
        "sweep",
        (
            ArmPath("left", "cartesian", np.concatenate([out, back[1:]])),
            ArmPath("right", "cartesian", line(RIGHT_HIGH, (0.40, -0.02, 0.20))),
        ),
    )
    return ready(), up, seg


def synchronised() -> dict[str, Segment]:
    """Two-arm Cartesian moves for the merges (after ``ready``): parallel lines of 20 and
    10 cm (the shorter arm can follow the longer one's timing everywhere), and a line beside
    an L whose corner the faster arm must take slowly."""
    lx, ly, lz = LEFT_READY
    rx, ry, rz = RIGHT_READY
    corner = (rx + 0.06, ry, rz)
    return {
        "parallel": Segment(
            1,
            "parallel lines",
            (
                ArmPath("left", "cartesian", line(LEFT_READY, (lx + 0.2, ly, lz))),
                ArmPath("right", "cartesian", line(RIGHT_READY, (rx + 0.1, ry, rz))),
            ),
        ),
        "corner": Segment(
            1,
            "line and corner",
            (
                ArmPath("left", "cartesian", line(LEFT_READY, (lx + 0.2, ly, lz))),
                ArmPath(
                    "right",
                    "cartesian",
                    np.concatenate(
                        [line(RIGHT_READY, corner), line(corner, (rx + 0.06, ry - 0.06, rz))[1:]]
                    ),
                ),
            ),
        ),
    }
