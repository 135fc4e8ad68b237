"""Collision scene and checks with known answers, on the cable-routing cell: the arms at home,
an arm driven into the other arm, the table and a guide, a held vial, segments that pass through
an obstacle between free end points, the ACM and SRDF pairs, determinism."""

from __future__ import annotations

import math
import shutil
from collections.abc import Callable
from pathlib import Path
from types import MappingProxyType
from typing import Any

import coal
import numpy as np
import pinocchio as pin
import pytest

from cellengine import geometry as g
from cellengine.errors import InputError
from cellengine.info import primitives
from cellengine.info.cell import Obstacle
from cellengine.info.load import load_world
from cellengine.info.mesh import Mesh
from cellengine.info.platform import CollisionBox, Platform
from cellengine.motion.collision import CollisionChecker, Contact
from cellengine.motion.robot import CellModel, build_cell_model
from cellengine.motion.scene import (
    CollisionScene,
    _mesh_shape,
    attach,
    build_scene,
    detach,
    held_box,
    held_cylinder,
    held_from_world,
    load_srdf,
    sampled_self_pairs,
)
from cellengine.motion.ur_ik import URKinematics
from cellengine.world import World
from tests.conftest import CELLS
from tests.helpers import element

CELL = CELLS / "cable_routing"
Write = Callable[[str, str], Path]
HOME = np.radians([0, -90, 90, -90, -90, 0])
# An elbow-up posture reaching in front of the arm (+x of the cell): IK seeds for the targets.
FRONT = np.array([0.0, -1.8, -2.0, -1.0, math.pi / 2, 0.0])
DOWN = g.rot_x(math.pi)  # the TCP's z (the approach) pointing down


@pytest.fixture(scope="module")
def world(tmp_path_factory: pytest.TempPathFactory) -> World:
    """The reference cell with its tools as the stand-in box (flange to TCP, 20 mm square):
    the postures below were chosen for it (tests/motion/test_tool.py checks the real shape)."""
    folder = tmp_path_factory.mktemp("stand_in") / "cable_routing"
    shutil.copytree(CELL, folder)
    text = (folder / "cell.yaml").read_text()
    start = text.index("    shape:\n")
    end = text.index("    fingers:")
    end = text.index("\n", end) + 1
    (folder / "cell.yaml").write_text(text[:start] + text[end:])
    return load_world(folder / "cell.yaml", folder / "objects.yaml")


@pytest.fixture(scope="module")
def cell(world: World) -> CellModel:
    return build_cell_model(world)


@pytest.fixture(scope="module")
def scene(cell: CellModel, world: World) -> CollisionScene:
    return build_scene(cell, world)


@pytest.fixture
def checker(scene: CollisionScene) -> CollisionChecker:
    return CollisionChecker(scene)


def ik(cell: CellModel, arm: str, T_cell_tcp: np.ndarray, seed: np.ndarray = FRONT) -> np.ndarray:
    a = cell.arms[arm]
    assert a.dh is not None
    T_base_flange = g.inverse(a.T_cell_base) @ T_cell_tcp @ g.inverse(a.T_flange_tcp)
    q = URKinematics.from_dh(a.dh, a.limits.lower, a.limits.upper).ik(T_base_flange, seed)
    assert q is not None
    np.testing.assert_allclose(a.fk(q), T_cell_tcp, atol=1e-9)
    return q


def both(cell: CellModel, left: np.ndarray = HOME, right: np.ndarray = HOME) -> np.ndarray:
    return cell.join({"left": left, "right": right})


def all_contacts(scene: CollisionScene, q: np.ndarray) -> set[tuple[str, str]]:
    """Every checked pair in contact, by pinocchio's plain pair loop (no broad phase)."""
    model = scene.cell.model
    gdata = pin.GeometryData(scene.geometry)
    pin.computeCollisions(model, model.createData(), scene.geometry, gdata, q, False)
    return {
        scene.pair_names(p)
        for p in range(len(scene.pairs))
        if gdata.collisionResults[p].isCollision()
    }


def segment_distance(p0: np.ndarray, p1: np.ndarray, r0: np.ndarray, r1: np.ndarray) -> float:
    """Distance between segments p0-p1 and r0-r1: a fine sampling of the first, the exact
    closest point on the second for each sample."""
    s = np.linspace(0.0, 1.0, 20001)[:, None]
    points = p0 + s * (p1 - p0)
    d = r1 - r0
    t = np.clip((points - r0) @ d / (d @ d), 0.0, 1.0)[:, None]
    return float(np.min(np.linalg.norm(points - (r0 + t * d), axis=1)))


