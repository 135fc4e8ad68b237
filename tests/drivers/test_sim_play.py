"""The simulated cell playing segments: where the arms end, events in order, the recorded
ticks, lag, real time, the checks before sending, the load cell, the registry."""

from __future__ import annotations

import json
import time

import numpy as np
import pytest

from cellengine.drivers import (
    DRIVERS,
    DriverRefused,
    GripperState,
    SimDriver,
    State,
    make_driver,
    play,
    segment_events,
)
from cellengine.drivers.fault import DriverFault
from cellengine.drivers.record import Played, Sent, Transition
from cellengine.drivers.sim import servo_ticks
from cellengine.errors import EXIT_DRIVER
from cellengine.program import Program
from tests.drivers.simcell import (
    JOINTS,
    NAMES,
    N,
    active,
    cell,
    compiled,
    event,
    objects,
    q_with,
    quintic,
    still,
)

A = q_with(left_elbow_joint=0.8, left_wrist_1_joint=-0.4, right_shoulder_pan_joint=-0.6)
B = q_with(left_elbow_joint=0.2, right_shoulder_pan_joint=0.3, right_wrist_3_joint=1.0)


def program() -> list[tuple[object, list[object]]]:
    """Three segments on one time axis: move to A (0-1 s) with both grippers set at the
    start, grasp at 1.0 s (no motion), move to B (1-1.6 s) releasing the left at the end."""
    return [
        (
            compiled(quintic(np.zeros(N), A, 1.0), "PickCable: approach", 0),
            [event(0.0, "left", "slide", "cable1"), event(0.0, "right", "slide", "cable1")],
        ),
        (
            compiled(still(A, 1.0), "PickCable: grasp", 0),
            [event(1.0, "right", "grasp", "cable1")],
        ),
        (
            compiled(quintic(A, B, 0.6, 1.0), "RouteCable guide1: lift", 1),
            [event(1.3, "left", "grasp", "cable1"), event(1.6, "left", "open", None)],
        ),
    ]


def run_program(d: SimDriver) -> list[Played]:
    return [d.execute(seg, events) for seg, events in program()]  # type: ignore[arg-type]


def test_program_ends_at_its_last_point_with_events_in_order() -> None:
    d = active()
    played = run_program(d)
    assert np.array_equal(d.joint_state(), B)
    assert d.gripper("left") == GripperState("open", None)
    assert d.gripper("right") == GripperState("grasp", "cable1")
    applied = [(e.time, e.arm, e.mode, e.holds, e.done) for p in played for e in p.events]
    assert applied == [
        (0.0, "left", "slide", "cable1", True),
        (0.0, "right", "slide", "cable1", True),
        (1.0, "right", "grasp", "cable1", True),
        (1.3, "left", "grasp", "cable1", True),
        (1.6, "left", "open", None, True),
    ]
    assert d.state is State.ACTIVE and all(p.completed for p in played)


def as_program() -> Program:
    segments = [seg for seg, _ in program()]
    events = [e for _, evs in program() for e in evs]
    return Program(NAMES, tuple(segments), tuple(events))  # type: ignore[arg-type]


def test_a_whole_program_plays_with_each_event_in_its_segment() -> None:
    prog = as_program()
    assert [[e.time for e in evs] for evs in segment_events(prog)] == [
        [0.0, 0.0, 1.0],  # 1.0: the first segment ends there, the grasp goes with it
        [],
        [1.3, 1.6],
    ]
    d = active()
    played = play(d, prog)
    assert len(played) == 3 and np.array_equal(d.joint_state(), B)
    assert d.gripper("right") == GripperState("grasp", "cable1")
    assert d.gripper("left") == GripperState("open", None)


def test_an_event_outside_every_segment_is_a_program_error() -> None:
    prog = as_program()
    late = Program(prog.joint_names, prog.segments, (*prog.events, event(2.0, "left", "open")))
    with pytest.raises(ValueError, match=r"event 'open' of arm 'left' at t = 2\.000 s is in no"):
        segment_events(late)


def test_ticks_are_the_servo_period_and_commands_the_trajectory() -> None:
    d = active()
    traj = quintic(np.zeros(N), A, 1.0)
    p = d.execute(compiled(traj))
    assert len(p.t) == 501 and p.t[0] == 0.0 and p.t[-1] == 1.0
    assert np.allclose(np.diff(p.t), 0.002)
    assert np.array_equal(p.commanded, traj.sample(p.t)[0])
    assert np.array_equal(p.measured, p.commanded)  # no lag: the arms follow exactly
    assert not p.max_deviation.any() and p.late is None


def test_servo_ticks_end_exactly_at_the_end() -> None:
    assert servo_ticks(0.0, 0.005, 0.002).tolist() == [0.0, 0.002, 0.004, 0.005]
    assert servo_ticks(1.0, 1.0, 0.002).tolist() == [1.0]
    ticks = servo_ticks(0.3, 1.3, 0.002)
    assert len(ticks) == 501 and ticks[-1] == 1.3


