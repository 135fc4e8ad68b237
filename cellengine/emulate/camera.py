"""A camera over the bench, for tests and benchmarks of `cellengine locate`: the image a
camera of cell.yaml's intrinsics and distortion takes from a known pose, of the world markers
and the containers standing with theirs on top, blurred and noisy.

A pinhole image is drawn first at ``SUPERSAMPLE`` times the resolution (each marker
warped onto its plane, the containers painted furthest from the camera's axis first, so
that nearer, taller ones hide what they would hide), smoothed to one pixel and resampled
through the lens' distortion. Nothing here is used by the locator."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from cellengine.arrays import FloatArray, Mat
from cellengine.info.camera import Camera
from cellengine.locate.lens import dictionary, matrix
from cellengine.world import World

SUPERSAMPLE = 3
CELL_PX = 16  # texture pixels per marker bit
TABLE, SIDE, TOP, PAPER = 140, 90, 200, 235  # grey levels


@dataclass(frozen=True)
class Solid:
    """A container as the camera sees it: a cylinder (diameter) or a box (size x, y), its
    base's pose in the cell frame, its height, and the marker on its top's centre."""

    T_cell_base: Mat
    height: float
    diameter: float | None = None
    size: tuple[float, float] | None = None
    marker: int | None = None


@dataclass(frozen=True)
class Shot:
    """What is in front of the camera and how the image is spoilt."""

    T_cell_camera: Mat
    world: dict[int, Mat] = field(default_factory=dict)  # world markers' poses
    solids: tuple[Solid, ...] = ()
    blur: float = 0.6  # px: the optics' Gaussian blur
    noise: float = 2.0  # grey levels: the sensor's Gaussian noise
    vignetting: float = 0.25  # the corners' light lost
    seed: int = 0


def looking_down(x: float, y: float, height: float, yaw: float = 0.0) -> Mat:
    """T_cell_camera of a camera at (x, y, height) looking straight down, the image's x
    along the cell's x turned by ``yaw`` and its top towards the cell's +y."""
    c, s = np.cos(yaw), np.sin(yaw)
    T = np.eye(4)
    T[:3, :3] = np.array([[c, s, 0.0], [s, -c, 0.0], [0.0, 0.0, -1.0]])
    T[:3, 3] = (x, y, height)
    return T


@dataclass(frozen=True)
class Lens:
    """For each pixel of the camera's image: where its ray meets the supersampled pinhole
    image (mapx, mapy), and its squared distance from the centre (1 at the corners) for the
    vignetting. About a second to build at 1080p: build it once per camera."""

    mapx: Any
    mapy: Any
    r2: Any

    @classmethod
    def of(cls, camera: Camera) -> Lens:
        return cls(*_lens_maps(camera))


def render(camera: Camera, shot: Shot, lens: Lens | None = None) -> Any:
    """The grey image (uint8, rows x columns) the camera takes (``lens``: the camera's,
    built here if not given)."""
    import cv2

    w, h = camera.resolution
    K = _scaled(matrix(camera))
    P = K @ np.linalg.inv(shot.T_cell_camera)[:3, :]
    ideal = np.full((h * SUPERSAMPLE, w * SUPERSAMPLE), TABLE, np.uint8)
    for marker, T in shot.world.items():
        _paste(ideal, P, T, _texture(camera, marker), camera.world_side)
    origin = shot.T_cell_camera[:3, 3]
    far_first = sorted(
        shot.solids, key=lambda s: -float(np.hypot(*(s.T_cell_base[:2, 3] - origin[:2])))
    )
    for solid in far_first:
        _solid(camera, ideal, P, solid)
    smooth = cv2.GaussianBlur(ideal.astype(np.float32), (0, 0), SUPERSAMPLE / 2.0)
    lens = lens or Lens.of(camera)
    mapx, mapy, light = lens.mapx, lens.mapy, lens.r2
    image = cv2.remap(smooth, mapx, mapy, cv2.INTER_LINEAR, borderValue=float(TABLE))
    image = image * (1.0 - shot.vignetting * light)
    if shot.blur > 0:
        image = cv2.GaussianBlur(image, (0, 0), shot.blur)
    noise = np.random.default_rng(shot.seed).normal(0.0, shot.noise, image.shape)
    return np.clip(np.rint(image + noise), 0, 255).astype(np.uint8)


def _scaled(K: FloatArray) -> FloatArray:
    """The matrix of the supersampled image: pixel centres at (i + 0.5) S - 0.5."""
    S = float(SUPERSAMPLE)
    out = K.copy()
    out[0, 0] *= S
    out[1, 1] *= S
    out[0, 2] = (K[0, 2] + 0.5) * S - 0.5
    out[1, 2] = (K[1, 2] + 0.5) * S - 0.5
    return out


def _texture(camera: Camera, marker: int) -> Any:
    """The marker as printed: its 6 x 6 bits (the black border included) on a margin of
    white paper one bit wide."""
    import cv2

    bits = int(camera.dictionary.split("x")[0]) + 2
    art = cv2.aruco.generateImageMarker(dictionary(camera), marker, bits * CELL_PX, borderBits=1)
    return cv2.copyMakeBorder(art, *(CELL_PX,) * 4, cv2.BORDER_CONSTANT, value=PAPER)


def _paste(ideal: Any, P: FloatArray, T_cell_marker: Mat, texture: Any, side: float) -> None:
    """The texture warped onto the marker's plane (its frame's z = 0): texture pixel (u, v)
    at x = (u + 0.5 - n/2) m, y = (n/2 - v - 0.5) m, m the size of a texture pixel."""
    import cv2

    n = texture.shape[0]
    m = side / (n - 2 * CELL_PX)  # the black square is the texture less its paper margin
    A = np.array([[m, 0.0, m * (0.5 - n / 2)], [0.0, -m, m * (n / 2 - 0.5)], [0.0, 0.0, 1.0]])
    H = P @ T_cell_marker[:, [0, 1, 3]] @ A
    cv2.warpPerspective(
        texture,
        H,
        (ideal.shape[1], ideal.shape[0]),
        dst=ideal,
        flags=cv2.INTER_NEAREST,
        borderMode=cv2.BORDER_TRANSPARENT,
    )


def _solid(camera: Camera, ideal: Any, P: FloatArray, solid: Solid) -> None:
    """Its sides (the hull of its base and top outlines: the camera is above it), its top,
    and the marker on the top."""
    import cv2

    outline = _outline(solid)
    T = solid.T_cell_base
    top = T.copy()
    top[:3, 3] = T[:3, 3] + T[:3, 2] * solid.height
    base_px = _project(P, T, outline)
    top_px = _project(P, top, outline)
    hull = cv2.convexHull(np.vstack([base_px, top_px]).astype(np.float32))
    cv2.fillConvexPoly(ideal, np.rint(hull).astype(np.int32), SIDE, lineType=cv2.LINE_AA)
    cv2.fillConvexPoly(ideal, np.rint(top_px).astype(np.int32), TOP, lineType=cv2.LINE_AA)
    if solid.marker is not None:
        _paste(ideal, P, top, _texture(camera, solid.marker), camera.marker)


def _outline(solid: Solid) -> FloatArray:
    """Its footprint's outline in its base frame (N x 3)."""
    if solid.size is not None:
        x, y = solid.size[0] / 2.0, solid.size[1] / 2.0
        return np.array([[-x, -y, 0.0], [x, -y, 0.0], [x, y, 0.0], [-x, y, 0.0]])
    r = (solid.diameter or 0.0) / 2.0
    a = np.linspace(0.0, 2.0 * np.pi, 96, endpoint=False)
    return np.column_stack([r * np.cos(a), r * np.sin(a), np.zeros_like(a)])


