"""The lab bench's rotation joints on Dynamixel servos, on the driver's clock beside the
GRBL streams: each segment's goals written every ``PERIOD`` s, one period ahead of the plan
(the servo's profile gets there), its position read as often and tracked within a window
of the plan's time, as GRBL's axes are (lab_stream.py); the segment ends when each servo
has reached its last goal."""

from __future__ import annotations

import math
import time
from collections.abc import Mapping

import numpy as np

from cellengine.drivers.dynamixel_joint import ServoError, ServoJoint
from cellengine.drivers.fault import Fault
from cellengine.motion.trajectory import Trajectory

STOPPED = "both robots stopped (feed hold)"
PERIOD = 0.02  # s between goals (50 Hz)
WINDOW = 0.25  # s: a servo is on the plan when it is where the plan is at most this off in time
REACHED = 0.01  # rad of the last goal: the segment's end reached
SETTLE = 1.0  # s after the segment's end for the servos to reach their last goal


class ServoJoints:
    """``joints``: the cell's joint index -> (robot, joint name, its servo)."""

    def __init__(self, joints: Mapping[int, tuple[str, str, ServoJoint]], tolerance: float) -> None:
        self.joints = dict(joints)
        self.tolerance = tolerance  # rad
        self._traj: Trajectory | None = None
        self._next = -math.inf
        self._ended: float | None = None  # wall time the plan's end was first due
        self.positions: dict[int, float] = {}  # each servo's last read (rad)
        self.samples: list[tuple[float, dict[int, float]]] = []  # (program time, reads)

    def start(self, traj: Trajectory) -> None:
        self._traj, self._next, self._ended = traj, -math.inf, None
        self.samples = []

    def at(self, t: float) -> Fault | None:
        traj = self._traj
        if traj is None or not self.joints or t < self._next:
            return None
        self._next = t + PERIOD
        goals = traj.sample(np.array([min(t + PERIOD, traj.end_time)]))[0][0]
        for j, (robot, name, servo) in self.joints.items():
            try:
                servo.goal(float(goals[j]))
                self.positions[j] = servo.position()
            except ServoError as e:
                return Fault("connection", f"robot '{robot}' joint '{name}': {e}; {STOPPED}", robot)
            off = self._off(traj, j, t)
            if off > self.tolerance:
                return Fault(
                    "tracking",
                    f"robot '{robot}' joint '{name}' (Dynamixel) is {off:.3f} rad off the plan "
                    f"(more than {self.tolerance:g}); {STOPPED}",
                    robot,
                    name,
                    time=t,
                    value=off,
                )
        self.samples.append((t, dict(self.positions)))
        if t >= traj.end_time and self._ended is None:
            self._ended = time.monotonic()
        return None

    def busy(self) -> bool:
        """Until every servo is at the segment's last goal (a fault past SETTLE s)."""
        traj = self._traj
        if traj is None or not self.joints:
            return False
        last = traj.q[-1]
        away = [j for j in self.joints if abs(self.positions.get(j, math.inf) - last[j]) > REACHED]
        if away and self._ended is not None and time.monotonic() - self._ended > SETTLE:
            return False  # at() reports it as off the plan
        return bool(away)

    def fill(self, times: list[float], rows: list[np.ndarray]) -> None:
        """The servos' columns of the measured ``rows`` (at program ``times``): their reads
        interpolated to each row's time."""
        if not self.samples or not rows:
            return
        at = np.array([t for t, _ in self.samples])
        for j in self.joints:
            read = np.array([p.get(j, np.nan) for _, p in self.samples])
            values = np.interp(times, at, read)
            for row, v in zip(rows, values, strict=True):
                row[j] = v

    def _off(self, traj: Trajectory, j: int, t: float) -> float:
        """How far the servo is from where the plan has its joint within WINDOW of ``t``."""
        times = np.linspace(max(traj.start_time, t - WINDOW), min(traj.end_time, t + WINDOW), 51)
        q = traj.sample(times)[0][:, j]
        return float(np.min(np.abs(q - self.positions[j])))