def test_events_at_one_time_apply_in_the_given_order() -> None:
    d = active()
    d.execute(
        compiled(still(np.zeros(N))),
        [event(0.0, "left", "grasp", "vial1"), event(0.0, "left", "slide", "cable1")],
    )
    assert d.gripper("left") == GripperState("slide", "cable1")


def test_recorder_tells_what_was_sent_and_what_happened() -> None:
    d = active()
    run_program(d)
    kinds = [type(e).__name__ for e in d.recorder]
    assert kinds == ["Transition"] * 2 + ["Sent", "Played"] * 3
    sent = d.recorder.of(Sent)
    assert [(s.step, s.label, s.start, s.end) for s in sent] == [
        (0, "PickCable: approach", 0.0, 1.0),
        (0, "PickCable: grasp", 1.0, 1.0),
        (1, "RouteCable guide1: lift", 1.0, 1.6),
    ]
    assert sent[2].q == tuple(A.tolist())
    data = d.recorder.to_json(every=50)
    json.dumps(data)  # plain data
    last = data[-1]
    assert last["entry"] == "played" and last["t"][0] == 1.0 and last["t"][-1] == 1.6
    assert len(last["t"]) == 7  # 301 ticks: every 50th (the last is one of them)
    assert last["measured"][-1] == B.tolist()


def test_listeners_hear_each_entry_as_it_is_added() -> None:
    d = SimDriver(cell(), JOINTS)
    heard: list[str] = []
    d.recorder.listen(lambda e: heard.append(type(e).__name__))
    d.configure()
    d.activate()
    d.execute(compiled(still(np.zeros(N))))
    assert heard == ["Transition", "Transition", "Sent", "Played"]


def test_lag_gives_a_tracking_error_of_velocity_times_time_constant() -> None:
    lag = 0.01
    d = active(lag=lag)
    traj = quintic(np.zeros(N), A, 1.0)
    p = d.execute(compiled(traj))
    peak_velocity = np.abs(traj.sample(np.linspace(0, 1, 1001))[1]).max(axis=0)
    expected = peak_velocity * lag
    moving = expected > 0
    assert np.allclose(p.max_deviation[moving], expected[moving], rtol=0.1)
    assert not p.max_deviation[~moving].any()
    # the arms end within the start tolerance of the last point: the next segment goes
    assert np.abs(d.joint_state() - A).max() < d.start_tolerance
    d.execute(compiled(quintic(A, B, 0.6, 1.0)))


def test_realtime_takes_about_the_trajectory_duration() -> None:
    d = active(realtime=True)
    traj = quintic(np.zeros(N), A, 0.3)
    began = time.perf_counter()
    p = d.execute(compiled(traj))
    wall = time.perf_counter() - began
    assert 0.29 <= wall <= 1.0
    assert p.late is not None and p.late < 0.2
    assert np.array_equal(d.joint_state(), A)


def test_simulated_time_does_not_wait() -> None:
    d = active()
    began = time.perf_counter()
    d.execute(compiled(quintic(np.zeros(N), A, 10.0)))
    assert time.perf_counter() - began < 2.0


def test_start_state_mismatch_is_refused_naming_the_joint() -> None:
    d = active(q0=q_with(left_elbow_joint=0.05, right_wrist_2_joint=-0.3))
    with pytest.raises(DriverRefused) as info:
        d.execute(compiled(quintic(np.zeros(N), A, 1.0), "PickCable: approach", 2))
    assert info.value.problems[0].message == (
        "segment 'PickCable: approach' (step 3) not sent: arm 'right' joint "
        "'right_wrist_2_joint' is at -0.3000, the segment starts at 0.0000 "
        "(deviation 0.3000 > tolerance 0.01)"
    )
    assert info.value.exit_code == EXIT_DRIVER
    assert d.state is State.ACTIVE  # a refusal is not a fault
    assert not d.recorder.of(Sent)
    assert d.joint_state()[NAMES.index("right_wrist_2_joint")] == -0.3


def test_start_within_tolerance_is_accepted() -> None:
    d = active(q0=q_with(left_elbow_joint=0.009), start_tolerance=0.01)
    d.execute(compiled(quintic(np.zeros(N), A, 1.0)))
    assert np.array_equal(d.joint_state(), A)


@pytest.mark.parametrize(
    ("events", "message"),
    [
        (
            [event(0.5, "left", "pinch")],
            "segment 'move' (step 1): arm 'left' has no gripper mode 'pinch'; "
            "known: grasp, open, slide",
        ),
        (
            [event(1.5, "left", "grasp")],
            "segment 'move' (step 1): event 'grasp' of arm 'left' at t = 1.500 s is outside "
            "the segment (0.000 to 1.000 s)",
        ),
        ([event(0.5, "middle", "grasp")], "unknown arm 'middle'; known: left, right"),
    ],
)
def test_bad_events_are_refused_before_anything_moves(events: list[object], message: str) -> None:
    d = active()
    with pytest.raises(DriverRefused) as info:
        d.execute(compiled(quintic(np.zeros(N), A, 1.0)), events)  # type: ignore[arg-type]
    assert info.value.problems[0].message == message
    assert d.state is State.ACTIVE and not d.recorder.of(Sent)
    assert not d.joint_state().any()