def _project(P: FloatArray, T: Mat, points: FloatArray) -> FloatArray:
    cell = (T[:3, :3] @ points.T).T + T[:3, 3]
    p = (P @ np.column_stack([cell, np.ones(len(cell))]).T).T
    return p[:, :2] / p[:, 2:3]


def _lens_maps(camera: Camera) -> tuple[Any, Any, Any]:
    """The lens is undone here by its own code, not by the locator's (OpenCV's
    undistortPoints), so that a test of one against the other means something."""
    w, h = camera.resolution
    u, v = np.meshgrid(np.arange(w, dtype=float), np.arange(h, dtype=float))
    K = matrix(camera)
    x, y = _undistorted(camera, (u - K[0, 2]) / K[0, 0], (v - K[1, 2]) / K[1, 1])
    S = _scaled(K)
    mapx = (S[0, 0] * x + S[0, 2]).astype(np.float32)
    mapy = (S[1, 1] * y + S[1, 2]).astype(np.float32)
    r2 = ((u - w / 2.0) ** 2 + (v - h / 2.0) ** 2) / ((w / 2.0) ** 2 + (h / 2.0) ** 2)
    return mapx, mapy, r2.astype(np.float32)


def distorted(camera: Camera, x: FloatArray, y: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Brown-Conrady, as OpenCV defines its five coefficients: a ray's normalized (x, y)
    where the lens puts it."""
    k1, k2, p1, p2, k3 = (*camera.distortion, 0.0)[:5]
    r2 = x * x + y * y
    radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))
    return (
        x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x),
        y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y,
    )


def _undistorted(camera: Camera, xd: FloatArray, yd: FloatArray) -> tuple[FloatArray, FloatArray]:
    """The rays the lens puts at (xd, yd), by Newton's method on :func:`distorted`, to 1e-11
    of a normalized unit (1e-8 px)."""
    k1, k2, p1, p2, k3 = (*camera.distortion, 0.0)[:5]
    x, y = xd.copy(), yd.copy()
    for _ in range(30):
        fx, fy = distorted(camera, x, y)
        rx, ry = fx - xd, fy - yd
        if max(np.abs(rx).max(), np.abs(ry).max()) < 1e-11:
            break
        r2 = x * x + y * y
        radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))
        slope = k1 + r2 * (2.0 * k2 + 3.0 * r2 * k3)  # d radial / d r2
        j11 = radial + 2.0 * x * x * slope + 2.0 * p1 * y + 6.0 * p2 * x
        j12 = 2.0 * x * y * slope + 2.0 * p1 * x + 2.0 * p2 * y
        j22 = radial + 2.0 * y * y * slope + 6.0 * p1 * y + 2.0 * p2 * x
        det = j11 * j22 - j12 * j12  # the Jacobian is symmetric
        x = x - (j22 * rx - j12 * ry) / det
        y = y - (j11 * ry - j12 * rx) / det
    return x, y


def solids(world: World, moved: dict[str, Mat] | None = None) -> tuple[Solid, ...]:
    """Every container of the world that stands somewhere at the start, where it stands
    (or at ``moved[name]``: T_cell_base), its marker on its top."""
    out = []
    for name, c in world.objects.containers.items():
        T = (moved or {}).get(name)
        if T is None and c.at is None:
            continue
        T = world.standing(c) if T is None else T
        size = None if c.size is None else (c.size[0], c.size[1])
        out.append(Solid(T, c.full_height or 0.0, c.diameter, size, c.marker))
    return tuple(out)


def world_markers(camera: Camera) -> dict[int, Mat]:
    """The world markers where cell.yaml has them."""
    return {m: p.matrix() for m, p in camera.world.items()}
