"""The clearance of a motion: how close the arms come to each other and to the environment.

Two figures per trajectory, each the least distance over its states with the pair at it:

- ``arms``: every object of one arm (links, tool, what it holds) against every object of
  another;
- ``environment``: every arm's objects against the environment (platform elements,
  obstacles, standing containers).

Pairs touched on purpose are left out: those the scene's allowed-collision matrix lets touch
because of the task (``held``: a held object and its gripper, or a held cable or connector
and the guides it goes into; ``contact``: the segment's declared contacts; ``user``,
``srdf``), those that never move relative to each other (``static``, ``stands_on``,
``same_body``, ``adjacent``), and ``never``: an arm's own pairs, and what its first joint
alone moves (a UR's shoulder, 5 mm over the table it stands on) against the environment,
where the distance is the cell's layout, the same in every plan. Pairs out of each other's
reach (``out_of_reach``: they cannot collide) may still pass close, so they are measured.

Where: at every ``MEASURE_EVERY``-th of the gate's 1 ms samples (10 ms), then at the 1 ms
samples between the closest one's neighbours for its pair: measuring every pair at every 1 ms
sample costs ~0.15 ms per state on the cable-routing cell (meshes are slow in coal), 5 s for
the four-guide plan's 36 000 states. The least at 10 ms samples is within 5 ms of motion of
the least at 1 ms, and the 1 ms pass around it finds that one when both lie in the same dip
(tests/execute/test_clearance.py checks it against every 1 ms sample).

How: per kind, the states in a fixed shuffled order; a collision check on the exact shapes
with every pair's security margin at the least distance found so far (through the broad
phase, ~13 us) rules out a state where no pair is closer, and a state it lets through is
measured: convex bounds (meshes' hulls) in one call, then the meshes whose bound is below the
least exact distance. In a shuffled order the least distance falls fast (a state is a new
least with probability 1/k at the k-th), so few states are measured.

A model holds pinocchio and coal data: not thread-safe (like the checker).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from itertools import combinations
from typing import Any, Literal

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from cellengine.arrays import Vec
from cellengine.motion.collision import _Checked
from cellengine.motion.scene import CollisionScene, Pair, SceneObject, pair_key

MEASURE_EVERY = 10  # gate samples (1 ms) between measured states: 10 ms
RESOLUTION = 1e-6  # m: a state closer by less than this is not measured again
# ACM reasons of pairs that may come close without touching on purpose: they are measured
MEASURED_REASONS = frozenset({"out_of_reach"})

Kind = Literal["arms", "environment"]
KINDS: tuple[Kind, ...] = ("arms", "environment")


@dataclass(frozen=True)
class Closest:
    distance: float  # m; negative: convex shapes overlapping
    pair: Pair  # two arms: sorted; the environment: the arm's object first
    time: float  # s, on the trajectory's time axis
    arm: str  # the arm of the pair's first object (environment: the arm passing it)

    def figures(self) -> dict[str, Any]:
        return {"distance_m": self.distance, "pair": list(self.pair), "time_s": self.time}


@dataclass(frozen=True)
class Clearance:
    """The least distance of each kind; None where a kind has no pair (one arm: no arms)."""

    arms: Closest | None
    environment: Closest | None

    def figures(self) -> dict[str, dict[str, Any] | None]:
        """report.json's ``clearance`` of a segment."""
        return {k: None if c is None else c.figures() for k, c in self.items()}

    def items(self) -> tuple[tuple[Kind, Closest | None], ...]:
        return (("arms", self.arms), ("environment", self.environment))

    def shortfalls(self, clearance: float) -> list[tuple[Closest, str]]:
        """Each figure under ``clearance`` (m) with what it means, in plan terms."""
        out = []
        for kind, c in self.items():
            if c is None or c.distance >= clearance:
                continue
            a, b = c.pair
            where = "the arms pass" if kind == "arms" else f"the {c.arm} arm passes"
            apart = "apart" if kind == "arms" else "from the environment"
            out.append(
                (
                    c,
                    f"{where} {c.distance * 1000:.1f} mm {apart} ({a}, {b}) at t = {c.time:.1f} s; "
                    f"the cell's clearance is {clearance * 1000:g} mm",
                )
            )
        return out


