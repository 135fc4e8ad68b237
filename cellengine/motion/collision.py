"""Collision checks on a :class:`CollisionScene`: one state, many states, the minimum distance,
and a straight joint-space segment with no collision slipping between samples.

Per state, pinocchio does forward kinematics, places every object and runs coal through a
broad phase (pinocchio's BroadPhaseManager) over the checked pairs, all in one C++ call: of the
~270 checked pairs in the cable-routing cell most are far apart, and their bounding boxes
reject them before any narrow-phase call (see BROAD_PHASE).

Segments, by conservative advancement with per-pair margins. ``scene.motion[p] @ |dq|`` bounds
how far any point of one object of pair p can move relative to the other over the whole
segment (each joint's radius: distance from its axis to the farthest point it moves). A check
at fraction t with pair p's security margin set to ``h * scene.motion[p] @ |dq|`` (coal reports
a pair closer than its margin) proves every state in [t, t + h] free when it passes: no point
moved further than the pair was apart. The step h doubles after a pass. After a failure, the
pair coal flagged is measured (d: its distance, or its convex bound's, a lower bound) and h
becomes 0.9 d / (motion bound of the pair): the largest step that pair allows. A pair closer
than ``clearance`` stops the segment: a collision, or a near miss (the resolution: nothing is
accepted closer than that; DEFAULT_CLEARANCE = 1 mm). So the step never falls below
0.9 clearance / (largest motion bound), and a short segment in free space passes in one check.

A checker preallocates pinocchio and coal data: not thread-safe; one per thread.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike, NDArray

from cellengine.arrays import Vec
from cellengine.motion.scene import CollisionScene, HeldObject, Pair, attach, detach

STEP_SAFETY = 0.9  # of the largest step a flagged pair's distance allows
STEP_GROWTH = 2.0  # after a passed step
# Measured on the cable-routing cell (31 objects, 272 pairs), per free state: the pair loop
# 215 us, a dynamic AABB tree 14 us, SSaP 12.5 us, all-pairs AABB tests ("naive") 7.6 us:
# with so few objects, testing every pair of boxes beats maintaining a tree.
BROAD_PHASE = pin.BroadPhaseManager_NaiveCollisionManager
DEFAULT_CLEARANCE = 1e-3  # m: check_segment refuses a segment passing closer than this
PATH_SLACK = 1e-5  # m: check_path's margins over the motion bound, room for GJK's tolerance
# distance's and apart's answers kept per checker (states): the cable skills measure the same
# pairs of IK solutions again for each way sharing a path (about a third of their calls);
# emptied when full
ANSWERS = 16384
# two owners of the objects measured between: arms, or None for the environment
Between = tuple[str | None, str | None]


def _owners(between: Between) -> tuple[str, ...]:
    """``between`` in one order, as a key."""
    return tuple(sorted("" if o is None else o for o in between))


@dataclass(frozen=True)
class Contact:
    """Two objects in contact (distance <= 0) or, from a segment check, closer than the
    clearance (distance > 0). ``t`` is the fraction along the segment, None for one state."""

    a: str
    b: str
    distance: float  # m; for a mesh element, the distance to its surface (0 when crossing it)
    q: Vec
    t: float | None = None

    @property
    def pair(self) -> Pair:
        return (self.a, self.b)

    def __str__(self) -> str:
        what = "collision" if self.distance <= 0 else f"{self.distance * 1000:.2f} mm apart"
        at = f" at t={self.t:.4f}" if self.t is not None else ""
        return f"{self.a} / {self.b}: {what}{at}"


class CollisionChecker:
    """Checks of the cell's q (all arms, ``scene.cell.joint_names`` order) against a scene."""

    def __init__(self, scene: CollisionScene) -> None:
        self._set_scene(scene)

    @property
    def scene(self) -> CollisionScene:
        return self._scene

    def attach(self, obj: HeldObject) -> None:
        """Hold ``obj`` at its arm's TCP from now on."""
        self._set_scene(attach(self._scene, obj))

    def detach(self, name: str) -> None:
        self._set_scene(detach(self._scene, name))

    def _set_scene(self, scene: CollisionScene) -> None:
        self._scene = scene
        model = scene.cell.model
        self._model, self._data = model, model.createData()
        self._nq = int(model.nq)
        # exact: margins 0; inflated: per-pair margins for segments, and the bounds'
        # distances there, built on the first segment check (each is MBs on a cell of a few
        # hundred pairs, and a checker of states only, a skill's reach tests, needs neither)
        self._exact = _Checked(model, scene.geometry)
        self._segments: tuple[_Checked, Any] | None = None
        self._selections: dict[tuple[str, ...] | None, tuple[Any, NDArray[np.bool_]]] = {}
        self._kept_apart: dict[tuple[tuple[str, str], float], _Checked] = {}
        self._n_pairs = len(scene.pairs)
        self._answers: dict[tuple[object, ...], Any] = {}  # distance's and apart's, by state

    # ------------------------------------------------------------------------------ states

    def in_collision(self, q: ArrayLike) -> bool:
        """True when any checked pair is in contact at q (the fast path)."""
        return bool(
            pin.computeCollisions(self._model, self._data, self._exact.manager, self._q(q), True)
        )

    def check(self, q: ArrayLike) -> Contact | None:
        """The first contact found at q, naming the two objects, or None."""
        qa = self._q(q)
        p = self._exact.first_hit(self._model, self._data, qa)
        if p is None:
            return None
        return self._contact(p, qa, None)

    def check_batch(self, Q: ArrayLike) -> NDArray[np.bool_]:
        """in_collision of each row of Q (n, nq)."""
        Qa = np.asarray(Q, dtype=float)
        if Qa.ndim != 2 or Qa.shape[1] != self._nq:
            raise ValueError(f"Q has shape {Qa.shape}, expected (n, {self._nq})")
        manager, model, data = self._exact.manager, self._model, self._data
        return np.fromiter(
            (pin.computeCollisions(model, data, manager, q, True) for q in Qa),
            dtype=bool,
            count=len(Qa),
        )

    def check_path(self, Q: ArrayLike) -> NDArray[np.bool_]:
        """check_batch's answers for states along a path (rows a small motion apart: a
        trajectory's samples), proved a run of rows at a time: a check of the run's first row
        with each pair's margin its motion bound to the farthest row of the run (the module's
        notes) clears them all. The run doubles after a pass; after a failure the first row
        is checked exactly and the runs start again from the next. ~2x faster than
        check_batch on the cable-routing plans' trajectories, where most runs pass."""
        Qa = np.asarray(Q, dtype=float)
        if Qa.ndim != 2 or Qa.shape[1] != self._nq:
            raise ValueError(f"Q has shape {Qa.shape}, expected (n, {self._nq})")
        out = np.zeros(len(Qa), dtype=bool)
        inflated, motion = self._for_segments()[0], self._scene.motion
        i, h = 0, 1
        while i < len(Qa):
            h = min(h, len(Qa) - i)
            if h == 1:
                out[i] = self._exact.first_hit(self._model, self._data, Qa[i]) is not None
                i, h = i + 1, 2
                continue
            moved = np.abs(Qa[i : i + h] - Qa[i]).max(axis=0)
            inflated.set_margins(motion @ moved + PATH_SLACK)
            if inflated.first_hit(self._model, self._data, Qa[i]) is None:
                i, h = i + h, 2 * h
            else:
                h = 1
        return out

    def distance(self, q: ArrayLike, between: Between | None = None) -> tuple[float, Pair]:
        """The minimum distance over the checked pairs at q and the pair at it; ``between``
        two arms: over the pairs with one object of each (links, and objects they hold; None:
        the environment).
        Negative when convex shapes overlap (their penetration depth); a mesh element's
        distance is to its surface. Mesh elements are first measured as their convex hulls (a
        lower bound, cheap), and only pairs whose bound is below the best exact distance are
        measured exactly. (inf, ("", "")) when no pair qualifies."""
        qa = self._q(q)
        key = (qa.tobytes(), None if between is None else _owners(between))
        out: tuple[float, Pair] = self._answer(key, lambda: self._distance(qa, between))
        return out

    def _distance(self, qa: Vec, between: Between | None) -> tuple[float, Pair]:
        scene = self._scene
        gdata, mask = self._selection(between)
        if not mask.any():
            return math.inf, ("", "")
        k = int(pin.computeDistances(self._model, self._data, scene.bounds, gdata, qa))
        if scene.exact_bounds[k]:
            return float(gdata.distanceResults[k].min_distance), scene.pair_names(k)
        return self._refined_distance(gdata, mask)

    def apart(self, q: ArrayLike, keep: float, between: tuple[str, str]) -> bool:
        """True when every pair with one object of each of two arms is at least ``keep`` (m)
        apart at q: a yes/no that stops at the first pair within it, ~4x cheaper than
        :meth:`distance` on the cable-routing cell (coal's security margin: no distance
        measured for a pair it proves farther)."""
        qa = self._q(q)
        a, b = sorted(between)
        free: bool = self._answer((qa.tobytes(), a, b, keep), lambda: self._apart(qa, (a, b), keep))
        return free

    def _apart(self, qa: Vec, arms: tuple[str, str], keep: float) -> bool:
        checked = self._kept_apart.get((arms, keep))
        if checked is None:
            mask = self._between(arms)
            checked = _Checked(self._model, self._scene.geometry, active=mask)
            checked.set_margins(np.where(mask, keep, 0.0))
            self._kept_apart[(arms, keep)] = checked
        return checked.first_hit(self._model, self._data, qa) is None

    def _answer(self, key: tuple[object, ...], compute: Callable[[], Any]) -> Any:
        """``compute()``, or its answer kept from the last time ``key`` was asked."""
        if key not in self._answers:
            if len(self._answers) >= ANSWERS:
                self._answers.clear()
            self._answers[key] = compute()
        return self._answers[key]

    def closer_than(self, q: ArrayLike, limits: Vec) -> dict[int, float]:
        """The checked pairs closer than their limit (m, one per pair) at q, each with its
        distance (a mesh element's exact one): convex bounds for every pair in one call, then
        the meshes whose bound is under their limit."""
        qa = self._q(q)
        scene = self._scene
        gdata, _ = self._selection(None)
        pin.computeDistances(self._model, self._data, scene.bounds, gdata, qa)
        bounds = np.fromiter(
            (r.min_distance for r in gdata.distanceResults), dtype=float, count=self._n_pairs
        )
        exact = self._exact
        pin.updateGeometryPlacements(self._model, self._data, scene.geometry, exact.data)
        out = {}
        for p in map(int, np.flatnonzero(bounds < limits)):
            d = float(bounds[p]) if scene.exact_bounds[p] else exact.distance(p)
            if d < limits[p]:
                out[p] = d
        return out

    def _selection(self, between: Between | None) -> tuple[Any, NDArray[np.bool_]]:
        """A GeometryData on the bounds model with only the selected pairs active (pinocchio
        skips inactive pairs), and the selection as a mask; made once per selection."""
        key = None if between is None else _owners(between)
        if key not in self._selections:
            mask = np.ones(self._n_pairs, dtype=bool) if between is None else self._between(between)
            gdata = pin.GeometryData(self._scene.bounds)
            for p in np.flatnonzero(~mask):
                gdata.deactivateCollisionPair(int(p))
            self._selections[key] = (gdata, mask)
        return self._selections[key]

    def _between(self, arms: Between) -> NDArray[np.bool_]:
        """Pairs with one object owned by each of two arms (None: the environment)."""
        for arm in arms:
            if arm is not None and arm not in self._scene.cell.arms:
                known = ", ".join(self._scene.cell.arms)
                raise ValueError(f"unknown arm '{arm}' (arms: {known})")
        owners = [o.owner for o in self._scene.objects]
        return np.array(
            [{owners[i], owners[j]} == set(arms) for i, j in self._scene.pairs], dtype=bool
        )

    def _refined_distance(self, gdata: Any, mask: NDArray[np.bool_]) -> tuple[float, Pair]:
        """After computeDistances on the bounds: measure inexact pairs on the exact model in
        increasing order of their lower bound, until no bound is below the best found."""
        scene = self._scene
        bounds = np.fromiter(
            (r.min_distance for r in gdata.distanceResults), dtype=float, count=self._n_pairs
        )
        bounds[~mask] = math.inf  # inactive pairs keep stale results
        exact = self._exact
        pin.updateGeometryPlacements(self._model, self._data, scene.geometry, exact.data)
        best, best_pair = math.inf, int(np.argmin(bounds))
        for p in np.argsort(bounds, kind="stable"):
            if bounds[p] >= best:
                break
            d = bounds[p] if scene.exact_bounds[p] else exact.distance(int(p))
            if d < best:
                best, best_pair = float(d), int(p)
        return best, scene.pair_names(best_pair)

    # ------------------------------------------------------------------------------ segments

    def check_segment(
        self,
        q0: ArrayLike,
        q1: ArrayLike,
        clearance: float | Vec = DEFAULT_CLEARANCE,
        margins: Vec | None = None,
    ) -> Contact | None:
        """None when every state on the straight joint-space segment q0 -> q1 is free (proved,
        not sampled: see the module's notes); else the first contact found, or the first state
        found closer than ``clearance`` (m; or one per checked pair). ``margins`` (m, one per
        checked pair): each pair must stay its margin apart, proved the same way (the margin
        added to every check's), and a pair found closer than its margin plus its clearance
        stops the segment."""
        near = np.broadcast_to(np.asarray(clearance, dtype=float), (self._n_pairs,))
        if np.any(near <= 0):
            raise ValueError("clearance must be greater than 0")
        qa, qb = self._q(q0), self._q(q1)
        dq = qb - qa
        motion = self._scene.motion @ np.abs(dq)  # (P,) m over the whole segment
        keep = np.zeros(self._n_pairs) if margins is None else np.asarray(margins, dtype=float)
        inflated = self._for_segments()[0]
        t, h = 0.0, 1.0
        while t < 1.0:
            h = min(h, 1.0 - t)
            q = qa + t * dq
            inflated.set_margins(keep + motion * h)
            p = inflated.first_hit(self._model, self._data, q)
            if p is None:
                t += h
                h *= STEP_GROWTH
                continue
            if t == 0.0 and h == 1.0:  # the start itself may be in collision: say so at once
                start = self._exact.first_hit(self._model, self._data, qa)
                if start is not None:
                    return self._contact(start, qa, 0.0)
            # The flagged pair is closer than its margin: the largest step it allows is its
            # room (distance less the margin to keep) over its motion bound (a hull's distance
            # is a lower bound: also safe).
            room = self._pair_distance(p, keep[p] + near[p]) - keep[p]
            if room <= near[p]:
                return self._contact(p, q, t)
            # below room / motion[p] < h: the pair passes next time (with room for GJK's
            # tolerance); the step never falls below 0.9 min(near) / max(motion): terminates
            h = STEP_SAFETY * room / motion[p]
        return None

    def _pair_distance(self, p: int, clearance: float) -> float:
        """Pair p's distance at the state of the last check: its convex bound's, or, when
        that is within ``clearance`` and the pair has a mesh, the exact one."""
        scene = self._scene
        bounds = self._for_segments()[1]
        pin.updateGeometryPlacements(self._model, self._data, scene.bounds, bounds)
        d = float(pin.computeDistance(scene.bounds, bounds, p).min_distance)
        if d > clearance or scene.exact_bounds[p]:
            return d
        exact = self._exact
        pin.updateGeometryPlacements(self._model, self._data, scene.geometry, exact.data)
        return exact.distance(p)

    def _for_segments(self) -> tuple[_Checked, Any]:
        """The inflated check and the bounds' GeometryData of segment checks."""
        if self._segments is None:
            scene = self._scene
            self._segments = (_Checked(self._model, scene.geometry), pin.GeometryData(scene.bounds))
        return self._segments

    # ------------------------------------------------------------------------------ helpers

    def _contact(self, p: int, q: Vec, t: float | None) -> Contact:
        """Contact of pair p at q, with the pair's exact distance."""
        scene, exact = self._scene, self._exact
        pin.framesForwardKinematics(self._model, self._data, q)
        pin.updateGeometryPlacements(self._model, self._data, scene.geometry, exact.data)
        a, b = scene.pair_names(p)
        return Contact(a, b, exact.distance(p), q.copy(), t)

    def _q(self, q: ArrayLike) -> Vec:
        qa = np.asarray(q, dtype=float)
        if qa.shape != (self._nq,):
            raise ValueError(f"q has shape {qa.shape}, expected ({self._nq},)")
        return qa