def capsule_axis(
    cell: CellModel, q: np.ndarray, joint: str, xyz: list[float], rpy: list[float], length: float
) -> tuple[np.ndarray, np.ndarray]:
    """The end points of a capsule's axis in the cell frame, from the URDF's numbers."""
    data = cell.model.createData()
    pin.forwardKinematics(cell.model, data, q)
    T_cell_joint = data.oMi[cell.model.getJointId(joint)].homogeneous
    T = T_cell_joint @ g.pose(xyz, rpy)
    return T @ [0, 0, -length / 2, 1], T @ [0, 0, length / 2, 1]


# ---------------------------------------------------------------------------------- states


def test_home_is_free_with_the_forearm_and_wrist_3_closest(
    cell: CellModel, checker: CollisionChecker
) -> None:
    q = both(cell)
    assert not checker.in_collision(q)
    assert checker.check(q) is None
    d, pair = checker.distance(q)
    assert pair == ("left/forearm_link", "left/wrist_3_link")  # the arms are mirror images
    # ur5e.urdf: forearm tube and wrist 3 housing, both of radius 45 mm
    a = capsule_axis(
        cell, q, "left_elbow_joint", [-0.1961, 0, 0.007], [math.pi / 2, 0, -math.pi / 2], 0.3922
    )
    b = capsule_axis(cell, q, "left_wrist_3_joint", [0, 0, -0.0723], [0, 0, 0], 0.0546)
    expected = segment_distance(a[0][:3], a[1][:3], b[0][:3], b[1][:3]) - 0.045 - 0.045
    assert d == pytest.approx(expected, abs=1e-6)
    assert d == pytest.approx(0.0709, abs=1e-4)


def test_distance_between_the_arms_at_home(cell: CellModel, checker: CollisionChecker) -> None:
    q = both(cell)
    d, pair = checker.distance(q, between=("left", "right"))
    assert pair == ("left/upper_arm_link", "right/shoulder_link")
    # upper arm tube (r 55 mm) and the shoulder lift housing (r 65 mm)
    a = capsule_axis(
        cell,
        q,
        "left_shoulder_lift_joint",
        [-0.2125, 0, 0.138],
        [math.pi / 2, 0, -math.pi / 2],
        0.425,
    )
    b = capsule_axis(
        cell, q, "right_shoulder_pan_joint", [0, -0.069, 0], [math.pi / 2, 0, math.pi], 0.138
    )
    expected = segment_distance(a[0][:3], a[1][:3], b[0][:3], b[1][:3]) - 0.055 - 0.065
    assert d == pytest.approx(expected, abs=1e-6)
    with pytest.raises(ValueError, match="unknown arm 'middle'"):
        checker.distance(q, between=("left", "middle"))


def test_apart_agrees_with_the_distance_and_sees_only_the_two_arms(
    cell: CellModel, checker: CollisionChecker, world: World
) -> None:
    q = both(cell)
    d, _ = checker.distance(q, between=("left", "right"))
    assert checker.apart(q, d - 1e-4, ("left", "right"))
    assert not checker.apart(q, d + 1e-4, ("right", "left"))
    # the left tool in a guide: in collision, but not with the other arm
    T_cell_slot = world.pose("routing.guide2.slot")
    q = both(cell, left=ik(cell, "left", g.transform(DOWN, T_cell_slot[:3, 3])))
    assert checker.in_collision(q)
    assert checker.apart(q, 0.01, ("left", "right"))


def test_distance_between_an_arm_and_the_environment(
    cell: CellModel, checker: CollisionChecker, world: World
) -> None:
    """None as an owner: the cell's fixtures; the left tool in a guide touches it, not the
    other arm."""
    T_cell_slot = world.pose("routing.guide2.slot")
    q = both(cell, left=ik(cell, "left", g.transform(DOWN, T_cell_slot[:3, 3])))
    d, pair = checker.distance(q, between=("left", None))
    assert d <= 0.0 and pair[0].startswith("left/tool") and pair[1].startswith("routing.")
    assert checker.distance(q, between=(None, "right"))[0] > 0.0
    assert checker.distance(q, between=("left", "right"))[0] > 0.0


