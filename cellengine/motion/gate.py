"""The trajectory gate: the last check before anything reaches a driver.

A trajectory passes when, sampled every millisecond, its times strictly increase, every
value is finite, every joint stays within its position, velocity and acceleration limits,
and no sampled state collides. Each violation names the joint or the pair of objects, the
time and the value; the minimum distance between the arms is reported either way. Given the
cell's clearance, the whole cell's gate also measures the arms' clearance (clearance.py) and
refuses a trajectory passing closer than it, but for a pair that is leaving: closest where
the motion starts (the step before worked there on purpose) and farther where it ends.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from cellengine.arrays import Vec
from cellengine.motion.clearance import Clearance, Closest, measure, pair_distances
from cellengine.motion.robot import CellModel, Limits
from cellengine.motion.scene import CollisionScene, Pair, pair_key
from cellengine.motion.trajectory import Trajectory

SAMPLE_DT = 0.001  # seconds between checked samples
TOLERANCE = 1e-6  # relative slack on limits, for rounding in the producers
DISTANCE_EVERY = 10  # the arms' minimum distance is computed on every 10th sample
# A pair closer than the clearance where the motion starts, never closer after it and farther
# at its end, is leaving (within this, m); so many such pairs per trajectory at most
LEAVING_TOLERANCE = 1e-4
MAX_LEAVING = 4


class Checker(Protocol):
    def check_batch(self, Q: Vec) -> NDArray[np.bool_]: ...
    def check(self, q: Vec) -> object | None: ...  # a contact naming the pair, or None


Distance = tuple[float, tuple[str, str]]


class ArmDistance(Protocol):
    def __call__(self, q: Vec) -> Distance: ...


@dataclass(frozen=True)
class Violation:
    kind: str  # finite | position | velocity | acceleration | collision | clearance
    time: float
    what: str  # the joint, or the colliding pair
    value: float | None = None
    limit: float | None = None
    pair: tuple[str, str] | None = None  # collision, clearance: the two objects' names

    def __str__(self) -> str:
        at = f"t={self.time:.3f} s"
        if self.kind == "collision":
            return f"{at}: collision between {self.what}"
        if self.kind == "clearance":
            return self.what  # said in full, time included
        if self.kind == "finite":
            return f"{at}: {self.what}"
        unit = {"position": "", "velocity": "/s", "acceleration": "/s^2"}[self.kind]
        return (
            f"{at}: {self.what} {self.kind} {self.value:.6g}{unit} outside the limit "
            f"{self.limit:.6g}{unit}"
        )


@dataclass(frozen=True)
class GateReport:
    violations: tuple[Violation, ...]
    samples: int
    min_arm_distance: float | None = None
    closest_pair: tuple[str, str] | None = None
    clearance: Clearance | None = None

    @property
    def ok(self) -> bool:
        return not self.violations


def check_trajectory(
    traj: Trajectory,
    joint_names: Sequence[str],
    limits: Limits,
    checker: Checker | None = None,
    arm_distance: ArmDistance | None = None,
    dt: float = SAMPLE_DT,
) -> GateReport:
    """Check ``traj`` whose joints must be ``joint_names`` (the model's order)."""
    t, q, violations = _sampled(traj, joint_names, limits, checker, dt)
    d, pair = _arm_distance(q, arm_distance)
    return GateReport(tuple(violations), len(t), d, pair)


def _sampled(
    traj: Trajectory,
    joint_names: Sequence[str],
    limits: Limits,
    checker: Checker | None,
    dt: float,
) -> tuple[Vec, Vec, list[Violation]]:
    """The sample times and states, and the violations found at them."""
    if tuple(traj.joint_names) != tuple(joint_names):
        raise ValueError(
            f"trajectory joints {list(traj.joint_names)} differ from the model's "
            f"{list(joint_names)}"
        )
    # A Trajectory cannot be built with times that do not increase or values that are not
    # finite; what is checked here is what its samples show.
    t = _sample_times(traj, dt)
    q, qd, qdd = traj.sample(t)
    violations = _finite(t, q, qd, qdd) or _limits(t, q, qd, qdd, joint_names, limits)
    if checker is not None:
        violations += _collisions(t, q, checker)
    return t, q, violations


def _finite(t: Vec, q: Vec, qd: Vec, qdd: Vec) -> list[Violation]:
    bad = ~(np.isfinite(q) & np.isfinite(qd) & np.isfinite(qdd)).all(axis=1)
    if not bad.any():
        return []
    i = int(np.argmax(bad))
    return [Violation("finite", float(t[i]), "a sampled value is not a finite number")]


def _sample_times(traj: Trajectory, dt: float) -> Vec:
    t = np.arange(traj.start_time, traj.end_time, dt)
    return np.append(t, traj.end_time)  # the last knot is always checked


def _limits(
    t: Vec, q: Vec, qd: Vec, qdd: Vec, names: Sequence[str], limits: Limits
) -> list[Violation]:
    """The first violation of each kind for each joint (not one per sample)."""
    out = []
    lo, hi = np.asarray(limits.lower), np.asarray(limits.upper)
    slack = TOLERANCE * np.maximum(1.0, np.abs(hi - lo))
    checks = (
        ("position", q, np.maximum(lo - q - slack, q - hi - slack), None),
        (
            "velocity",
            qd,
            np.abs(qd) - np.asarray(limits.velocity) * (1 + TOLERANCE),
            limits.velocity,
        ),
        (
            "acceleration",
            qdd,
            np.abs(qdd) - np.asarray(limits.acceleration) * (1 + TOLERANCE),
            limits.acceleration,
        ),
    )
    for kind, values, excess, bound in checks:
        for j in map(int, np.flatnonzero((excess > 0).any(axis=0))):
            i = int(np.argmax(excess[:, j] > 0))
            v = float(values[i, j])
            limit = (
                float(np.asarray(bound)[j])
                if bound is not None
                else (float(lo[j]) if v < lo[j] else float(hi[j]))
            )
            out.append(Violation(kind, float(t[i]), names[j], v, limit))
    return out


def _collisions(t: Vec, q: Vec, checker: Checker) -> list[Violation]:
    colliding = np.flatnonzero(checker.check_batch(q))
    if len(colliding) == 0:
        return []
    i = int(colliding[0])
    contact = checker.check(q[i])
    what = str(contact) if contact else "unknown objects"
    pair = getattr(contact, "pair", None)
    return [Violation("collision", float(t[i]), what, pair=None if pair is None else tuple(pair))]


def _arm_distance(
    q: Vec, arm_distance: ArmDistance | None
) -> tuple[float | None, tuple[str, str] | None]:
    if arm_distance is None or len(q) == 0:
        return None, None
    best: Distance | None = None
    for row in (*q[::DISTANCE_EVERY], q[-1]):
        d = arm_distance(row)
        if best is None or d[0] < best[0]:
            best = d
    assert best is not None
    return best


class CellChecker(Checker, Protocol):
    def check_path(self, Q: Vec) -> NDArray[np.bool_]: ...  # check_batch of a path's states
    def distance(self, q: Vec, between: tuple[str, str] | None = None) -> Distance: ...

    @property
    def scene(self) -> CollisionScene: ...


def _leaving(scene: CollisionScene, c: Closest, t: Vec, q: Vec) -> bool:
    """Whether the pair of ``c`` is at its closest where the motion starts and ends farther:
    a motion leaving where the step before worked closer than the clearance on purpose (a
    hand letting go of a cable by a guide) is held to the distance it starts at."""
    d = pair_distances(scene, c.pair, q[[0, -1]])
    return bool(c.distance >= d[0] - LEAVING_TOLERANCE and d[1] > d[0] + LEAVING_TOLERANCE)


def check_cell_trajectory(
    traj: Trajectory,
    cell: CellModel,
    checker: CellChecker,
    clearance: float | None = None,
    near: frozenset[Pair] = frozenset(),
    dt: float = SAMPLE_DT,
) -> GateReport:
    """The gate for a whole cell: its joint order and limits, its collision checker, and the
    minimum distance between its two arms (when it has two). Given ``clearance`` (m), the
    trajectory's clearance is measured instead (the arms' distance is then its ``arms``) and a
    trajectory passing closer than it is refused; ``near``: pairs the motion works closer than
    that on purpose, not measured. ``dt``: between the samples checked (a scheduler trying
    many starts looks coarser first; what is sent is checked at the default)."""
    if clearance is not None:
        return _with_clearance(traj, cell, checker, clearance, near, dt)
    arms = tuple(cell.arms)
    distance: ArmDistance | None = None
    if len(arms) == 2:
        between = (arms[0], arms[1])

        def distance(q: Vec) -> Distance:
            return checker.distance(q, between)

    return check_trajectory(traj, cell.joint_names, cell.limits, _OnPath(checker), distance, dt)


@dataclass(frozen=True)
class _OnPath:
    """A cell checker checking the gate's samples as the path they are (check_path)."""

    checker: CellChecker

    def check_batch(self, Q: Vec) -> NDArray[np.bool_]:
        return self.checker.check_path(Q)

    def check(self, q: Vec) -> object | None:
        return self.checker.check(q)


def _with_clearance(
    traj: Trajectory,
    cell: CellModel,
    checker: CellChecker,
    clearance: float,
    near: frozenset[Pair],
    dt: float,
) -> GateReport:
    t, q, violations = _sampled(traj, cell.joint_names, cell.limits, _OnPath(checker), dt)
    measured = measure(checker.scene, t, q, near)
    found = measured
    for _ in range(MAX_LEAVING):
        leaving = [c for c, _ in found.shortfalls(clearance) if _leaving(checker.scene, c, t, q)]
        if not leaving:
            break
        near = near | {pair_key(*c.pair) for c in leaving}
        found = measure(checker.scene, t, q, near)
    short = [
        Violation("clearance", c.time, why, c.distance, clearance, c.pair)
        for c, why in found.shortfalls(clearance)
    ]
    arms = measured.arms
    return GateReport(
        (*violations, *short),
        len(t),
        None if arms is None else arms.distance,
        None if arms is None else arms.pair,
        measured,
    )
