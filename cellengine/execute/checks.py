"""The checks every compiled piece must pass before it joins the program.

- the gate (:func:`~cellengine.motion.gate.check_cell_trajectory`): limits at 1 ms samples,
  collisions, the distance between the arms; given the cell's clearance, the clearance
  between the arms and to the environment (:mod:`~cellengine.motion.clearance`);
- a kept distance: the two fingertips (the arms' TCPs) at a constant distance, within
  ``KEEP_DISTANCE_TOLERANCE``, all along the timed motion (a taut cable between the hands).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from cellengine.arrays import Vec
from cellengine.execute.failure import FailedAt, Kind
from cellengine.execute.refused import Refused
from cellengine.motion.collision import CollisionChecker
from cellengine.motion.gate import SAMPLE_DT, GateReport, Violation, check_cell_trajectory
from cellengine.motion.robot import CellModel, tool_parts
from cellengine.motion.scene import CollisionScene, Pair, pair_key
from cellengine.motion.trajectory import Trajectory
from cellengine.program import Segment

KEEP_DISTANCE_TOLERANCE = 0.001  # m: the fingertips' distance may vary by this much
KEEP_DISTANCE_DT = 0.005  # s between the samples where it is measured


def gate(
    traj: Trajectory,
    cell: CellModel,
    checker: CollisionChecker,
    clearance: float | None = None,
    near: frozenset[Pair] = frozenset(),
    dt: float = SAMPLE_DT,
) -> GateReport:
    """The gate's report; Refused naming every violation when it fails (a clearance
    shortfall as it is: its message is already in plan terms)."""
    report = check_cell_trajectory(traj, cell, checker, clearance, near, dt)
    if not report.ok:
        unsafe = [str(v) for v in report.violations if v.kind != "clearance"]
        short = [str(v) for v in report.violations if v.kind == "clearance"]
        failed = ["the trajectory fails the gate: " + "; ".join(unsafe)] if unsafe else []
        raise Refused("; ".join(failed + short), at=_shown(traj, report.violations))
    return report


def near_pairs(cell: CellModel, scene: CollisionScene, segment: Segment) -> frozenset[Pair]:
    """The scene pairs of the segment's ``near``: the arm's tool parts and the object's
    shapes (an element of several boxes has ``name``, ``name#2``, ...)."""
    names = [o.name for o in scene.objects]
    out: set[Pair] = set()
    for arm, obj in segment.near:
        shapes = [n for n in names if n == obj or n.startswith(obj + "#")]
        if not shapes:
            raise ValueError(f"{segment.label}: near '{obj}', which the scene does not have")
        parts = tool_parts(cell.arms[arm])
        out |= {pair_key(p, s) for p in parts for s in shapes}
    return frozenset(out)


def _shown(traj: Trajectory, violations: Sequence[Violation]) -> FailedAt:
    """The violation the report shows: a collision first, then a clearance shortfall, then
    a limit; the cell's configuration at its time."""
    kinds: dict[str, Kind] = {"collision": "collision", "clearance": "clearance"}
    v = min(violations, key=lambda v: (list(kinds).index(v.kind) if v.kind in kinds else 2, v.time))
    q, _, _ = traj.sample(np.array([v.time]))
    return FailedAt(kinds.get(v.kind, "limit"), q[0], v.pair, v.time)


@dataclass(frozen=True)
class KeptDistance:
    distance: float  # m at the start
    deviation: float  # m: the largest change along the motion


def kept_distance(traj: Trajectory, cell: CellModel, arms: tuple[str, str]) -> KeptDistance:
    """The fingertips' distance along ``traj``; Refused when it changes by more than the
    tolerance."""
    t = np.append(np.arange(traj.start_time, traj.end_time, KEEP_DISTANCE_DT), traj.end_time)
    q, _, _ = traj.sample(t)
    d = tcp_distances(cell, q, arms)
    change = np.abs(d - d[0])
    worst = int(np.argmax(change))
    kept = KeptDistance(float(d[0]), float(change[worst]))
    if kept.deviation > KEEP_DISTANCE_TOLERANCE:
        a, b = arms
        raise Refused(
            f"the distance between the {a} and {b} fingertips must stay "
            f"{1000 * kept.distance:.1f} mm (within {1000 * KEEP_DISTANCE_TOLERANCE:g} mm) "
            f"but is {1000 * d[worst]:.1f} mm at t={t[worst]:.3f} s",
            at=FailedAt("limit", q[worst], time=float(t[worst])),
        )
    return kept


def tcp_distances(cell: CellModel, Q: Vec, arms: tuple[str, str]) -> Vec:
    """Distance between two arms' TCPs at each whole-cell state (k, nq)."""
    model, data = cell.model, cell.model.createData()
    a, b = (cell.tcp[arm] for arm in arms)
    out = np.empty(len(Q))
    for i, q in enumerate(Q):
        pin.forwardKinematics(model, data, q)
        pa = pin.updateFramePlacement(model, data, a).translation
        pb = pin.updateFramePlacement(model, data, b).translation
        out[i] = float(np.linalg.norm(pa - pb))
    return out
