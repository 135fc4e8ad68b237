"""replay_data: shapes, link capsules against pinocchio, TCPs against Arm.fk, static meshes,
the timeline and the cable spans; sampling and decimation on their own."""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin
import pytest

from cellengine.info import primitives
from cellengine.info.cell import Obstacle
from cellengine.motion.robot import finger_placements
from cellengine.motion.trajectory import Trajectory
from cellengine.program import CompiledSegment, GripperEvent, Program, Segment, TimedEvent
from cellengine.report import replay_data
from cellengine.report.replay import REPLAY_RATE, cables, decimate, jaw_openings, obstacle_mesh
from cellengine.report.sampling import sample_program, sample_times
from tests.report.programs import cable_cell, home, trajectory
from tests.report.programs import sample_program as make_program

TOL = 1e-4  # positions are rounded to 0.1 mm


@pytest.fixture(scope="module")
def replay() -> dict:
    world, cell = cable_cell()
    return replay_data(make_program(cell), cell, world)


def _q_at(replay: dict, k: int) -> np.ndarray:
    return np.array([series[k] for series in replay["q"]])


def test_shapes(replay: dict) -> None:
    _, cell = cable_cell()
    n = len(replay["times"])
    assert n == int(6.0 * REPLAY_RATE) + 1
    assert replay["times"][0] == 0.0 and replay["times"][-1] == pytest.approx(6.0)
    assert replay["duration"] == pytest.approx(6.0)
    assert replay["joint_names"] == list(cell.joint_names)
    assert len(replay["q"]) == len(replay["qd"]) == 12
    assert all(len(s) == n for s in (*replay["q"], *replay["qd"]))
    assert replay["arm_joints"] == {"left": list(range(6)), "right": list(range(6, 12))}
    assert {a: len(p) for a, p in replay["tcp"].items()} == {"left": 3 * n, "right": 3 * n}
    assert len(replay["arm_distance"]) == n
    links = replay["links"]
    assert [link["name"] for link in links] == [str(o.name) for o in cell.collision.geometryObjects]
    strides = {"capsule": 6, "cylinder": 6, "sphere": 3, "box": 12}
    for link in links:
        assert link["stride"] == strides[link["kind"]]
        samples = 1 if link["fixed"] else n
        assert len(link["points"]) == link["stride"] * samples
    kinds = {link["name"]: link["kind"] for link in links}
    assert kinds["left/base"] == "sphere" and kinds["left/tool"] == "box"
    assert kinds["right/upper_arm_link"] == "capsule"
    assert [link["fixed"] for link in links].count(True) == 2  # the two bases


def test_joint_states_are_the_programs(replay: dict) -> None:
    _, cell = cable_cell()
    program = make_program(cell)
    k = 40  # 1.6 s, inside segment 0
    q, qd, _ = program.segments[0].trajectory.sample(replay["times"][k])
    assert _q_at(replay, k) == pytest.approx(q, abs=1e-5)
    assert np.array([s[k] for s in replay["qd"]]) == pytest.approx(qd, abs=1e-5)


@pytest.mark.parametrize("k", [0, 37, 90, 150])
def test_capsule_end_points_are_pinocchios_placements(replay: dict, k: int) -> None:
    """Each capsule's axis ends from the joint placement times the object's placement."""
    _, cell = cable_cell()
    q = _q_at(replay, k)
    data = cell.model.createData()
    pin.forwardKinematics(cell.model, data, q)
    checked = 0
    for link, obj in zip(replay["links"], cell.collision.geometryObjects, strict=True):
        if not isinstance(obj.geometry, coal.Capsule):
            continue
        M = data.oMi[obj.parentJoint] * obj.placement
        half = float(obj.geometry.halfLength)
        ends = [M.act(np.array([0.0, 0.0, s * half])) for s in (-1.0, 1.0)]
        j = 0 if link["fixed"] else k
        got = np.array(link["points"][6 * j : 6 * j + 6]).reshape(2, 3)
        assert got == pytest.approx(np.array(ends), abs=TOL), link["name"]
        assert link["radius"] == pytest.approx(float(obj.geometry.radius))
        checked += 1
    assert checked == 16


