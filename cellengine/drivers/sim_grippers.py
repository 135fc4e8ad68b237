"""The simulated grippers: each arm's jaw mode and the object it holds."""

from __future__ import annotations

from collections.abc import Iterable

from cellengine.drivers.base import GripperState
from cellengine.program import GripperEvent


class SimGrippers:
    def __init__(self, initial: dict[str, GripperState]) -> None:
        self._state = dict(initial)

    def __getitem__(self, arm: str) -> GripperState:
        return self._state[arm]

    def items(self) -> Iterable[tuple[str, GripperState]]:
        return self._state.items()

    def snapshot(self) -> dict[str, GripperState]:
        return dict(self._state)

    def set(self, arm: str, state: GripperState) -> None:
        self._state[arm] = state

    def apply(self, event: GripperEvent, works: bool) -> bool:
        """Change mode and what is held; a gripper that does not work keeps both."""
        if works:
            self._state[event.arm] = GripperState(event.mode, event.holds)
        return works
