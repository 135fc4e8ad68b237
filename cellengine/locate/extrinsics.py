"""The camera's pose from the world markers (paper 004, II-C): their corners' known places
in the cell frame against where the image has them, by PnP refined with Levenberg-Marquardt."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cellengine.arrays import FloatArray, Mat
from cellengine.info.camera import Camera
from cellengine.locate.lens import distortion, matrix
from cellengine.locate.markers import Corners, square


class PoseError(ValueError):
    """The world markers do not give the camera's pose; the message says why."""


@dataclass(frozen=True)
class CameraPose:
    T_cell_camera: Mat
    used: tuple[int, ...]  # the world markers it comes from
    rms: float  # px: their corners' reprojection error
    worst: tuple[int, float]  # the world marker seen farthest from where the pose puts it


def world_corners(camera: Camera, marker: int) -> FloatArray:
    """A world marker's four corners in the cell frame (m), in OpenCV's order."""
    T = camera.world[marker].matrix()
    return (T[:3, :3] @ square(camera.world_side).T).T + T[:3, 3]


def camera_pose(camera: Camera, seen: Corners) -> CameraPose:
    used = tuple(sorted(m for m in camera.world if m in seen))
    missing = sorted(set(camera.world) - set(used))
    if len(used) < camera.world_seen:
        raise PoseError(
            f"{len(used)} of the world markers seen ({_ids(used) or 'none'}); the camera's "
            f"pose needs {camera.world_seen} (world_seen); not seen: {_ids(missing)}"
        )
    pose = _solved(camera, seen, used)
    if pose.rms > camera.reprojection:
        raise PoseError(_disagreeing(camera, seen, pose))
    return pose


def _solved(camera: Camera, seen: Corners, used: tuple[int, ...]) -> CameraPose:
    import cv2

    obj = np.vstack([world_corners(camera, m) for m in used])
    img = np.vstack([seen[m] for m in used])
    K, D = matrix(camera), distortion(camera)
    ok, rvec, tvec = cv2.solvePnP(obj, img, K, D, flags=cv2.SOLVEPNP_SQPNP)
    if not ok:
        raise PoseError("the world markers' corners give no camera pose (PnP failed)")
    rvec, tvec = cv2.solvePnPRefineLM(obj, img, K, D, rvec, tvec)
    projected = cv2.projectPoints(obj, rvec, tvec, K, D)[0].reshape(-1, 2)
    off = np.linalg.norm(projected - img, axis=1)
    per_marker = off.reshape(len(used), 4).mean(axis=1)
    worst = int(np.argmax(per_marker))
    T_camera_cell = np.eye(4)
    T_camera_cell[:3, :3] = cv2.Rodrigues(rvec)[0]
    T_camera_cell[:3, 3] = tvec.ravel()
    return CameraPose(
        np.asarray(np.linalg.inv(T_camera_cell), dtype=float),
        used,
        float(np.sqrt(np.mean(off**2))),
        (used[worst], float(per_marker[worst])),
    )


def _disagreeing(camera: Camera, seen: Corners, pose: CameraPose) -> str:
    """Why the world markers give no pose: the one marker whose place disagrees with the
    others' (they agree without it; how far it is from cell.yaml's place), else all."""
    head = (
        f"the world markers do not agree with cell.yaml: their corners are {pose.rms:.1f} px "
        f"(RMS) from where the best camera pose puts them, more than camera.reprojection "
        f"({camera.reprojection:g} px)"
    )
    if len(pose.used) - 1 >= max(camera.world_seen, 3):
        tries = {m: _solved(camera, seen, tuple(k for k in pose.used if k != m)) for m in pose.used}
        m, others = min(tries.items(), key=lambda kv: kv[1].rms)
        if others.rms <= camera.reprojection:
            from cellengine.locate.plane import centre_and_yaw, on_plane

            z = float(camera.world[m].matrix()[2, 3])
            centre, _ = centre_and_yaw(on_plane(camera, others.T_cell_camera, seen[m], z))
            place = camera.world[m].matrix()[:3, 3]
            moved = float(np.linalg.norm(centre[:2] - place[:2])) * 1000.0
            return (
                f"{head}: world marker {m} is {moved:.1f} mm from its place in cell.yaml "
                f"(the others agree within {others.rms:.1f} px); put it back, or correct "
                f"camera.world.{m}"
            )
    return (
        f"{head}; the farthest is world marker {pose.worst[0]} ({pose.worst[1]:.1f} px): "
        "check the world markers' places in cell.yaml, or whether they have moved"
    )


def _ids(ids: list[int] | tuple[int, ...]) -> str:
    return ", ".join(str(i) for i in ids)
