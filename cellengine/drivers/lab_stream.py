"""Playing one segment on the lab bench's GRBL controllers from one clock.

Each robot's blocks (gcode.py) are sent when their start is within ``LOOKAHEAD`` of the
program's time and they fit in the controller's receive buffer (character counting). Both
controllers are held while their buffers fill with the first blocks, then started with one
cycle start each: both robots begin on one instant with their planners full (GRBL, with no
clock of its own, would otherwise plan the first blocks to stop at the end of a short
queue and trail the plan from then on).
Status reports are asked for at the cell's rate (>= 10 Hz) and each is compared with where
the plan has that robot then. An alarm, an ``error:N``, a lost port, a robot off its plan or
a segment that overruns is a fault: a feed hold on every controller at once (the time from
detection to the last hold written is kept), then, once they stand, a soft reset that
empties their queues without losing position.
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Protocol

import numpy as np

from cellengine.drivers.fault import Fault
from cellengine.drivers.gcode import AxisMap, Block, blocks
from cellengine.drivers.grbl_link import ALARMS, ERRORS, GrblLink, GrblLost
from cellengine.motion.trajectory import Trajectory
from cellengine.program import SAME_INSTANT

LOOKAHEAD = 1.0  # s of blocks sent ahead of the program's time
STOPPED = "both robots stopped (feed hold)"
HOLD_WAIT = 2.0  # s for the robots to stand after a feed hold
OVERRUN = 1.5  # a segment may take this many times its duration (plus 2 s) before it stops
LAG = 0.25  # s a robot may trail the plan's time (five blocks)
PRIME_WAIT = 1.0  # s at most for the controllers to take the first blocks before the start
LAG_SAMPLES = 26  # the plan's moments it is compared with, over LAG


class Side(Protocol):
    def at(self, t: float) -> Fault | None:
        """Do what is due at program time ``t``; the fault if something failed."""

    def busy(self) -> bool:
        """Whether something it started has not finished."""


@dataclass(frozen=True)
class Sides:
    """What else is done on the same clock, each in turn: the grippers, servo joints."""

    parts: Sequence[Side]

    def at(self, t: float) -> Fault | None:
        for part in self.parts:
            fault = part.at(t)
            if fault is not None:
                return fault
        return None

    def busy(self) -> bool:
        return any(part.busy() for part in self.parts)


@dataclass
class Stream:
    """One robot's part of a segment."""

    robot: str
    link: GrblLink
    axes: Sequence[AxisMap]
    blocks: list[Block]
    sent: int = 0
    seen: float = 0.0  # the last status report looked at (its arrival time)


@dataclass
class Outcome:
    times: list[float] = field(default_factory=list)  # program time of each status sample
    measured: list[np.ndarray] = field(default_factory=list)  # the cell's q then
    fault: Fault | None = None
    hold_latency: float | None = None  # s from detection to the last feed hold written
    # each block sent after the start: how long before its planned start it went (s)
    leads: list[float] = field(default_factory=list)
    blocks: int = 0  # blocks sent, every controller


def play(
    traj: Trajectory,
    links: Mapping[str, GrblLink],
    axes: Mapping[str, Sequence[AxisMap]],
    accel: Mapping[str, Sequence[float]],
    q_now: np.ndarray,
    tolerance: tuple[float, float],
    status_hz: float,
    joint_names: Sequence[str],
    side: Side | None = None,
) -> Outcome:
    """Play ``traj`` (see the module notes); ``side``: what else is done on the same clock
    (the grippers), asked at every turn of the loop."""
    streams = [Stream(r, links[r], axes[r], blocks(traj, axes[r], accel.get(r))) for r in links]
    out = Outcome()
    q = np.array(q_now, dtype=float)
    try:
        _prime(streams, traj.start_time)
    except GrblLost as e:
        lost = Fault("connection", f"{e}; {STOPPED}", time=traj.start_time)
        return _stopped(out, lost, streams, traj.end_time)
    wall0 = time.perf_counter()
    period = 1.0 / status_hz
    next_status = wall0
    deadline = wall0 + OVERRUN * traj.duration + 2.0
    while True:
        now = time.perf_counter()
        t = traj.start_time + (now - wall0)
        try:
            for s in streams:
                _feed(s, t, out)
            if now >= next_status:
                for s in streams:
                    s.link.ask_status()
                next_status += period
            for s in streams:
                s.link.poll()
        except GrblLost as e:
            out.fault = Fault("connection", f"{e}; {STOPPED}", time=t)
        fault = out.fault or _check(streams, traj, q, out, tolerance, joint_names, wall0, t)
        if fault is None and side is not None:
            fault = side.at(t)
        # a gripper still taking its mode has its own timeout, which names it
        if fault is None and now > deadline and (side is None or not side.busy()):
            fault = Fault(
                "overrun", f"the segment ran past {deadline - wall0:.1f} s; {STOPPED}", time=t
            )
        if fault is not None:
            return _stopped(out, fault, streams, traj.end_time)
        if _done(streams, traj, t) and (side is None or not side.busy()):
            return out
        time.sleep(0.001)


# s before a segment's end: a fault while its robots stand at the end is in the segment
UNFINISHED = 1e3 * SAME_INSTANT


