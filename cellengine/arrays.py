"""The shared type aliases of numpy arrays, in one place. They say what an array holds; numpy's
typing cannot check shapes, so the shape is in the name or the comment.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]  # any float array
BoolArray = NDArray[np.bool_]
IntArray = NDArray[np.int64]  # indices into vertices (mesh faces), counts
Vec = FloatArray  # a vector (3,), a joint configuration (n,), or a batch of them (k, n)
Mat = FloatArray  # a matrix: a rotation (3, 3), a transform (4, 4)
Poses = FloatArray  # (k, 4, 4) transforms (k T_cell_tcp), or (k, 3, 3) rotations

__all__ = ["BoolArray", "FloatArray", "IntArray", "Mat", "Poses", "Vec"]
