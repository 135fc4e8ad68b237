"""Both arms' motions on one time axis: the published merge and the joint one.

- **published** (MergePlans of the cable-routing paper): each arm is timed on its own; the
  trajectory with fewer points gets intermediate points until both have as many, and both
  take the slower arm's times. MoveIt's Cartesian trajectories have one point per waypoint,
  so a point's index is a place along the path, and the faster arm ends up following the
  slower arm's timing place by place. Timed trajectories here have knots where the timing
  needs them, not per waypoint, so the pairing is made by place directly: at each of the
  slower arm's knots, every other arm is at the same fraction of its own path as the slower
  arm is of its. The paper copies interpolated velocities and accelerations, which do not
  belong to the new timing; here they come from the chain rule, so the result is one
  consistent C2 motion. Following another arm's timing can ask more of the faster arm than
  its limits allow (where its path turns while the slower one's runs straight); the merged
  trajectory is then slowed uniformly until it is within every velocity, acceleration and
  jerk limit. It never takes less than the slower arm alone.
- **joint**: the pair timed together, on the pairing the strategy solved them on.
  Arms solved on one grid (a 12-DOF transit, both Cartesian paths followed together, a
  closed chain) keep that grid's pairing, and two timings of the combined path are built:
  the combined path time-parameterised over all twelve joints (every joint's limits bound one
  common speed: each arm is slowed only where the pair must be), and the slower arm's own
  timing with the other arm following it along the grid (optimal whenever the other arm can
  follow; slowed uniformly when it cannot). The shorter is taken: the twelve-joint timing is
  a smoothed optimum, and where the slower arm's own timing is feasible nothing is faster.
  Arms solved apart have no pairing to keep: each keeps its own timing's shape, the faster
  stretched uniformly to the slower's duration (velocities scale by the stretch,
  accelerations by its square). That is the twelve-joint optimum of the pair paired by
  fraction of each arm's own duration, built exactly rather than re-solved.

Both are compared with the bound of the part: the slower arm's time-optimal duration on its
own path with no jerk limit (``bound``), and its jerk-limited duration alone (``bound_jerk``,
what any timing with the executor's limits needs).

Trajectories of separate arms are put on one axis exactly (:func:`on_one_axis`): at the union
of their knot times, each arm sampled from its own trajectory; a quintic piece cut at an inner
point is the same polynomial on both halves, so nothing is approximated.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Literal

import numpy as np

from cellengine.arrays import Vec
from cellengine.execute.retime import (
    jerk_limits,
    moves,
    still,
    thinned,
    timed,
    timed_and_fastest,
)
from cellengine.motion.jerk import TCP_MARGIN
from cellengine.motion.robot import CellModel
from cellengine.motion.speed import tcp_limit, tcp_speeds
from cellengine.motion.topp import SplinePath
from cellengine.motion.trajectory import Trajectory

Merge = Literal["joint", "published"]
MERGES: tuple[Merge, ...] = ("joint", "published")

# Knot times closer than this (s) are one knot of the merged trajectory.
SAME_TIME = 1e-7


@dataclass(frozen=True)
class Merged:
    """One part's timing: the chosen merge's trajectory (whole cell, from t = 0) and the
    figures of both merges on the same rows."""

    trajectory: Trajectory
    alone: Mapping[str, Trajectory]  # each moving arm timed on its own (its joints, from 0)
    durations: Mapping[str, float]  # merge name -> duration (s)
    bound: float  # the slower arm's time-optimal duration (TOPP-RA, no jerk limit)
    bound_jerk: float  # the slower arm's jerk-limited duration on its own


def merge_rows(
    cell: CellModel,
    q: Vec,
    rows: Mapping[str, Vec],
    coupled: Vec | None,
    merge: Merge,
) -> Merged:
    """Time a part: each moving arm's ``rows`` (its joints, ``q``'s first), ``coupled`` the
    whole-cell rows when the arms were solved on one grid. Both merges are built (the report
    compares them); ``merge`` chooses the one returned."""
    moving = {arm: r for arm, r in rows.items() if moves(r)}
    if not moving:
        return Merged(still(q, cell.joint_names), {}, {m: 0.0 for m in MERGES}, 0.0, 0.0)
    timings = {
        arm: timed_and_fastest(
            r, cell.timing_limits(arm), cell.arms[arm].joint_names, tcp_limit(cell, (arm,))
        )
        for arm, r in moving.items()
    }
    alone = {arm: traj for arm, (traj, _) in timings.items()}
    bound = max(fastest for _, fastest in timings.values())
    bound_jerk = max(t.duration for t in alone.values())
    built = {
        "published": published(cell, q, alone, moving),
        "joint": joint(cell, q, alone, coupled),
    }
    durations: dict[str, float] = {m: built[m].duration for m in MERGES}
    return Merged(built[merge], alone, durations, bound, bound_jerk)


def slowest(alone: Mapping[str, Trajectory]) -> str:
    return max(alone, key=lambda arm: alone[arm].duration)


# ------------------------------------------------------------------------------ joint


def joint(
    cell: CellModel, q: Vec, alone: Mapping[str, Trajectory], coupled: Vec | None
) -> Trajectory:
    """The pair timed together (see the module notes)."""
    if len(alone) == 1:
        return on_one_axis(cell, q, alone)
    if coupled is None:
        return stretched(cell, q, alone)
    lead = slowest(alone)
    pairing = _grid_pairing(cell, thinned(coupled), lead, alone)
    following = None if pairing is None else follow(cell, q, alone[lead], lead, pairing)
    if following is not None and following.duration <= alone[lead].duration * (1 + 1e-9):
        return following  # the slower arm's own timing, unslowed: nothing does better
    together = timed(coupled, cell.timing_limits(), cell.joint_names, tcp_limit(cell))
    if following is None or together.duration <= following.duration:
        return together
    return following


def _grid_pairing(
    cell: CellModel, rows: Vec, lead: str, alone: Mapping[str, Trajectory]
) -> dict[str, tuple[Vec, Vec]] | None:
    """Each other arm's rows of the combined path against the lead arm's fraction of its
    path at those rows; None where the lead stands while another arm moves (no function of
    the lead's progress then)."""
    steps = np.linalg.norm(np.diff(rows[:, cell.slices[lead]], axis=0), axis=1)
    if len(steps) == 0 or steps.min() <= 1e-9 * steps.sum():
        return None
    fraction = np.concatenate([[0.0], np.cumsum(steps)]) / steps.sum()
    return {arm: (rows[:, cell.slices[arm]], fraction) for arm in alone if arm != lead}


def stretched(cell: CellModel, q: Vec, alone: Mapping[str, Trajectory]) -> Trajectory:
    """Every arm's own trajectory, the faster ones slowed uniformly to the slowest's
    duration."""
    longest = max(t.duration for t in alone.values())
    same = {
        arm: t.time_scaled(longest / t.duration) if t.duration < longest else t
        for arm, t in alone.items()
    }
    return on_one_axis(cell, q, same)


# ------------------------------------------------------------------------------ published


def published(
    cell: CellModel, q: Vec, alone: Mapping[str, Trajectory], rows: Mapping[str, Vec]
) -> Trajectory:
    """The paper's merge (see the module notes), made consistent and slowed to the limits."""
    if len(alone) == 1:
        return on_one_axis(cell, q, alone)
    lead = slowest(alone)
    pairing = {arm: _own_place(rows[arm]) for arm in alone if arm != lead}
    return follow(cell, q, alone[lead], lead, pairing)


def _own_place(rows: Vec) -> tuple[Vec, Vec]:
    """An arm's rows against their fraction of its own path (chord length)."""
    R = thinned(rows)
    steps = np.linalg.norm(np.diff(R, axis=0), axis=1)
    return R, np.concatenate([[0.0], np.cumsum(steps)]) / steps.sum()


# ------------------------------------------------------------------------------ following


def follow(
    cell: CellModel,
    q: Vec,
    lead: Trajectory,
    lead_arm: str,
    pairing: Mapping[str, tuple[Vec, Vec]],
) -> Trajectory:
    """The lead arm on its own timing; each other arm at the place ``pairing[arm]`` = (its
    rows, the lead's path fraction at each row) gives for the lead's progress; slowed
    uniformly to the limits when the others cannot keep up."""
    times = lead.t
    phi, dphi, ddphi = _progress(lead)
    Q = np.repeat(q[None, :], len(times), axis=0)
    V, A = np.zeros_like(Q), np.zeros_like(Q)
    cols = cell.slices[lead_arm]
    Q[:, cols], V[:, cols], A[:, cols] = lead.q, lead.qd, lead.qdd
    for arm, (rows, fraction) in pairing.items():
        # q(t) = P(phi(t)): v = P' phi', a = P'' phi'^2 + P' phi''
        P, dP, ddP = SplinePath(rows, knots=fraction).derivatives(phi)
        cols = cell.slices[arm]
        Q[:, cols] = P
        V[:, cols] = dP * dphi[:, None]
        A[:, cols] = ddP * (dphi * dphi)[:, None] + dP * ddphi[:, None]
    return within_limits(Trajectory(cell.joint_names, times - times[0], Q, V, A), cell)


# Gauss-Legendre nodes and weights on [0, 1]: the arc length over each knot interval
_GL = np.polynomial.legendre.leggauss(4)
_GL_NODES, _GL_WEIGHTS = 0.5 + 0.5 * _GL[0], 0.5 * _GL[1]


def _progress(traj: Trajectory) -> tuple[Vec, Vec, Vec]:
    """The fraction of its joint-space path length a trajectory has covered at each knot,
    and its first two time derivatives (|v| / L and v.a / (|v| L))."""
    h = np.diff(traj.t)
    inner = (traj.t[:-1, None] + h[:, None] * _GL_NODES).ravel()
    _, v_inner, _ = traj.sample(inner)
    speed = np.linalg.norm(v_inner, axis=1).reshape(len(h), len(_GL_NODES))
    covered = np.concatenate([[0.0], np.cumsum(h * (speed @ _GL_WEIGHTS))])
    length = float(covered[-1])
    speed_k = np.linalg.norm(traj.qd, axis=1)
    along = np.einsum("ij,ij->i", traj.qd, traj.qdd)
    moving = speed_k > 1e-12
    dd = np.where(moving, along / np.where(moving, speed_k, 1.0), 0.0)
    return np.clip(covered / length, 0.0, 1.0), speed_k / length, dd / length


def within_limits(traj: Trajectory, cell: CellModel) -> Trajectory:
    """``traj`` slowed uniformly (velocity and TCP speed scale as 1/k, acceleration 1/k^2,
    jerk 1/k^3) until the bounds of Trajectory.peaks are within the cell's timing limits
    and its TCPs within the cell's TCP speed cap."""
    if len(traj) < 2:
        return traj
    peaks = traj.peaks()
    lim = cell.timing_limits()
    k = max(
        1.0,
        float(np.max(peaks.velocity / lim.velocity)),
        float(np.max(peaks.acceleration / lim.acceleration)) ** 0.5,
        float(np.max(peaks.jerk / jerk_limits(lim))) ** (1.0 / 3.0),
    )
    if cell.speed.tcp is not None:
        fastest_tcp = max(float(v.max()) for v in tcp_speeds(cell, traj).values())
        k = max(k, fastest_tcp / (cell.speed.tcp * TCP_MARGIN))
    return traj if k <= 1.0 else traj.time_scaled(k * (1.0 + 1e-9))


# ------------------------------------------------------------------------------ one axis


def on_one_axis(
    cell: CellModel,
    q: Vec,
    trajectories: Mapping[str, Trajectory],
    starts: Mapping[str, float] | None = None,
) -> Trajectory:
    """Arms' own trajectories (their joints, from t = 0) as one whole-cell trajectory: each
    arm starting at ``starts[arm]`` (default 0), standing at its first point before and at
    its last after; arms not given stand at ``q``."""
    starts = starts or {}
    knots = np.concatenate([t.t + starts.get(arm, 0.0) for arm, t in trajectories.items()])
    times = _union(np.append(knots, 0.0))
    n = len(times)
    Q = np.repeat(q[None, :], n, axis=0)
    V, A = np.zeros_like(Q), np.zeros_like(Q)
    for arm, traj in trajectories.items():
        cols = cell.slices[arm]
        # before its start and after its end an arm stands: sample() clamps to the end
        # points, which are at rest for every trajectory the executor builds
        Q[:, cols], V[:, cols], A[:, cols] = traj.sample(times - starts.get(arm, 0.0))
    return Trajectory(cell.joint_names, times, Q, V, A)


def _union(times: Vec) -> Vec:
    t = np.sort(times)
    keep = np.concatenate([[True], np.diff(t) > SAME_TIME])
    out: Vec = t[keep]
    return out
