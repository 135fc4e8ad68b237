"""Faults injected into the simulated cell, for tests: each is a condition from a program
time on (a joint stops following, a gripper stops changing mode, a connection is lost),
which persists until :meth:`Injections.clear` (someone fixed it)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cellengine.arrays import BoolArray


@dataclass(frozen=True)
class Injection:
    kind: str  # freeze | gripper | connection
    at: float  # program time (s) from which it holds
    joint: int | None = None  # freeze: index in q
    arm: str | None = None  # gripper, connection (None: every arm)


class Injections:
    def __init__(self, n_joints: int) -> None:
        self.n_joints = n_joints
        self.items: list[Injection] = []

    def add(self, injection: Injection) -> None:
        self.items.append(injection)

    def clear(self) -> None:
        self.items.clear()

    def active(self, t: float) -> list[Injection]:
        return [i for i in self.items if i.at <= t]

    def frozen(self, t: float) -> BoolArray:
        mask = np.zeros(self.n_joints, dtype=bool)
        for i in self.active(t):
            if i.kind == "freeze" and i.joint is not None:
                mask[i.joint] = True
        return mask

    def gripper_fails(self, arm: str, t: float) -> bool:
        return any(i.kind == "gripper" and i.arm == arm for i in self.active(t))

    def connection_lost(self, t: float) -> Injection | None:
        return next((i for i in self.active(t) if i.kind == "connection"), None)