def _stopped(out: Outcome, fault: Fault, streams: list[Stream], end: float) -> Outcome:
    """Every controller held at once; the fault journaled with how long that took from its
    detection (``hold_commands_s``: the feed holds written, as the UR driver's
    ``stop_commands_s``), before the segment's end (``end``): past it the robots stand
    there, waiting for a gripper to take its mode or a controller to finish, and the
    segment has not finished (a resumed run does what is left of it, its last gripper
    event too)."""
    out.hold_latency = _hold(streams)
    details = {**fault.details, "hold_commands_s": round(out.hold_latency, 6)}
    at = None if fault.time is None else min(fault.time, end - UNFINISHED)
    out.fault = replace(fault, details=details, time=at)
    return out


def _prime(streams: list[Stream], t0: float) -> None:
    """Every controller held, then filled with the blocks of the first LOOKAHEAD s (as
    many as its buffers take), then all started at once: each robot begins with its
    planner full, as a running one has it, and both on one instant."""
    for s in streams:
        s.link.hold()
    deadline = time.perf_counter() + PRIME_WAIT
    while time.perf_counter() < deadline:
        for s in streams:
            _feed(s, t0)
            s.link.poll(0.001)
        if all(_primed(s, t0) for s in streams):
            break
    for s in streams:
        s.link.resume()


def _primed(s: Stream, t0: float) -> bool:
    if s.sent >= len(s.blocks) or s.blocks[s.sent].start > t0 + LOOKAHEAD:
        return True
    return not s.link.fits(s.blocks[s.sent].line)  # its buffers are full


def _feed(s: Stream, t: float, out: Outcome | None = None) -> None:
    while s.sent < len(s.blocks):
        b = s.blocks[s.sent]
        if b.start > t + LOOKAHEAD or not s.link.fits(b.line):
            return
        s.link.stream(b.line)
        s.sent += 1
        if out is not None:
            out.leads.append(b.start - t)
            out.blocks += 1


def _check(
    streams: list[Stream],
    traj: Trajectory,
    q: np.ndarray,
    out: Outcome,
    tolerance: tuple[float, float],
    joint_names: Sequence[str],
    wall0: float,
    now: float,
) -> Fault | None:
    """The first fault in what the controllers said (at program time ``now``); each new
    status recorded."""
    for s in streams:
        link = s.link
        if link.alarm is not None:
            what = ALARMS.get(link.alarm, "")
            return Fault(
                "alarm",
                f"robot '{s.robot}' ({link.port}): ALARM:{link.alarm} ({what}); {STOPPED}",
                s.robot,
                time=now,
                value=link.alarm,
            )
        if link.errors:
            line, code = link.errors[0]
            return Fault(
                "controller_error",
                f"robot '{s.robot}' ({link.port}) answered '{line}' with error:{code} "
                f"({ERRORS.get(code, '')}); {STOPPED}",
                s.robot,
                time=now,
                value=code,
            )
        status = link.last
        if status is None or status.time <= s.seen or not status.mpos:
            continue
        s.seen = status.time
        t = traj.start_time + (status.time - wall0)
        for a in s.axes:
            q[a.joint] = a.joint_value(status.mpos["XYZA".index(a.letter)])
        out.times.append(t)
        out.measured.append(q.copy())
        # GRBL keeps to the plan's time only as well as its planner can (it has no clock):
        # on track if it is where the plan is at some moment within LAG s of now
        lo, hi = max(traj.start_time, t - LAG), min(traj.end_time, t + LAG)
        window = np.linspace(lo, max(lo, hi), LAG_SAMPLES)
        planned = traj.sample(window)[0]
        cols = [a.joint for a in s.axes]
        most = np.array([tolerance[1] if a.letter == "A" else tolerance[0] for a in s.axes])
        off = np.abs(planned[:, cols] - q[cols])  # (samples, axes)
        best = int(np.argmin((off / most).max(axis=1)))
        k = int(np.argmax(off[best] / most))
        if off[best, k] > most[k]:
            name = joint_names[s.axes[k].joint]
            return Fault(
                "tracking",
                f"robot '{s.robot}' joint '{name}' is {off[best, k]:.4f} from the plan at "
                f"t = {t:.3f} s (the nearest within {LAG:g} s; tolerance {most[k]:g}); "
                f"{STOPPED}",
                s.robot,
                name,
                t,
                float(off[best, k]),
            )
    return None


def _done(streams: list[Stream], traj: Trajectory, t: float) -> bool:
    if t < traj.end_time:
        return False
    for s in streams:
        status = s.link.last
        if s.sent < len(s.blocks) or s.link.pending or status is None:
            return False
        if status.state != "Idle" or status.planner_free != 15:
            return False
    return True


def _hold(streams: list[Stream]) -> float:
    """A feed hold on every controller at once, then, once they stand (or after
    HOLD_WAIT), a soft reset; the time from detection to the last hold written."""
    detected = time.perf_counter()
    for s in streams:
        with contextlib.suppress(GrblLost):
            s.link.hold()
    latency = time.perf_counter() - detected
    deadline = detected + HOLD_WAIT
    live = list(streams)
    while live and time.perf_counter() < deadline:
        for s in list(live):
            try:
                s.link.ask_status()
                s.link.poll(0.01)
            except GrblLost:
                live.remove(s)
                continue
            st = s.link.last
            if s.link.alarm is not None or (st is not None and st.state in ("Hold:0", "Idle")):
                live.remove(s)
    for s in streams:
        with contextlib.suppress(GrblLost):
            s.link.reset()
    return latency
