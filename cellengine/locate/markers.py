"""ArUco markers found in an image: each id's four corners (px), in OpenCV's order (the
marker's top left, top right, bottom right, bottom left as printed)."""

from __future__ import annotations

from typing import Any

import numpy as np

from cellengine.arrays import FloatArray
from cellengine.info.camera import Camera
from cellengine.locate.lens import dictionary

Corners = dict[int, FloatArray]  # marker id -> 4 x 2 px


def detect(camera: Camera, image: Any) -> tuple[Corners, list[int]]:
    """The markers of the camera's dictionary in ``image`` (grey or BGR, uint8), corners
    refined to a fraction of a pixel; and the ids seen more than once (left out: which
    one is meant cannot be told)."""
    import cv2

    grey = image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
    params = cv2.aruco.DetectorParameters()
    # markers of 15-20 px across a 1080p image of a whole bench: OpenCV's default keeps
    # none under 3 % of the image's width in perimeter (58 px)
    params.minMarkerPerimeterRate = 0.01
    # each bit read from 8 x 8 samples, its outer 30 % left out: a blurred 3 px bit is read
    # from its middle; one wrong bit corrected (4x4_50's markers differ in 4 bits or more).
    # On bench/bench_locate.py's images these find 162 of 168 markers where OpenCV's
    # defaults find 136, with no marker taken for another
    params.perspectiveRemovePixelPerCell = 8
    params.perspectiveRemoveIgnoredMarginPerCell = 0.3
    params.errorCorrectionRate = 1.0
    # corners from lines fitted to the marker's edges: on markers of 15-20 px the corner
    # detector's refinement (SUBPIX) put the camera 0.4-0.9 mm off its place, this 0.02 mm
    # (one picture of bench/bench_locate.py's kind, sharp and blurred)
    params.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_CONTOUR
    detector = cv2.aruco.ArucoDetector(dictionary(camera), params)
    corners, ids, _ = detector.detectMarkers(grey)
    found: Corners = {}
    twice: set[int] = set()
    for c, i in zip(corners, [] if ids is None else ids.ravel(), strict=True):
        key = int(i)
        if key in found:
            twice.add(key)
        found[key] = np.asarray(c, dtype=float).reshape(4, 2)
    for key in twice:
        del found[key]
    return found, sorted(twice)


def square(side: float) -> FloatArray:
    """A marker's corners in its own frame (x right, y up, z out), in OpenCV's order."""
    h = side / 2.0
    return np.array([[-h, h, 0.0], [h, h, 0.0], [h, -h, 0.0], [-h, -h, 0.0]])
