"""The one lifecycle every driver follows (after ros2_control's managed nodes).

::

    unconfigured --configure--> inactive --activate--> active
                                inactive <-deactivate-- active
    unconfigured | inactive | active | error --finalize--> finalized
    any fault --> error --recover--> inactive (or unconfigured, if the fault came first)

- ``configure`` connects and reads where the arms are; ``activate`` makes the driver ready
  to move them (arms a watchdog on real hardware); only an active driver executes.
- Asking for the state a driver is already in is a no-op (activate when active, deactivate
  when inactive, configure when inactive, finalize when finalized).
- A fault moves the driver to ``error`` and it stays there until someone calls
  ``recover()``; it never resumes on its own. ``finalize`` is allowed from every state so a
  driver can always be shut down (connections released), even after a fault.
- An illegal request raises :class:`LifecycleError` naming the state and what is allowed
  from it; the state does not change.
"""

from __future__ import annotations

from collections.abc import Iterable
from enum import StrEnum

from cellengine.errors import DriverError, Problem


class State(StrEnum):
    UNCONFIGURED = "unconfigured"
    INACTIVE = "inactive"
    ACTIVE = "active"
    FINALIZED = "finalized"
    ERROR = "error"


# transition -> (states it starts from, state it leads to). recover's target is decided at
# run time (inactive when the driver was configured before the fault, else unconfigured).
TRANSITIONS: dict[str, tuple[frozenset[State], State]] = {
    "configure": (frozenset({State.UNCONFIGURED}), State.INACTIVE),
    "activate": (frozenset({State.INACTIVE}), State.ACTIVE),
    "deactivate": (frozenset({State.ACTIVE}), State.INACTIVE),
    "recover": (frozenset({State.ERROR}), State.INACTIVE),
    "finalize": (
        frozenset({State.UNCONFIGURED, State.INACTIVE, State.ACTIVE, State.ERROR}),
        State.FINALIZED,
    ),
}
# requests that are no-ops in their target state
IDEMPOTENT: dict[str, State] = {
    "configure": State.INACTIVE,
    "activate": State.ACTIVE,
    "deactivate": State.INACTIVE,
    "finalize": State.FINALIZED,
}
# operations that are not transitions, and the states they need
OPERATIONS: dict[str, frozenset[State]] = {
    "execute": frozenset({State.ACTIVE}),
    "change_tool": frozenset({State.ACTIVE}),
    "joint_state": frozenset({State.INACTIVE, State.ACTIVE, State.ERROR}),
    "gripper": frozenset({State.INACTIVE, State.ACTIVE, State.ERROR}),
    "read_mass": frozenset({State.INACTIVE, State.ACTIVE}),
}
# how refusals name the operations that are not transitions
DISPLAY = {
    "change_tool": "change tools",
    "joint_state": "read joint states",
    "gripper": "read grippers",
    "read_mass": "read masses",
}
# states in which the driver holds a configuration (a connection, the arms' state)
CONFIGURED = frozenset({State.INACTIVE, State.ACTIVE})


class LifecycleError(DriverError):
    """A request the current state does not allow; the state is unchanged."""

    def __init__(self, kind: str, message: str) -> None:
        super().__init__(Problem(message, f"{kind} driver"))


def allowed_from(state: State) -> tuple[str, ...]:
    """The transitions that leave ``state``, in lifecycle order."""
    return tuple(name for name, (sources, _) in TRANSITIONS.items() if state in sources)


def _names(states: Iterable[State]) -> str:
    order = list(State)
    names = [f"'{s}'" for s in sorted(states, key=order.index)]
    return names[0] if len(names) == 1 else ", ".join(names[:-1]) + " or " + names[-1]


def refusal(op: str, state: State, needs: Iterable[State]) -> str:
    """The message of an illegal request, e.g. "cannot execute: the driver is 'inactive',
    not 'active'; allowed from 'inactive': activate, finalize"."""
    allowed = ", ".join(allowed_from(state)) or "nothing"
    what = DISPLAY.get(op, op)
    return (
        f"cannot {what}: the driver is '{state}', not {_names(needs)}; "
        f"allowed from '{state}': {allowed}"
    )


class Lifecycle:
    """The state of one driver and the rules above. Knows nothing about hardware."""

    def __init__(self, kind: str) -> None:
        self.kind = kind
        self.state = State.UNCONFIGURED
        # the state before the last fault: recover returns to inactive only if configured
        self.before_error: State | None = None

    def is_noop(self, transition: str) -> bool:
        return IDEMPOTENT.get(transition) is self.state

    def check_transition(self, transition: str) -> State:
        """The state ``transition`` leads to, or LifecycleError if it is not allowed now."""
        sources, target = TRANSITIONS[transition]
        if self.state not in sources:
            raise LifecycleError(self.kind, refusal(transition, self.state, sources))
        if transition == "recover":
            configured = self.before_error in CONFIGURED
            return State.INACTIVE if configured else State.UNCONFIGURED
        return target

    def check_operation(self, operation: str) -> None:
        needs = OPERATIONS[operation]
        if self.state not in needs:
            raise LifecycleError(self.kind, refusal(operation, self.state, needs))

    def fail(self) -> None:
        """Enter the error state (from any state but finalized)."""
        if self.state is not State.ERROR:
            self.before_error = self.state
        self.state = State.ERROR