class Keeping:
    """A checker's states and segments with each checked pair kept its margin apart (m, one per
    pair; 0: touching is the only failure): a state with a pair closer than its margin is in
    collision, a segment passing closer is refused. What a transit plans with to keep the
    cell's clearance (:mod:`~cellengine.motion.margins`)."""

    def __init__(
        self, checker: CollisionChecker, margins: Vec, near: float | Vec = DEFAULT_CLEARANCE
    ) -> None:
        scene = checker.scene
        self.checker, self.margins = checker, np.asarray(margins, dtype=float)
        self.near = near  # check_segment's clearance: a pair within margin + near stops it
        self._model = scene.cell.model
        self._data = self._model.createData()
        self._within = _Checked(self._model, scene.geometry)
        self._within.set_margins(self.margins)

    def in_collision(self, q: ArrayLike) -> bool:
        """True when any checked pair is closer than its margin at q."""
        manager = self._within.manager
        qa = np.asarray(q, dtype=float)
        return bool(pin.computeCollisions(self._model, self._data, manager, qa, True))

    def check_segment(self, q0: ArrayLike, q1: ArrayLike) -> Contact | None:
        return self.checker.check_segment(q0, q1, self.near, self.margins)


class _Checked:
    """One GeometryData over the scene's pairs, with its broad-phase tree and a callback that
    records the first pair in contact."""

    def __init__(self, model: Any, geometry: Any, active: NDArray[np.bool_] | None = None) -> None:
        self.geometry = geometry
        self.data = pin.GeometryData(geometry)
        if active is not None:  # before the broad phase selects the pairs it checks
            for p in np.flatnonzero(~active):
                self.data.deactivateCollisionPair(int(p))
        self.manager = BROAD_PHASE(model, geometry, self.data)
        self.callback = pin.CollisionCallBackDefault(geometry, self.data, True)
        n = int(geometry.ngeoms)
        self._margins = np.zeros((n, n))
        self._rows = np.array([pair.first for pair in geometry.collisionPairs], dtype=int)
        self._cols = np.array([pair.second for pair in geometry.collisionPairs], dtype=int)

    def first_hit(self, model: Any, data: Any, q: Vec) -> int | None:
        """The index of a pair in contact (within its margin) at q, or None."""
        self.callback.init()
        if not pin.computeCollisions(model, data, self.manager, self.callback, q):
            return None
        return int(self.callback.collisionPairIndex)

    def set_margins(self, margins: Vec) -> None:
        self._margins[self._rows, self._cols] = margins
        self.data.setSecurityMargins(self.geometry, self._margins, True, True)

    def distance(self, p: int) -> float:
        """Pair p's distance at the placements already in ``data``."""
        return float(pin.computeDistance(self.geometry, self.data, p).min_distance)