def test_answers_asked_again_are_kept_until_the_held_objects_change(
    cell: CellModel, scene: CollisionScene, world: World
) -> None:
    """distance and apart keep their answers per state: asked again (the arms the other way
    round), the first answer; after an attach, measured anew with what is held."""
    checker = CollisionChecker(scene)
    T_cell_slot = world.pose("routing.guide3.slot")
    q = both(cell, left=ik(cell, "left", g.transform(DOWN, T_cell_slot[:3, 3] + [0, 0, 0.1])))
    first = checker.distance(q, between=("left", "right"))
    assert checker.distance(q.copy(), between=("right", "left")) == first
    assert checker.apart(q, first[0] - 1e-4, ("left", "right"))
    assert checker.apart(q, first[0] - 1e-4, ("right", "left"))
    alone = checker.distance(q)
    checker.attach(held_box("box1", "left", (0.02, 0.02, 0.18), np.eye(4)))
    held = checker.distance(q)
    assert held[0] < alone[0] - 0.01 and "box1" in held[1]  # 90 mm below the TCP, 100 above


def test_check_path_answers_as_check_batch(cell: CellModel, checker: CollisionChecker) -> None:
    """Along a path into a contact and out again (1000 states), and at unrelated states:
    the same answers as checking each state."""
    T_cell_tcp = g.transform(g.rot_x(math.pi / 2), [-0.1, -0.33, 0.6])
    inside = both(cell, left=ik(cell, "left", T_cell_tcp, HOME))
    f = np.concatenate([np.linspace(0.0, 1.0, 500), np.linspace(1.0, 0.0, 500)])[:, None]
    path = both(cell) + f * (inside - both(cell))
    hits = checker.check_batch(path)
    assert 0 < hits.sum() < len(path)
    np.testing.assert_array_equal(checker.check_path(path), hits)
    still = np.repeat(inside[None, :], 5, axis=0)  # standing in the contact: every state
    np.testing.assert_array_equal(checker.check_path(still), np.ones(5, dtype=bool))
    rng = np.random.default_rng(3)
    scattered = both(cell) + rng.uniform(-1.5, 1.5, (200, len(HOME) * 2))
    hits = checker.check_batch(scattered)
    assert 0 < hits.sum() < len(scattered)
    np.testing.assert_array_equal(checker.check_path(scattered), hits)


def test_left_arm_into_the_right_forearm(cell: CellModel, checker: CollisionChecker) -> None:
    # the left TCP pointing along -y, 20 mm inside the right forearm's tube at home
    T_cell_tcp = g.transform(g.rot_x(math.pi / 2), [-0.1, -0.33, 0.6])
    q = both(cell, left=ik(cell, "left", T_cell_tcp, HOME))
    assert all_contacts(checker.scene, q) == {("left/tool", "right/forearm_link")}
    contact = checker.check(q)
    assert contact is not None
    assert contact.pair == ("left/tool", "right/forearm_link")
    assert contact.distance < 0
    assert checker.in_collision(q)
    d, pair = checker.distance(q)
    assert pair == ("left/tool", "right/forearm_link")
    assert d == pytest.approx(contact.distance)


def test_an_arm_into_the_table(cell: CellModel, checker: CollisionChecker) -> None:
    q = both(cell, left=ik(cell, "left", g.transform(DOWN, [0.3, 0.45, -0.01])))
    assert all_contacts(checker.scene, q) == {("left/tool", "table")}
    contact = checker.check(q)
    assert contact is not None and contact.pair == ("left/tool", "table")
    assert contact.distance == pytest.approx(-0.01, abs=1e-9)  # the tool's end 10 mm in


def test_an_arm_into_a_routing_guide(
    cell: CellModel, checker: CollisionChecker, world: World
) -> None:
    T_cell_slot = world.pose("routing.guide2.slot")  # 5 mm below the guide's top, in its slot
    q = both(cell, left=ik(cell, "left", g.transform(DOWN, T_cell_slot[:3, 3])))
    assert all_contacts(checker.scene, q) == {("left/tool", "routing.guide2")}
    contact = checker.check(q)
    assert contact is not None and contact.pair == ("left/tool", "routing.guide2")
    # 60 mm higher the tool clears it
    q_above = both(
        cell, left=ik(cell, "left", g.transform(DOWN, T_cell_slot[:3, 3] + [0, 0, 0.06]))
    )
    assert checker.check(q_above) is None