def test_box_and_sphere_placements(replay: dict) -> None:
    _, cell = cable_cell()
    k = 100
    q = _q_at(replay, k)
    data = cell.model.createData()
    pin.forwardKinematics(cell.model, data, q)
    by_name = {link["name"]: link for link in replay["links"]}
    # the fingers at the opening of each gripper's mode at sample k
    program = make_program(cell)
    jaw = jaw_openings(program, cell, np.array(replay["times"]))[k]
    fingers = {n: M for a, o in jaw.items() for n, M in finger_placements(cell.arms[a], o).items()}
    for obj in cell.collision.geometryObjects:
        link = by_name[str(obj.name)]
        M = data.oMi[obj.parentJoint] * fingers.get(str(obj.name), obj.placement)
        if isinstance(obj.geometry, coal.Box):
            got = np.array(link["points"][12 * k : 12 * k + 12]).reshape(4, 3)
            half = np.asarray(obj.geometry.halfSide)
            want = [M.translation, *(M.rotation[:, i] * half[i] for i in range(3))]
            assert got == pytest.approx(np.array(want), abs=TOL)
        elif isinstance(obj.geometry, coal.Sphere):
            assert link["points"] == pytest.approx(M.translation, abs=TOL)


def test_tcp_is_arm_fk(replay: dict) -> None:
    _, cell = cable_cell()
    for k in (0, 60, 150):
        q = cell.split(_q_at(replay, k))
        for arm in ("left", "right"):
            got = replay["tcp"][arm][3 * k : 3 * k + 3]
            assert got == pytest.approx(cell.arms[arm].fk(q[arm])[:3, 3], abs=TOL)


def test_static_meshes(replay: dict) -> None:
    world, _ = cable_cell()
    statics = {s["name"]: s for s in replay["static"]}
    elements = {f"{p}.{e}" for p, pl in world.platforms.items() for e in pl.elements}
    assert set(statics) == elements | {"table"}
    table = statics["table"]
    assert table["ground"] is True and table["kind"] == "obstacle"
    assert not any(s["ground"] for n, s in statics.items() if n != "table")
    for s in statics.values():
        v = np.array(s["vertices"]).reshape(-1, 3)
        f = np.array(s["triangles"]).reshape(-1, 3)
        assert len(f) > 0 and f.min() >= 0 and f.max() < len(v)
    # an element's mesh placed in the cell frame
    platform = world.platforms["routing"]
    element = platform.elements["guide2"]
    T = platform.T_cell_platform @ element.T_platform_element
    want = np.asarray(element.mesh.vertices) @ T[:3, :3].T + T[:3, 3]
    got = np.array(statics["routing.guide2"]["vertices"]).reshape(-1, 3)
    assert got == pytest.approx(want, abs=TOL)
    v = np.array(table["vertices"]).reshape(-1, 3)
    assert v.min(axis=0) == pytest.approx([-0.2, -0.7, -0.02])
    assert v.max(axis=0) == pytest.approx([1.2, 0.7, 0.0], abs=1e-9)
    assert len(replay["keypoints"]) == len(world.keypoints())


def test_timeline_events_and_cable(replay: dict) -> None:
    assert replay["steps"] == [
        {"step": 0, "label": "PickCable", "title": "step 1 PickCable", "start": 0.0, "end": 3.0},
        {
            "step": 1,
            "label": "RouteCable guide2",
            "title": "step 2 RouteCable guide2",
            "start": 3.0,
            "end": 6.0,
        },
    ]
    assert [(s["index"], s["strategy"]) for s in replay["segments"]] == [
        (0, "split"),
        (1, "split"),
        (2, "sync"),
    ]
    assert [e["time"] for e in replay["events"]] == [2.0, 2.0, 6.0]
    # both hands hold cable1 (one by its connector) from the grasp to the right's release;
    # segment 2's facts place it in guide2's slot at its end
    assert replay["cables"] == [
        {
            "name": "cable1",
            "held": [{"arms": ["left", "right"], "start": 2.0, "end": 6.0}],
            "anchors": [{"time": 6.0, "guide": "routing.guide2", "p": [0.3, -0.2, 0.065]}],
            "members": [{"name": "cable1", "color": "grey"}],
        }
    ]


