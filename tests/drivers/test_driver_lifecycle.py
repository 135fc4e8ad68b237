"""The lifecycle every driver shares: legal and illegal transitions (exact messages),
idempotent requests, faults into the error state and the explicit way out."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from cellengine.drivers import (
    DriverFault,
    Fault,
    GripperState,
    LifecycleError,
    Played,
    SimDriver,
    State,
)
from cellengine.drivers.base import Driver
from cellengine.drivers.lifecycle import TRANSITIONS, allowed_from
from cellengine.drivers.record import FaultRecord, Transition
from cellengine.errors import EXIT_DRIVER
from cellengine.program import CompiledSegment, TimedEvent
from tests.drivers.simcell import JOINTS, N, cell, compiled, quintic, still


def fresh() -> SimDriver:
    return SimDriver(cell(), JOINTS)


def transitions(d: Driver) -> list[tuple[str, str, str]]:
    return [(e.name, e.source, e.target) for e in d.recorder.of(Transition)]


def in_state(state: State) -> SimDriver:
    """A sim driver brought to ``state`` by legal means."""
    d = fresh()
    if state is State.UNCONFIGURED:
        return d
    if state is State.FINALIZED:
        d.finalize()
        return d
    d.configure()
    if state is State.INACTIVE:
        return d
    d.activate()
    if state is State.ERROR:
        d.freeze_joint("left_elbow_joint")
        with pytest.raises(DriverFault):
            d.execute(compiled(quintic(np.zeros(N), np.full(N, 0.5), 1.0)))
    return d


def test_legal_path_through_every_state_is_recorded() -> None:
    d = fresh()
    assert d.state is State.UNCONFIGURED
    d.configure()
    assert d.state is State.INACTIVE
    d.activate()
    assert d.state is State.ACTIVE
    d.deactivate()
    assert d.state is State.INACTIVE
    d.activate()
    d.finalize()  # from active: stops the arms, then shuts down
    assert d.state is State.FINALIZED
    assert transitions(d) == [
        ("configure", "unconfigured", "inactive"),
        ("activate", "inactive", "active"),
        ("deactivate", "active", "inactive"),
        ("activate", "inactive", "active"),
        ("finalize", "active", "finalized"),
    ]


@pytest.mark.parametrize(
    ("state", "request_", "message"),
    [
        (
            State.UNCONFIGURED,
            "activate",
            "cannot activate: the driver is 'unconfigured', not 'inactive'; "
            "allowed from 'unconfigured': configure, finalize",
        ),
        (
            State.UNCONFIGURED,
            "deactivate",
            "cannot deactivate: the driver is 'unconfigured', not 'active'; "
            "allowed from 'unconfigured': configure, finalize",
        ),
        (
            State.ACTIVE,
            "configure",
            "cannot configure: the driver is 'active', not 'unconfigured'; "
            "allowed from 'active': deactivate, finalize",
        ),
        (
            State.ACTIVE,
            "recover",
            "cannot recover: the driver is 'active', not 'error'; "
            "allowed from 'active': deactivate, finalize",
        ),
        (
            State.FINALIZED,
            "configure",
            "cannot configure: the driver is 'finalized', not 'unconfigured'; "
            "allowed from 'finalized': nothing",
        ),
        (
            State.ERROR,
            "activate",
            "cannot activate: the driver is 'error', not 'inactive'; "
            "allowed from 'error': recover, finalize",
        ),
        (
            State.ERROR,
            "deactivate",
            "cannot deactivate: the driver is 'error', not 'active'; "
            "allowed from 'error': recover, finalize",
        ),
        (
            State.UNCONFIGURED,
            "joint_state",
            "cannot read joint states: the driver is 'unconfigured', not 'inactive', 'active' "
            "or 'error'; allowed from 'unconfigured': configure, finalize",
        ),
        (
            State.FINALIZED,
            "gripper",
            "cannot read grippers: the driver is 'finalized', not 'inactive', 'active' or "
            "'error'; allowed from 'finalized': nothing",
        ),
        (
            State.ERROR,
            "read_mass",
            "cannot read masses: the driver is 'error', not 'inactive' or 'active'; "
            "allowed from 'error': recover, finalize",
        ),
    ],
)
def test_illegal_requests_name_the_state_and_what_is_allowed(
    state: State, request_: str, message: str
) -> None:
    d = in_state(state)
    before = len(d.recorder)
    calls: dict[str, Callable[[], object]] = {
        "gripper": lambda: d.gripper("left"),
        "read_mass": lambda: d.read_mass("left"),
    }
    with pytest.raises(LifecycleError) as info:
        calls.get(request_, getattr(d, request_))()
    assert info.value.problems[0].message == message
    assert str(info.value) == f"sim driver: {message}"
    assert info.value.exit_code == EXIT_DRIVER
    assert d.state is state and len(d.recorder) == before


@pytest.mark.parametrize("state", [State.UNCONFIGURED, State.INACTIVE, State.FINALIZED])
def test_execute_needs_active(state: State) -> None:
    d = in_state(state)
    with pytest.raises(LifecycleError) as info:
        d.execute(compiled(still(np.zeros(N))))
    allowed = ", ".join(allowed_from(state)) or "nothing"
    assert info.value.problems[0].message == (
        f"cannot execute: the driver is '{state}', not 'active'; allowed from '{state}': {allowed}"
    )


def test_execute_in_error_is_refused_naming_recover() -> None:
    d = in_state(State.ERROR)
    with pytest.raises(LifecycleError, match="allowed from 'error': recover, finalize"):
        d.execute(compiled(still(d.joint_state())))


@pytest.mark.parametrize(
    ("state", "request_"),
    [
        (State.INACTIVE, "configure"),
        (State.ACTIVE, "activate"),
        (State.INACTIVE, "deactivate"),
        (State.FINALIZED, "finalize"),
    ],
)
def test_asking_for_the_current_state_is_a_no_op(state: State, request_: str) -> None:
    d = in_state(state)
    before = transitions(d)
    getattr(d, request_)()
    getattr(d, request_)()
    assert d.state is state and transitions(d) == before


def test_every_state_but_finalized_can_be_finalized() -> None:
    assert allowed_from(State.FINALIZED) == ()
    for state in (State.UNCONFIGURED, State.INACTIVE, State.ACTIVE, State.ERROR):
        assert "finalize" in allowed_from(state)
        d = in_state(state)
        d.finalize()
        assert d.state is State.FINALIZED
    assert set(TRANSITIONS) == {"configure", "activate", "deactivate", "finalize", "recover"}


def test_a_fault_moves_to_error_which_only_recover_leaves() -> None:
    d = in_state(State.ERROR)
    assert d.fault is not None and d.fault.kind == "tracking"
    names = transitions(d)
    assert names[-1] == ("fault", "active", "error")
    for _ in range(3):  # nothing leaves error on its own: reading state is fine
        d.joint_state()
        assert d.state is State.ERROR
    d.clear_faults()
    d.recover()
    assert d.state is State.INACTIVE and d.fault is None  # configured, not active
    assert transitions(d)[-1] == ("recover", "error", "inactive")
    d.activate()
    assert d.state is State.ACTIVE


def test_context_manager_finalizes() -> None:
    with fresh() as d:
        d.configure()
        d.activate()
    assert d.state is State.FINALIZED


class Faulty(Driver):
    """A driver whose hooks fail on request: the base class's handling, on its own."""

    kind = "faulty"

    def __init__(self, fail_in: str, error: BaseException) -> None:
        super().__init__(cell(), JOINTS)
        self.fail_in, self.error, self.stops = fail_in, error, 0

    def _hook(self, name: str) -> None:
        if name == self.fail_in:
            raise self.error

    def _on_configure(self) -> None:
        self._hook("configure")

    def _on_activate(self) -> None:
        self._hook("activate")

    def _on_deactivate(self) -> None:
        self._hook("deactivate")

    def _on_finalize(self) -> None:
        self._hook("finalize")

    def _on_recover(self) -> None:
        self.fail_in = ""

    def _on_execute(self, segment: CompiledSegment, events: tuple[TimedEvent, ...]) -> Played:
        raise AssertionError("not used")

    def _on_fault(self) -> None:
        self.stops += 1

    def _read_joints(self) -> np.ndarray:
        return np.zeros(N)

    def _read_gripper(self, arm: str) -> GripperState:
        return GripperState(None, None)

    def _last_known(self) -> tuple[np.ndarray, dict[str, GripperState]]:
        return np.zeros(N), {"left": GripperState(None, None), "right": GripperState(None, None)}