def test_an_unmapped_cad_part_is_an_obstacle(tmp_path: Path) -> None:
    """A U guide added to the X3D between guide1 and guide2, not to map.csv: in the scene as
    routing.Stray_Guide (it was left out, and a plan ran through it)."""
    folder = tmp_path / "cable_routing"
    shutil.copytree(CELL, folder)
    x3d = folder / "routing" / "routing.x3d"
    text = x3d.read_text()
    i = text.index('<Transform DEF="Guide_U_001"')
    # a 60 mm box centred 40 mm up: standing on the plate like the guides
    stray = '<Transform DEF="Stray_Guide" translation="150 205 40" rotation="0 0 1 1.570796">'
    stray += '<Shape><Box size="10 24 60"/></Shape></Transform>\n'
    x3d.write_text(text[:i] + stray + text[i:])
    world = load_world(folder / "cell.yaml")
    assert [w.message.split(":")[0] for w in world.warnings] == [
        "CAD part 'Stray_Guide' is in no row of map.csv"
    ]
    cell = build_cell_model(world)
    scene = build_scene(cell, world)
    routing = world.platforms["routing"]
    T = routing.T_cell_platform @ routing.elements["Stray_Guide"].T_platform_element
    # the open fingers 30 mm off the TCP along y: one of them where the stray guide stands
    q = both(cell, left=ik(cell, "left", g.transform(DOWN, T[:3, 3] + [0, 0.03, 0])))
    assert ("left/tool/finger_left", "routing.Stray_Guide") in all_contacts(scene, q)


def test_a_held_vial_hits_a_guide_but_not_its_gripper(
    cell: CellModel, scene: CollisionScene, world: World
) -> None:
    checker = CollisionChecker(scene)
    # a 28 x 60 mm vial centred on the TCP: its half beyond the fingertips reaches 30 mm down
    vial = held_cylinder("vial1", "left", 0.014, 0.06, np.eye(4))
    above = world.pose("routing.guide3.slot")[:3, 3] + [0, 0, 0.025]  # TCP 20 mm above the top
    q = both(cell, left=ik(cell, "left", g.transform(DOWN, above)))
    assert checker.check(q) is None
    checker.attach(vial)
    assert checker.scene.acm.reason("vial1", "left/tool") == "held"
    contact = checker.check(q)
    assert contact is not None and contact.pair == ("routing.guide3", "vial1")
    assert all_contacts(checker.scene, q) == {("routing.guide3", "vial1")}
    assert checker.check(both(cell)) is None  # at home it overlaps only its gripper
    checker.detach("vial1")
    assert checker.check(q) is None
    assert "vial1" not in checker.scene.names


def test_held_objects_from_the_world_and_refusals(
    cell: CellModel, scene: CollisionScene, world: World
) -> None:
    connector = held_from_world(world, "cable1.connector", "right", np.eye(4))
    assert isinstance(connector.shape, coal.Box)
    np.testing.assert_allclose(2 * connector.shape.halfSide, [0.035, 0.031, 0.016])
    held = attach(scene, connector)
    assert held.acm.reason("cable1.connector", "right/tool") == "held"
    assert held.acm.reason("cable1.connector", "right/wrist_3_link") == "same_body"
    assert ("cable1.connector", "left/tool") in held.checked
    with pytest.raises(ValueError, match="already in the scene"):
        attach(held, connector)
    with pytest.raises(KeyError, match="no held object 'vial9'"):
        detach(held, "vial9")
    with pytest.raises(ValueError, match="unknown arm 'middle'"):
        attach(scene, held_box("box1", "middle", (0.01, 0.01, 0.01), np.eye(4)))
    # 150 mm up the tool from the TCP it would sit inside the wrist it rides with
    inside = held_box("box1", "left", (0.02, 0.02, 0.02), g.transform(t=[0, 0, -0.2]))
    with pytest.raises(ValueError, match="intersects 'left/wrist_3_link'"):
        attach(scene, inside)


def test_distance_into_a_guide_slot_is_to_the_mesh_not_its_hull(
    cell: CellModel, scene: CollisionScene, world: World
) -> None:
    """A 6 mm ball held 50 mm beyond the TCP, at the centre of guide1's slot (10 mm wide, its
    floor 5 mm below): free, 2 mm from the slot's walls and floor; inside the guide's hull."""
    ball = held_box("ball", "left", (0.006, 0.006, 0.006), g.transform(t=[0, 0, 0.05]))
    checker = CollisionChecker(attach(scene, ball))
    slot = world.pose("routing.guide1.slot")[:3, 3]
    q = both(cell, left=ik(cell, "left", g.transform(DOWN, slot + np.array([0, 0, 0.05]))))
    assert checker.check(q) is None
    d, pair = checker.distance(q)
    assert pair == ("ball", "routing.guide1")
    assert d == pytest.approx(0.002, abs=1e-6)