def test_arm_without_tool_has_no_gripper_and_refuses_events() -> None:
    bare = cell().model_copy(update={"robots": {**cell().robots}})
    robots = dict(bare.robots)
    robots["right"] = robots["right"].model_copy(update={"tool": None})
    d = SimDriver(bare.model_copy(update={"robots": robots}), JOINTS)
    d.configure()
    d.activate()
    assert d.gripper("right") == GripperState(None, None)
    with pytest.raises(DriverRefused, match="arm 'right' has no tool to set to 'grasp'"):
        d.execute(compiled(still(np.zeros(N))), [event(0.0, "right", "grasp")])


def test_other_joint_names_are_refused() -> None:
    d = active()
    traj = quintic(np.zeros(N), A, 1.0)
    swapped = type(traj)(NAMES[6:] + NAMES[:6], traj.t, traj.q, traj.qd, traj.qdd)
    with pytest.raises(DriverRefused, match="moves \\['right_shoulder_pan_joint'"):
        d.execute(compiled(swapped))


def test_q0_and_grippers_per_arm() -> None:
    d = active(
        q0={"left": np.full(6, 0.1), "right": np.full(6, -0.1)},
        grippers={"right": GripperState("grasp", "vial1")},
    )
    assert d.joint_state().tolist() == [0.1] * 6 + [-0.1] * 6
    assert d.gripper("left") == GripperState("open", None)
    assert d.gripper("right") == GripperState("grasp", "vial1")


def test_read_mass_is_the_held_object_plus_seeded_noise() -> None:
    d = active(grippers={"left": GripperState("grasp", "cable1")})
    assert d.read_mass("left") == 0.04
    assert d.read_mass("right") == 0.0  # holds nothing
    vial = {"left": GripperState("grasp", "vial1")}
    noisy = [active(mass_noise=0.001, seed=7, grippers=vial) for _ in range(2)]
    reads = [[n.read_mass("left") for _ in range(400)] for n in noisy]
    assert reads[0] == reads[1]  # same seed, same readings
    assert abs(np.mean(reads[0]) - 0.012) < 4 * 0.001 / np.sqrt(400)
    assert 0.0007 < np.std(reads[0]) < 0.0013


@pytest.mark.parametrize("reading", [0.0, -0.002, float("nan"), 1e308])
def test_a_weighing_that_reads_no_mass_is_a_fault(reading: float) -> None:
    """What a weighing reads goes in the journal and decides heavier_of: a broken load cell's
    reading stops the run rather than being trusted (an empty hand may read noise about 0)."""
    d = active(grippers={"left": GripperState("grasp", "vial1")})
    d._read_mass = lambda arm: reading  # type: ignore[method-assign]
    if reading <= 0.0:  # no object named: an empty load cell reads noise about 0
        assert d.read_mass("left") == reading
    with pytest.raises(DriverFault) as e:
        d.read_mass("left", of="vial1")
    assert e.value.fault.kind == "load_cell" and d.state is State.ERROR
    assert e.value.fault.message == (
        f"the load cell of 'left' read {reading!r} kg weighing 'vial1', which is no mass (more "
        "than 0, at most 1000 kg); both arms stopped"
    )


def test_read_mass_of_an_object_without_mass_is_refused() -> None:
    d = active(grippers={"left": GripperState("grasp", "box7")})
    with pytest.raises(DriverRefused, match="arm 'left' holds 'box7', which is not in the objects"):
        d.read_mass("left")


def test_same_inputs_same_record() -> None:
    def once() -> str:
        d = active(lag=0.005, mass_noise=0.01, seed=3)
        run_program(d)
        d.read_mass("right")
        return json.dumps(d.recorder.to_json()) + repr(d.read_mass("right"))

    assert once() == once()


def test_registry_and_make_driver() -> None:
    from cellengine.drivers.lab import LabBenchDriver
    from cellengine.drivers.ur_rtde import UrDriver

    assert {"sim": SimDriver, "ur_rtde": UrDriver, "lab": LabBenchDriver} == DRIVERS
    d = make_driver(cell(), JOINTS, objects=objects(), lag=0.01, realtime=False)
    assert isinstance(d, SimDriver) and d.state is State.UNCONFIGURED
    assert d.joint_names == NAMES and d.arms.gain < 1.0
    assert d.recorder.of(Transition) == []


def test_make_driver_names_a_missing_driver() -> None:
    ur = cell(kind="ur_rtde", arms={"left": "127.0.0.2", "right": "127.0.0.3"})
    with pytest.raises(DriverRefused) as info:
        make_driver(ur, JOINTS, kind="kuka")
    assert str(info.value) == "kuka driver: no driver 'kuka' is available; known: lab, sim, ur_rtde"
    assert isinstance(make_driver(ur, JOINTS, kind="sim"), SimDriver)


def test_layout_needs_every_robots_joints() -> None:
    with pytest.raises(ValueError, match="joints are given for \\['left'\\]"):
        SimDriver(cell(), {"left": JOINTS["left"]})
    with pytest.raises(ValueError, match="joint names repeat: left_elbow_joint"):
        SimDriver(cell(), {"left": JOINTS["left"], "right": ("left_elbow_joint",)})