def least(clearances: list[Clearance]) -> Clearance:
    """The least of each kind over several (a segment's parts)."""

    def pick(kind: Kind) -> Closest | None:
        found = [c for cl in clearances for k, c in cl.items() if k == kind and c is not None]
        return min(found, key=lambda c: c.distance, default=None)

    return Clearance(pick("arms"), pick("environment"))


def measure(
    scene: CollisionScene, t: Vec, Q: Vec, near: frozenset[Pair] = frozenset()
) -> Clearance:
    """The clearance of the states Q (n, nq) at times t (the gate's 1 ms samples); ``near``:
    pairs (object names, :func:`pair_key` order) the motion works closer than the clearance
    on purpose, left out."""
    model = _model(scene)
    return model.measure(np.asarray(t, dtype=float), np.asarray(Q, dtype=float), near)


def _model(scene: CollisionScene) -> ClearanceModel:
    """One model per scene, kept on the scene (a compile comes back to the same held states
    again and again); the pairs left out are switched off in it for each measurement. (A
    model per set of pairs left out was ~17 KB per pair each: 1.4 GB of models on a board
    of 200 guides, issue 19.)"""
    model = scene.clearance_model
    if model is None:
        model = ClearanceModel(scene)
        object.__setattr__(scene, "clearance_model", model)
    out: ClearanceModel = model
    return out


class ClearanceModel:
    """The measured pairs of one scene, one :class:`_Pairs` per kind."""

    def __init__(self, scene: CollisionScene) -> None:
        pairs, kinds = measured_pairs(scene)
        self.kinds = {
            k: _Pairs(scene, [p for p, x in zip(pairs, kinds, strict=True) if x == k])
            for k in KINDS
        }

    def measure(self, t: Vec, Q: Vec, near: frozenset[Pair] = frozenset()) -> Clearance:
        """The least distances of the states Q at times t, the pairs ``near`` left out."""
        coarse = np.unique(np.append(np.arange(0, len(Q), MEASURE_EVERY), len(Q) - 1))
        out = []
        for k in KINDS:
            pairs = self.kinds[k]
            pairs.leave_out(near)
            out.append(pairs.closest(t, Q, coarse))
        return Clearance(*out)