def test_batch_matches_single_states(cell: CellModel, checker: CollisionChecker) -> None:
    rng = np.random.default_rng(7)
    limits = cell.limits
    Q = rng.uniform(limits.lower, limits.upper, (300, cell.nq))
    batch = checker.check_batch(Q)
    single = np.array([checker.in_collision(q) for q in Q])
    reference = np.array([bool(all_contacts(checker.scene, q)) for q in Q])
    np.testing.assert_array_equal(batch, single)
    np.testing.assert_array_equal(batch, reference)
    assert 0 < batch.mean() < 1
    for q, hit in zip(Q[:60], batch[:60], strict=True):
        contact = checker.check(q)
        assert (contact is not None) == hit
        if contact is not None:
            assert contact.pair in all_contacts(checker.scene, q)
        assert (checker.distance(q)[0] <= 0) == hit
    with pytest.raises(ValueError, match="expected"):
        checker.check_batch(Q[:, :6])
    with pytest.raises(ValueError, match="expected"):
        checker.in_collision(Q[0, :6])


# ---------------------------------------------------------------------------------- segments


def with_obstacles(world: World, obstacles: dict[str, dict[str, Any]]) -> World:
    extra = {k: Obstacle.model_validate(v) for k, v in obstacles.items()}
    cell = world.cell.model_copy(update={"obstacles": {**world.cell.obstacles, **extra}})
    return World(cell, world.cell_file, world.platforms, world.objects)


def test_a_segment_through_an_obstacle_between_free_ends(cell: CellModel, world: World) -> None:
    q0 = ik(cell, "left", g.transform(DOWN, [0.35, 0.45, 0.3]))
    q1 = ik(cell, "left", g.transform(DOWN, [0.35, 0.20, 0.3]), q0)
    mid = cell.arms["left"].fk((q0 + q1) / 2)[:3, 3]
    # a 20 mm ball 10 mm above where the TCP passes half way: the tool's end goes through it
    ball = {
        "ball": {"sphere": {"radius": 0.02}, "pose": {"xyz": list(mid + np.array([0, 0, 0.01]))}}
    }
    checker = CollisionChecker(build_scene(cell, with_obstacles(world, ball)))
    a, b = both(cell, left=q0), both(cell, left=q1)
    assert not checker.in_collision(a) and not checker.in_collision(b)  # a 2-sample check passes
    contact = checker.check_segment(a, b)
    assert contact is not None
    assert contact.pair == ("ball", "left/tool")
    assert contact.t is not None and 0.2 < contact.t < 0.5
    assert contact.distance <= 1e-3
    assert checker.check_segment(b, a) is not None
    # the same move with the ball 100 mm aside passes
    aside = {
        "ball": {"sphere": {"radius": 0.02}, "pose": {"xyz": list(mid + np.array([0.1, 0, 0.01]))}}
    }
    assert (
        CollisionChecker(build_scene(cell, with_obstacles(world, aside))).check_segment(a, b)
        is None
    )


def test_a_near_miss_is_refused_below_the_clearance_only(cell: CellModel, world: World) -> None:
    q0 = ik(cell, "left", g.transform(DOWN, [0.35, 0.45, 0.3]))
    q1 = ik(cell, "left", g.transform(DOWN, [0.35, 0.20, 0.3]), q0)
    centre = cell.arms["left"].fk((q0 + q1) / 2)[:3, 3] + [0, 0, -0.1]
    probe = {"ball": {"sphere": {"radius": 0.01}, "pose": {"xyz": list(centre)}}}
    probing = CollisionChecker(build_scene(cell, with_obstacles(world, probe)))
    path = [both(cell, left=q0 + s * (q1 - q0)) for s in np.linspace(0, 1, 4001)]
    tool = probing.scene.index("left/tool")
    p = next(
        i
        for i, (x, y) in enumerate(probing.scene.pairs)
        if tool in (x, y) and probing.scene.objects[x if y == tool else y].name == "ball"
    )
    closest = min(_pair_distance(probing, q, p) for q in path)
    # grow the ball until the tool passes 0.5 mm from it
    radius = 0.01 + closest - 0.0005
    near = {"ball": {"sphere": {"radius": radius}, "pose": {"xyz": list(centre)}}}
    checker = CollisionChecker(build_scene(cell, with_obstacles(world, near)))
    a, b = path[0], path[-1]
    contact = checker.check_segment(a, b, clearance=1e-3)
    assert contact is not None and contact.pair == ("ball", "left/tool")
    assert 0 < contact.distance <= 1e-3
    assert checker.check_segment(a, b, clearance=1e-4) is None
    with pytest.raises(ValueError, match="clearance"):
        checker.check_segment(a, b, clearance=0)


