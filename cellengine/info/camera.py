"""cell.yaml `camera`: a camera over the bench that locates objects by their ArUco markers
(`cellengine locate`): its intrinsics, its lens' distortion, the marker dictionary and the
world markers whose known places give the camera's pose (paper 004, II-C)."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, model_validator

from cellengine.info.pose import Pose
from cellengine.info.units import Frozen, Length, Number

MarkerId = Annotated[int, Field(ge=0, le=999)]

# OpenCV's predefined ArUco dictionaries: 4x4 to 7x7 bits, 50 to 1000 markers each
DICTIONARIES = tuple(
    f"{bits}x{bits}_{count}" for bits in (4, 5, 6, 7) for count in (50, 100, 250, 1000)
)
Dictionary = Literal[DICTIONARIES]  # type: ignore[valid-type]


class Intrinsics(Frozen):
    """The pinhole matrix, in pixels of the camera's full resolution."""

    fx: float = Field(gt=0, allow_inf_nan=False)
    fy: float = Field(gt=0, allow_inf_nan=False)
    cx: float = Field(allow_inf_nan=False)
    cy: float = Field(allow_inf_nan=False)


class Camera(Frozen):
    resolution: tuple[Annotated[int, Field(gt=0, le=20000)], Annotated[int, Field(gt=0, le=20000)]]
    matrix: Intrinsics
    # OpenCV's order: k1, k2, p1, p2[, k3]
    distortion: tuple[Number, ...] = Field((0.0, 0.0, 0.0, 0.0, 0.0), min_length=4, max_length=5)
    dictionary: Dictionary = "4x4_50"
    # the side of the object markers' black square, and the world markers' (larger ones
    # give the camera's pose more pixels; default: as the objects')
    marker: Length = Field(gt=0)
    world_marker: Length | None = Field(None, gt=0)
    # the world markers: each one's centre and its axes (x to the right of its printed image,
    # y up it, z out of it) in the cell frame; the camera's pose comes from them
    world: dict[MarkerId, Pose] = Field(min_length=3)
    # at least this many of them must be seen (each gives four corners to the pose)
    world_seen: int = Field(3, ge=1)
    # the world markers' corners must be seen within this of where the pose puts them
    # (px, RMS): past it a world marker has moved, or cell.yaml has its place wrong
    reprojection: float = Field(2.0, gt=0, allow_inf_nan=False)
    # an object located within this (horizontally) of a keypoint is taken as standing there;
    # one farther from every keypoint, as standing on the plane z = table
    snap: Length = Field(0.005, ge=0)
    table: Length = 0.0

    @property
    def world_side(self) -> float:
        return self.world_marker if self.world_marker is not None else self.marker

    @model_validator(mode="after")
    def _consistent(self) -> Camera:
        if self.world_seen > len(self.world):
            raise ValueError(
                f"world_seen is {self.world_seen} but only {len(self.world)} world markers "
                "are given"
            )
        w, h = self.resolution
        if not (0 <= self.matrix.cx <= w and 0 <= self.matrix.cy <= h):
            raise ValueError(f"matrix: the principal point (cx, cy) must be inside {w} x {h} px")
        return self
