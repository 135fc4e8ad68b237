"""Playing a whole :class:`~cellengine.program.Program` on a driver, segment by segment.

Each of the program's timed events goes with the first segment whose time span contains it
(an event at the instant one segment ends and the next begins goes with the earlier one, at
its last tick: the arms are at the same place either way), so events keep their program
order. An event in no segment's span is a program error.
"""

from __future__ import annotations

from cellengine.drivers.base import EVENT_TIME_SLACK, Driver
from cellengine.drivers.record import Played
from cellengine.program import Program, TimedEvent


def segment_events(program: Program) -> list[tuple[TimedEvent, ...]]:
    """The events of each segment of ``program``, in program order."""
    spans = [(s.trajectory.start_time, s.trajectory.end_time) for s in program.segments]
    out: list[list[TimedEvent]] = [[] for _ in spans]
    for ev in program.events:
        k = next(
            (
                i
                for i, (lo, hi) in enumerate(spans)
                if lo - EVENT_TIME_SLACK <= ev.time <= hi + EVENT_TIME_SLACK
            ),
            None,
        )
        if k is None:
            raise ValueError(
                f"event '{ev.event.mode}' of arm '{ev.event.arm}' at t = {ev.time:.3f} s is "
                "in no segment of the program"
            )
        out[k].append(ev)
    return [tuple(events) for events in out]


def play(driver: Driver, program: Program) -> list[Played]:
    """Execute every segment of ``program`` with its events on an active ``driver``; a
    fault raises DriverFault after the segment it happened in (the rest is not sent)."""
    return [
        driver.execute(segment, events)
        for segment, events in zip(program.segments, segment_events(program), strict=True)
    ]
