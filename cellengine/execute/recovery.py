"""A safe move from where the arms are to where a program goes on (``run --resume``).

The arms may have stopped anywhere (a protective stop mid-segment) and may hold things (the
journal says what). The move is planned like any transit: OMPL for the arms that are off,
every segment proved free with the held objects riding on their grippers, timed with the
executor's limits and passed through the gate.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from cellengine.arrays import Vec
from cellengine.drivers.fault import DriverRefused
from cellengine.execute.held import Holding
from cellengine.execute.retime import timed
from cellengine.motion.gate import check_cell_trajectory
from cellengine.motion.robot import CellModel
from cellengine.motion.scene import CollisionScene
from cellengine.motion.speed import tcp_limit
from cellengine.motion.transit import plan_for_arms
from cellengine.program import CompiledSegment, Segment
from cellengine.world import World


def recovery_segment(
    world: World,
    cell: CellModel,
    scene: CollisionScene,
    q_now: Vec,
    q_target: Vec,
    holds: Mapping[str, str | None],
    tolerance: float,
    step: int,
) -> CompiledSegment | None:
    """The move from ``q_now`` to ``q_target`` for the arms more than ``tolerance`` off (None
    when none is); DriverRefused when no safe move is found."""
    off = [
        arm
        for arm, s in cell.slices.items()
        if float(np.max(np.abs(q_now[s] - q_target[s]))) > tolerance
    ]
    if not off:
        return None
    holding = Holding(world, scene)
    for arm, obj in holds.items():
        if obj is not None:
            holding.set(arm, obj, cell.arms[arm].fk(cell.split(q_now)[arm]))
    result = plan_for_arms(cell, holding.checker, off, q_now, q_target[None, :])
    if result.path is None:
        raise DriverRefused("recovery", f"no safe move back for {', '.join(off)}: {result.reason}")
    traj = timed(result.path, cell.timing_limits(), cell.joint_names, tcp_limit(cell))
    gate = check_cell_trajectory(traj, cell, holding.checker)
    if not gate.ok:
        raise DriverRefused("recovery", f"the move back fails the gate: {gate.violations[0]}")
    label = f"recovery: {', '.join(off)} back to where the run goes on"
    report = {"merge": "none", "checks_passed": True, "duration_s": traj.duration}
    return CompiledSegment(Segment(step, label), "transit", traj, report)
