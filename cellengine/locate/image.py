"""A camera's picture: from a file (decoded from bytes read with the image cap, so a FIFO or
a huge file is refused before decoding) or from a camera device; the camera's resolution
checked, since its intrinsics are for that resolution."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from cellengine.errors import InputError
from cellengine.info.camera import Camera
from cellengine.info.files import read_capped

# pixels a picture may decode to (a 64 MB PNG can claim far more): 8K is 33 M
MAX_PIXELS = 100_000_000


def from_file(path: Path, camera: Camera) -> Any:
    # read by OpenCV when it first decodes: set before any picture is
    os.environ.setdefault("OPENCV_IO_MAX_IMAGE_PIXELS", str(MAX_PIXELS))
    import cv2

    data = read_capped(path, "image")
    image = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_GRAYSCALE)
    if image is None:
        raise InputError.at("not an image OpenCV can read (PNG, JPEG, TIFF, BMP, ...)", path)
    return _sized(image, camera, path)


def from_device(index: int, camera: Camera) -> Any:
    """One frame of video device ``index`` at the camera's resolution."""
    import cv2

    capture = cv2.VideoCapture(index)
    try:
        if not capture.isOpened():
            raise InputError.at(f"cannot open camera {index}", None)
        w, h = camera.resolution
        capture.set(cv2.CAP_PROP_FRAME_WIDTH, w)
        capture.set(cv2.CAP_PROP_FRAME_HEIGHT, h)
        ok, frame = capture.read()
    finally:
        capture.release()
    if not ok:
        raise InputError.at(f"camera {index} gave no picture", None)
    return _sized(cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY), camera, f"camera {index}")


def _sized(image: Any, camera: Camera, source: Path | str) -> Any:
    w, h = camera.resolution
    if image.shape[:2] != (h, w):
        raise InputError.at(
            f"the picture is {image.shape[1]} x {image.shape[0]} px; cell.yaml's camera is "
            f"{w} x {h} (camera.resolution): its intrinsics are for that size",
            source,
        )
    return image
