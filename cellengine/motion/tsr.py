"""Task Space Regions (Berenson et al.): a set of end-effector poses as a frame, an offset
and bounds on x, y, z, roll, pitch, yaw; sampled into poses, and through IK into goal
configurations for transit planning."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from cellengine import geometry as g
from cellengine.arrays import Mat, Vec


def _bounds(b: ArrayLike) -> Vec:
    a = np.array(b, dtype=float).reshape(6, 2)
    if np.any(a[:, 0] > a[:, 1]):
        raise ValueError("each TSR bound must be [min, max] with min <= max")
    a.setflags(write=False)
    return a


@dataclass(frozen=True)
class TaskSpaceRegion:
    """Poses T_cell_frame · T(x, y, z, roll, pitch, yaw) · T_frame_ee, each of the six in its
    bounds (metres, radians; rpy as everywhere: Rz(yaw) Ry(pitch) Rx(roll))."""

    T_cell_frame: Mat
    T_frame_ee: Mat = field(default_factory=lambda: np.eye(4))
    bounds: Vec = field(default_factory=lambda: _bounds(np.zeros((6, 2))))

    def __post_init__(self) -> None:
        object.__setattr__(self, "bounds", _bounds(self.bounds))
        for name in ("T_cell_frame", "T_frame_ee"):
            if np.shape(getattr(self, name)) != (4, 4):
                raise ValueError(f"{name} must be 4x4, got {np.shape(getattr(self, name))}")

    def sample(self, rng: np.random.Generator, k: int) -> Vec:
        """k poses (k, 4, 4) drawn uniformly from the bounds."""
        d = rng.uniform(self.bounds[:, 0], self.bounds[:, 1], size=(k, 6))
        return np.array([self.pose(x) for x in d])

    def pose(self, d: ArrayLike) -> Mat:
        x = np.asarray(d, dtype=float)
        T: Mat = self.T_cell_frame @ g.pose(x[:3], x[3:]) @ self.T_frame_ee
        return T

    def displacement(self, T_cell_ee: Mat) -> Vec:
        """The (x, y, z, roll, pitch, yaw) of a pose in this region's frame."""
        T = g.inverse(self.T_cell_frame) @ T_cell_ee @ g.inverse(self.T_frame_ee)
        return np.concatenate(g.xyz_rpy(T))

    def contains(self, T_cell_ee: Mat, tol: float = 1e-9) -> bool:
        d = self.displacement(T_cell_ee)
        return bool(np.all(d >= self.bounds[:, 0] - tol) and np.all(d <= self.bounds[:, 1] + tol))


def goal_configurations(
    tsr: TaskSpaceRegion,
    ik: Callable[[Mat], Iterable[Vec]],
    samples: int = 16,
    seed: int = 0,
    is_valid: Callable[[Vec], bool] | None = None,
) -> Vec:
    """IK solutions of poses sampled from ``tsr``: (k, n), k may be 0. ``ik`` returns every
    solution it finds for a pose (all UR branches, say); ``is_valid`` drops colliding ones."""
    rng = np.random.default_rng(seed)
    found = [q for T in tsr.sample(rng, samples) for q in ik(T) if is_valid is None or is_valid(q)]
    return np.array(found) if found else np.zeros((0, 0))
