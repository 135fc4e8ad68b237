"""The simulated arm: six joints and the motion the control script gives them.

The motion sets the controller's setpoint (``target_q``); the arm is where the setpoint is
(``actual_q``), unless it is frozen: then it stays put and says nothing. Every motion steps
in fixed 2 ms ticks, so the same commands give the same joint values.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Sequence
from typing import Protocol

DT = 0.002  # s, the controller's cycle (e-Series, 500 Hz)
JOINT_SPEED_LIMIT = math.pi  # rad/s, 180 deg/s on every UR5e joint
N = 6

Vec = list[float]


class Motion(Protocol):
    done: bool

    def step(self, q: Vec, qd: Vec, dt: float, scale: float) -> tuple[Vec, Vec]:
        """The setpoint and its velocity one tick later (``scale``: the speed slider)."""
        ...


class Hold:
    """Stand still."""

    done = True

    def step(self, q: Vec, qd: Vec, dt: float, scale: float) -> tuple[Vec, Vec]:
        return q, [0.0] * N


class JointMove:
    """moveJ: every joint starts and arrives together; the joint going farthest follows a
    trapezoidal speed profile (``v`` rad/s, ``a`` rad/s^2), the others in proportion."""

    def __init__(self, start: Sequence[float], goal: Sequence[float], v: float, a: float) -> None:
        self.start, self.goal = list(start), list(goal)
        self.delta = [g - s for s, g in zip(start, goal, strict=True)]
        self.distance = max(abs(d) for d in self.delta)
        v, a = max(v, 1e-6), max(a, 1e-6)
        ta = v / a
        if self.distance < v * ta:  # never reaches v: a triangle
            ta = math.sqrt(self.distance / a)
            v = a * ta
        self.a, self.v, self.ta = a, v, ta
        self.duration = 2 * ta + (self.distance - v * ta) / v if self.distance > 0 else 0.0
        self.t = 0.0
        self.done = self.duration == 0.0

    def _s(self, t: float) -> tuple[float, float]:
        """Distance and speed of the leading joint at ``t``."""
        a, v, ta, T = self.a, self.v, self.ta, self.duration
        if t < ta:
            return 0.5 * a * t * t, a * t
        if t < T - ta:
            return 0.5 * a * ta * ta + v * (t - ta), v
        r = T - t
        return self.distance - 0.5 * a * r * r, a * r

    def step(self, q: Vec, qd: Vec, dt: float, scale: float) -> tuple[Vec, Vec]:
        self.t = min(self.t + dt * scale, self.duration)
        if self.t >= self.duration:
            self.done = True
            return list(self.goal), [0.0] * N
        s, sd = self._s(self.t)
        f, fd = s / self.distance, sd * scale / self.distance
        return [x + d * f for x, d in zip(self.start, self.delta, strict=True)], [
            d * fd for d in self.delta
        ]


class Servo:
    """servoJ: the setpoint averages the commands of the last ``lookahead`` seconds (the
    command sampled once a tick, so it is at most one tick old) and moves towards that
    average by ``gain * dt`` of the way each tick, within the joint speed limit. The delay
    is about lookahead / 2 + 1 / gain."""

    done = False

    def __init__(self, q: Sequence[float]) -> None:
        self.command = list(q)
        self.lookahead, self.gain = 0.1, 300.0
        self._window: deque[Vec] = deque()
        self._sum = [0.0] * N

    def set(self, q: Sequence[float], lookahead: float, gain: float) -> None:
        self.command = list(q)
        self.lookahead, self.gain = lookahead, gain

    def step(self, q: Vec, qd: Vec, dt: float, scale: float) -> tuple[Vec, Vec]:
        size = max(1, round(self.lookahead / dt))
        if not self._window:  # start from where the arm is, not from a jump
            self._window.extend([list(q)] * size)
            self._sum = [x * size for x in q]
        self._window.append(self.command)
        self._sum = [s + c for s, c in zip(self._sum, self.command, strict=True)]
        while len(self._window) > size:
            old = self._window.popleft()
            self._sum = [s - o for s, o in zip(self._sum, old, strict=True)]
        k = min(1.0, self.gain * dt)
        limit = JOINT_SPEED_LIMIT * dt
        new = []
        for x, s in zip(q, self._sum, strict=True):
            move = k * (s / len(self._window) - x)
            new.append(x + max(-limit, min(limit, move)))
        return new, [(n - x) / dt for n, x in zip(new, q, strict=True)]


class Speed:
    """speedJ: each joint's speed goes to its target at ``a`` rad/s^2 and stays there."""

    done = False

    def __init__(self) -> None:
        self.target, self.a = [0.0] * N, 1.0

    def set(self, qd: Sequence[float], a: float) -> None:
        self.target = [max(-JOINT_SPEED_LIMIT, min(JOINT_SPEED_LIMIT, v)) for v in qd]
        self.a = max(a, 1e-6)

    def step(self, q: Vec, qd: Vec, dt: float, scale: float) -> tuple[Vec, Vec]:
        dv = self.a * dt
        v = [c + max(-dv, min(dv, t * scale - c)) for c, t in zip(qd, self.target, strict=True)]
        return [x + s * dt for x, s in zip(q, v, strict=True)], v


class Stop:
    """stopJ and the other stops: every joint slows down at ``a`` rad/s^2 to a standstill."""

    def __init__(self, a: float) -> None:
        self.a = max(a, 1e-6)
        self.done = False

    def step(self, q: Vec, qd: Vec, dt: float, scale: float) -> tuple[Vec, Vec]:
        dv = self.a * dt
        v = [math.copysign(max(0.0, abs(s) - dv), s) for s in qd]
        self.done = not any(v)
        mean = [(s0 + s1) / 2 for s0, s1 in zip(qd, v, strict=True)]
        return [x + s * dt for x, s in zip(q, mean, strict=True)], v


class Arm:
    """Six joints: the setpoint the motion gives and where the arm actually is."""

    def __init__(self, q0: Sequence[float]) -> None:
        self.target, self.target_qd, self.target_qdd = list(q0), [0.0] * N, [0.0] * N
        self.actual, self.actual_qd = list(q0), [0.0] * N
        self.motion: Motion = Hold()
        self.frozen = False

    def start(self, motion: Motion) -> None:
        self.motion = motion

    def stop(self, a: float) -> None:
        """Slow down to a standstill (or keep standing)."""
        if any(self.target_qd):
            self.motion = Stop(a)
        else:
            self.motion = Hold()

    @property
    def steady(self) -> bool:
        return not any(self.target_qd)

    def unfreeze(self) -> None:
        """Move again, from where the arm is: the setpoint jumps back to it."""
        self.frozen = False
        self.target, self.target_qd, self.motion = list(self.actual), [0.0] * N, Hold()

    def step(self, scale: float) -> None:
        qd0 = self.target_qd
        self.target, self.target_qd = self.motion.step(self.target, qd0, DT, scale)
        self.target_qdd = [(b - a) / DT for a, b in zip(qd0, self.target_qd, strict=True)]
        if self.motion.done and not isinstance(self.motion, Hold):
            self.motion = Hold()
        if self.frozen:
            self.actual_qd = [0.0] * N
        else:
            self.actual, self.actual_qd = list(self.target), list(self.target_qd)
