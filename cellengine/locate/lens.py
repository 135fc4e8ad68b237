"""The camera of cell.yaml as OpenCV takes it: the pinhole matrix, the distortion
coefficients and the marker dictionary."""

from __future__ import annotations

from typing import Any

import numpy as np

from cellengine.arrays import FloatArray
from cellengine.info.camera import Camera


def matrix(camera: Camera) -> FloatArray:
    m = camera.matrix
    return np.array([[m.fx, 0.0, m.cx], [0.0, m.fy, m.cy], [0.0, 0.0, 1.0]])


def distortion(camera: Camera) -> FloatArray:
    return np.array(camera.distortion, dtype=float)


def dictionary(camera: Camera) -> Any:
    """OpenCV's predefined dictionary named by cell.yaml (``4x4_50``: DICT_4X4_50)."""
    import cv2

    return cv2.aruco.getPredefinedDictionary(
        getattr(cv2.aruco, f"DICT_{camera.dictionary.upper()}")
    )


def normalized(camera: Camera, pixels: FloatArray) -> FloatArray:
    """Image points (N x 2, px, as the distorted image has them) as rays (N x 3) in the
    camera frame: x right, y down, z along the optical axis, z = 1."""
    import cv2

    pts = np.ascontiguousarray(pixels, dtype=np.float64).reshape(-1, 1, 2)
    # the iterative undoing of the distortion, to far below a pixel at a wide lens' edge
    criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-12)
    xy = cv2.undistortPoints(pts, matrix(camera), distortion(camera), None, None, None, criteria)
    xy = xy.reshape(-1, 2)
    return np.column_stack([xy, np.ones(len(xy))])
