"""A small dual-arm cell and hand-made compiled segments for the driver tests."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from cellengine.drivers import SimDriver
from cellengine.info.cell import Cell
from cellengine.info.objects import Objects
from cellengine.motion.trajectory import Trajectory
from cellengine.program import CompiledSegment, GripperEvent, Segment, TimedEvent

UR_JOINTS = ("shoulder_pan", "shoulder_lift", "elbow", "wrist_1", "wrist_2", "wrist_3")
JOINTS = {arm: tuple(f"{arm}_{j}_joint" for j in UR_JOINTS) for arm in ("left", "right")}
NAMES = JOINTS["left"] + JOINTS["right"]
N = len(NAMES)


def cell(**driver: object) -> Cell:
    return Cell.model_validate(
        {
            "name": "pair",
            "robots": {
                "left": {"model": "ur5e", "tool": "gripper"},
                "right": {"model": "ur5e", "tool": "gripper"},
            },
            "tools": {
                "gripper": {
                    "kind": "parallel_gripper",
                    "jaw": {"open": 0.06, "slide": 0.007, "grasp": 0.004},
                }
            },
            "driver": driver or {"kind": "sim"},
        }
    )


def objects() -> Objects:
    return Objects.model_validate(
        {
            "cables": {"cable1": {"length": 0.65, "diameter": 0.006, "mass": 0.04}},
            "containers": {
                "vial1": {"kind": "vial", "diameter": 0.028, "height": 0.06, "mass": 0.012}
            },
        }
    )


def quintic(q0: ArrayLike, q1: ArrayLike, duration: float, t0: float = 0.0) -> Trajectory:
    """Rest to rest from q0 to q1 (cell order) with a quintic in time, 21 knots."""
    a, b = np.asarray(q0, dtype=float), np.asarray(q1, dtype=float)
    t = np.linspace(0.0, duration, 21)
    s = (t / duration)[:, None]
    d = b - a
    pos = a + d * (10 * s**3 - 15 * s**4 + 6 * s**5)
    vel = d * (30 * s**2 - 60 * s**3 + 30 * s**4) / duration
    acc = d * (60 * s - 180 * s**2 + 120 * s**3) / duration**2
    pos[0], pos[-1] = a, b  # exactly
    return Trajectory(NAMES, t + t0, pos, vel, acc)


def still(q: ArrayLike, t0: float = 0.0) -> Trajectory:
    """One point: no motion (a segment of gripper events only)."""
    row = np.asarray(q, dtype=float)[None, :]
    return Trajectory(NAMES, np.array([t0]), row, np.zeros_like(row), np.zeros_like(row))


def compiled(traj: Trajectory, label: str = "move", step: int = 0) -> CompiledSegment:
    return CompiledSegment(Segment(step, label), "sync", traj, {})


def event(time: float, arm: str, mode: str, holds: str | None = None) -> TimedEvent:
    return TimedEvent(time, GripperEvent(arm, mode, holds))


def q_with(**values: float) -> np.ndarray:
    """The zero q with some joints set: q_with(left_elbow_joint=0.5)."""
    q = np.zeros(N)
    for name, v in values.items():
        q[NAMES.index(name)] = v
    return q


def active(**options: object) -> SimDriver:
    d = SimDriver(cell(), JOINTS, objects=objects(), **options)  # type: ignore[arg-type]
    d.configure()
    d.activate()
    return d


def play(d: SimDriver, segments: Sequence[tuple[CompiledSegment, Sequence[TimedEvent]]]) -> None:
    for seg, events in segments:
        d.execute(seg, events)
