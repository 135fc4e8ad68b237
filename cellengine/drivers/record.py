"""The log of what a driver was asked to do and what happened: plain data, in order.

Entries are frozen dataclasses with ``to_json()``; the run journal and the report read them
(or subscribe with :meth:`Recorder.listen` to get each entry as it is added, e.g. to append
it to ``journal.jsonl`` and flush). Times are program times (the time axis of the
trajectories played), in seconds.

- :class:`Transition`: a lifecycle change (``configure``: unconfigured -> inactive, ...).
- :class:`Sent`: a segment about to be played, with where the arms are.
- :class:`Played`: the segment as played: every servo tick's time, the commanded and the
  measured q (cell order), the gripper events as applied, the largest deviation per joint,
  and the fault that stopped it, if one did (then the arrays end at the stop).
- :class:`FaultRecord`: a fault, with the state of both arms when they were stopped.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any, TypeVar

import numpy as np
from numpy.typing import NDArray

from cellengine.arrays import FloatArray
from cellengine.drivers.fault import Fault


@dataclass(frozen=True)
class Transition:
    name: str  # configure | activate | deactivate | finalize | recover | fault
    source: str
    target: str

    def to_json(self) -> dict[str, Any]:
        return {"entry": "transition", "name": self.name, "from": self.source, "to": self.target}


@dataclass(frozen=True)
class Sent:
    step: int
    label: str
    start: float  # the segment's planned start and end
    end: float
    q: tuple[float, ...]  # measured when sent

    def to_json(self) -> dict[str, Any]:
        return {
            "entry": "sent",
            "step": self.step,
            "label": self.label,
            "start": self.start,
            "end": self.end,
            "q": list(self.q),
        }


@dataclass(frozen=True)
class ToolChanged:
    """An arm's tool changer locked ``tool`` (None: unlocked, leaving ``was`` in its slot)."""

    arm: str
    tool: str | None
    was: str | None

    def to_json(self) -> dict[str, Any]:
        return {"entry": "tool", "arm": self.arm, "tool": self.tool, "was": self.was}


@dataclass(frozen=True)
class Triggered:
    """``arm``'s ``tool`` worked from program time ``start`` to ``end`` (a taping gun)."""

    arm: str
    tool: str
    start: float
    end: float

    def to_json(self) -> dict[str, Any]:
        return {
            "entry": "triggered",
            "arm": self.arm,
            "tool": self.tool,
            "start": self.start,
            "end": self.end,
        }


@dataclass(frozen=True)
class AppliedEvent:
    time: float  # when it was applied (the servo tick), program time
    arm: str
    mode: str
    holds: str | None
    done: bool  # False: the gripper did not reach the mode

    def to_json(self) -> dict[str, Any]:
        return {
            "time": self.time,
            "arm": self.arm,
            "mode": self.mode,
            "holds": self.holds,
            "done": self.done,
        }


@dataclass(frozen=True, eq=False)
class Played:
    step: int
    label: str
    joint_names: tuple[str, ...]
    t: FloatArray  # (M,) servo ticks
    commanded: FloatArray  # (M, n)
    measured: FloatArray  # (M, n)
    events: tuple[AppliedEvent, ...]
    fault: Fault | None = None
    late: float | None = None  # realtime: the largest lateness of a tick (s)
    max_deviation: FloatArray = field(init=False)  # (n,) max |commanded - measured|

    def __post_init__(self) -> None:
        for name in ("t", "commanded", "measured"):
            a = np.array(getattr(self, name), dtype=np.float64)
            a.flags.writeable = False
            object.__setattr__(self, name, a)
        dev = np.abs(self.commanded - self.measured)
        worst = dev.max(axis=0) if len(dev) else np.zeros(len(self.joint_names))
        worst.flags.writeable = False
        object.__setattr__(self, "max_deviation", worst)

    @property
    def completed(self) -> bool:
        return self.fault is None

    def to_json(self, every: int = 1) -> dict[str, Any]:
        """JSON-ready; ``every`` keeps one tick in that many (and always the last)."""
        keep = _decimated(len(self.t), every)
        return {
            "entry": "played",
            "step": self.step,
            "label": self.label,
            "joint_names": list(self.joint_names),
            "t": self.t[keep].tolist(),
            "commanded": self.commanded[keep].tolist(),
            "measured": self.measured[keep].tolist(),
            "events": [e.to_json() for e in self.events],
            "fault": self.fault.to_json() if self.fault else None,
            "late": self.late,
            "max_deviation": self.max_deviation.tolist(),
        }


@dataclass(frozen=True)
class FaultRecord:
    fault: Fault
    q: tuple[float, ...]  # where both arms were stopped (cell order)
    grippers: tuple[tuple[str, str | None, str | None], ...]  # (arm, mode, holds)

    def to_json(self) -> dict[str, Any]:
        return {
            "entry": "fault",
            **self.fault.to_json(),
            "q": list(self.q),
            "grippers": [{"arm": a, "mode": m, "holds": h} for a, m, h in self.grippers],
        }


Entry = Transition | Sent | Played | FaultRecord | ToolChanged | Triggered
E = TypeVar("E", Transition, Sent, Played, FaultRecord)


def _decimated(count: int, every: int) -> NDArray[np.intp]:
    if every < 1:
        raise ValueError(f"every must be at least 1, got {every}")
    keep = np.arange(0, count, every)
    if count and keep[-1] != count - 1:
        keep = np.append(keep, count - 1)
    return keep


class Recorder:
    """Every entry in the order it happened; listeners hear each one as it is added."""

    def __init__(self) -> None:
        self.entries: list[Entry] = []
        self._listeners: list[Callable[[Entry], None]] = []

    def listen(self, callback: Callable[[Entry], None]) -> None:
        self._listeners.append(callback)

    def add(self, entry: Entry) -> None:
        self.entries.append(entry)
        for callback in self._listeners:
            callback(entry)

    def of(self, kind: type[E]) -> list[E]:
        return [e for e in self.entries if isinstance(e, kind)]

    def __iter__(self) -> Iterator[Entry]:
        return iter(self.entries)

    def __len__(self) -> int:
        return len(self.entries)

    def to_json(self, every: int = 1) -> list[dict[str, Any]]:
        """All entries, JSON-ready; played ticks decimated to one in ``every``."""
        return [e.to_json(every) if isinstance(e, Played) else e.to_json() for e in self.entries]
