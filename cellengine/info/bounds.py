"""Bounds where physics has them, for every format that places geometry.

A cell is metres: a platform's parts and a link's meshes lie within MAX_COORDINATE of their
frame's origin, every length a cell, objects or plan file gives is MAX_COORDINATE at most
either way, a scale (X3D Transform, URDF mesh) is SCALES in size at most, either sign, and a
mass is MAX_MASS at most. Past them, numbers are a mistake (a file in mm read as m) or an
attack (coal's qhull crashes the process on coordinates of 1e80, 1e300 overflows the
geometry, and a scale of 0 leaves nothing to collide).
"""

from __future__ import annotations

from collections.abc import Iterable

MAX_COORDINATE = 100.0  # m; every length in cell, objects and plan files too
MAX_MASS = 1000.0  # kg: what a cell's files and its load cells may give
SCALES = (1e-6, 1e6)


def scale_ok(values: Iterable[float]) -> bool:
    """Every factor of a scale within SCALES in size."""
    return all(SCALES[0] <= abs(float(v)) <= SCALES[1] for v in values)
