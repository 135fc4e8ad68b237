"""Faults on the simulated cell: a joint that stops following, a gripper that fails, a lost
connection, too much lag, an interrupt. Each stops both arms at the tick it is found,
records what happened, moves the driver to error (exit code 3) and stays there until the
fault is cleared and recover() is called."""

from __future__ import annotations

import numpy as np
import pytest

from cellengine.drivers import DriverFault, DriverRefused, Fault, GripperState, SimDriver, State
from cellengine.drivers.record import FaultRecord, Played, Transition
from cellengine.drivers.sim import servo_ticks
from cellengine.errors import EXIT_DRIVER
from cellengine.program import CompiledSegment
from tests.drivers.simcell import NAMES, N, active, compiled, event, q_with, quintic

END = q_with(left_elbow_joint=1.0, right_shoulder_pan_joint=-0.6)
ELBOW = NAMES.index("left_elbow_joint")


def move(duration: float = 2.0) -> CompiledSegment:
    return compiled(quintic(np.zeros(N), END, duration), "RouteCable guide1: lift", 3)


def fail(d: SimDriver, seg: CompiledSegment, events: list[object] | None = None) -> DriverFault:
    with pytest.raises(DriverFault) as info:
        d.execute(seg, events or [])  # type: ignore[arg-type]
    assert info.value.exit_code == EXIT_DRIVER
    return info.value


def assert_stopped_in_error(d: SimDriver, fault: Fault) -> Played:
    """Both arms hold where the last tick measured them; the record tells the same."""
    assert d.state is State.ERROR and d.fault == fault
    played = d.recorder.of(Played)[-1]
    assert played.fault == fault and not played.completed
    q = d.arms.q
    assert d.arms.stopped and np.array_equal(d.commanded(), q)
    assert np.array_equal(played.measured[-1], q)
    (record,) = d.recorder.of(FaultRecord)
    assert record.fault == fault and record.q == tuple(q.tolist())
    assert d.recorder.of(Transition)[-1] == Transition("fault", "active", "error")
    return played


def test_frozen_joint_stops_both_arms_naming_joint_time_and_value() -> None:
    d = active()
    d.freeze_joint("left_elbow_joint", at=0.5)
    seg = move()
    ticks = servo_ticks(0.0, 2.0, 0.002)
    cmd = seg.trajectory.sample(ticks)[0]
    k0 = int(np.argmax(ticks >= 0.5))
    held = cmd[k0 - 1, ELBOW]  # where the joint was when it froze
    k = k0 + int(np.argmax(np.abs(cmd[k0:, ELBOW] - held) > 0.05))
    dev = abs(cmd[k, ELBOW] - held)
    message = (
        f"arm 'left' joint 'left_elbow_joint' does not follow at t = {ticks[k]:.3f} s: "
        f"commanded {cmd[k, ELBOW]:.4f}, measured {held:.4f} (deviation {dev:.4f} > "
        f"tolerance 0.05); both arms stopped"
    )
    error = fail(d, seg)
    assert error.problems[0].message == message
    assert error.fault == Fault("tracking", message, "left", "left_elbow_joint", ticks[k], dev)
    played = assert_stopped_in_error(d, error.fault)
    assert played.t[-1] == ticks[k] and len(played.t) == k + 1
    # the right arm was moving too: stopped where it was, short of its end
    right = NAMES.index("right_shoulder_pan_joint")
    assert d.joint_state()[right] == cmd[k, right] and -0.6 < cmd[k, right] < 0.0


def test_frozen_joint_must_be_cleared_before_recover() -> None:
    d = active()
    d.freeze_joint("left_elbow_joint", at=0.5)
    fail(d, move())
    with pytest.raises(DriverRefused) as info:
        d.recover()
    assert info.value.problems[0].message == (
        "cannot recover: joint 'left_elbow_joint' is still frozen (clear the fault first)"
    )
    assert d.state is State.ERROR
    d.clear_faults()
    d.recover()
    assert d.state is State.INACTIVE
    # continue from where the arms stopped to the end
    d.activate()
    here = d.joint_state()
    d.execute(compiled(quintic(here, END, 2.0, 2.0)))
    assert np.array_equal(d.joint_state(), END) and d.state is State.ACTIVE


