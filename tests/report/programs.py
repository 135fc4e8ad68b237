"""Hand-made programs on the cable-routing cell, for the report's tests (no executor)."""

from __future__ import annotations

from functools import cache
from typing import Any

import numpy as np

from cellengine.info.load import load_world
from cellengine.motion.robot import CellModel, build_cell_model
from cellengine.motion.trajectory import Trajectory
from cellengine.program import (
    Anchor,
    ArmPath,
    CompiledSegment,
    GripperEvent,
    Program,
    Segment,
    TimedEvent,
)
from cellengine.world import World
from tests.conftest import CELLS

CELL_FILE = CELLS / "cable_routing" / "cell.yaml"
OBJECTS_FILE = CELLS / "cable_routing" / "objects.yaml"


@cache
def cable_cell() -> tuple[World, CellModel]:
    world = load_world(CELL_FILE, OBJECTS_FILE)
    return world, build_cell_model(world)


def home(cell: CellModel) -> np.ndarray:
    return cell.join({name: arm.home for name, arm in cell.arms.items()})


def min_jerk(q0: np.ndarray, q1: np.ndarray, t0: float, duration: float, knots: int = 21) -> Any:
    """A rest-to-rest quintic (minimum-jerk) move from q0 to q1, as a Trajectory."""
    s = np.linspace(0.0, 1.0, knots)
    p = 10 * s**3 - 15 * s**4 + 6 * s**5
    dp = (30 * s**2 - 60 * s**3 + 30 * s**4) / duration
    ddp = (60 * s - 180 * s**2 + 120 * s**3) / duration**2
    dq = q1 - q0
    return (
        t0 + s * duration,
        q0 + np.outer(p, dq),
        np.outer(dp, dq),
        np.outer(ddp, dq),
    )


def trajectory(
    cell: CellModel, q0: np.ndarray, q1: np.ndarray, t0: float, duration: float
) -> Trajectory:
    t, q, qd, qdd = min_jerk(q0, q1, t0, duration)
    return Trajectory(cell.joint_names, t, q, qd, qdd)


def cartesian(cell: CellModel, arm: str, qs: list[np.ndarray]) -> ArmPath:
    poses = np.array([cell.arms[arm].fk(cell.split(q)[arm]) for q in qs])
    return ArmPath(arm, "cartesian", poses)


def transit(cell: CellModel, arm: str, q: np.ndarray) -> ArmPath:
    return ArmPath(arm, "transit", cell.arms[arm].fk(cell.split(q)[arm])[None])


def sample_program(cell: CellModel, seconds: float = 1.0) -> Program:
    """Three segments in two steps (times scale with ``seconds``):

    0. step 0 'PickCable: approach', both arms Cartesian from home, 2 s; the executor's
       figures given, distance not given (the report measures it);
    1. step 0 'PickCable: grasp', both grippers grasp cable1 at its start, left arm moves
       (transit), 1 s;
    2. step 1 'RouteCable guide2: lift', both arms Cartesian, sync; distance and a failed
       check reported; the right gripper opens at its end.
    """
    q0 = home(cell)
    q1 = q0 + np.array([0.3, 0.2, -0.3, 0.1, 0.2, 0.0, -0.3, 0.2, -0.3, 0.1, -0.2, 0.0])
    q2 = q1 + np.array([0.1, -0.1, 0.0, 0.0, 0.0, 0.3, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    q3 = q2 + np.array([-0.2, 0.1, 0.2, 0.0, 0.1, 0.0, 0.2, -0.1, 0.2, 0.0, 0.0, 0.4])
    d0, d1, d2 = 2.0 * seconds, 1.0 * seconds, 3.0 * seconds
    grasp = (
        GripperEvent("left", "grasp", "cable1.connector"),
        GripperEvent("right", "grasp", "cable1"),
    )
    release = (GripperEvent("right", "open", None),)
    segments = (
        CompiledSegment(
            Segment(
                0,
                "PickCable: approach",
                (cartesian(cell, "left", [q0, q1]), cartesian(cell, "right", [q0, q1])),
            ),
            "split",
            trajectory(cell, q0, q1, 0.0, d0),
            {
                "merge": "joint",
                "durations_s": {"joint": d0, "published": d0 + 1.5},
                "fraction": {"left": 1.0, "right": 0.97},
                "planning_time_s": 0.125,
                "checks": {"gate": True, "gate_samples": 2001, "keep_distance": None},
                "custom": np.array([1.0, 2.0]),
                "keep_distance": {"arms": ["left", "right"], "distance_m": 0.3},
            },
        ),
        CompiledSegment(
            Segment(0, "PickCable: grasp", (transit(cell, "left", q2),), before=grasp),
            "split",
            trajectory(cell, q1, q2, d0, d1),
            {"merge": "none", "fraction": {}, "planning_time_s": 0.05, "checks_passed": True},
        ),
        CompiledSegment(
            Segment(
                1,
                "RouteCable guide2: lift",
                (cartesian(cell, "left", [q2, q3]), cartesian(cell, "right", [q2, q3])),
                after=release,
                keep_distance=("left", "right"),
                facts={"guide": "routing.guide2", "slot": np.array([0.3, -0.2, 0.065])},
                annotations=(Anchor("cable1", (0.3, -0.2, 0.065), "routing.guide2"),),
            ),
            "sync",
            trajectory(cell, q2, q3, d0 + d1, d2),
            {
                "merge": "published",
                "durations_s": {"joint": d2 - 0.5, "published": d2},
                "cartesian_fraction": 0.5,
                "min_arm_distance_m": 0.2345,
                "closest_pair": ("left/tool", "right/tool"),
                "checks_passed": False,
                "nan_figure": float("nan"),
            },
        ),
    )
    events = (
        *(TimedEvent(d0, e) for e in grasp),
        TimedEvent(d0 + d1 + d2, release[0]),
    )
    return Program(cell.joint_names, segments, events)
