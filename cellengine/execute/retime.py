"""Joint rows to timed trajectories, with the executor's one choice of jerk limits.

Every trajectory the executor builds is jerk-limited: ``JERK_PER_ACCELERATION`` times each
joint's acceleration limit, so full acceleration is reached in 20 ms, ten servo periods at
500 Hz. A servo stream whose accelerations step from one period to the next makes an arm
shake; ramps much longer than that only cost time: at 10x (0.1 s ramps) the four-guide plan
took 46.2 s instead of 36.0 s, 28 % more, because the cable skills' moves are short (0.4-1 s)
and a ramp is paid at each end. UR publishes no jerk limit (UR's ur_moveit_config gives none
either). The report gives the time-optimal bound, with no jerk limit, beside the jerk-limited
one.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TypeVar

import numpy as np

from cellengine.arrays import Vec
from cellengine.execute.refused import Refused
from cellengine.motion.robot import Limits
from cellengine.motion.timing import (
    PathOutOfRange,
    TcpSpeedLimit,
    speed_profile,
    time_parameterize,
    time_parameterize_and_bound,
)
from cellengine.motion.trajectory import Trajectory

JERK_PER_ACCELERATION = 50.0  # 1/s: jerk limit = 50 x acceleration limit, per joint
# Rows closer than this (rad or m, largest joint) are one: a zero-length spline interval.
SAME_ROW = 1e-9
# An inner row closer to the previous one than this share of the median step is dropped. Two
# paths resampled onto one grid (the union of both arms' waypoint parameters) give rows a
# fraction of a millimetre apart; a cubic spline's third derivative jumps at every row, and
# pieces that short make the timing's jerk and between-sample bounds (and so the durations)
# worse for nothing: the rows around them pin the same curve.
THIN_ROW = 0.5
T = TypeVar("T")


def jerk_limits(limits: Limits) -> Vec:
    out: Vec = JERK_PER_ACCELERATION * np.asarray(limits.acceleration, dtype=float)
    return out


def distinct(rows: Vec) -> Vec:
    """The rows without consecutive repeats (the first of each run kept)."""
    R = np.asarray(rows, dtype=float)
    if len(R) < 2:
        return R
    keep = np.concatenate([[True], np.abs(np.diff(R, axis=0)).max(axis=1) > SAME_ROW])
    out: Vec = R[keep]
    return out


def thinned(rows: Vec) -> Vec:
    """:func:`distinct` rows without inner rows much closer to the previous kept row than
    the median step (the first and last rows are always kept)."""
    R = distinct(rows)
    if len(R) < 3:
        return R
    steps = np.linalg.norm(np.diff(R, axis=0), axis=1)
    gap = THIN_ROW * float(np.median(steps))
    keep = [0]
    for i in range(1, len(R) - 1):
        if np.linalg.norm(R[i] - R[keep[-1]]) >= gap:
            keep.append(i)
    if np.linalg.norm(R[-1] - R[keep[-1]]) < gap and len(keep) > 1:
        keep.pop()  # the last row stays; the one just before it goes instead
    keep.append(len(R) - 1)
    out: Vec = R[keep]
    return out


def moves(rows: Vec) -> bool:
    """Whether the rows go anywhere at all."""
    return len(distinct(rows)) >= 2


def timed(
    rows: Vec, limits: Limits, names: Sequence[str], tcp: TcpSpeedLimit | None = None
) -> Trajectory:
    """The jerk-limited trajectory through ``rows`` (rest to rest), its TCPs within ``tcp``
    when given; one point when they do not move."""
    R = thinned(rows)
    if len(R) < 2:
        return still(R[0], names)
    return _in_range(
        lambda W: time_parameterize(
            W, limits, jerk=jerk_limits(limits), joint_names=tuple(names), tcp=tcp
        ),
        R,
        rows,
    )


def timed_and_fastest(
    rows: Vec, limits: Limits, names: Sequence[str], tcp: TcpSpeedLimit | None = None
) -> tuple[Trajectory, float]:
    """:func:`timed` and :func:`fastest` of the same rows, their spline built once."""
    R = thinned(rows)
    if len(R) < 2:
        return still(R[0], names), 0.0
    return _in_range(
        lambda W: time_parameterize_and_bound(
            W, limits, jerk=jerk_limits(limits), joint_names=tuple(names), tcp=tcp
        ),
        R,
        rows,
    )


def fastest(rows: Vec, limits: Limits, tcp: TcpSpeedLimit | None = None) -> float:
    """The time-optimal duration along the spline through ``rows``: the TOPP-RA profile
    itself (velocity and acceleration limits, the TCPs within ``tcp`` when given,
    accelerations bang-bang), the lower bound of
    any timing of the path. (timing.time_optimal makes that profile playable, C2 and checked
    between samples, which costs ten times more and a few per cent of duration.)"""
    R = thinned(rows)
    if len(R) < 2:
        return 0.0
    return _in_range(lambda W: speed_profile(W, limits, tcp=tcp).duration, R, rows)


def _in_range(time: Callable[[Vec], T], R: Vec, rows: Vec) -> T:
    """``time(R)``; where the spline through the thinned rows ``R`` bulges past a joint's
    range (a path running along a limit), ``time`` of every distinct row; Refused when that
    bulges past it too."""
    try:
        return time(R)
    except PathOutOfRange:
        pass
    try:
        return time(distinct(rows))
    except PathOutOfRange as e:
        raise Refused(f"the path runs along a joint's limit: {e}") from None


def still(q: Vec, names: Sequence[str], t: float = 0.0) -> Trajectory:
    """Standing at ``q``: a one-point trajectory at time ``t``."""
    qa = np.asarray(q, dtype=float)[None, :]
    z = np.zeros_like(qa)
    return Trajectory(tuple(names), np.array([t]), qa, z, z)


def standing(q: Vec, names: Sequence[str], t: float, seconds: float) -> Trajectory:
    """Standing at ``q`` from ``t`` for ``seconds``."""
    qa = np.repeat(np.asarray(q, dtype=float)[None, :], 2, axis=0)
    z = np.zeros_like(qa)
    return Trajectory(tuple(names), np.array([t, t + seconds]), qa, z, z)
