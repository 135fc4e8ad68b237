"""The UR driver end to end: `cellengine run` with the real ur-rtde client streaming to two
emulated controllers (`cellengine emulate ur`, each on its own loopback address), and a
protective stop injected mid-run, then the run resumed once it is cleared.

Both the emulator and `cellengine run` are subprocesses with deadlines (the client's calls
block without one), killed at the end whatever happens."""

from __future__ import annotations

import itertools
import json
import re
from pathlib import Path

import numpy as np

import cellengine.skills.cable  # noqa: F401  (registers the cable skills)
from cellengine.pipeline import compile_plan
from tests.drivers.urcell import journal, run_cli, start, ur_cell
from tests.emulate.harness import Emulator


def test_the_four_guide_plan_runs_on_two_emulated_arms(
    tmp_path: Path, emulated: tuple[Path, list[str], list[Emulator]]
) -> None:
    folder, hosts, started = emulated
    plan = folder / "plan_two_turns.yaml"
    program = compile_plan(plan).program
    start(hosts, program.segments[0].trajectory.q[0], started)
    run = tmp_path / "run"
    result = run_cli(str(plan), "--out", str(run), timeout=300)
    assert result.returncode == 0, result.stderr[-2000:]
    entries = journal(run)
    assert entries[-1]["entry"] == "end"
    finished = [e for e in entries if e["entry"] == "finished"]
    assert [e["segment"] for e in finished] == list(range(len(program.segments)))
    # where the controllers said the arms were after each segment: where it ends
    for e, seg in zip(finished, program.segments, strict=True):
        assert np.allclose(e["q"], seg.trajectory.q[-1], atol=0.005), seg.segment.label
    # the servo loop's timing: journaled and in the report, every tick of the motion counted
    servo = json.loads((run / "report.json").read_text())["run"]["servo"]
    assert servo == next(e for e in entries if e["entry"] == "timing")["servo"]
    assert servo["ticks"] >= program.duration / 0.002
    e = servo["period_error_ms"]
    assert 0 <= e["p50"] <= e["p99"] <= e["p99.9"] <= e["max"]
    assert servo["stop_commands_ms"] == []


