"""The distance between the arms of a cell along a program, for the report.

Measured on the arms' own collision shapes (links and tools, :attr:`CellModel.collision`):
every pair with one object on each of two different arms. Held objects are not part of the
cell model, so they are not counted (the executor's gate, which knows them, may report its
own figure; the report prefers that one).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from cellengine.arrays import Vec
from cellengine.motion.robot import CellModel

Pair = tuple[str, str]


class ArmDistance:
    """Minimum distance between objects of different arms at a cell configuration."""

    def __init__(self, cell: CellModel) -> None:
        geometry = cell.collision.copy()
        geometry.removeAllCollisionPairs()
        names = [str(o.name) for o in geometry.geometryObjects]
        owners = [n.split("/", 1)[0] for n in names]
        self.pairs: list[Pair] = []
        for i in range(len(names)):
            for j in range(i + 1, len(names)):
                if owners[i] != owners[j]:
                    geometry.addCollisionPair(pin.CollisionPair(i, j))
                    self.pairs.append((names[i], names[j]))
        self._model: Any = cell.model
        self._geometry: Any = geometry
        self._data: Any = cell.model.createData()
        self._gdata: Any = pin.GeometryData(geometry)
        self._nq = int(cell.model.nq)

    def __call__(self, q: ArrayLike) -> tuple[float, Pair] | None:
        """The minimum distance (m; negative: penetration) and its pair, or None when the
        cell has fewer than two arms."""
        if not self.pairs:
            return None
        qa = np.asarray(q, dtype=float)
        if qa.shape != (self._nq,):
            raise ValueError(f"q has shape {qa.shape}, expected ({self._nq},)")
        k = int(pin.computeDistances(self._model, self._data, self._geometry, self._gdata, qa))
        return float(self._gdata.distanceResults[k].min_distance), self.pairs[k]

    def series(self, Q: ArrayLike) -> tuple[Vec, list[Pair]] | None:
        """The distance and pair at each row of Q (n, nq)."""
        if not self.pairs:
            return None
        rows = np.asarray(Q, dtype=float)
        out, pairs = np.empty(len(rows)), []
        for i, q in enumerate(rows):
            found = self(q)
            assert found is not None
            out[i] = found[0]
            pairs.append(found[1])
        return out, pairs

    def minimum(self, Q: ArrayLike) -> tuple[float, Pair] | None:
        """The smallest distance over the rows of Q and its pair."""
        found = self.series(Q)
        if found is None or len(found[0]) == 0:
            return None
        k = int(np.argmin(found[0]))
        d = float(found[0][k])
        return (d, found[1][k]) if math.isfinite(d) else None
