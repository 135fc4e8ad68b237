"""A marker's place on a horizontal plane: its image corners as rays from the camera, met
with the plane z = height of the cell frame (the object's top, where its marker is)."""

from __future__ import annotations

import math

import numpy as np

from cellengine.arrays import FloatArray, Mat
from cellengine.info.camera import Camera
from cellengine.locate.lens import normalized


def on_plane(camera: Camera, T: Mat, corners: FloatArray, z: float) -> FloatArray:
    """The corners (4 x 2 px) on the plane z (cell frame, m): 4 x 3, seen by the camera
    at T (T_cell_camera)."""
    rays = normalized(camera, corners) @ T[:3, :3].T
    origin = T[:3, 3]
    if np.any(rays[:, 2] >= 0.0) or origin[2] <= z:
        raise ValueError(f"the plane z = {z * 1000:.1f} mm is not below the camera")
    s = (z - origin[2]) / rays[:, 2]
    out: FloatArray = origin + s[:, None] * rays
    return out


def centre_and_yaw(points: FloatArray) -> tuple[FloatArray, float]:
    """A marker's centre (where its diagonals meet) and its yaw (its x axis: top left to
    top right corner) from its corners on the plane (4 x 3, OpenCV's order)."""
    p0, p1, p2, p3 = (points[i, :2] for i in range(4))
    # p0 + a (p2 - p0) = p1 + b (p3 - p1)
    a, _ = np.linalg.solve(np.column_stack([p2 - p0, p1 - p3]), p1 - p0)
    centre = p0 + a * (p2 - p0)
    x_axis = (p1 - p0) + (p2 - p3)
    return np.array([centre[0], centre[1], points[0, 2]]), math.atan2(x_axis[1], x_axis[0])
