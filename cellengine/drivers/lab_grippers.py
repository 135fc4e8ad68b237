"""The lab bench's grippers and load cells on the driver's clock: each gripper event set at
its time (without stopping the axes' streams), each mode confirmed (dynamixel_grip.py), a
gripper that does not do it a fault."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from cellengine.drivers.base import GripperState
from cellengine.drivers.dynamixel_grip import Gripper, GripperError
from cellengine.drivers.fault import Fault
from cellengine.program import TimedEvent

STOPPED = "both robots stopped (feed hold)"


class Grippers:
    """The grippers of the arms that have one, and what each holds."""

    def __init__(
        self, grippers: Mapping[str, Gripper], holding: Mapping[str, tuple[str, ...]]
    ) -> None:
        self.grippers = dict(grippers)
        self.holding = dict(holding)  # each arm's modes that close on something
        self.states = {arm: GripperState(None, None) for arm in grippers}
        self._due: list[TimedEvent] = []
        # each gripper taking a mode, and the state it will be in once it has: a grasp
        # that does not close leaves the gripper as it was (it holds nothing)
        self._moving: dict[str, GripperState] = {}

    def start(self, events: Sequence[TimedEvent]) -> None:
        self._due = sorted(events, key=lambda e: e.time)

    def at(self, t: float) -> Fault | None:
        who = None
        try:
            while self._due and self._due[0].time <= t:
                e = self._due.pop(0).event
                who = e.arm
                self.grippers[e.arm].set(e.mode, e.mode in self.holding.get(e.arm, ()))
                self._moving[e.arm] = GripperState(e.mode, e.holds)
            for who in sorted(self._moving):
                if self.grippers[who].settled():
                    self.states[who] = self._moving.pop(who)
        except GripperError as err:
            return Fault("gripper", f"gripper of '{who}': {err}; {STOPPED}", who, time=t)
        return None

    def busy(self) -> bool:
        return bool(self._due or self._moving)