def _pair_distance(checker: CollisionChecker, q: np.ndarray, p: int) -> float:
    scene = checker.scene
    data, gdata = scene.cell.model.createData(), pin.GeometryData(scene.geometry)
    pin.updateGeometryPlacements(scene.cell.model, data, scene.geometry, gdata, q)
    return float(pin.computeDistance(scene.geometry, gdata, p).min_distance)


def test_segments_agree_with_dense_sampling(cell: CellModel, checker: CollisionChecker) -> None:
    """No segment passed by check_segment has a colliding state among 400 samples, and every
    segment with one is refused."""
    rng = np.random.default_rng(3)
    limits = cell.limits
    starts = rng.uniform(limits.lower, limits.upper, (4000, cell.nq))
    starts = starts[~checker.check_batch(starts)][:120]
    refused = passed = 0
    for q0 in starts:
        q1 = q0 + rng.normal(0.0, 0.3, cell.nq)
        samples = q0 + np.linspace(0, 1, 400)[:, None] * (q1 - q0)
        dense_hit = bool(checker.check_batch(samples).any())
        contact = checker.check_segment(q0, q1)
        if contact is None:
            assert not dense_hit
            passed += 1
        else:
            refused += 1
            assert isinstance(contact, Contact) and contact.t is not None
    assert passed > 20 and refused > 20


def test_a_segment_from_a_colliding_start_names_it_at_t0(
    cell: CellModel, checker: CollisionChecker
) -> None:
    q = both(cell, left=ik(cell, "left", g.transform(DOWN, [0.3, 0.45, -0.01])))
    contact = checker.check_segment(q, both(cell))
    assert contact is not None and contact.t == 0.0 and contact.pair == ("left/tool", "table")
    assert checker.check_segment(both(cell), both(cell)) is None  # no motion, free


# ---------------------------------------------------------------------------------- ACM


def test_acm_contents(scene: CollisionScene) -> None:
    acm, checked = scene.acm, scene.checked
    for arm in ("left", "right"):
        for a, b in [
            ("base", "shoulder_link"),
            ("shoulder_link", "upper_arm_link"),
            ("upper_arm_link", "forearm_link"),
            ("forearm_link#2", "wrist_1_link"),
            ("wrist_1_link", "wrist_2_link"),
            ("wrist_2_link", "wrist_3_link"),
        ]:
            assert acm.reason(f"{arm}/{a}", f"{arm}/{b}") == "adjacent"
        assert acm.reason(f"{arm}/wrist_3_link", f"{arm}/tool") == "same_body"
        assert acm.reason(f"{arm}/base", "table") == "stands_on"
        assert (f"{arm}/tool", "table") in checked
        assert (f"{arm}/tool", f"{arm}/upper_arm_link") in checked  # can fold back onto it
        # d5 - 2 r = 99.7 - 90 mm: wrist 1 and wrist 3 never touch
        assert str(acm.reason(f"{arm}/wrist_1_link", f"{arm}/wrist_3_link")).startswith("never")
        assert str(acm.reason(f"{arm}/shoulder_link#2", "table")).startswith("never")
    # environment against environment: in the ACM, never checked
    statics = [o.name for o in scene.objects if o.kind == "static"]
    assert "routing.guide1" in statics and "table" in statics
    for a in statics:
        for b in statics:
            if a < b:
                assert acm.reason(a, b) == "static"
                assert (a, b) not in checked
    assert acm.reason("left/base", "right/base") == "static"
    assert str(acm.reason("left/shoulder_link", "right/shoulder_link")).startswith("out_of_reach")
    assert ("left/tool", "right/tool") in checked
    # every pair is either checked or allowed, never both
    names = scene.names
    every = {tuple(sorted((a, b))) for i, a in enumerate(names) for b in names[i + 1 :]}
    assert checked | acm.pairs == every and not checked & acm.pairs
    assert acm.by_reason("adjacent") <= acm.pairs


