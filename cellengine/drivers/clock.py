"""The clocks a simulated execution runs on: simulated time (no waiting) or real time."""

from __future__ import annotations

import time
from typing import Protocol


class Clock(Protocol):
    def start(self, t0: float) -> None:
        """Program time ``t0`` is now."""

    def wait_until(self, t: float) -> float:
        """Return when program time ``t`` has come; the lateness (s) of that return."""


class SimulatedClock:
    """As fast as possible: every tick is on time."""

    def start(self, t0: float) -> None:
        pass

    def wait_until(self, t: float) -> float:
        return 0.0


class RealClock:
    """Program time runs with the wall clock (time.perf_counter) from ``start``."""

    def __init__(self) -> None:
        self._wall0 = 0.0
        self._t0 = 0.0

    def start(self, t0: float) -> None:
        self._wall0, self._t0 = time.perf_counter(), t0

    def wait_until(self, t: float) -> float:
        deadline = self._wall0 + (t - self._t0)
        ahead = deadline - time.perf_counter()
        if ahead > 0:
            time.sleep(ahead)
        return max(0.0, time.perf_counter() - deadline)


SPIN = 0.0002  # s: the last stretch before a deadline is waited out busily


def sleep_until(deadline: float) -> None:
    """Return at ``deadline`` (time.perf_counter): sleep, then spin the last SPIN seconds,
    as a sleep alone wakes up to a tenth of a millisecond late."""
    ahead = deadline - time.perf_counter() - SPIN
    if ahead > 0:
        time.sleep(ahead)
    while time.perf_counter() < deadline:
        pass