def test_failed_gripper_stops_both_arms() -> None:
    d = active()
    d.fail_gripper("right", at=0.8)
    seg = move()
    events = [event(0.4, "right", "slide", "cable1"), event(1.0, "right", "grasp", "cable1")]
    message = (
        "gripper of arm 'right' did not reach mode 'grasp' at t = 1.000 s (still 'slide'); "
        "both arms stopped"
    )
    error = fail(d, seg, events)  # type: ignore[arg-type]
    assert error.fault == Fault("gripper", message, "right", None, 1.0, "slide")
    played = assert_stopped_in_error(d, error.fault)
    assert played.t[-1] == 1.0
    assert np.allclose(d.joint_state(), seg.trajectory.sample(1.0)[0])
    assert d.gripper("right") == GripperState("slide", "cable1")  # the mode it stayed in
    assert [(e.mode, e.done) for e in played.events] == [("slide", True), ("grasp", False)]
    with pytest.raises(DriverRefused, match="the gripper of arm 'right' still fails"):
        d.recover()


def test_lost_connection_stops_both_arms_and_readings_fail() -> None:
    d = active()
    d.drop_connection(at=0.3, arm="right")
    message = "connection to arm 'right' lost at t = 0.300 s; both arms stopped"
    error = fail(d, move())
    assert error.fault == Fault("connection", message, "right", None, 0.3)
    assert d.state is State.ERROR and d.fault == error.fault
    played = d.recorder.of(Played)[-1]
    assert played.t[-1] == pytest.approx(0.298)  # the 0.3 s command was never sent
    assert d.arms.stopped and np.array_equal(d.arms.q, played.measured[-1])
    for read in (d.joint_state, lambda: d.gripper("left")):
        with pytest.raises(DriverFault) as info:
            read()
        assert info.value.problems[0].message == message
    assert len(d.recorder.of(FaultRecord)) == 1  # reading did not add a second fault
    with pytest.raises(DriverRefused, match="the connection to arm 'right' is still down"):
        d.recover()
    d.clear_faults()
    d.recover()
    assert np.array_equal(d.joint_state(), played.measured[-1])


def test_lost_connection_to_the_cell() -> None:
    d = active()
    d.drop_connection(at=0.0)
    error = fail(d, move())
    assert error.problems[0].message == (
        "connection to the cell lost at t = 0.000 s; both arms stopped"
    )
    assert len(d.recorder.of(Played)[-1].t) == 0 and not d.arms.q.any()


def test_lag_beyond_tolerance_is_a_tracking_fault_that_recovers_at_once() -> None:
    d = active(lag=0.1)  # about 0.09 rad behind at the elbow's peak speed
    error = fail(d, move())
    assert error.fault.kind == "tracking" and error.fault.joint == "left_elbow_joint"
    assert error.fault.value is not None and float(error.fault.value) > 0.05
    assert_stopped_in_error(d, error.fault)
    d.recover()  # nothing injected: nothing to clear
    assert d.state is State.INACTIVE


def test_fault_injected_after_the_segment_does_not_fire() -> None:
    d = active()
    d.freeze_joint("left_elbow_joint", at=5.0)
    d.drop_connection(at=5.0)
    d.execute(move())
    assert d.state is State.ACTIVE and np.array_equal(d.joint_state(), END)


def test_interrupt_during_execution_stops_and_records(monkeypatch: pytest.MonkeyPatch) -> None:
    d = active()
    real_step, calls = d.arms.step, [0]

    def step(command: np.ndarray, frozen: np.ndarray) -> np.ndarray:
        calls[0] += 1
        if calls[0] == 101:
            raise KeyboardInterrupt
        return real_step(command, frozen)

    monkeypatch.setattr(d.arms, "step", step)
    error = fail(d, move())
    assert error.fault == Fault(
        "interrupted", "interrupted at t = 0.200 s; both arms stopped", time=0.2
    )
    played = assert_stopped_in_error(d, error.fault)
    assert len(played.t) == 100


def test_bug_during_execution_stops_arms_and_propagates(monkeypatch: pytest.MonkeyPatch) -> None:
    d = active()

    def broken(command: np.ndarray, frozen: np.ndarray) -> np.ndarray:
        raise ValueError("bad shape")

    monkeypatch.setattr(d.arms, "step", broken)
    with pytest.raises(ValueError, match="bad shape"):
        d.execute(move())
    assert d.state is State.ERROR and d.arms.stopped
    assert d.fault == Fault("internal", "ValueError: bad shape; both arms stopped")


def test_injection_names_are_checked() -> None:
    d = active()
    with pytest.raises(KeyError, match="unknown joint 'left_knee'"):
        d.freeze_joint("left_knee")
    with pytest.raises(DriverRefused, match="unknown arm 'middle'; known: left, right"):
        d.fail_gripper("middle")


def test_faults_are_deterministic() -> None:
    def once() -> list[dict[str, object]]:
        d = active(lag=0.01)
        d.freeze_joint("right_shoulder_pan_joint", at=0.7)
        with pytest.raises(DriverFault):
            d.execute(move())
        return d.recorder.to_json()

    assert once() == once()