def test_platform_boxes_obstacle_shapes_and_notes(cell: CellModel, world: World) -> None:
    boxes = (
        CollisionBox((0.01, 0.02, 0.03), g.pose([0, 0, 0.015])),
        CollisionBox((0.04, 0.01, 0.01), g.pose([0.02, 0, 0.03])),
    )
    jig = element("jig", (0.4, 0.0, 0.0), {})
    jig = type(jig)(**{**jig.__dict__, "boxes": boxes})
    bare = element("plate", (0.0, 0.0, 0.0), {})
    platform = Platform("bench", g.pose([0.1, 0, 0]), MappingProxyType({"jig": jig, "plate": bare}))
    obstacles = {
        "post": {"cylinder": {"radius": 0.02, "length": 0.3}, "pose": {"xyz": [0.6, 0, 0.15]}},
        "lamp": {"sphere": {"radius": 0.05}, "pose": {"xyz": [0.6, 0.3, 0.8]}},
    }
    w = with_obstacles(world, obstacles)
    w = World(w.cell, w.cell_file, MappingProxyType({"bench": platform}), w.objects)
    scene = build_scene(cell, w)
    shapes = {
        o.name: type(scene.geometry.geometryObjects[i].geometry)
        for i, o in enumerate(scene.objects)
    }
    assert shapes["bench.jig"] is coal.Box and shapes["bench.jig#2"] is coal.Box
    assert shapes["post"] is coal.Cylinder and shapes["lamp"] is coal.Sphere
    assert shapes["table"] is coal.Box
    placement = scene.geometry.geometryObjects[scene.index("bench.jig#2")].placement
    np.testing.assert_allclose(placement.translation, [0.52, 0, 0.03])
    assert any("'bench.plate' has no collision geometry" in n for n in scene.notes)
    # the cable-routing elements: meshes with concavities as BVHs, their hulls as bounds
    routing = build_scene(cell, world)
    i = routing.index("routing.guide1")
    assert isinstance(routing.geometry.geometryObjects[i].geometry, coal.BVHModelOBBRSS)
    assert isinstance(routing.bounds.geometryObjects[i].geometry, coal.Convex)


def test_mesh_shapes_by_convexity() -> None:
    """A convex mesh is its hull, exactly; a concave one a BVH bounded by its hull; a flat one
    a BVH bounding itself. Wherever the mesh lies in its element's frame."""
    T = np.eye(4)
    box = primitives.box((0.1, 0.2, 0.3)).transformed(g.pose([5.0, 0, 0]))
    s = _mesh_shape("box", T, box)
    assert isinstance(s.shape, coal.Convex) and s.bound is s.shape and s.exact
    assert s.shape.computeVolume() == pytest.approx(0.006)
    assert isinstance(_mesh_shape("ball", T, primitives.sphere(0.1)).shape, coal.Convex)
    apart = Mesh.concatenate(
        [box, primitives.box((0.1, 0.2, 0.3)).transformed(g.pose([5.2, 0, 0]))]
    )
    s = _mesh_shape("two boxes", T, apart)  # closed, but with a gap between its parts
    assert isinstance(s.shape, coal.BVHModelOBBRSS) and isinstance(s.bound, coal.Convex)
    assert not s.exact
    open_box = Mesh(box.vertices, box.faces[:-1])  # a missing triangle: not a solid
    assert isinstance(_mesh_shape("open", T, open_box).shape, coal.BVHModelOBBRSS)
    flat = Mesh([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]])
    s = _mesh_shape("flat", T, flat)
    assert isinstance(s.shape, coal.BVHModelOBBRSS) and s.bound is s.shape and s.exact


# ---------------------------------------------------------------------------------- SRDF


def test_srdf_pairs_are_honoured(cell: CellModel, world: World, write: Write) -> None:
    path = write(
        "left.srdf",
        """<?xml version="1.0"?>
<robot name="ur5e">
  <disable_collisions link1="upper_arm_link" link2="tool" reason="Never"/>
  <disable_collisions link1="forearm_link" link2="wrist_3_link" reason="User"/>
  <disable_collisions link1="base_link" link2="shoulder_link" reason="Adjacent"/>
</robot>
""",
    )
    pairs = load_srdf(path)
    assert pairs == {
        ("tool", "upper_arm_link"),
        ("forearm_link", "wrist_3_link"),
        ("base_link", "shoulder_link"),
    }
    scene = build_scene(cell, world, srdf={"left": pairs})
    assert scene.acm.reason("left/tool", "left/upper_arm_link") == "srdf"
    # a link with two shapes: both
    assert scene.acm.reason("left/forearm_link", "left/wrist_3_link") == "srdf"
    assert scene.acm.reason("left/forearm_link#2", "left/wrist_3_link") == "srdf"
    assert ("right/tool", "right/upper_arm_link") in scene.checked  # only the left's SRDF
    assert any("link 'base_link' has no collision geometry" in n for n in scene.notes)
    # the home state's closest pair is now allowed: the next one is reported
    _, pair = CollisionChecker(scene).distance(both(cell))
    assert pair != ("left/forearm_link", "left/wrist_3_link")


