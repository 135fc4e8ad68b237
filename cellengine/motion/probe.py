"""How far an arm's tool would be from the environment with its TCP at a pose: a check a skill
makes on its candidate poses before anything is planned (no inverse kinematics, no arm links).

The tool's solids are the arm's own (cell.yaml's ``tools.<name>`` shape, mesh or stand-in box),
the fingers at the jaw mode's opening. Distances come from coal on the exact shapes; a
bounding-sphere test skips pairs that cannot be within the distance asked about.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Collection, Sequence
from dataclasses import dataclass
from typing import Any

import coal
import numpy as np
from numpy.typing import NDArray

from cellengine import geometry as g
from cellengine.arrays import Mat, Vec
from cellengine.motion.robot import Arm, CellModel, finger_placements
from cellengine.motion.scene import CollisionScene
from cellengine.motion.tool import is_tool


@dataclass(frozen=True)
class _Solid:
    name: str
    T: Mat  # a tool's solid: in the TCP frame; the environment's: in the cell frame
    shape: Any
    centre: Vec  # of its bounding sphere, in its own frame
    radius: float
    half: Vec  # its bounding box's half-extents about centre, along its own axes
    # its bounding capsule, in its own frame: the segment centre +- axis (the box's longest
    # half-extent) and the radius girth about it (a finger 90 mm long is not a 90 mm ball)
    axis: Vec
    girth: float
    placed: Any  # T as coal's transform (built once: a probe measures a static many times)


@dataclass(frozen=True)
class Nearest:
    distance: float  # m; negative: overlapping (coal's penetration estimate)
    tool: str  # the tool's solid, e.g. 'left/tool/finger_left'
    other: str  # the environment object


class ToolProbe:
    """The environment of a scene (its statics) against the arms' tools at given TCP poses.
    Holds coal objects: not thread-safe, like the checker."""

    def __init__(self, cell: CellModel, scene: CollisionScene) -> None:
        self.cell = cell
        self.statics = [
            _solid(s.name, np.asarray(s.T_cell_shape, dtype=float), s.shape) for s in scene.statics
        ]
        self._tools: dict[tuple[str, float | None], list[_Solid]] = {}
        # Skills ask again about the same paths (RouteCable's ways share their inserts).
        self._asked: dict[tuple[object, ...], Nearest | None] = {}
        self._found: dict[tuple[object, ...], Nearest | None] = {}  # comes_within's

    def nearest(
        self,
        arm: str,
        poses: Sequence[Mat],
        mode: str | None = None,
        skip: Collection[str] = (),
        within: float = math.inf,
        only: Collection[str] | None = None,
    ) -> Nearest | None:
        """The closest environment object to ``arm``'s tool over ``poses`` (T_cell_tcp), its
        fingers at jaw ``mode``'s opening (None: the widest); objects named in ``skip`` (or
        their parts ``name#k``) left out, and with ``only`` every object it does not name;
        only pairs closer than ``within`` (m) are measured, None when none is."""
        return self._ask(arm, poses, mode, skip, within, only, False)

    def comes_within(
        self,
        arm: str,
        poses: Sequence[Mat],
        mode: str | None,
        skip: Collection[str],
        within: float,
        only: Collection[str] | None = None,
    ) -> bool:
        """Whether :meth:`nearest` finds an object: its pairs measured in the same order, up
        to the first closer than ``within`` (a third of the measuring, when one is)."""
        return self._ask(arm, poses, mode, skip, within, only, True) is not None

    def _ask(
        self,
        arm: str,
        poses: Sequence[Mat],
        mode: str | None,
        skip: Collection[str],
        within: float,
        only: Collection[str] | None,
        first: bool,
    ) -> Nearest | None:
        if only is not None:
            skip = {*skip, *(s.name for s in self.statics if s.name.split("#")[0] not in only)}
        # poses to 0.1 um and 1e-7 rad: the same path computed along another way's arcs
        digest = hashlib.sha1(np.round(np.asarray(poses, dtype=float), 7).tobytes()).digest()
        key = (arm, mode, frozenset(skip), within, digest)
        if key in self._asked:  # the nearest itself answers both
            return self._asked[key]
        if not first:
            self._asked[key] = self._nearest(arm, poses, mode, skip, within, False)
            return self._asked[key]
        if key not in self._found:
            self._found[key] = self._nearest(arm, poses, mode, skip, within, True)
        return self._found[key]

    def _nearest(
        self,
        arm: str,
        poses: Sequence[Mat],
        mode: str | None,
        skip: Collection[str],
        within: float,
        first: bool,
    ) -> Nearest | None:
        """The nearest pair closer than ``within``; ``first``: the first found instead."""
        tool = self._tool(arm, mode)
        statics = [
            s for s in self.statics if s.name not in skip and s.name.split("#")[0] not in skip
        ]
        if not statics or not tool or len(poses) == 0:
            return None
        # every (pose, static, tool solid)'s bound (_bounds), then coal on the pairs in the
        # order of their bounds, until no bound is below the nearest found
        P = np.asarray(poses, dtype=float).reshape(-1, 4, 4)
        bound = _bounds(P, tool, statics)
        near = np.argwhere(bound < within)  # (pose, static, solid), in the loops' order
        best: Nearest | None = None
        limit, earliest = within, (len(P), 0, 0)
        request, result = coal.DistanceRequest(), coal.DistanceResult()
        bounds = bound[tuple(near.T)]
        order = np.argsort(bounds, kind="stable")
        placed: dict[tuple[int, int], Any] = {}  # a tool solid at a pose, for every static
        for (i, k, m), b in zip(near[order].tolist(), bounds[order].tolist(), strict=True):
            if b > limit:
                break
            s, t = statics[k], tool[m]
            if (i, m) not in placed:
                placed[i, m] = _transform(P[i] @ t.T)
            result.clear()
            d = float(coal.distance(t.shape, placed[i, m], s.shape, s.placed, request, result))
            # ties: the first in pose, static, solid order, as looping over them would give
            if d < limit or (d == limit and best is not None and (i, k, m) < earliest):
                limit, earliest = d, (i, k, m)
                best = Nearest(d, t.name, s.name)
                if first:
                    break
        return best

    def under(self, level: float, up: Vec) -> frozenset[str]:
        """The environment objects (names without ``#k``) wholly below ``level`` (m, along
        ``up``): the surfaces something held at that level lies over."""
        tops: dict[str, float] = {}
        for s in self.statics:
            box = s.shape.aabb_local
            lo, hi = np.asarray(box.min_), np.asarray(box.max_)
            corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])
                                for z in (lo[2], hi[2])])  # fmt: skip
            top = float(((corners @ s.T[:3, :3].T + s.T[:3, 3]) @ up).max())
            name = s.name.split("#")[0]
            tops[name] = max(tops.get(name, -math.inf), top)
        return frozenset(name for name, top in tops.items() if top < level)

    def between(
        self,
        arm: str,
        poses: Sequence[Mat],
        mode: str | None,
        other: str,
        T_cell_other: Mat,
        other_mode: str | None,
    ) -> Nearest | None:
        """The closest pair of solids of ``arm``'s tool over ``poses`` and ``other``'s tool
        held at ``T_cell_other`` (both T_cell_tcp, fingers at their modes), None when no
        pair is nearer than 1 m."""
        mine, theirs = self._tool(arm, mode), self._tool(other, other_mode)
        best: Nearest | None = None
        limit = 1.0
        request, result = coal.DistanceRequest(), coal.DistanceResult()
        placed = [(s, T_cell_other @ s.T) for s in theirs]
        for T_cell_tcp in poses:
            for t in mine:
                T = T_cell_tcp @ t.T
                for s, T_s in placed:
                    result.clear()
                    d = coal.distance(
                        t.shape, _transform(T), s.shape, _transform(T_s), request, result
                    )
                    if d < limit:
                        limit = float(d)
                        best = Nearest(float(d), t.name, s.name)
        return best

    def _tool(self, arm: str, mode: str | None) -> list[_Solid]:
        a = self.cell.arms[arm]
        opening = None if a.fingers is None or mode is None else a.fingers.opening(mode)
        key = (arm, opening)
        if key not in self._tools:
            self._tools[key] = _tool_solids(a, opening)
        return self._tools[key]


def _tool_solids(arm: Arm, opening: float | None) -> list[_Solid]:
    """The tool's solids in the TCP frame; the fingers at ``opening`` (None: as the arm's
    model holds them, at the widest)."""
    T_joint_tcp = np.asarray(arm.model.frames[arm.tcp].placement.homogeneous)
    T_tcp_joint = g.inverse(T_joint_tcp)
    fingers = finger_placements(arm, opening) if opening is not None else {}
    out = []
    for o in arm.collision.geometryObjects:
        if not is_tool(o.name, arm.name):
            continue
        placement = fingers.get(o.name, o.placement)
        out.append(_solid(o.name, T_tcp_joint @ np.asarray(placement.homogeneous), o.geometry))
    return out


def _bounds(
    P: NDArray[np.float64], tool: Sequence[_Solid], statics: Sequence[_Solid]
) -> NDArray[np.float64]:
    """(pose, static, tool solid): a lower bound on their distance with the tool at each of
    the TCP poses ``P`` (n, 4, 4), the largest of three: the two bounding spheres; the tool
    solid's capsule and the static's sphere; the tool solid's sphere and the static's box."""
    R_t = np.array([t.T[:3, :3] for t in tool])
    c_tcp = np.einsum("mij,mj->mi", R_t, [t.centre for t in tool]) + [t.T[:3, 3] for t in tool]
    u_tcp = np.einsum("mij,mj->mi", R_t, [t.axis for t in tool])
    c_t = np.einsum("nij,mj->nmi", P[:, :3, :3], c_tcp) + P[:, None, :3, 3]  # (n, m, 3)
    u_t = np.einsum("nij,mj->nmi", P[:, :3, :3], u_tcp)
    c_s = np.array([s.T[:3, :3] @ s.centre + s.T[:3, 3] for s in statics])  # (k, 3)
    r_s = np.array([s.radius for s in statics])[None, :, None]
    d = c_s[None, :, None, :] - c_t[:, None, :, :]  # (n, k, m, 3)
    spheres = np.linalg.norm(d, axis=-1) - r_s - [t.radius for t in tool]
    u = u_t[:, None, :, :]
    uu = np.maximum(np.einsum("nkmi,nkmi->nkm", u, u), 1e-18)  # a cube's axis may be 0
    along = np.clip(np.einsum("nkmi,nkmi->nkm", d, u) / uu, -1.0, 1.0)
    off = np.linalg.norm(d - along[..., None] * u, axis=-1)
    capsules = off - r_s - [t.girth for t in tool]
    # the tool solid's sphere against the static's box (a board's sphere is as wide as it is)
    R_s = np.array([s.T[:3, :3] for s in statics])
    local = np.einsum("kji,nkmj->nkmi", R_s, -d)  # from the box's centre, in its frame
    half = np.array([s.half for s in statics])[None, :, None, :]
    box = np.linalg.norm(local - np.clip(local, -half, half), axis=-1) - [t.radius for t in tool]
    out: NDArray[np.float64] = np.maximum(np.maximum(spheres, capsules), box)
    return out


def _solid(name: str, T: Mat, shape: Any) -> _Solid:
    shape.computeLocalAABB()
    box = shape.aabb_local
    lo, hi = np.asarray(box.min_), np.asarray(box.max_)
    radius = float(np.linalg.norm(hi - lo)) / 2.0
    half = (hi - lo) / 2.0
    longest = int(np.argmax(half))
    axis = np.zeros(3)
    axis[longest] = half[longest]
    girth = float(np.linalg.norm(np.delete(half, longest)))
    return _Solid(name, T, shape, (lo + hi) / 2.0, radius, half, axis, girth, _transform(T))


def _transform(T: Mat) -> Any:
    return coal.Transform3s(np.ascontiguousarray(T[:3, :3]), np.ascontiguousarray(T[:3, 3]))