def test_a_protective_stop_stops_the_run_and_resume_completes_it(
    tmp_path: Path, emulated: tuple[Path, list[str], list[Emulator]]
) -> None:
    folder, hosts, started = emulated
    plan = folder / "plan_straight.yaml"
    program = compile_plan(plan).program
    emulator = start(
        hosts,
        program.segments[0].trajectory.q[0],
        started,
        "--fault",
        f"{hosts[1]}@6:protective_stop",
    )
    run = tmp_path / "run"
    result = run_cli(str(plan), "--out", str(run), timeout=300)
    assert result.returncode == 3, result.stderr[-2000:]
    assert f"arm 'right' at {hosts[1]}: " in result.stderr and "protective stop" in result.stderr
    fault = next(e for e in journal(run) if e["entry"] == "fault")["fault"]
    assert fault["kind"] == "protective_stop" and fault["arm"] == "right"
    assert fault["details"]["safety_status_bits"] & 1 << 2
    # the report says what stopped the run, where and when, and the servo loop's figures
    stopped = json.loads((run / "report.json").read_text())["run"]
    assert (stopped["outcome"], stopped["fault"]["kind"]) == ("fault", "protective_stop")
    assert (stopped["fault"]["arm"], stopped["fault"]["time"]) == ("right", fault["time"])
    assert stopped["servo"]["ticks"] > 0 and stopped["stopped_in"] is not None
    # not cleared yet: the resumed run is refused before anything moves
    again = run_cli(str(plan), "--resume", str(run), timeout=120)
    assert again.returncode == 3, again.stderr[-2000:]
    assert emulator.fault(hosts[1], "clear")
    done = run_cli(str(plan), "--resume", str(run), timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    entries = journal(run)
    finished = [e["segment"] for e in entries if e["entry"] == "finished"]
    assert finished == list(range(len(program.segments)))
    assert entries[-1]["entry"] == "end"
    resumed = json.loads((run / "report.json").read_text())["run"]
    assert (resumed["outcome"], resumed["fault"]) == ("completed", None)
    assert resumed["resumed"][-1]["from_segment"] == stopped["segments_finished"]


def test_a_controller_reporting_another_model_is_refused(
    tmp_path: Path, emulated: tuple[Path, list[str], list[Emulator]]
) -> None:
    """The cell says ur5e; the right controller says it is a UR10: refused at configure,
    before anything moves, naming the arm, the address and both models."""
    folder, hosts, started = emulated
    plan = folder / "plan_straight.yaml"
    program = compile_plan(plan).program
    start(hosts, program.segments[0].trajectory.q[0], started, "--model", f"{hosts[1]}=UR10")
    result = run_cli(str(plan), "--out", str(tmp_path / "run"), timeout=120)
    assert result.returncode == 3, result.stderr[-2000:]
    assert (
        f"arm 'right' at {hosts[1]} reports robot model 'UR10', but the cell says 'ur5e' (UR5)"
    ) in result.stderr
    kinds = [e["entry"] for e in journal(tmp_path / "run")]
    assert "sent" not in kinds


def test_arms_far_from_the_plans_start_get_a_planned_move_there_first(
    tmp_path: Path, emulated: tuple[Path, list[str], list[Emulator]]
) -> None:
    """The emulated arms start 0.3 rad off the plan's start on two joints each: the run
    begins with a planned move there (journaled), then runs the plan."""
    folder, hosts, started = emulated
    plan = folder / "plan_straight.yaml"
    program = compile_plan(plan).program
    q0 = program.segments[0].trajectory.q[0].copy()
    q0[[0, 2, 6, 8]] += 0.3
    start(hosts, q0, started)
    run = tmp_path / "run"
    result = run_cli(str(plan), "--out", str(run), timeout=300)
    assert result.returncode == 0, result.stderr[-2000:]
    kinds = [e["entry"] for e in journal(run)]
    assert kinds.index("recovery") < kinds.index("sent") and kinds[-1] == "end"


def test_arms_farther_than_the_start_move_limit_are_refused_before_motion(
    tmp_path: Path, emulated: tuple[Path, list[str], list[Emulator]]
) -> None:
    """The right arm's elbow 0.8 rad from the plan's start, more than the default
    start_move_limit (0.5 rad): refused before anything moves, naming arm, joint, where it
    is and the option."""
    folder, hosts, started = emulated
    plan = folder / "plan_straight.yaml"
    program = compile_plan(plan).program
    q0 = program.segments[0].trajectory.q[0].copy()
    q0[8] += 0.8
    _ = start(hosts, q0, started)
    run = tmp_path / "run"
    result = run_cli(str(plan), "--out", str(run), timeout=120)
    assert result.returncode == 3, result.stderr[-2000:]
    first = program.segments[0]
    assert (
        f"ur_rtde driver: arm 'right' joint 'right_elbow_joint' is at {q0[8]:.4f}, 0.8000 rad "
        f"from where '{first.segment.label}' starts ({q0[8] - 0.8:.4f}): farther than "
        "start_move_limit (0.5 rad), so the run does not move it there on its own; jog the "
        "arms closer, or raise the driver's start_move_limit in the cell file"
    ) in result.stderr
    kinds = [e["entry"] for e in journal(run)]
    assert "recovery" not in kinds and "sent" not in kinds


def test_grippers_on_digital_outputs_follow_the_programs_events(
    tmp_path: Path, emulated: tuple[Path, list[str], list[Emulator]]
) -> None:
    """With ``gripper_io`` each gripper event sets the arm's standard digital outputs
    through the real RTDEIOInterface: each controller's outputs go through the program's
    jaw modes in order, each arm its own, one pin at a time (ur-rtde sets one output per
    call), with no change that a mode does not need."""
    _, hosts, started = emulated
    pins = {"open": [], "slide": [0], "grasp": [0, 1]}
    folder = ur_cell(tmp_path, hosts, f", gripper_io: {pins}".replace("'", ""))
    plan = folder / "plan_short.yaml"
    plan.write_text(
        "cell: cell.yaml\nobjects: objects.yaml\nexecution: split\nsteps:\n"
        "  - {skill: PickCable, cable: cable1, from: [holder.comb_a, holder.comb_b]}\n"
        "  - {skill: PlaceConnector, cable: cable1, guide: routing.connector}\n"
    )
    program = compile_plan(plan).program
    emulator = start(hosts, program.segments[0].trajectory.q[0], started)
    result = run_cli(str(plan), "--out", str(tmp_path / "run"), timeout=300)
    assert result.returncode == 0, result.stderr[-2000:]
    log = emulator.stderr()
    for arm, host in zip(("left", "right"), hosts, strict=True):
        modes = [
            sum(1 << p for p in pins[e.event.mode]) for e in program.events if e.event.arm == arm
        ]
        assert len(set(modes)) > 1, f"arm {arm}: no gripper change"  # the plan uses both
        seen = [0] + [
            int(v, 16) for v in re.findall(rf"{re.escape(host)}: digital outputs (0x\w+)", log)
        ]
        # one pin per change, and every mode passed through in order
        assert all(bin(a ^ b).count("1") == 1 for a, b in itertools.pairwise(seen)), seen
        flips = sum(bin(a ^ b).count("1") for a, b in itertools.pairwise([0, *modes]))
        assert len(seen) - 1 == flips, (seen, modes)
        rest = iter(seen)
        assert all(m in rest for m in modes), (seen, modes)  # a subsequence
        assert seen[-1] == modes[-1]


def test_tool_changes_and_the_taping_gun_on_their_outputs(
    tmp_path: Path, emulated: tuple[Path, list[str], list[Emulator]]
) -> None:
    """With ``changer_release`` each tool change sets that standard digital output of the
    changing arm's controller through the real RTDEIOInterface (high to leave the tool in
    its slot, low to lock the next), and with ``trigger_io`` the taping gun's output is high
    while it tapes; the other arm's outputs are not touched. The driver plays the program's
    segments from its first tool change to the end of the taping (the emulator starts the
    arms there: the route before it is what the other tests run)."""
    from cellengine.drivers.play import segment_events
    from cellengine.drivers.registry import make_driver
    from tests.skills.atc import atc_cell
    from tests.skills.test_cable_tape import ROUTE, TAPE

    _, hosts, started = emulated
    arms = f"arms: {{left: {hosts[0]}, right: {hosts[1]}}}"
    driver = f"{{kind: ur_rtde, {arms}, changer_release: 4, trigger_io: {{taping_gun: 5}}}}"
    steps = ROUTE + TAPE % "routing.guide2"
    plan = atc_cell(tmp_path / "atc", steps, ("driver: {kind: sim}", f"driver: {driver}"))
    compiled = compile_plan(plan)
    program, world = compiled.program, compiled.world
    labels = [s.segment.label for s in program.segments]
    first = next(k for k, label in enumerate(labels) if label.startswith("ChangeTool"))
    last = next(k for k, s in enumerate(program.segments) if s.segment.triggers)
    events = segment_events(program)
    q0 = program.segments[first].trajectory.q[0]
    start(hosts, q0, started)
    joints = {n: arm.joint_names for n, arm in compiled.cell.arms.items()}
    t0 = program.segments[first].trajectory.start_time
    ur = make_driver(world.cell, joints, objects=world.objects, tools=program.tools_at(t0))
    ur.configure()
    ur.activate()
    try:
        for k in range(first, last + 1):
            ur.execute(program.segments[k], events[k])
    finally:
        ur.deactivate()
        ur.finalize()
    log = started[-1].stderr()
    seen = {
        host: [int(v, 16) for v in re.findall(rf"{re.escape(host)}: digital outputs (0x\w+)", log)]
        for host in hosts
    }
    # released (pin 4), locked on the gun, the gun on (pin 5) and off
    assert seen == {hosts[0]: [0x10, 0x00, 0x20, 0x00], hosts[1]: []}
    assert ur.tools == {"left": "taping_gun", "right": "cable_gripper"}
