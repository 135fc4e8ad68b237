"""A program's joint state at given times, in a chosen joint order."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from cellengine.arrays import Vec
from cellengine.program import Program


def joint_order(program: Program, names: Sequence[str]) -> NDArray[np.intp]:
    """Indices into the program's joints giving ``names``' order (ValueError naming a joint
    the program does not have)."""
    index = {n: i for i, n in enumerate(program.joint_names)}
    missing = [n for n in names if n not in index]
    if missing:
        raise ValueError(
            f"the program has no joint {', '.join(missing)} (it has "
            f"{', '.join(program.joint_names)})"
        )
    return np.array([index[n] for n in names], dtype=np.intp)


def program_span(program: Program) -> tuple[float, float]:
    """First and last time of the program (0, 0 when it is empty)."""
    if not program.segments:
        return 0.0, 0.0
    return program.segments[0].trajectory.start_time, program.duration


def sample_times(program: Program, rate: float, max_samples: int) -> Vec:
    """Times every 1/rate s from the program's start, its end included; the rate is lowered
    when that would give more than ``max_samples``."""
    if rate <= 0 or max_samples < 2:
        raise ValueError("rate must be > 0 and max_samples >= 2")
    start, end = program_span(program)
    span = end - start
    if span <= 0:
        return np.array([start])
    dt = max(1.0 / rate, span / (max_samples - 1))
    count = int(np.floor(span / dt + 1e-9))
    times: Vec = start + dt * np.arange(count + 1, dtype=np.float64)
    if end - times[-1] > 1e-9:
        times = np.append(times, end)
    else:
        times[-1] = end
    return times


def sample_program(
    program: Program, times: Vec, order: NDArray[np.intp] | None = None
) -> tuple[Vec, Vec]:
    """Positions and velocities (len(times), n) at ``times``: each time from the segment
    covering it (the later one at a junction); between or outside segments, the state where
    the previous segment ended (or where the first begins), at rest."""
    if not program.segments:
        raise ValueError("the program has no segments")
    n = len(program.joint_names)
    q, qd = np.empty((len(times), n)), np.zeros((len(times), n))
    first = program.segments[0].trajectory
    q[:] = first.q[0]
    for seg in program.segments:  # in time order: a later segment overwrites
        traj = seg.trajectory
        after = times >= traj.start_time
        q[after] = traj.q[-1]  # held until a later segment says otherwise
        qd[after] = 0.0
        inside = after & (times <= traj.end_time)
        if inside.any():
            pos, vel, _ = traj.sample(times[inside])
            q[inside], qd[inside] = pos, vel
    if order is not None:
        q, qd = q[:, order], qd[:, order]
    return q, qd
