"""Tool geometry of cell.yaml (shape, fingers, mesh): parsing, the solids, fingers following
the jaw, and every part treated as the tool (held objects, contacts)."""

from __future__ import annotations

from pathlib import Path

import coal
import numpy as np
import pinocchio as pin
import pytest

from cellengine import geometry as g
from cellengine.errors import InputError
from cellengine.execute.held import Holding
from cellengine.info.cell import Robot, Tool
from cellengine.info.load import load_world
from cellengine.info.units import Units
from cellengine.motion.collision import CollisionChecker
from cellengine.motion.robot import CellModel, build_arm, build_cell_model, is_tool, tool_parts
from cellengine.motion.scene import CollisionScene, StaticShape, build_scene, rearranged, with_jaw
from cellengine.motion.tool import tool_solids
from cellengine.world import World
from tests.conftest import CELLS

MM = {"length": 1e-3, "angle": 1.0, "mass": 1.0}
GRIPPER = {
    "kind": "parallel_gripper",
    "tcp": {"xyz": [0, 0, 200]},
    "finger_width": 20,
    "jaw": {"open": 60, "grasp": 4},
    "shape": [
        {"box": [50, 90, 110], "pose": {"xyz": [0, 0, 55]}},
        {"name": "camera", "cylinder": {"radius": 15, "length": 30}, "pose": {"xyz": [40, 0, 50]}},
    ],
    "fingers": {"size": [8, 6, 90]},
}


def tool(data: dict[str, object] = GRIPPER, context: dict[str, float] = MM) -> Tool:
    return Tool.model_validate(data, context=context)