def test_fault_during_configure_recovers_to_unconfigured() -> None:
    fault = Fault("connection", "arm 'left' at 192.168.0.2 does not answer", "left")
    d = Faulty("configure", DriverFault("faulty", fault))
    with pytest.raises(DriverFault) as info:
        d.configure()
    assert str(info.value) == "faulty driver: arm 'left' at 192.168.0.2 does not answer"
    assert d.state is State.ERROR and d.fault == fault and d.stops == 1
    (record,) = d.recorder.of(FaultRecord)
    assert record.fault == fault and record.q == (0.0,) * N
    d.recover()
    assert d.state is State.UNCONFIGURED  # it never was configured
    assert transitions(d) == [
        ("fault", "unconfigured", "error"),
        ("recover", "error", "unconfigured"),
    ]


def test_unexpected_exception_in_a_hook_is_a_fault_and_propagates() -> None:
    d = Faulty("activate", RuntimeError("boom"))
    d.configure()
    with pytest.raises(RuntimeError, match="boom"):
        d.activate()
    assert d.state is State.ERROR and d.stops == 1
    assert d.fault == Fault("internal", "RuntimeError: boom; both arms stopped")
    d.recover()
    assert d.state is State.INACTIVE  # configured before the fault


def test_interrupt_in_a_hook_is_a_fault_and_propagates() -> None:
    d = Faulty("deactivate", KeyboardInterrupt())
    d.configure()
    d.activate()
    with pytest.raises(KeyboardInterrupt):
        d.deactivate()
    assert d.state is State.ERROR
    assert d.fault == Fault("interrupted", "interrupted; both arms stopped")
