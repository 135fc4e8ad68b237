"""A program's segments as one trajectory (what a driver plays, what trajectory.json holds)."""

from __future__ import annotations

from cellengine.motion.trajectory import Trajectory, concatenate
from cellengine.program import Program


def program_trajectory(program: Program) -> Trajectory:
    """Every segment's motion in order on the program's time axis. Segments that only
    change grippers take no time and add no points; segments join where the arms are at
    rest, so their ends agree."""
    if not program.segments:
        raise ValueError("an empty program has no trajectory")
    moving = [s.trajectory for s in program.segments if len(s.trajectory) > 1]
    return concatenate(moving) if moving else program.segments[0].trajectory
