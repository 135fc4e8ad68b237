"""How fast a cell's trajectories are timed: fractions of the joints' velocity and
acceleration limits and a cap on the tools' speed, from cell.yaml and plan.yaml and the
command line's ``--speed``. The timing uses them (:meth:`CellModel.timing_limits
<cellengine.motion.robot.CellModel.timing_limits>`, :func:`tcp_limit`); the gate checks the
arms' own limits, so a slowed trajectory passes it as a full-speed one does."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from cellengine.arrays import Vec
from cellengine.info.speed import SpeedScaling, scaling
from cellengine.motion.timing import TcpSpeedLimit
from cellengine.motion.ur_ik import URKinematics

if TYPE_CHECKING:
    from cellengine.info.cell import Cell
    from cellengine.info.plan import Plan
    from cellengine.motion.robot import Arm, CellModel
    from cellengine.motion.trajectory import Trajectory


@dataclass(frozen=True)
class Speed:
    """``velocity``, ``acceleration``: fractions of the joints' limits (``factor``, the
    command line's, included); ``tcp``: the TCPs' speed cap (m/s, ``factor`` included), None
    for none; ``factor``: the command line's ``--speed`` (1: none)."""

    velocity: float = 1.0
    acceleration: float = 1.0
    tcp: float | None = None
    factor: float = 1.0


def resolve(cell: Cell, plan: Plan | None = None, factor: float = 1.0) -> Speed:
    """The speed a plan runs at: the plan's ``speed`` or else the cell's, the lower of their
    ``tcp_speed`` caps (a cell's cap is the installation's: a plan cannot raise it), all
    times ``factor`` (a first run slowed on the command line)."""
    own = plan.speed if plan is not None else None
    fractions = own or scaling(cell.speed) or SpeedScaling()
    caps = [c for c in (cell.tcp_speed, plan.tcp_speed if plan else None) if c is not None]
    tcp = min(caps) * factor if caps else None
    return Speed(fractions.velocity * factor, fractions.acceleration * factor, tcp, factor)


def speed_json(speed: Speed) -> dict[str, float | None]:
    """report.json's ``speed``: the fractions and the TCP cap (m/s) the program was timed
    with, and the command line's factor."""
    return {
        "velocity": speed.velocity,
        "acceleration": speed.acceleration,
        "tcp_m_s": speed.tcp,
        "factor": speed.factor,
    }


def tcp_limit(cell: CellModel, arms: tuple[str, ...] | None = None) -> TcpSpeedLimit | None:
    """The cell's TCP speed cap on ``arms``' TCPs (default: every arm; rows of their joints
    only when ``arms`` is one arm), for the timing; None without a cap."""
    if cell.speed.tcp is None:
        return None
    names = tuple(cell.arms) if arms is None else arms
    one = len(names) == 1 and arms is not None

    def position(Q: Vec) -> Vec:
        rows = np.asarray(Q, dtype=float)
        tcps = [tcp_points(cell.arms[n], rows if one else rows[:, cell.slices[n]]) for n in names]
        return np.stack(tcps, axis=1)

    return TcpSpeedLimit(cell.speed.tcp, position)


def tcp_points(arm: Arm, Q: Vec) -> Vec:
    """The arm's TCP positions (M, 3) in the cell frame at its configurations ``Q`` (M, n):
    a built-in UR's from its DH table all at once (the timing asks for thousands), any
    other's one by one."""
    if arm.dh is None:
        return np.array([arm.fk(q)[:3, 3] for q in Q])
    T = URKinematics.from_dh(arm.dh).fk_batch(Q)  # T_base_flange
    tcp = T @ arm.T_flange_tcp[:, 3]
    out: Vec = (tcp @ arm.T_cell_base.T)[:, :3]
    return out


def tcp_speeds(cell: CellModel, traj: Trajectory, dt: float = 0.002) -> dict[str, Vec]:
    """Each arm's TCP speed (m/s), J(q) qd, every ``dt`` (default: the servo period) and at
    the end."""
    times = np.append(np.arange(traj.start_time, traj.end_time, dt), traj.end_time)
    Q, QD, _ = traj.sample(times)
    out: dict[str, Vec] = {}
    for name, arm in cell.arms.items():
        s = cell.slices[name]
        out[name] = np.array(
            [
                float(np.linalg.norm(arm.jacobian(q[s])[:3] @ qd[s]))
                for q, qd in zip(Q, QD, strict=True)
            ]
        )
    return out