def test_shape_parses_in_mm_and_in_m() -> None:
    in_m = {
        **GRIPPER,
        "tcp": {"xyz": [0, 0, 0.2]},
        "finger_width": 0.02,
        "jaw": {"open": 0.06, "grasp": 0.004},
        "shape": [{"box": [0.05, 0.09, 0.11], "pose": {"xyz": [0, 0, 0.055]}}],
        "fingers": {"size": [0.008, 0.006, 0.09]},
    }
    a, b = tool(), tool(in_m, {})
    assert a.shape is not None and b.shape is not None
    np.testing.assert_allclose(a.shape[0].box or (), b.shape[0].box or ())
    np.testing.assert_allclose(a.shape[0].pose.xyz, [0, 0, 0.055])
    assert a.shape[1].cylinder is not None and a.shape[1].cylinder.radius == pytest.approx(0.015)
    assert a.fingers == b.fingers


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"fingers": {"size": [8, 0, 90]}}, "finger sizes must be greater than 0"),
        ({"shape": [{"box": [1, 1, 1], "cylinder": {"radius": 1, "length": 1}}]}, "got both"),
        ({"shape": [{"pose": {"xyz": [0, 0, 1]}}]}, "give exactly one shape of box, cylinder"),
        ({"shape": [{"box": [1, -1, 1]}]}, "box sizes must be greater than 0"),
        ({"jaw": {}}, "fingers need the jaw's openings"),
        ({"shape": [{"box": [1, 1, 1], "name": "finger_left"}]}, "'finger_left' is used twice"),
    ],
)
def test_bad_shapes_are_refused(change: dict[str, object], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        tool({**GRIPPER, **change})


def solids(t: Tool) -> dict[str, tuple[np.ndarray, coal.CollisionGeometry]]:
    return {s.name: (s.T_flange_solid, s.shape) for s in tool_solids(t, t.tcp.matrix(), str)}


def test_solids_names_and_places() -> None:
    out = solids(tool())
    assert list(out) == ["tool", "tool/camera", "tool/finger_left", "tool/finger_right"]
    T_left, box = out["tool/finger_left"]
    assert isinstance(box, coal.Box)
    np.testing.assert_allclose(2 * box.halfSide, [0.008, 0.006, 0.09])
    # at the widest opening (60): the inner face 30 mm from the TCP, the tip at the TCP
    np.testing.assert_allclose(T_left[:3, 3], [0, 0.030 + 0.003, 0.2 - 0.045])
    np.testing.assert_allclose(out["tool/finger_right"][0][:3, 3], [0, -0.033, 0.155])
    assert isinstance(out["tool/camera"][1], coal.Cylinder)


def test_a_tool_without_shape_is_the_stand_in_box() -> None:
    plain = {k: v for k, v in GRIPPER.items() if k not in ("shape", "fingers")}
    out = solids(tool(plain))
    assert list(out) == ["tool"]
    box = out["tool"][1]
    assert isinstance(box, coal.Box)
    np.testing.assert_allclose(2 * box.halfSide, [0.02, 0.02, 0.2])
    # fingers alone: no body named 'tool'
    fingers_only = {k: v for k, v in GRIPPER.items() if k != "shape"}
    assert list(solids(tool(fingers_only))) == ["tool/finger_left", "tool/finger_right"]


def test_tool_mesh_is_its_hull_in_the_file_unit(tmp_path: Path) -> None:
    cube = "\n".join(
        [f"v {x} {y} {z}" for x in (-10, 10) for y in (-10, 10) for z in (0, 40)]
        + ["f 1 2 3", "f 2 4 3", "f 5 7 6", "f 6 7 8", "f 1 5 2", "f 2 5 6"]
        + ["f 3 4 7", "f 4 8 7", "f 1 3 5", "f 3 7 5", "f 2 6 4", "f 4 6 8"]
    )
    (tmp_path / "gripper.obj").write_text(cube)
    t = tool({**{k: v for k, v in GRIPPER.items() if k != "shape"}, "mesh": "gripper.obj"})
    mm = Units(length="mm")
    arm = build_arm("left", Robot(model="ur5e", tool="g"), t, tmp_path / "cell.yaml", mm)
    hull = arm.collision.geometryObjects[arm.collision.getGeometryId("left/tool")].geometry
    hull.computeLocalAABB()
    np.testing.assert_allclose(hull.aabb_local.max_, [0.01, 0.01, 0.04], atol=1e-9)
    assert tool_parts(arm) == ("left/tool", "left/tool/finger_left", "left/tool/finger_right")


def test_tool_mesh_outside_the_cell_folder(tmp_path: Path) -> None:
    t = tool({**GRIPPER, "mesh": "../gripper.stl"})
    with pytest.raises(InputError, match="points outside the cell folder"):
        build_arm("left", Robot(model="ur5e", tool="g"), t, tmp_path / "cell.yaml")


def test_is_tool() -> None:
    assert is_tool("left/tool", "left") and is_tool("left/tool/finger_left", "left")
    assert not is_tool("left/toolbox", "left") and not is_tool("right/tool", "left")


# ------------------------------------------------------------------ in the reference cell


Cable = tuple[World, CellModel, CollisionScene]


@pytest.fixture(scope="module")
def cable() -> Cable:
    world = load_world(CELLS / "cable_routing" / "cell.yaml")
    cell = build_cell_model(world)
    scene = build_scene(cell, world, samples=200)
    return world, cell, scene


def placed(scene: CollisionScene, q: np.ndarray) -> dict[str, pin.SE3]:
    geometry = scene.geometry
    model = scene.cell.model
    data, gdata = model.createData(), pin.GeometryData(geometry)
    pin.updateGeometryPlacements(model, data, geometry, gdata, q)
    return {str(o.name): gdata.oMg[i] for i, o in enumerate(geometry.geometryObjects)}


def test_fingertips_follow_the_jaw(cable: Cable) -> None:
    _, cell, scene = cable
    q = cell.join({n: a.home for n, a in cell.arms.items()})
    for opening in (0.060, 0.004):
        at = placed(with_jaw(scene, {"left": opening}), q)
        gap = at["left/tool/finger_left"].translation - at["left/tool/finger_right"].translation
        # centre to centre: the opening plus a finger's 6 mm along the jaw
        assert float(np.linalg.norm(gap)) == pytest.approx(opening + 0.006)
        # the right arm keeps its fingers at the widest
        right = at["right/tool/finger_left"].translation - at["right/tool/finger_right"].translation
        assert float(np.linalg.norm(right)) == pytest.approx(0.066)


def post_between_the_fingers(cell: CellModel) -> tuple[np.ndarray, np.ndarray]:
    """The arms at home, and a pose 40 mm above the left TCP, between its fingers."""
    q = cell.join({n: a.home for n, a in cell.arms.items()})
    T_tcp = cell.arms["left"].fk(q[:6])
    T = T_tcp @ g.transform(np.eye(3), (0, 0, -0.04))
    return q, T


def checker_with_post(
    world: World, cell: CellModel, size: tuple[float, float, float], T: np.ndarray
) -> CollisionChecker:
    """The cell with a box ``size`` at ``T`` as its only environment."""
    base = build_scene(cell, world, samples=200)
    post = coal.Box(*size)
    statics = [StaticShape("post", T, post, post, True)]
    return CollisionChecker(rearranged(base, statics, {}, {}))


def test_fingers_touch_where_the_stand_in_box_would_not_and_vice_versa(
    cable: Cable, tmp_path: Path
) -> None:
    world, cell, _ = cable
    q, T = post_between_the_fingers(cell)
    # a 10 mm post between the open fingers: free, the old 20 mm box would collide
    free = checker_with_post(world, cell, (0.01, 0.01, 0.01), T)
    assert free.check(q) is None
    old = tool_solids(
        Tool.model_validate({"kind": "parallel_gripper", "tcp": {"xyz": [0, 0, 0.2]}}),
        np.array(cell.arms["left"].T_flange_tcp),
        str,
    )[0]
    T_flange = cell.arms["left"].fk_flange(q[:6])
    assert _collide(old.shape, T_flange @ old.T_flange_solid, coal.Box(0.01, 0.01, 0.01), T)
    # a post 40 mm to the side along the jaw axis: the open left finger touches it, the
    # body does not, and the stand-in box would not
    T_side = T @ g.transform(np.eye(3), (0, 0.04, 0))
    hit = checker_with_post(world, cell, (0.01, 0.01, 0.01), T_side).check(q)
    assert hit is not None and hit.pair == ("left/tool/finger_left", "post")
    assert not _collide(
        old.shape, T_flange @ old.T_flange_solid, coal.Box(0.01, 0.01, 0.01), T_side
    )


def _collide(
    a: coal.CollisionGeometry, Ta: np.ndarray, b: coal.CollisionGeometry, Tb: np.ndarray
) -> bool:
    request, result = coal.CollisionRequest(), coal.CollisionResult()
    T1 = coal.Transform3s(Ta[:3, :3], Ta[:3, 3])
    T2 = coal.Transform3s(Tb[:3, :3], Tb[:3, 3])
    return bool(coal.collide(a, T1, b, T2, request, result))


def test_holding_places_the_fingers_at_the_mode(cable: Cable) -> None:
    world, cell, scene = cable
    holding = Holding(world, scene)
    q = cell.join({n: a.home for n, a in cell.arms.items()})
    T = cell.arms["left"].fk(q[:6])
    holding.set("left", "cable1", T, "grasp")
    assert holding.state.jaw == {"left": pytest.approx(0.004)}
    at = placed(holding.checker.scene, q)
    gap = at["left/tool/finger_left"].translation - at["left/tool/finger_right"].translation
    assert float(np.linalg.norm(gap)) == pytest.approx(0.010)
    # every tool part holds the cable: none is checked against it
    acm = holding.checker.scene.acm
    for part in tool_parts(cell.arms["left"]):
        assert acm.reason(part, "cable1@left") == "held"
    holding.set("left", "cable1", T, "open")
    assert holding.state.jaw == {"left": pytest.approx(0.060)}


def test_contacts_cover_every_tool_part(cable: Cable) -> None:
    world, cell, scene = cable
    holding = Holding(world, scene)
    holding.touch([("left", "routing.guide1")])
    acm = holding.checker.scene.acm
    for part in tool_parts(cell.arms["left"]):
        assert acm.reason(part, "routing.guide1") == "contact"
