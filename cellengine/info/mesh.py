"""A read-only triangle mesh: the geometry of platform elements and obstacles, in metres.

Just the arrays and the few measures the engine uses; heavier mesh work (reading STL, round
primitives) stays with trimesh, imported only where it is needed, since importing it costs
about half a second.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from cellengine import geometry as g
from cellengine.arrays import IntArray, Vec


def _frozen(a: ArrayLike, dtype: type[np.generic]) -> NDArray[np.generic]:
    """``a`` as a read-only, C-ordered (k, 3) array (as coal takes it); copied unless it is
    one already, so that the caller's array cannot change the mesh."""
    out = np.asarray(a, dtype=dtype)
    if out.size == 0:
        out = out.reshape(0, 3)
    if out.ndim != 2 or out.shape[1] != 3:
        raise ValueError(f"a mesh's vertices and faces are (k, 3) arrays, got {out.shape}")
    if out.flags.writeable or not out.flags.c_contiguous:
        out = np.array(out, order="C")
        out.setflags(write=False)
    return out


@dataclass(frozen=True, eq=False)  # eq=False: compared by identity, as arrays compare per item
class Mesh:
    vertices: Vec  # (n, 3)
    faces: IntArray  # (m, 3) indices into vertices, counter-clockwise seen from outside

    def __post_init__(self) -> None:
        # read-only: a mesh is shared by elements and USE'd nodes, none of which may change it
        object.__setattr__(self, "vertices", _frozen(self.vertices, np.float64))
        object.__setattr__(self, "faces", _frozen(self.faces, np.int64))

    @property
    def bounds(self) -> Vec:
        """(2, 3): the lowest and highest corner of the axis-aligned box around the vertices."""
        return np.array([self.vertices.min(axis=0), self.vertices.max(axis=0)])

    @property
    def extents(self) -> Vec:
        lo, hi = self.bounds
        out: Vec = hi - lo
        return out

    @property
    def is_watertight(self) -> bool:
        """Closed: every undirected edge is shared by exactly two faces."""
        if len(self.faces) == 0:
            return False
        edges = np.sort(self.faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
        _, counts = np.unique(edges, axis=0, return_counts=True)
        return bool((counts == 2).all())

    @property
    def volume(self) -> float:
        """The signed volume enclosed (positive when faces wind outwards); meaningful for a
        watertight mesh only."""
        if len(self.faces) == 0:
            return 0.0
        v = self.vertices - self.vertices.mean(axis=0)  # the same volume, less cancellation
        a, b, c = (v[self.faces[:, k]] for k in range(3))
        return float(np.einsum("ij,ij->", a, np.cross(b, c))) / 6.0

    def transformed(self, T: Vec) -> Mesh:
        """This mesh under the 4x4 affine ``T``; a mirroring ``T`` flips the faces so they
        still wind outwards."""
        faces = self.faces if np.linalg.det(T[:3, :3]) >= 0 else self.faces[:, ::-1]
        return Mesh(g.transform_points(T, self.vertices), faces)

    @staticmethod
    def concatenate(parts: Sequence[Mesh]) -> Mesh:
        """One mesh of all ``parts`` (their vertices are not merged)."""
        offsets = np.cumsum([0] + [len(p.vertices) for p in parts[:-1]])
        return Mesh(
            np.concatenate([p.vertices for p in parts]),
            np.concatenate([p.faces + k for p, k in zip(parts, offsets, strict=True)]),
        )
