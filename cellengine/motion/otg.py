"""ruckig where joint space is free: point-to-point moves and online re-targeting.

ruckig (Berscheid & Kroeger 2021) computes time-optimal, jerk-limited motions between
arbitrary states in microseconds. A ptp move is one ruckig trajectory, turned into a
`Trajectory` exactly: knots at every phase boundary of every joint, where each joint is a
cubic in between, which a quintic piece reproduces. `Retargeter` wraps ruckig's online
(OTG) interface for a driver loop at a fixed period.

Jerk: a Trajectory is C2 (accelerations continuous), so "no jerk limit" cannot mean an
infinite jerk. It means accelerations ramp over `UNLIMITED_JERK_RAMP` seconds, one servo
period at 500 Hz (jerk = acceleration / ramp), the same convention as timing.py.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import ruckig
from numpy.typing import ArrayLike

from cellengine.arrays import FloatArray
from cellengine.motion.trajectory import Trajectory

UNLIMITED_JERK_RAMP = 0.002
# Phase boundaries closer than this are one knot (ruckig gives zero-length phases).
_SAME_TIME = 1e-9


def jerk_or_default(acceleration: FloatArray, jerk: ArrayLike | None) -> FloatArray:
    """The jerk limits to use: the given ones, or accelerations ramping over one servo
    period when none are given."""
    if jerk is None:
        return np.asarray(acceleration / UNLIMITED_JERK_RAMP, dtype=np.float64)
    out = np.broadcast_to(np.asarray(jerk, dtype=np.float64), acceleration.shape).copy()
    if not np.all(out > 0.0):
        raise ValueError(f"jerk limits must be positive, got {out.tolist()}")
    return out


def default_names(dof: int) -> tuple[str, ...]:
    return tuple(f"joint_{i + 1}" for i in range(dof))


def _input(
    dof: int, velocity: FloatArray, acceleration: FloatArray, jerk: FloatArray
) -> ruckig.InputParameter:
    inp = ruckig.InputParameter(dof)
    inp.max_velocity = velocity.tolist()
    inp.max_acceleration = acceleration.tolist()
    inp.max_jerk = jerk.tolist()
    # one straight line in joint space when ruckig can, else every joint finishing together
    inp.synchronization = ruckig.Synchronization.Phase
    return inp


def _check_in_range(what: str, q: FloatArray, lower: FloatArray, upper: FloatArray) -> None:
    outside = (q < lower) | (q > upper)
    if np.any(outside):
        j = int(np.argmax(outside))
        raise ValueError(
            f"{what}: joint {j} at {q[j]:.6g} is outside its range [{lower[j]:.6g}, {upper[j]:.6g}]"
        )


def ptp(
    q0: ArrayLike,
    q1: ArrayLike,
    lower: FloatArray,
    upper: FloatArray,
    velocity: FloatArray,
    acceleration: FloatArray,
    jerk: FloatArray,
    joint_names: Sequence[str] | None = None,
) -> Trajectory:
    """The time-optimal jerk-limited rest-to-rest move from q0 to q1, every joint
    starting and finishing together (both arms when given both arms' joints)."""
    start = np.asarray(q0, dtype=np.float64)
    goal = np.asarray(q1, dtype=np.float64)
    dof = velocity.size
    if start.shape != (dof,) or goal.shape != (dof,):
        raise ValueError(f"q0 and q1 must have {dof} values, got {start.shape} and {goal.shape}")
    _check_in_range("start", start, lower, upper)
    _check_in_range("goal", goal, lower, upper)
    names = tuple(joint_names) if joint_names is not None else default_names(dof)
    inp = _input(dof, velocity, acceleration, jerk)
    inp.current_position = start.tolist()
    inp.target_position = goal.tolist()
    plan = ruckig.Trajectory(dof)
    result = ruckig.Ruckig(dof).calculate(inp, plan)
    if result != ruckig.Result.Working:
        raise ValueError(f"ruckig could not plan the move: {result}")
    return _to_trajectory(plan, names, goal)


def _to_trajectory(plan: ruckig.Trajectory, names: tuple[str, ...], goal: FloatArray) -> Trajectory:
    """Knots at every joint's phase boundaries: in between, each joint is a cubic."""
    duration = float(plan.duration)
    times = [0.0, duration]
    for section in plan.profiles:
        for profile in section:
            times.extend(np.cumsum([profile.brake.duration, *profile.t]).tolist())
    knots = np.unique(np.clip(np.array(times), 0.0, duration))
    knots = knots[np.concatenate([[True], np.diff(knots) > _SAME_TIME])]
    knots[-1] = duration
    if knots.size == 1:  # already there: a single resting point
        zero = np.zeros((1, goal.size))
        return Trajectory(names, np.zeros(1), goal[None, :], zero, zero)
    states = [plan.at_time(float(t)) for t in knots]
    q = np.array([s[0] for s in states])
    qd = np.array([s[1] for s in states])
    qdd = np.array([s[2] for s in states])
    q[-1], qd[-1], qdd[-1] = goal, 0.0, 0.0  # exactly at rest on the goal
    qd[0], qdd[0] = 0.0, 0.0
    return Trajectory(names, knots, q, qd, qdd)


class Retargeter:
    """Online trajectory generation for streaming to a driver: each `step()` advances one
    period `dt` (0.002 s for a UR's servoJ at 500 Hz) along ruckig's time-optimal
    jerk-limited motion from the current state toward the target, which `set_target` may
    change between any two steps. Velocity, acceleration and jerk stay within the limits
    throughout; position limits are checked on every target (and ruckig refuses a motion
    that would leave them).
    """

    def __init__(
        self,
        q0: ArrayLike,
        lower: FloatArray,
        upper: FloatArray,
        velocity: FloatArray,
        acceleration: FloatArray,
        jerk: FloatArray,
        dt: float = 0.002,
    ) -> None:
        if not dt > 0.0:
            raise ValueError(f"dt must be positive, got {dt!r}")
        start = np.asarray(q0, dtype=np.float64)
        self.dof = velocity.size
        if start.shape != (self.dof,):
            raise ValueError(f"q0 must have {self.dof} values, got shape {start.shape}")
        _check_in_range("start", start, lower, upper)
        self.dt = float(dt)
        self._lower, self._upper = lower, upper
        self._otg = ruckig.Ruckig(self.dof, self.dt)
        self._inp = _input(self.dof, velocity, acceleration, jerk)
        self._inp.min_position = lower.tolist()
        self._inp.max_position = upper.tolist()
        self._inp.current_position = start.tolist()
        self._inp.current_velocity = [0.0] * self.dof
        self._inp.current_acceleration = [0.0] * self.dof
        self._inp.target_position = start.tolist()
        self._out = ruckig.OutputParameter(self.dof)
        self._time = 0.0
        self._finished = True

    @property
    def time(self) -> float:
        """Seconds stepped since construction."""
        return self._time

    @property
    def finished(self) -> bool:
        """True once the state is at the target (positions, velocities)."""
        return self._finished

    @property
    def target(self) -> FloatArray:
        return np.array(self._inp.target_position)

    def state(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Current positions, velocities, accelerations."""
        inp = self._inp
        return (
            np.array(inp.current_position),
            np.array(inp.current_velocity),
            np.array(inp.current_acceleration),
        )

    def set_target(self, q: ArrayLike, qd: ArrayLike | None = None) -> None:
        """Aim at positions q (and velocities qd, zero by default) from the next step on."""
        goal = np.asarray(q, dtype=np.float64)
        if goal.shape != (self.dof,):
            raise ValueError(f"target must have {self.dof} values, got shape {goal.shape}")
        _check_in_range("target", goal, self._lower, self._upper)
        speed = np.zeros(self.dof) if qd is None else np.asarray(qd, dtype=np.float64)
        if speed.shape != (self.dof,):
            raise ValueError(f"target velocity must have {self.dof} values")
        self._inp.target_position = goal.tolist()
        self._inp.target_velocity = speed.tolist()
        self._finished = False

    def step(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Advance one period; the new positions, velocities and accelerations."""
        result = self._otg.update(self._inp, self._out)
        if result not in (ruckig.Result.Working, ruckig.Result.Finished):
            raise RuntimeError(f"ruckig refused the motion: {result}")
        self._out.pass_to_input(self._inp)
        self._time += self.dt
        self._finished = result == ruckig.Result.Finished
        return self.state()