class _Pairs:
    """Some pairs of a scene's objects, on copies of its two geometry models, with a broad
    phase that rules out a state where no pair is within the least distance found so far."""

    def __init__(self, scene: CollisionScene, pairs: list[tuple[int, int]]) -> None:
        self.objects, self.pairs = scene.objects, pairs
        exact = {s.name: s.exact for s in scene.statics}
        self.exact = [
            exact.get(self.objects[i].name, True) and exact.get(self.objects[j].name, True)
            for i, j in pairs
        ]
        self.model = scene.cell.model
        self.data = self.model.createData()
        self.geometry, self.bounds = (_with_pairs(m, pairs) for m in (scene.geometry, scene.bounds))
        self.gdata, self.bdata = pin.GeometryData(self.geometry), pin.GeometryData(self.bounds)
        self.within = _Checked(self.model, self.geometry)  # margins: the least distance so far
        self.names = [pair_key(self.objects[i].name, self.objects[j].name) for i, j in pairs]
        self.active = np.ones(len(pairs), dtype=bool)  # measured now (leave_out)

    def leave_out(self, near: frozenset[Pair]) -> None:
        """Measure every pair but those named in ``near`` from now on: pinocchio skips an
        inactive pair in the broad phase's check and in computeDistances."""
        active = np.array([n not in near for n in self.names], dtype=bool)
        for p in map(int, np.flatnonzero(active != self.active)):
            for data in (self.within.data, self.bdata):
                if active[p]:
                    data.activateCollisionPair(p)
                else:
                    data.deactivateCollisionPair(p)
        self.active = active

    def closest(self, t: Vec, Q: Vec, coarse: NDArray[np.intp]) -> Closest | None:
        """The least distance at the coarse states, then at the 1 ms states between the
        closest one's neighbours for its pair."""
        if not self.active.any():
            return None
        d, p, i = self._least(Q, coarse)
        k = int(np.searchsorted(coarse, i))
        lo, hi = int(coarse[max(k - 1, 0)]), int(coarse[min(k + 1, len(coarse) - 1)])
        for j in range(lo + 1, hi):
            pin.updateGeometryPlacements(self.model, self.data, self.geometry, self.gdata, Q[j])
            dj = float(pin.computeDistance(self.geometry, self.gdata, p).min_distance)
            if dj < d:
                d, i = dj, j
        a, b = (self.objects[n] for n in self.pairs[p])
        if a.owner is None:  # the environment: the arm's object first
            a, b = b, a
        pair = pair_key(a.name, b.name) if b.owner is not None else (a.name, b.name)
        return Closest(d, pair, float(t[i]), str(a.owner))

    def _least(self, Q: Vec, states: NDArray[np.intp]) -> tuple[float, int, int]:
        """(distance, pair, state): states in a fixed shuffled order, so the least distance
        found falls fast and the broad phase rules most states out; a state it lets through
        is measured."""
        order = np.random.default_rng(0).permutation(states)
        best = (math.inf, -1, -1)
        for i in map(int, order):
            if best[1] >= 0 and self.within.first_hit(self.model, self.data, Q[i]) is None:
                continue  # no pair closer than the least distance so far
            d, p = self._distance(Q[i])
            if d < best[0]:
                best = (d, p, i)
                # not d: a state as close (an arm standing still) is no news
                self.within.set_margins(np.full(len(self.pairs), d - RESOLUTION))
        return best

    def _distance(self, q: Vec) -> tuple[float, int]:
        """The least distance at q and its pair: the convex bounds in one call, then the
        meshes whose bound is below the least exact distance, lowest first."""
        k = int(pin.computeDistances(self.model, self.data, self.bounds, self.bdata, q))
        results = self.bdata.distanceResults
        if self.exact[k]:
            return float(results[k].min_distance), k
        bounds = np.fromiter((r.min_distance for r in results), float, len(self.pairs))
        bounds[~self.active] = math.inf  # inactive pairs keep stale results
        pin.updateGeometryPlacements(self.model, self.data, self.geometry, self.gdata)
        best = (math.inf, k)
        for p in map(int, np.argsort(bounds, kind="stable")):
            if bounds[p] >= best[0]:
                break
            d = bounds[p] if self.exact[p] else self._exact(p)
            if d < best[0]:
                best = (float(d), p)
        return best

    def _exact(self, p: int) -> float:
        return float(pin.computeDistance(self.geometry, self.gdata, p).min_distance)


def pair_distances(scene: CollisionScene, pair: Pair, Q: Vec) -> Vec:
    """The distance of one pair (object names, either order) at each state of Q (k, nq)."""
    index = {o.name: n for n, o in enumerate(scene.objects)}
    i, j = sorted((index[pair[0]], index[pair[1]]))
    p = _Pairs(scene, [(i, j)])
    return np.array([p._distance(q)[0] for q in np.asarray(Q, dtype=float)])


def measured_pairs(
    scene: CollisionScene, near: frozenset[Pair] = frozenset()
) -> tuple[list[tuple[int, int]], list[Kind]]:
    """The pairs measured (object ids) and the kind of each; ``near`` left out."""
    pairs: list[tuple[int, int]] = []
    kinds: list[Kind] = []
    for i, j in combinations(range(len(scene.objects)), 2):
        a, b = scene.objects[i], scene.objects[j]
        kind = _kind(a, b)
        why = scene.acm.reason(a.name, b.name)
        if kind is None or (why is not None and why.split(" ")[0] not in MEASURED_REASONS):
            continue
        if pair_key(a.name, b.name) in near:
            continue
        pairs.append((i, j))
        kinds.append(kind)
    return pairs, kinds


def _kind(a: SceneObject, b: SceneObject) -> Kind | None:
    if a.owner is not None and b.owner is not None:
        return "arms" if a.owner != b.owner else None
    return "environment" if (a.owner is None) != (b.owner is None) else None


def _with_pairs(geometry: Any, pairs: list[tuple[int, int]]) -> Any:
    out = geometry.copy()
    out.removeAllCollisionPairs()
    for i, j in pairs:
        out.addCollisionPair(pin.CollisionPair(i, j))
    return out
