"""The executor end to end on the cable-routing cell, with hand-made segments."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from cellengine.errors import InputError
from cellengine.execute import STRATEGIES, Compiler, compile_segments, program_trajectory
from cellengine.execute.checks import tcp_distances
from cellengine.motion.cartesian import ArmInCell, cartesian_path
from cellengine.motion.gate import check_cell_trajectory
from cellengine.motion.ik import arm_ik
from cellengine.program import ArmPath, GripperEvent, Program, Segment
from tests.execute.scenes import (
    LEFT_READY,
    cable_cell,
    home,
    line,
    pose,
    ready,
    reference_segments,
    states,
    tcp,
)


@pytest.fixture(scope="module", params=STRATEGIES)
def program(request: pytest.FixtureRequest) -> Program:
    world, cell, checker = cable_cell()
    return compile_segments(world, cell, checker, reference_segments(), home(cell), request.param)


def test_every_segment_is_compiled_in_order(program: Program) -> None:
    labels = [s.segment.label for s in program.segments]
    assert labels == [s.label for s in reference_segments()]
    for a, b in zip(program.segments, program.segments[1:], strict=False):
        assert b.trajectory.start_time == pytest.approx(a.trajectory.end_time, abs=1e-6)
    assert program.segments[0].trajectory.start_time == 0.0
    assert program.duration == program.segments[-1].trajectory.end_time > 0


def test_the_whole_program_is_continuous_and_within_limits_at_1ms(program: Program) -> None:
    _, cell, checker = cable_cell()
    whole = program_trajectory(program)  # concatenate refuses any jump at a junction
    assert whole.joint_names == cell.joint_names == program.joint_names
    report = check_cell_trajectory(whole, cell, checker)
    assert report.ok, [str(v) for v in report.violations]
    q, _, _ = whole.sample(np.arange(0.0, whole.end_time, 0.001))
    assert np.abs(np.diff(q, axis=0)).max() < 0.01  # rad per ms: no jump anywhere
    assert np.allclose(whole.q[0], home(cell))
    assert np.allclose(whole.qd[[0, -1]], 0.0) and np.allclose(whole.qdd[[0, -1]], 0.0)


def test_events_at_the_start_and_end_of_their_segments(program: Program) -> None:
    expected = []
    for s in program.segments:
        expected += [(s.trajectory.start_time, e) for e in s.segment.before]
        expected += [(s.trajectory.end_time, e) for e in s.segment.after]
    assert [(e.time, e.event) for e in program.events] == expected
    times = [e.time for e in program.events]
    assert times == sorted(times)
    grasp = next(e for e in program.events if e.event.mode == "grasp")
    assert grasp.time == pytest.approx(program.segments[1].trajectory.end_time)


def test_reports_say_what_was_checked(program: Program) -> None:
    for s in program.segments:
        r = s.report
        assert r["strategy"] == s.strategy
        assert r["checks"]["gate"] is True and r["checks"]["gate_samples"] > 0
        cartesian = {p.arm for p in s.segment.paths if p.kind == "cartesian"}
        assert set(r["fraction"]) == cartesian | set(s.segment.closed_chain or ())
        assert all(f == 1.0 for f in r["fraction"].values())
        assert r["duration_s"] == pytest.approx(s.trajectory.duration)
        assert r["planning_time_s"] > 0
        assert r["min_arm_distance_m"] > 0.001  # the checker's clearance
        assert set(r["durations_s"]) == {"joint", "published"}
        # TOPP-RA's profile is a lower bound; the jerk-limited one alone is a smoothed
        # optimum, which timing the pair together can beat by a little
        assert r["time_optimal_bound_s"] <= r["jerk_limited_bound_s"]
        assert r["time_optimal_bound_s"] <= r["duration_s"]


def test_the_cartesian_line_is_followed(program: Program) -> None:
    _, cell, _ = cable_cell()
    p = tcp(cell, "left", states(program.segments[1].trajectory, 0.005))[:, :3, 3]
    a = np.array(LEFT_READY)
    b = a + np.array([0.1, 0.0, 0.0])
    off_line = np.linalg.norm(np.cross(p - a, b - a), axis=1) / np.linalg.norm(b - a)
    assert off_line.max() < 2e-4  # m: the spline between 5 mm waypoints stays on the line
    assert np.allclose(p[[0, -1]], [a, b], atol=1e-6)


def test_closed_chain_keeps_the_hands_relative_pose(program: Program) -> None:
    _, cell, _ = cable_cell()
    q = states(program.segments[3].trajectory, 0.01)
    right, left = tcp(cell, "right", q), tcp(cell, "left", q)
    rel = np.linalg.inv(right) @ left
    assert np.abs(rel - rel[0]).max() < 2e-4
    assert right[-1, 2, 3] - right[0, 2, 3] == pytest.approx(0.1, abs=1e-6)


def test_kept_distance_along_the_arc(program: Program) -> None:
    _, cell, _ = cable_cell()
    seg = program.segments[4]
    d = tcp_distances(cell, states(seg.trajectory), ("left", "right"))
    assert np.ptp(d) < 1e-3
    kept = seg.report["keep_distance"]
    assert kept["deviation_m"] < 1e-3 and kept["distance_m"] == pytest.approx(d[0], abs=1e-9)
    assert seg.report["checks"]["keep_distance"] is True


def test_compiling_is_deterministic_and_pure() -> None:
    world, cell, checker = cable_cell()
    scene = checker.scene
    runs = [
        compile_segments(world, cell, checker, reference_segments(), home(cell), "split")
        for _ in range(2)
    ]
    assert checker.scene is scene and not scene.held  # the caller's checker is untouched
    a, b = runs
    assert a.events == b.events
    for x, y in zip(a.segments, b.segments, strict=True):
        for key in ("t", "q", "qd", "qdd"):
            assert np.array_equal(getattr(x.trajectory, key), getattr(y.trajectory, key))
        rx = {k: v for k, v in x.report.items() if k != "planning_time_s"}
        ry = {k: v for k, v in y.report.items() if k != "planning_time_s"}
        assert rx == ry


def test_a_goal_out_of_reach_is_refused_naming_step_and_segment() -> None:
    world, cell, checker = cable_cell()
    goal = pose((1.5, 0.15, 0.2))[None]
    far = Segment(4, "PickCable: reach", (ArmPath("left", "transit", goal),))
    with pytest.raises(InputError) as e:
        compile_segments(world, cell, checker, [far], home(cell))
    assert str(e.value) == (
        "step 5 (PickCable: reach): the left arm cannot reach its transit goal at "
        "(1500.0, 150.0, 200.0) mm: no IK solution within its joint limits"
    )


def test_a_cartesian_path_out_of_reach_is_refused_with_its_stop() -> None:
    world, cell, checker = cable_cell()
    start = compile_segments(world, cell, checker, [ready()], home(cell))
    q = start.segments[-1].trajectory.q[-1]
    poses = line(LEFT_READY, (1.2, 0.15, 0.2))
    seg = Segment(2, "RouteCable guide3: slide", (ArmPath("left", "cartesian", poses),))
    expected = cartesian_path(
        cell.arms["left"], poses, q[cell.slices["left"]], check=ArmInCell(checker, cell, "left", q)
    )
    assert expected.stop is not None and 0 < expected.fraction < 1
    with pytest.raises(InputError) as e:
        compile_segments(world, cell, checker, [ready(), seg], home(cell))
    assert str(e.value) == (
        f"step 3 (RouteCable guide3: slide): the left arm's Cartesian path stops at "
        f"{100 * expected.fraction:.0f} % of its length: {expected.stop.message}"
    )


def test_the_error_carries_the_step_to_put_it_in_the_plan_file(tmp_path) -> None:  # type: ignore[no-untyped-def]
    from cellengine.errors import StepError
    from cellengine.info.yamlio import load_yaml

    world, cell, checker = cable_cell()
    plan = tmp_path / "plan.yaml"
    plan.write_text("cell: cell.yaml\nsteps:\n  - skill: A\n  - skill: B\n    cable: c\n")
    far = Segment(1, "B: reach", (ArmPath("left", "transit", pose((1.5, 0.15, 0.2))[None]),))
    with pytest.raises(StepError) as e:
        compile_segments(world, cell, checker, [far], home(cell))
    assert e.value.step == 1
    line, col = load_yaml(plan).where(("steps", e.value.step)) or (None, None)
    (problem,) = e.value.located(plan, line, col).problems
    assert (problem.file, problem.line, problem.col) == (str(plan), 4, 5)
    assert problem.message.startswith("step 2 (B: reach): the left arm cannot reach")


def test_the_gate_stops_a_held_object_in_the_table() -> None:
    """A 6 mm cable piece taken 2 mm above the table (beyond the routing plate's edge, at
    y = 0.21 m): the tool clears the table, what it holds does not, and the gate says so
    before anything would move."""
    world, cell, checker = cable_cell()
    low = (0.40, 0.30, 0.002)
    segments = [
        ready(),
        Segment(
            1,
            "down to the table",
            (ArmPath("left", "cartesian", line(LEFT_READY, low)),),
            near=(("left", "table"),),  # within the clearance on purpose
        ),
        Segment(1, "grasp", before=(GripperEvent("left", "grasp", "cable1"),)),
    ]
    with pytest.raises(InputError) as e:
        compile_segments(world, cell, checker, segments, home(cell))
    message = str(e.value)
    assert message.startswith("step 2 (grasp): the trajectory fails the gate: t=")
    assert "collision between cable1@left / table" in message


def test_held_objects_follow_the_gripper_events() -> None:
    from cellengine.execute import Compiler

    world, cell, checker = cable_cell()
    c = Compiler(world, cell, checker, home(cell))
    for s in reference_segments()[:2]:
        c.add(s)
    assert set(c.checker.scene.held) == {"cable1@left"}
    c.add(reference_segments()[2])
    c.add(reference_segments()[3])
    assert set(c.checker.scene.held) == {"cable1@left", "cable1@right"}
    c.add(reference_segments()[4])
    assert set(c.checker.scene.held) == {"cable1@right"}  # left opened after the arc


def test_a_refused_segment_leaves_the_compiler_as_it_was() -> None:
    from cellengine.execute import Compiler

    world, cell, checker = cable_cell()
    c = Compiler(world, cell, checker, home(cell))
    c.add(ready())
    q, t, events, held = c.q.copy(), c.t, list(c.events), c.checker.scene.held
    bad = Segment(
        1,
        "grasp and reach too far",
        (ArmPath("left", "transit", pose((1.5, 0.15, 0.2))[None]),),
        before=(GripperEvent("left", "grasp", "cable1"),),
    )
    with pytest.raises(InputError):
        c.add(bad)
    assert np.array_equal(c.q, q) and c.t == t and c.events == events
    assert c.checker.scene.held == held and len(c.segments) == 1
    c.add(reference_segments()[1])  # and it goes on from there
    assert len(c.program().segments) == 2


def test_home_configuration() -> None:
    from cellengine.execute import home_configuration

    _, cell, _ = cable_cell()
    assert np.array_equal(home_configuration(cell), home(cell))


def test_held_shapes() -> None:
    from cellengine.execute.held import held_object

    world, _, checker = cable_cell()
    connector = held_object(world, checker.scene, "left", "cable1.connector")
    assert connector.name == "cable1.connector@left"
    assert np.allclose(connector.shape.halfSide * 2, [0.035, 0.031, 0.016])
    piece = held_object(world, checker.scene, "right", "cable1")
    assert np.allclose(piece.shape.halfSide * 2, 0.006)
    assert "routing.guide1" in piece.allowed and "table" not in piece.allowed
    other = held_object(world, checker.scene, "right", "something")
    assert np.allclose(other.shape.halfSide * 2, 0.01)


def test_a_coupling_of_an_unknown_arm_is_refused() -> None:
    world, cell, checker = cable_cell()
    seg = Segment(0, "hands apart", keep_distance=("left", "middle"))
    with pytest.raises(InputError) as e:
        compile_segments(world, cell, checker, [seg], home(cell))
    assert str(e.value) == (
        "step 1 (hands apart): keep_distance names an unknown arm 'middle' "
        "(the cell has left, right)"
    )


def test_a_transit_reaches_its_goal_on_a_branch_the_segments_after_it_require() -> None:
    """A segment requiring a branch of an arm (Segment.branches): the transit before it puts
    the arm on one of them where it can; an arm on another is refused there, the error
    blaming the arm's configuration (execute/candidates.py then compiles again from the
    start)."""
    world, cell, checker = cable_cell()
    ik = arm_ik(cell.arms["left"])
    up = (LEFT_READY[0], LEFT_READY[1], LEFT_READY[2] + 0.05)
    lift = Segment(1, "lift", (ArmPath("left", "cartesian", line(LEFT_READY, up)),))
    first = compile_segments(world, cell, checker, [ready(), lift], home(cell))
    on = ik.branch(first.segments[-1].trajectory.q[-1][cell.slices["left"]])
    rows = ik.by_branch(pose(LEFT_READY))
    assert rows is not None

    def free(k: int) -> bool:  # the left arm there on branch k, the right one at home
        q = home(cell)
        q[cell.slices["left"]] = rows[k]
        return not np.isnan(rows[k]).any() and not checker.in_collision(q)

    other = next(k for k in range(8) if k != on and free(k))
    required = replace(lift, branches=(("left", frozenset({other})),))
    program = compile_segments(world, cell, checker, [ready(), required], home(cell))
    q = program.segments[-1].trajectory.q[-1][cell.slices["left"]]
    assert ik.branch(q) == other
    # a transit that did not look ahead at it: the arm there on its own branch, refused
    c = Compiler(world, cell, checker, home(cell))
    c.add(ready())
    with pytest.raises(InputError) as e:
        c.add(required)
    assert e.value.blames == "configuration"
    assert str(e.value) == (
        f"step 2 (lift): the left arm is on IK branch {on}; the skill checked this "
        f"segment's poses on branches [{other}] only"
    )


def test_two_arms_on_a_pair_of_branches_the_segment_does_not_pair_are_refused() -> None:
    """Segment.paired: each arm's branch may be among those it checked (Segment.branches)
    while the two together are not a pair it checked: refused, blaming the configuration;
    on a pair it names, the segment runs."""
    world, cell, checker = cable_cell()
    up = (LEFT_READY[0], LEFT_READY[1], LEFT_READY[2] + 0.05)
    lift = Segment(1, "lift", (ArmPath("left", "cartesian", line(LEFT_READY, up)),))
    c = Compiler(world, cell, checker, home(cell))
    c.add(ready())
    left, right = (
        arm_ik(cell.arms[arm]).branch(c.q[cell.slices[arm]]) for arm in ("left", "right")
    )
    other = next(k for k in range(8) if k not in (left, right))
    pairs = frozenset({(left, other), (other, right)})
    with pytest.raises(InputError) as e:
        c.add(replace(lift, paired=(("left", "right", pairs),)))
    assert e.value.blames == "configuration"
    assert str(e.value) == (
        f"step 2 (lift): the left and right arms are on IK branches {left} and {right}; the "
        f"skill checked this segment's poses with them on {sorted(pairs)} only"
    )
    c.add(replace(lift, paired=(("left", "right", pairs | {(left, right)}),)))
    assert c.program().segments[-1].segment.label == "lift"
