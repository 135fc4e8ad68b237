"""A pose in a file: a position and roll, pitch, yaw in the file's units."""

from __future__ import annotations

from cellengine import geometry
from cellengine.arrays import Mat
from cellengine.info.units import Frozen, Vec3Angle, Vec3Length


class Pose(Frozen):
    xyz: Vec3Length = (0.0, 0.0, 0.0)
    rpy: Vec3Angle = (0.0, 0.0, 0.0)  # URDF: R = Rz(yaw) Ry(pitch) Rx(roll)

    def matrix(self) -> Mat:
        return geometry.pose(self.xyz, self.rpy)
