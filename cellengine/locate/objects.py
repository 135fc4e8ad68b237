"""Where each container with a marker stands, from one image of the bench."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from cellengine.arrays import FloatArray
from cellengine.info.camera import Camera
from cellengine.info.objects import Container
from cellengine.locate.extrinsics import CameraPose, camera_pose
from cellengine.locate.markers import detect
from cellengine.locate.plane import centre_and_yaw, on_plane
from cellengine.world import World


@dataclass(frozen=True)
class Found:
    name: str
    marker: int
    xyz: FloatArray  # the centre of its base, cell frame (m)
    yaw: float  # rad: its marker's x axis from the cell's
    keypoint: str | None  # the keypoint it stands at (within camera.snap), if any
    off: float  # m: horizontally from that keypoint (inf: at none)


@dataclass(frozen=True)
class Located:
    pose: CameraPose
    found: tuple[Found, ...]
    unseen: tuple[str, ...]  # containers with a marker the image does not show
    strangers: tuple[int, ...]  # markers seen that are neither the world's nor an object's
    twice: tuple[int, ...]  # markers seen more than once (none of them used)


def locate(world: World, camera: Camera, image: Any) -> Located:
    """Raises extrinsics.PoseError when the world markers do not give the camera's pose."""
    seen, twice = detect(camera, image)
    pose = camera_pose(camera, seen)
    marked = {c.marker: (n, c) for n, c in world.objects.containers.items() if c.marker is not None}
    found = tuple(
        _found(world, camera, pose, name, c, seen[m])
        for m, (name, c) in sorted(marked.items(), key=lambda kv: kv[1][0])
        if m in seen
    )
    unseen = tuple(sorted(n for m, (n, _) in marked.items() if m not in seen and m not in twice))
    strangers = tuple(sorted(set(seen) - set(marked) - set(camera.world)))
    return Located(pose, found, unseen, strangers, tuple(twice))


def _found(
    world: World, camera: Camera, pose: CameraPose, name: str, c: Container, corners: FloatArray
) -> Found:
    """The marker is on the top's centre: found on the plane of the top of the object as
    the file has it standing (or on the table), then on the top as it stands at the keypoint
    it is found at (or on the table, at none), until its height no longer changes. Of the
    keypoints within camera.snap, it stands at the lowest: those above it are where hands
    hold things (a station's hold and cap points over its place)."""
    height = c.full_height or 0.0
    keypoints = world.keypoints()
    base = world.standing(c)[2, 3] if c.at is not None else camera.table
    for _ in range(3):
        centre, yaw = centre_and_yaw(on_plane(camera, pose.T_cell_camera, corners, base + height))
        at = base
        near = {k: d for k, d in _distances(keypoints, centre).items() if d <= camera.snap}
        keypoint = min(near, key=lambda k: (keypoints[k][2, 3], near[k])) if near else None
        standing = keypoints[keypoint][2, 3] if keypoint is not None else camera.table
        if math.isclose(standing, base, abs_tol=1e-9):
            break
        base = standing
    assert c.marker is not None
    off = near[keypoint] if keypoint is not None else math.inf
    return Found(name, c.marker, np.array([centre[0], centre[1], at]), yaw, keypoint, off)


def _distances(keypoints: dict[str, FloatArray], p: FloatArray) -> dict[str, float]:
    """Each keypoint's horizontal distance from ``p``."""
    return {n: math.hypot(T[0, 3] - p[0], T[1, 3] - p[1]) for n, T in keypoints.items()}