def test_srdf_errors(write: Write) -> None:
    bad = write("bad.srdf", '<robot>\n  <disable_collisions link1="a"/>\n</robot>\n')
    with pytest.raises(InputError) as e:
        load_srdf(bad)
    assert e.value.problems[0].line == 2 and "link1 and link2" in e.value.problems[0].message
    entity = write("x.srdf", '<!DOCTYPE r [<!ENTITY x "y">]>\n<robot>&x;</robot>\n')
    with pytest.raises(InputError, match="entity"):
        load_srdf(entity)


def test_user_allowed_pairs(cell: CellModel, world: World) -> None:
    scene = build_scene(cell, world, allowed=[("table", "left/tool")])
    assert scene.acm.reason("left/tool", "table") == "user"
    q = both(cell, left=ik(cell, "left", g.transform(DOWN, [0.3, 0.45, -0.01])))
    assert CollisionChecker(scene).check(q) is None


# ---------------------------------------------------------------------------------- determinism


def test_deterministic(cell: CellModel, world: World, scene: CollisionScene) -> None:
    again = build_scene(cell, world)
    assert again.acm.reasons == scene.acm.reasons
    assert again.pairs == scene.pairs
    np.testing.assert_array_equal(again.motion, scene.motion)
    # the sampling itself (no memo is shared between calls): same seed, same pairs, distances
    arm = cell.arms["left"]
    first = sampled_self_pairs(arm, 2000)
    assert sampled_self_pairs(arm, 2000) == first
    # the two arms are the same UR5e with the same tool: the same pairs, prefixed
    right = sampled_self_pairs(cell.arms["right"], 2000)
    assert {tuple(n.replace("right/", "left/") for n in p) for p in right} == set(first)
    rng = np.random.default_rng(11)
    Q = rng.uniform(cell.limits.lower, cell.limits.upper, (200, cell.nq))
    c1, c2 = CollisionChecker(scene), CollisionChecker(again)
    np.testing.assert_array_equal(c1.check_batch(Q), c2.check_batch(Q))
    assert [str(c1.check(q)) for q in Q[:50]] == [str(c2.check(q)) for q in Q[:50]]
    assert [c1.distance(q) for q in Q[:20]] == [c2.distance(q) for q in Q[:20]]


def test_motion_bounds_hold(cell: CellModel, scene: CollisionScene) -> None:
    """Over small random joint steps no object point moves relative to its pair partner
    further than scene.motion says (checked on the objects' bounding-sphere centres and the
    corners of the tool box)."""
    rng = np.random.default_rng(5)
    model, data = cell.model, cell.model.createData()
    gdata = pin.GeometryData(scene.geometry)
    tool = scene.index("left/tool")
    box = scene.geometry.geometryObjects[tool].geometry
    corners = (
        np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * box.halfSide
    )
    table = scene.index("table")
    p = scene.pairs.index((min(tool, table), max(tool, table)))
    for _ in range(200):
        q0 = rng.uniform(cell.limits.lower, cell.limits.upper)
        dq = rng.normal(0, 0.05, cell.nq)
        moved = []
        for q in (q0, q0 + dq):
            pin.updateGeometryPlacements(model, data, scene.geometry, gdata, q)
            M = gdata.oMg[tool]
            moved.append(corners @ M.rotation.T + M.translation)
        assert np.linalg.norm(moved[1] - moved[0], axis=1).max() <= scene.motion[p] @ np.abs(dq)


def test_srdf_named_in_cell_yaml(tmp_path: Path) -> None:
    """robots.<name>.srdf in cell.yaml: read from inside the cell folder by build_scene."""
    import shutil

    from cellengine.info.load import load_world as load
    from cellengine.motion.robot import build_cell_model as build

    src = CELLS / "cable_routing"
    shutil.copytree(src, tmp_path / "cell")
    (tmp_path / "cell" / "left.srdf").write_text(
        '<robot name="ur5e"><disable_collisions link1="upper_arm_link" link2="tool"/></robot>'
    )
    cell_yaml = tmp_path / "cell" / "cell.yaml"
    text = cell_yaml.read_text().replace(
        "    tool: cable_gripper\n", "    tool: cable_gripper\n    srdf: left.srdf\n", 1
    )
    cell_yaml.write_text(text)
    w = load(cell_yaml)
    scene = build_scene(build(w), w)
    assert scene.acm.reason("left/tool", "left/upper_arm_link") == "srdf"
    assert ("right/tool", "right/upper_arm_link") in scene.checked