def test_cables_held_by_one_or_two_hands_and_anchored() -> None:
    world, cell = cable_cell()
    program = make_program(cell)  # segment 2 (3 s to 6 s) ends with a slot in its facts
    events = (
        TimedEvent(0.5, GripperEvent("left", "grasp", "vial1")),  # not a cable
        TimedEvent(1.0, GripperEvent("left", "slide", "cable1")),
        TimedEvent(1.5, GripperEvent("right", "grasp", "cable1.connector")),
        TimedEvent(2.0, GripperEvent("left", "grasp", "cable1")),  # same hands: one span
        TimedEvent(2.5, GripperEvent("left", "open", None)),
        TimedEvent(4.0, GripperEvent("left", "grasp", "cable1")),
    )
    out = cables(Program(program.joint_names, program.segments, events), world)
    assert out == [
        {
            "name": "cable1",
            "held": [
                {"arms": ["left"], "start": 1.0, "end": 1.5},
                {"arms": ["left", "right"], "start": 1.5, "end": 2.5},
                {"arms": ["right"], "start": 2.5, "end": 4.0},
                {"arms": ["left", "right"], "start": 4.0, "end": 6.0},
            ],
            "anchors": [{"time": 6.0, "guide": "routing.guide2", "p": [0.3, -0.2, 0.065]}],
            "members": [{"name": "cable1", "color": "grey"}],
        }
    ]
    # nobody holds a cable: nothing to draw, whatever the facts say
    assert cables(Program(program.joint_names, program.segments, ()), world) == []


def test_sampling_rate_is_capped_and_gaps_hold() -> None:
    _, cell = cable_cell()
    program = make_program(cell)
    times = sample_times(program, 25.0, 11)
    assert len(times) == 11 and times[-1] == 6.0
    assert np.diff(times) == pytest.approx(0.6)
    # a gap between two segments: the first one's end state, at rest
    q0 = home(cell)
    q1 = q0 + 0.2
    a = trajectory(cell, q0, q1, 0.0, 1.0)
    b = trajectory(cell, q1, q0, 2.0, 1.0)
    segs = tuple(CompiledSegment(Segment(0, "x"), "split", t, {}) for t in (a, b))
    gap = Program(cell.joint_names, segs, ())
    q, qd = sample_program(gap, np.array([0.5, 1.5, 2.5, 3.5]))
    assert q[1] == pytest.approx(q1) and qd[1] == pytest.approx(0.0, abs=1e-9)
    assert q[3] == pytest.approx(q0)
    assert q[0] == pytest.approx(a.sample(0.5)[0]) and q[2] == pytest.approx(b.sample(2.5)[0])


def test_decimate_keeps_the_shape() -> None:
    sphere = primitives.sphere(0.1, subdivisions=5)
    v, f = decimate(sphere.vertices, sphere.faces, 2000)
    assert 200 < len(f) <= 2000
    assert f.min() >= 0 and f.max() < len(v)
    assert np.linalg.norm(v, axis=1) == pytest.approx(0.1, abs=0.005)
    small = primitives.box((1, 2, 3))
    v2, f2 = decimate(small.vertices, small.faces, 2000)
    assert len(f2) == 12 and v2 is not None


def test_obstacle_meshes() -> None:
    cyl = obstacle_mesh(Obstacle.model_validate({"cylinder": {"radius": 0.1, "length": 0.4}}))
    assert cyl.bounds == pytest.approx(np.array([[-0.1, -0.1, -0.2], [0.1, 0.1, 0.2]]), abs=1e-9)
    ball = obstacle_mesh(Obstacle.model_validate({"sphere": {"radius": 0.05}}))
    assert np.linalg.norm(ball.vertices, axis=1) == pytest.approx(0.05)
    box = obstacle_mesh(Obstacle.model_validate({"box": [0.1, 0.2, 0.3]}))
    assert len(box.vertices) == 8 and len(box.faces) == 12
    assert box.is_watertight and box.volume == pytest.approx(0.006)


def test_program_joint_order_does_not_matter(replay: dict) -> None:
    world, cell = cable_cell()
    program = make_program(cell)
    perm = np.arange(12)[::-1]
    names = tuple(program.joint_names[i] for i in perm)

    def permuted(cs: CompiledSegment) -> CompiledSegment:
        t = cs.trajectory
        traj = Trajectory(names, t.t, t.q[:, perm], t.qd[:, perm], t.qdd[:, perm])
        return CompiledSegment(cs.segment, cs.strategy, traj, cs.report)

    other = Program(names, tuple(permuted(cs) for cs in program.segments), program.events)
    again = replay_data(other, cell, world)
    assert again["q"] == replay["q"] and again["links"] == replay["links"]


def test_empty_program_shows_the_cell_at_home() -> None:
    world, cell = cable_cell()
    out = replay_data(Program(cell.joint_names, (), ()), cell, world)
    assert out["times"] == [0.0] and out["duration"] == 0.0
    assert [s[0] for s in out["q"]] == pytest.approx(home(cell), abs=1e-5)
    assert out["steps"] == [] and out["segments"] == [] and out["cables"] == []
