"""The simulated arms: every joint follows its commanded position each servo period, either
exactly or through a first-order lag (time constant ``lag``): over one period of length dt,

    q <- q + (1 - exp(-dt / lag)) (q_cmd - q),

the exact response of dq/dt = (q_cmd - q) / lag to a command held for the period. At a
constant commanded velocity v the arm settles behind the command by about v * lag (the
tracking error, which the driver measures at every tick). Frozen joints do not move.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from cellengine.arrays import BoolArray, FloatArray


def lag_gain(lag: float, period: float) -> float:
    """The fraction of the remaining error a joint closes in one period (1: exact)."""
    if lag < 0 or not math.isfinite(lag):
        raise ValueError(f"lag must be a time constant >= 0 s, got {lag!r}")
    return 1.0 if lag == 0 else 1.0 - math.exp(-period / lag)


class SimArms:
    """Measured positions ``q`` and the command being held, both in cell order."""

    def __init__(self, q0: ArrayLike, lag: float = 0.0, period: float = 0.002) -> None:
        self.q: FloatArray = np.array(q0, dtype=np.float64)
        self.command: FloatArray = self.q.copy()
        self.gain = lag_gain(lag, period)

    def step(self, command: FloatArray, frozen: BoolArray) -> FloatArray:
        """One servo period toward ``command``; returns the measured q (a copy)."""
        self.command = np.array(command, dtype=np.float64)
        moved = self.command if self.gain == 1.0 else self.q + self.gain * (self.command - self.q)
        self.q = np.where(frozen, self.q, moved)
        return self.q.copy()

    def stop(self) -> None:
        """Hold every joint where it is now (both arms at once)."""
        self.command = self.q.copy()

    @property
    def stopped(self) -> bool:
        return bool(np.array_equal(self.command, self.q))
