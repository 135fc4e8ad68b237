"""Triangle meshes of the primitive shapes (X3D nodes, obstacles), centred on their origin.

Round shapes come from trimesh.creation, imported on first use: importing trimesh costs about
half a second, which cells made of boxes and CAD meshes never pay.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from cellengine.info.mesh import Mesh

# A unit cube's corners (vertex 4x + 2y + z) and outward-wound triangles, as trimesh's box.
_CUBE = np.array([[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)])
_CUBE_FACES = np.array(
    [
        [1, 3, 0],
        [4, 1, 0],
        [0, 3, 2],
        [2, 4, 0],
        [1, 7, 3],
        [5, 1, 4],
        [5, 7, 1],
        [3, 7, 2],
        [6, 4, 2],
        [2, 7, 6],
        [6, 5, 4],
        [7, 5, 6],
    ]
)


def box(size: ArrayLike) -> Mesh:
    """A box of edge lengths ``size`` (x, y, z): 8 vertices, 12 triangles."""
    return Mesh(_CUBE * np.asarray(size, dtype=float), _CUBE_FACES)


def cylinder(radius: float, height: float, sections: int) -> Mesh:
    """A closed cylinder along z, ``sections`` segments around."""
    from trimesh.creation import cylinder as make

    return _mesh(make(radius=radius, height=height, sections=sections))


def cone(radius: float, height: float, sections: int) -> Mesh:
    """A closed cone along z, its base at z = 0."""
    from trimesh.creation import cone as make

    return _mesh(make(radius=radius, height=height, sections=sections))


def sphere(radius: float, subdivisions: int = 2) -> Mesh:
    """An icosphere: 20 * 4**subdivisions triangles."""
    from trimesh.creation import icosphere

    return _mesh(icosphere(subdivisions=subdivisions, radius=radius))


def _mesh(m: Any) -> Mesh:
    return Mesh(np.asarray(m.vertices), np.asarray(m.faces))
