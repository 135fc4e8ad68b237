"""What went wrong in a driver, as data (:class:`Fault`), and the two ways a driver says no.

- :class:`DriverFault`: something failed while the driver was working (an arm stopped
  following, a gripper did not reach its mode, a connection dropped). Both arms are
  stopped and the driver is in its error state; it carries the :class:`Fault`.
- :class:`DriverRefused`: a request was turned down before anything was sent (the arms are not
  where the segment starts, an event names an unknown gripper mode). Nothing moved and the
  driver's state is unchanged.

Both are :class:`~cellengine.errors.DriverError` s (exit code 3) whose one problem is
located at the driver: printed as "sim driver: <message>".
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, Literal

from cellengine.errors import DriverError, Problem

# tracking: a joint deviates from its command; gripper: a mode not reached; connection: lost;
# protective_stop, emergency_stop: reported by a controller; overrun: a segment took longer
# than allowed; interrupted: the user stopped it; internal: a bug (the exception's text);
# load_cell: a reading that is no mass
FaultKind = Literal[
    "tracking",
    "gripper",
    "tool",  # a tool changer that did not lock or unlock, a tool that did not start or stop
    "connection",
    "protective_stop",
    "emergency_stop",
    "overrun",
    "interrupted",
    "internal",
    "load_cell",
    "alarm",  # a GRBL controller's ALARM:N (a limit switch, a soft limit, ...)
    "controller_error",  # a GRBL controller answered a line error:N
]


@dataclass(frozen=True)
class Fault:
    """One fault: what (``kind``), where (arm, joint), when (program time, s), the value that
    gave it away (a joint's deviation, the mode a gripper stayed in), the full message, and
    whatever else a driver knows (``details``: e.g. a controller's safety status bits)."""

    kind: FaultKind
    message: str
    arm: str | None = None
    joint: str | None = None
    time: float | None = None
    value: float | str | None = None
    details: Mapping[str, Any] = field(default_factory=lambda: MappingProxyType({}), hash=False)

    def to_json(self) -> dict[str, Any]:
        return {
            "kind": self.kind,
            "message": self.message,
            "arm": self.arm,
            "joint": self.joint,
            "time": self.time,
            "value": self.value,
            "details": dict(self.details),
        }


class DriverFault(DriverError):
    """A fault during operation: the driver is in its error state."""

    def __init__(self, kind: str, fault: Fault) -> None:
        self.fault = fault
        # both robots at once: where their streams were at the fault (the runner fills it
        # in; the journal's fault entry keeps it for --resume)
        self.streams: dict[str, Any] | None = None
        super().__init__(Problem(fault.message, f"{kind} driver"))


class DriverRefused(DriverError):
    """A request refused before anything was sent; the driver's state is unchanged."""

    def __init__(self, kind: str, message: str) -> None:
        super().__init__(Problem(message, f"{kind} driver"))
