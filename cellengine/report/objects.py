"""The lab objects report.html draws: each container (objects.yaml, with an ``at``) as the
shape the page draws for arm links (a cylinder by its axis' two ends, a box by its centre and
half-axes), per sample, carried by the gripper that holds it; and the cell's zones as boxes.

A container stands at its ``at`` keypoint (the centre of its base, z up) until a gripper event
says an arm holds it; from then on it keeps its pose relative to that arm's TCP (the TCP's
pose at the first sample at or after the grasp) until that arm lets go, where it stays.
A vial's screw cap is drawn on it, a cylinder of its own (the top quarter of the vial)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pinocchio as pin

from cellengine import geometry as g
from cellengine.arrays import Vec
from cellengine.info.objects import Container
from cellengine.motion.robot import CellModel
from cellengine.program import TimedEvent
from cellengine.world import World

CAP_SHARE = 0.25  # of a vial's height: its cap, drawn in the cap's colour
DECIMALS = 4


def containers(
    world: World, cell: CellModel, events: Sequence[TimedEvent], times: Vec, q: Vec
) -> list[dict[str, Any]]:
    """Each placed container (and a vial's cap) as a link-like shape over the samples
    ``times`` (arm joints ``q``, one row per sample)."""
    out: list[dict[str, Any]] = []
    ordered = sorted(events, key=lambda e: e.time)
    tcp: dict[str, Vec] | None = None
    for name, c in world.objects.containers.items():
        if c.at is None:
            continue
        if tcp is None and any(e.event.holds == name for e in ordered):
            tcp = _tcp_poses(cell, q)
        poses = _poses(name, world.standing(c), ordered, times, tcp or {})
        out.extend(_shapes(name, c, poses))
    return out


def zones(world: World) -> list[dict[str, Any]]:
    """The cell's zones: name, corners and robots."""
    return [
        {"name": name, "min": list(z.min), "max": list(z.max), "robots": list(z.robots)}
        for name, z in world.cell.zones.items()
    ]


def _tcp_poses(cell: CellModel, q: Vec) -> dict[str, Vec]:
    """Each arm's TCP pose (S, 4, 4) at the rows of ``q``."""
    return frame_poses(cell, q, cell.tcp)


def frame_poses(cell: CellModel, q: Vec, frames: Mapping[str, int]) -> dict[str, Vec]:
    """Each arm's pose (S, 4, 4) of its frame in ``frames`` (the TCP, the flange) at the
    rows of ``q``."""
    model = cell.model
    data = model.createData()
    out = {arm: np.empty((len(q), 4, 4)) for arm in frames}
    for s, row in enumerate(q):
        pin.framesForwardKinematics(model, data, row)
        for arm, frame in frames.items():
            out[arm][s] = data.oMf[frame].homogeneous
    return out


def _poses(
    name: str, start: Vec, events: Sequence[TimedEvent], times: Vec, tcp: dict[str, Vec]
) -> Vec:
    """The container's pose (S, 4, 4) at each sample."""
    poses = np.empty((len(times), 4, 4))
    T, holder, offset, k = start, None, np.eye(4), 0
    for s, t in enumerate(times):
        if holder is not None:
            T = tcp[holder][s] @ offset
        while k < len(events) and events[k].time <= t + 1e-9:
            e = events[k].event
            if e.holds == name and e.arm in tcp:
                holder, offset = e.arm, g.inverse(tcp[e.arm][s]) @ T
            elif e.arm == holder:
                holder = None  # let go: it stays where it is
            k += 1
        poses[s] = T
    return poses


def _shapes(name: str, c: Container, poses: Vec) -> list[dict[str, Any]]:
    """The container's shape (and its cap's) at ``poses``: one sample when it never moves."""
    fixed = bool(np.allclose(poses, poses[:1], atol=1e-9))
    M = poses[:1] if fixed else poses
    if c.size is not None:
        half = np.asarray(c.size, dtype=float) / 2
        centre = M[:, :3, 3] + M[:, :3, 2] * half[2]
        axes = [M[:, :3, k] * half[k] for k in range(3)]
        return [_entry(name, c.kind, "box", 0.0, fixed, np.hstack([centre, *axes]))]
    assert c.diameter is not None and c.height is not None  # Container's validator
    radius, height = c.diameter / 2, c.height
    split = height * (1 - CAP_SHARE) if c.cap is not None else height
    out = [_entry(name, c.kind, "cylinder", radius, fixed, _axis(M, 0.0, split))]
    if c.cap is not None:
        out.append(_entry(f"{name} cap", "cap", "cylinder", radius, fixed, _axis(M, split, height)))
    return out


def _axis(M: Vec, z0: float, z1: float) -> Vec:
    """(S, 6): the points at heights z0 and z1 along each pose's z."""
    p, z = M[:, :3, 3], M[:, :3, 2]
    return np.hstack([p + z * z0, p + z * z1])


def _entry(
    name: str, kind: str, shape: str, radius: float, fixed: bool, points: Vec
) -> dict[str, Any]:
    return {
        "name": name,
        "object": kind,
        "kind": shape,
        "radius": radius,
        "fixed": fixed,
        "stride": points.shape[1],
        "points": np.round(points.ravel(), DECIMALS).tolist(),
    }
