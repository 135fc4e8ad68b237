"""Robot models: built-in UR URDFs against the published DH, the cable-routing cell, user URDFs
(prismatic and continuous joints, meshes by package:// and relative paths, refusals)."""

from __future__ import annotations

import math
import os
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Literal

import coal
import numpy as np
import pinocchio as pin
import pytest

from cellengine import geometry as g
from cellengine.errors import InputError
from cellengine.info.cell import Robot, Tool
from cellengine.info.load import load_world
from cellengine.info.pose import Pose
from cellengine.motion.robot import (
    UR_ACCELERATION,
    Arm,
    CellModel,
    build_arm,
    build_cell_model,
    builtin_urdf,
)
from cellengine.motion.urdf import read_urdf
from tests.conftest import CELLS, DATA

URDF_DATA = DATA / "urdf"
Write = Callable[[str, str], Path]  # the conftest fixture `write`
DEG = math.pi / 180

# The published DH tables (NOTES.md, "UR kinematics"), typed in again here so the test does not
# share its numbers with the code under test.
HALF = math.pi / 2
ALPHA = (HALF, 0, 0, HALF, -HALF, 0)
PUBLISHED_DH = {
    "ur5e": ((0.1625, 0, 0, 0.1333, 0.0997, 0.0996), (0, -0.425, -0.3922, 0, 0, 0)),
    "ur5": ((0.089159, 0, 0, 0.10915, 0.09465, 0.0823), (0, -0.425, -0.39225, 0, 0, 0)),
    "ur10e": ((0.1807, 0, 0, 0.17415, 0.11985, 0.11655), (0, -0.6127, -0.57155, 0, 0, 0)),
    "ur3e": ((0.15185, 0, 0, 0.13105, 0.08535, 0.0921), (0, -0.24355, -0.2132, 0, 0, 0)),
}
# ur_description joint_limits.yaml: velocity (deg/s) per joint
VELOCITY_DEG = {
    "ur5e": (180,) * 6,
    "ur5": (180,) * 6,
    "ur3e": (180, 180, 180, 360, 360, 360),
    "ur10e": (120, 120, 180, 180, 180, 180),
}


def dh_product(q: np.ndarray, model: str) -> np.ndarray:
    """Standard DH: prod Rz(q_i) Tz(d_i) Tx(a_i) Rx(alpha_i), controller base to flange."""
    d, a = PUBLISHED_DH[model]
    T = np.eye(4)
    for i in range(6):
        ct, st = math.cos(q[i]), math.sin(q[i])
        ca, sa = math.cos(ALPHA[i]), math.sin(ALPHA[i])
        T = T @ np.array(
            [
                [ct, -st * ca, st * sa, a[i] * ct],
                [st, ct * ca, -ct * sa, a[i] * st],
                [0, sa, ca, d[i]],
                [0, 0, 0, 1],
            ]
        )
    return T


def builtin_arm(model: str, base: Pose | None = None, tool: Tool | None = None) -> Arm:
    robot = Robot(model=model, base=base or Pose())
    return build_arm("r", robot, tool, Path("cell.yaml"))  # a built-in reads no cell file


def problem(e: pytest.ExceptionInfo[InputError]) -> tuple[str, str | None, int | None]:
    p = e.value.problems[0]
    return p.message, Path(p.file).name if p.file else None, p.line


# ---------------------------------------------------------------------------------- built-ins


@pytest.mark.parametrize("model", sorted(PUBLISHED_DH))
def test_builtin_fk_base_to_tool0_equals_published_dh(model: str) -> None:
    arm = builtin_arm(model)
    rng = np.random.default_rng(1)
    qs = rng.uniform(-2 * math.pi, 2 * math.pi, size=(300, 6))
    worst = max(float(np.abs(arm.fk_flange(q) - dh_product(q, model)).max()) for q in qs)
    assert worst < 1e-9
    assert arm.dh is not None and arm.dh.d == pytest.approx(PUBLISHED_DH[model][0], abs=1e-9)


@pytest.mark.parametrize("model", sorted(PUBLISHED_DH))
def test_builtin_urdf_root_is_base_and_tip_is_tool0(model: str) -> None:
    urdf = read_urdf(builtin_urdf(model), builtin_urdf(model).parent)
    assert urdf.root == "base"
    chain = [j.name for j in urdf.chain("tool0") if j.movable]
    assert chain == [
        "shoulder_pan_joint",
        "shoulder_lift_joint",
        "elbow_joint",
        "wrist_1_joint",
        "wrist_2_joint",
        "wrist_3_joint",
    ]
    # ur_description's base_link is the controller base turned pi about z
    base_link = next(j for j in urdf.joints.values() if j.child == "base_link")
    np.testing.assert_allclose(base_link.T_parent_child(), g.transform(g.rot_z(math.pi)), atol=1e-9)


@pytest.mark.parametrize("model", sorted(PUBLISHED_DH))
def test_builtin_limits(model: str) -> None:
    arm = builtin_arm(model)
    lim = arm.limits
    two_pi = 2 * math.pi
    np.testing.assert_allclose(lim.upper, [two_pi, two_pi, math.pi, two_pi, two_pi, two_pi])
    np.testing.assert_allclose(lim.lower, -lim.upper)
    np.testing.assert_allclose(lim.velocity, np.array(VELOCITY_DEG[model]) * DEG)
    np.testing.assert_allclose(lim.acceleration, UR_ACCELERATION[model])
    assert np.all(lim.acceleration > 0)
    # pinocchio's model carries the same limits
    np.testing.assert_allclose(arm.model.upperPositionLimit, lim.upper)
    np.testing.assert_allclose(arm.model.velocityLimit, lim.velocity)
    with pytest.raises(ValueError, match="read-only"):
        lim.upper[0] = 0.0


def test_builtin_masses_are_plausible() -> None:
    arm = builtin_arm("ur5e")
    masses = [arm.model.inertias[i].mass for i in range(1, 7)]
    # ur_description: shoulder 3.761, upper arm 8.058, forearm 2.846, wrists 1.37, 1.3, 0.365 kg
    assert masses == pytest.approx([3.761, 8.058, 2.846, 1.37, 1.3, 0.365])


def test_base_pose_is_applied_in_the_cell_frame() -> None:
    base = Pose(xyz=(0.1, -0.2, 0.3), rpy=(0.1, -0.2, 0.7))
    arm = builtin_arm("ur10e", base)
    q = np.array([0.3, -1.2, 1.1, -0.4, 0.9, 2.0])
    np.testing.assert_allclose(arm.fk_flange(q), base.matrix() @ dh_product(q, "ur10e"), atol=1e-9)
    np.testing.assert_allclose(arm.T_cell_base, base.matrix())


# ---------------------------------------------------------------------------------- Jacobians


def numeric_jacobian(
    fk: Callable[[np.ndarray], np.ndarray], q: np.ndarray, h: float = 1e-6
) -> np.ndarray:
    """Central differences: linear velocity of the origin and angular velocity, cell axes."""
    J = np.zeros((6, len(q)))
    for i in range(len(q)):
        dq = np.zeros(len(q))
        dq[i] = h
        Tp, Tm = fk(q + dq), fk(q - dq)
        J[:3, i] = (Tp[:3, 3] - Tm[:3, 3]) / (2 * h)
        J[3:, i] = pin.log3(Tp[:3, :3] @ Tm[:3, :3].T) / (2 * h)
    return J


@pytest.mark.parametrize("frame", ["tcp", "flange"])
def test_jacobian_matches_finite_differences(frame: Literal["tcp", "flange"]) -> None:
    tool = Tool(kind="parallel_gripper", tcp=Pose(xyz=(0.01, -0.02, 0.2), rpy=(0.3, 0, 0)))
    arm = builtin_arm("ur5e", Pose(xyz=(0.1, 0.35, 0.0), rpy=(0, 0, 0.5)), tool)
    fk = arm.fk if frame == "tcp" else arm.fk_flange
    rng = np.random.default_rng(2)
    for q in rng.uniform(-math.pi, math.pi, size=(20, 6)):
        J = arm.jacobian(q, frame)
        assert J.shape == (6, 6)
        np.testing.assert_allclose(J, numeric_jacobian(fk, q), atol=1e-7)


def test_jacobian_of_a_prismatic_robot_matches_finite_differences() -> None:
    arm = cartesian().arms["gantry"]
    for q in ([0.2, 0.1, 0.05, 0.3], [0.9, 0.5, 0.25, -2.0]):
        qa = np.array(q)
        np.testing.assert_allclose(arm.jacobian(qa), numeric_jacobian(arm.fk, qa), atol=1e-8)


# ---------------------------------------------------------------------------------- the cell


@pytest.fixture(scope="module")
def cable_cell() -> CellModel:
    return build_cell_model(load_world(CELLS / "cable_routing" / "cell.yaml"))


def test_cable_routing_cell_model(cable_cell: CellModel) -> None:
    assert cable_cell.nq == 12 and cable_cell.model.nv == 12
    assert list(cable_cell.arms) == ["left", "right"]
    assert cable_cell.joint_names[0] == "left_shoulder_pan_joint"
    assert cable_cell.joint_names[6:] == cable_cell.arms["right"].joint_names
    assert cable_cell.joint_names[11] == "right_wrist_3_joint"
    left, right = cable_cell.arms["left"], cable_cell.arms["right"]
    np.testing.assert_allclose(left.T_cell_base[:3, 3], [0, 0.35, 0])
    np.testing.assert_allclose(right.T_cell_base[:3, 3], [0, -0.35, 0])
    np.testing.assert_allclose(left.T_flange_tcp[:3, 3], [0, 0, 0.2])
    assert left.home is not None
    np.testing.assert_allclose(left.home, np.array([0, -90, 90, -90, -90, 0]) * DEG)


def test_tcp_is_200_mm_along_the_flange_z(cable_cell: CellModel) -> None:
    arm = cable_cell.arms["left"]
    rng = np.random.default_rng(3)
    for q in rng.uniform(-math.pi, math.pi, size=(10, 6)):
        T_cell_flange, T_cell_tcp = arm.fk_flange(q), arm.fk(q)
        np.testing.assert_allclose(
            T_cell_tcp[:3, 3], T_cell_flange[:3, 3] + 0.2 * T_cell_flange[:3, 2], atol=1e-9
        )
        np.testing.assert_allclose(T_cell_tcp[:3, :3], T_cell_flange[:3, :3], atol=1e-9)
    # the left base is at y = +0.35 m: flange = that translation times the DH chain
    q = np.array([0.4, -1.0, 1.2, -0.3, 0.8, 0.1])
    np.testing.assert_allclose(
        arm.fk_flange(q), g.transform(t=(0, 0.35, 0)) @ dh_product(q, "ur5e"), atol=1e-9
    )


def test_cell_model_fk_agrees_with_each_arm(cable_cell: CellModel) -> None:
    rng = np.random.default_rng(4)
    qs = {name: rng.uniform(-3, 3, 6) for name in cable_cell.arms}
    q = cable_cell.join(qs)
    data = cable_cell.model.createData()
    pin.framesForwardKinematics(cable_cell.model, data, q)
    for name, arm in cable_cell.arms.items():
        np.testing.assert_allclose(
            data.oMf[cable_cell.tcp[name]].homogeneous, arm.fk(qs[name]), atol=1e-9
        )
        np.testing.assert_allclose(
            data.oMf[cable_cell.tool0[name]].homogeneous, arm.fk_flange(qs[name]), atol=1e-9
        )
    back = cable_cell.split(q)
    assert list(back) == ["left", "right"]
    np.testing.assert_array_equal(back["right"], qs["right"])
    with pytest.raises(ValueError, match="exactly the arms"):
        cable_cell.join({"left": qs["left"]})


def test_cell_limits_stack_both_arms(cable_cell: CellModel) -> None:
    lim = cable_cell.limits
    assert lim.velocity.shape == (12,)
    np.testing.assert_allclose(lim.upper[[2, 8]], [math.pi, math.pi])


def test_collision_geometry_names_and_shapes(cable_cell: CellModel) -> None:
    objs = {o.name: o for o in cable_cell.collision.geometryObjects}
    assert len(objs) == 24  # per arm: 9 link objects, the tool's body and two fingers
    assert {"left/base", "left/upper_arm_link", "left/forearm_link#2", "right/tool"} <= set(objs)
    assert {"left/tool/finger_left", "right/tool/finger_right"} <= set(objs)
    upper = objs["left/upper_arm_link"].geometry
    assert isinstance(upper, coal.Capsule)  # a URDF cylinder, read as a capsule
    assert upper.radius == pytest.approx(0.055) and 2 * upper.halfLength == pytest.approx(0.425)
    assert isinstance(objs["left/base"].geometry, coal.Sphere)
    tool = objs["left/tool"].geometry
    assert isinstance(tool, coal.Box)
    np.testing.assert_allclose(2 * tool.halfSide, [0.05, 0.09, 0.11])  # the body of cell.yaml


def test_tool_body_from_the_flange(cable_cell: CellModel) -> None:
    model, geom = cable_cell.model, cable_cell.collision
    q = cable_cell.join({n: a.home for n, a in cable_cell.arms.items() if a.home is not None})
    data, gdata = model.createData(), pin.GeometryData(geom)
    pin.framesForwardKinematics(model, data, q)
    pin.updateGeometryPlacements(model, data, geom, gdata)
    box = gdata.oMg[geom.getGeometryId("left/tool")]
    arm = cable_cell.arms["left"]
    np.testing.assert_allclose(
        box.translation,
        arm.fk_flange(q[:6])[:3, :3] @ [0, 0, 0.055] + arm.fk_flange(q[:6])[:3, 3],
        atol=1e-9,
    )


def test_at_home_only_adjacent_links_touch(cable_cell: CellModel) -> None:
    """Capsules are sized from the real links: at home no two links that are not neighbours
    overlap, and the arms are apart; pinocchio's collision and distance calls run on them."""
    model, geom = cable_cell.model, cable_cell.collision.copy()
    geom.addAllCollisionPairs()
    q = cable_cell.join({n: a.home for n, a in cable_cell.arms.items() if a.home is not None})
    data, gdata = model.createData(), pin.GeometryData(geom)
    pin.computeDistances(model, data, geom, gdata, q)
    overlapping = set()
    for k, pair in enumerate(geom.collisionPairs):
        if gdata.distanceResults[k].min_distance < 0:
            j1 = geom.geometryObjects[pair.first].parentJoint
            j2 = geom.geometryObjects[pair.second].parentJoint
            overlapping.add((min(j1, j2), max(j1, j2)))
    assert overlapping, "adjacent capsules share their joints: some must overlap"
    for j1, j2 in overlapping:
        assert j1 == j2 or model.parents[j2] == j1, (model.names[j1], model.names[j2])
    assert pin.computeCollisions(model, data, geom, gdata, q, False)  # the adjacent pairs


# ---------------------------------------------------------------------------------- user URDFs


def cartesian() -> CellModel:
    return build_cell_model(load_world(URDF_DATA / "cartesian" / "cell.yaml"))


def test_prismatic_robot_fk() -> None:
    arm = cartesian().arms["gantry"]
    assert arm.joint_names == ("gantry_x", "gantry_y", "gantry_z", "gantry_theta")
    assert arm.model.nq == arm.model.nv == 4  # continuous theta: one coordinate, not cos/sin
    assert arm.dh is None
    T_cell_base = g.pose((0.1, 0.2, 0.0), (0, 0, math.pi / 2))
    rng = np.random.default_rng(5)
    for x, y, z, th in rng.uniform([0, 0, 0, -6], [1, 0.6, 0.3, 6], size=(20, 4)):
        T_base_flange = (
            g.transform(t=(x, 0, 0.5))
            @ g.transform(t=(0, y, 0.05))
            @ g.transform(t=(0, 0, -0.05 - z))  # axis 0 0 -2: down, normalised
            @ g.transform(g.rot_z(th), (0, 0, -0.2))
            @ g.transform(g.rot_x(math.pi), (0, 0, -0.02))
        )
        q = np.array([x, y, z, th])
        np.testing.assert_allclose(arm.fk_flange(q), T_cell_base @ T_base_flange, atol=1e-9)
        tcp = T_cell_base @ T_base_flange @ g.transform(t=(0, 0, 0.05))
        np.testing.assert_allclose(arm.fk(q), tcp, atol=1e-9)


def test_prismatic_robot_limits() -> None:
    arm = cartesian().arms["gantry"]
    lim = arm.limits
    np.testing.assert_allclose(lim.lower, [0, 0, 0, -2 * math.pi])
    np.testing.assert_allclose(lim.upper, [1.0, 0.6, 0.3, 2 * math.pi])  # continuous: +-2 pi
    np.testing.assert_allclose(lim.velocity, [0.5, 0.4, 0.2, 3.0])
    np.testing.assert_allclose(lim.acceleration, 2 * lim.velocity)  # a user URDF's default
    assert arm.home is not None
    np.testing.assert_allclose(arm.home, [0.5, 0.3, 0.1, 0.0])


def test_joint_off_the_chain_is_locked_at_its_limit_nearest_zero() -> None:
    arm = cartesian().arms["gantry"]
    assert "gantry_finger_joint" not in arm.joint_names
    finger = arm.model.getFrameId("gantry_finger")
    q = np.array([0.2, 0.1, 0.05, 0.0])
    data = arm.model.createData()
    pin.framesForwardKinematics(arm.model, data, q)
    T_flange_finger = np.linalg.inv(arm.fk_flange(q)) @ data.oMf[finger].homogeneous
    np.testing.assert_allclose(T_flange_finger[:3, 3], [0.01 + 0.005, 0, 0], atol=1e-9)


def test_user_collision_shapes() -> None:
    objs = {o.name: o for o in cartesian().collision.geometryObjects}
    assert set(objs) == {"gantry/frame", "gantry/x_carriage", "gantry/z_carriage", "gantry/tool"}
    cyl = objs["gantry/z_carriage"].geometry
    assert isinstance(cyl, coal.Capsule)
    assert (cyl.radius, 2 * cyl.halfLength) == pytest.approx((0.02, 0.2))
    np.testing.assert_allclose(2 * objs["gantry/x_carriage"].geometry.halfSide, [0.1, 0.7, 0.05])
    np.testing.assert_allclose(2 * objs["gantry/tool"].geometry.halfSide, [0.01, 0.01, 0.05])


def test_meshes_by_package_and_relative_paths() -> None:
    cell = build_cell_model(load_world(URDF_DATA / "meshes" / "cell.yaml"))
    objs = {o.name: o for o in cell.collision.geometryObjects}
    assert set(objs) == {"arm/base", "arm/link1", "arm/link1#2"}
    folder = (URDF_DATA / "meshes").resolve()
    assert objs["arm/base"].meshPath == str(folder / "arm_pkg" / "meshes" / "cube_mm.stl")
    assert objs["arm/link1#2"].meshPath == str(folder / "vendor" / "tetra.STL")

    def extent(name: str) -> np.ndarray:
        shape = objs[name].geometry
        assert isinstance(shape, coal.Convex)
        pts = np.asarray(shape.points())
        return np.asarray(pts.max(axis=0) - pts.min(axis=0))

    np.testing.assert_allclose(extent("arm/base"), [0.1, 0.1, 0.1])  # mm cube, scale 0.001
    np.testing.assert_allclose(extent("arm/link1"), [0.1, 0.2, 0.3])  # scale 0.001 0.002 0.003
    np.testing.assert_allclose(extent("arm/link1#2"), [0.05, 0.05, 0.05])


def test_a_one_joint_cell_builds_its_scene() -> None:
    """pinocchio gives a one-joint model's Jacobian as a 1-D array: found by the fuzz target
    (an IndexError from `cellengine plan` in a cell of one one-joint arm)."""
    from cellengine.context import build_context
    from cellengine.motion.numeric_ik import NumericIK

    context = build_context(load_world(URDF_DATA / "meshes" / "cell.yaml"))
    arm = context.cell.arms["arm"]
    assert arm.jacobian([0.3]).shape == (6, 1)
    assert context.scene.names  # built: its objects are named
    assert NumericIK(arm.model, arm.tcp).solve(arm.fk([0.3]), [0.0]).success


@pytest.fixture
def mesh_cell(tmp_path: Path) -> Path:
    """A copy of the mesh cell in tmp_path/cell, with tmp_path/outside.stl beside it."""
    shutil.copytree(URDF_DATA / "meshes", tmp_path / "cell")
    shutil.copy(URDF_DATA / "meshes" / "vendor" / "tetra.STL", tmp_path / "outside.stl")
    return tmp_path / "cell"


def with_mesh(cell: Path, filename: str) -> InputError:
    """Build the mesh cell with link1's relative mesh reference replaced by ``filename``."""
    urdf = cell / "arm_pkg" / "urdf" / "arm.urdf"
    urdf.write_text(urdf.read_text().replace("../meshes/cube_mm.stl", filename))
    with pytest.raises(InputError) as e:
        build_cell_model(load_world(cell / "cell.yaml"))
    return e.value


LINK1_MESH_LINE = 13


@pytest.mark.parametrize(
    ("ref", "message"),
    [
        ("../../../outside.stl", "mesh '../../../outside.stl' points outside the cell folder"),
        ("/etc/hostname", "mesh '/etc/hostname' points outside the cell folder"),
        (
            "package://arm_pkg/../../../outside.stl",
            "mesh 'package://arm_pkg/../../../outside.stl' points outside the cell folder",
        ),
        (
            "file:///etc/hostname",
            "mesh 'file:///etc/hostname' is a URL; use a path inside the cell folder or package://",
        ),
        (
            "package://nowhere/x.stl",
            "mesh 'package://nowhere/x.stl' not found (looked for arm_pkg/urdf/nowhere/x.stl, "
            "arm_pkg/nowhere/x.stl, nowhere/x.stl)",
        ),
        ("package://arm_pkg", "mesh 'package://arm_pkg': write package://<package>/<path>"),
        (
            "../meshes/arm.dae",
            "mesh '../meshes/arm.dae' not found (looked for arm_pkg/meshes/arm.dae)",
        ),
    ],
)
def test_mesh_references_are_refused_outside_the_cell(
    mesh_cell: Path, ref: str, message: str
) -> None:
    err = with_mesh(mesh_cell, ref)
    p = err.problems[0]
    assert (p.message, Path(p.file or "").name, p.line) == (message, "arm.urdf", LINK1_MESH_LINE)


def test_mesh_link_leading_outside_is_refused(mesh_cell: Path) -> None:
    (mesh_cell / "arm_pkg" / "meshes" / "evil.stl").symlink_to(mesh_cell.parent / "outside.stl")
    p = with_mesh(mesh_cell, "../meshes/evil.stl").problems[0]
    assert p.message == (
        "mesh '../meshes/evil.stl': file reference 'arm_pkg/meshes/evil.stl' is a link that "
        "leads outside the cell folder"
    )


@pytest.mark.parametrize(
    ("make", "what"),
    [
        (lambda p: p.symlink_to(p.name), "cannot be used: a loop of symbolic links"),
        (os.mkfifo, "is a named pipe (FIFO), not a regular file"),  # refused before opening
        (Path.mkdir, "is a folder, not a file"),
    ],
)
def test_mesh_that_is_no_regular_file_is_refused(
    mesh_cell: Path, make: Callable[[Path], None], what: str
) -> None:
    make(mesh_cell / "arm_pkg" / "meshes" / "odd.stl")
    p = with_mesh(mesh_cell, "../meshes/odd.stl").problems[0]
    assert p.message == f"mesh '../meshes/odd.stl': file reference 'arm_pkg/meshes/odd.stl' {what}"
    assert p.line == LINK1_MESH_LINE


@pytest.mark.parametrize(
    ("name", "content", "message"),
    [
        (
            "arm.dae",
            "<COLLADA/>",
            "mesh '../meshes/arm.dae': unsupported format '.dae'; use STL, OBJ, PLY, OFF, GLB",
        ),
        (
            "empty.stl",
            "solid empty\nendsolid empty\n",
            "mesh '../meshes/empty.stl' has no triangles",
        ),
        ("flat.stl", None, "mesh '../meshes/flat.stl' is flat: its convex hull has no volume"),
        ("junk.obj", "v 1 2\nf 1 2 3\n", "mesh '../meshes/junk.obj' cannot be read: "),
        (  # its count says 1000 triangles: read as text, which it is not (found by the fuzz target)
            "liar.stl",
            b" " * 80 + (1000).to_bytes(4, "little") + bytes(50),
            "mesh '../meshes/liar.stl' cannot be read: not UTF-8 text, nor a binary STL whose "
            "size matches its triangle count",
        ),
    ],
)
def test_mesh_format_and_content_errors(
    mesh_cell: Path, name: str, content: str | bytes | None, message: str
) -> None:
    path = mesh_cell / "arm_pkg" / "meshes" / name
    if content is None:  # a single triangle: a hull of no volume
        tri = "vertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0"
        content = (
            f"solid flat\nfacet normal 0 0 1\nouter loop\n{tri}\nendloop\nendfacet\nendsolid flat\n"
        )
    path.write_bytes(content if isinstance(content, bytes) else content.encode())
    p = with_mesh(mesh_cell, f"../meshes/{name}").problems[0]
    assert p.message.startswith(message), p.message
    assert p.line == LINK1_MESH_LINE


SCALE_BOUNDS = "link 'link1' collision mesh: 'scale' must be between 1e-06 and 1e+06 in size"


@pytest.mark.parametrize(
    ("scale", "message"),
    [
        ("0 0.001 0.001", f"{SCALE_BOUNDS}, got '0 0.001 0.001'"),
        ("1e80 1e80 1e80", f"{SCALE_BOUNDS}, got '1e80 1e80 1e80'"),
        (
            "10 10 10",
            "mesh '../meshes/cube_mm.stl' has points beyond 100 m of its link (with its scale; "
            'a mesh in millimetres needs scale="0.001 0.001 0.001")',
        ),
    ],
)
def test_mesh_scales_within_physical_bounds(mesh_cell: Path, scale: str, message: str) -> None:
    urdf = mesh_cell / "arm_pkg" / "urdf" / "arm.urdf"
    urdf.write_text(urdf.read_text().replace('scale="0.001 0.002 0.003"', f'scale="{scale}"'))
    with pytest.raises(InputError) as e:
        build_cell_model(load_world(mesh_cell / "cell.yaml"))
    p = e.value.problems[0]
    assert (p.message, p.line) == (message, LINK1_MESH_LINE)


def test_urdf_entities_never_reach_pinocchio(mesh_cell: Path) -> None:
    urdf = mesh_cell / "arm_pkg" / "urdf" / "arm.urdf"
    text = urdf.read_text().replace(
        '<?xml version="1.0"?>',
        '<?xml version="1.0"?>\n<!DOCTYPE robot [<!ENTITY x SYSTEM "file:///etc/passwd">]>',
    )
    urdf.write_text(text.replace('name="mesh_arm"', 'name="&x;"'))
    with pytest.raises(InputError) as e:
        build_cell_model(load_world(mesh_cell / "cell.yaml"))
    assert problem(e)[0].startswith("XML entity declarations are not allowed (found 'x')")


def user_cell(write: Write, urdf: str, tip: str = "tip", home: str = "") -> InputError:
    write("robot.urdf", urdf)
    cell = write(
        "cell.yaml",
        f"name: c\nrobots:\n  arm:\n    model: {{urdf: robot.urdf, tip: {tip}}}\n{home}",
    )
    with pytest.raises(InputError) as e:
        build_cell_model(load_world(cell))
    return e.value


ONE_JOINT = """<robot name="one">
  <link name="base"/>
  <link name="tip"/>
  <joint name="j" type="{kind}">
    <parent link="base"/>
    <child link="tip"/>
    <axis xyz="0 0 1"/>
    {limit}
  </joint>
</robot>
"""
LIMIT = '<limit lower="-1" upper="1" velocity="1" effort="1"/>'


def test_unknown_tip_is_reported_in_the_cell_file(write: Write) -> None:
    err = user_cell(write, ONE_JOINT.format(kind="revolute", limit=LIMIT), tip="flange")
    p = err.problems[0]
    assert (
        p.message == "robots.arm.model.tip: unknown link 'flange' in robot.urdf; known: base, tip"
    )
    assert (Path(p.file or "").name, p.line) == ("cell.yaml", 4)


def test_home_must_have_one_value_per_joint(write: Write) -> None:
    err = user_cell(
        write, ONE_JOINT.format(kind="revolute", limit=LIMIT), home="    home: [0, 0]\n"
    )
    p = err.problems[0]
    assert p.message == "robots.arm.home: the robot has 1 joints, got 2 values"
    assert (Path(p.file or "").name, p.line) == ("cell.yaml", 5)


@pytest.mark.parametrize(
    ("kind", "limit", "message"),
    [
        (
            "floating",
            LIMIT,
            "joint 'j': type 'floating' is not supported; use one of revolute, continuous, "
            "prismatic, fixed",
        ),
        ("revolute", "", "joint 'j' needs <limit velocity=...> greater than 0"),
        (
            "prismatic",
            '<limit lower="1" upper="1" velocity="1"/>',
            "joint 'j' needs <limit lower=... upper=...> with lower < upper",
        ),
        (
            "revolute",
            '<limit lower="a" upper="1" velocity="1"/>',
            "joint 'j' limit: 'lower' must be a number, got 'a'",
        ),
        ("fixed", "", "no movable joint between the root link 'base' and the tip 'tip'"),
    ],
)
def test_bad_joints_are_input_errors(write: Write, kind: str, limit: str, message: str) -> None:
    err = user_cell(write, ONE_JOINT.format(kind=kind, limit=limit))
    p = err.problems[0]
    assert p.message == message
    assert Path(p.file or "").name == "robot.urdf"


def test_a_link_with_two_parents_is_refused(write: Write) -> None:
    urdf = ONE_JOINT.format(kind="revolute", limit=LIMIT).replace(
        "</robot>",
        '<joint name="k" type="fixed"><parent link="base"/><child link="tip"/></joint></robot>',
    )
    p = user_cell(write, urdf).problems[0]
    assert p.message == "joint 'k': link 'tip' already has parent joint 'j'; a URDF is a tree"
    assert p.line == 10


def test_home_of_prismatic_axes_in_length_units(tmp_path: Path) -> None:
    """With units mm/deg, home gives millimetres for the linear axes and degrees for the
    rotation: each converted by its joint's kind."""
    src = URDF_DATA / "cartesian"
    (tmp_path / "cartesian.urdf").write_text((src / "cartesian.urdf").read_text())
    text = (src / "cell.yaml").read_text()
    text = text.replace(
        "name: cartesian_lab\n", "name: cartesian_lab\nunits: {length: mm, angle: deg}\n"
    )
    text = text.replace(
        "xyz: [0.1, 0.2, 0.0], rpy: [0, 0, 1.5707963267948966]",
        "xyz: [100, 200, 0], rpy: [0, 0, 90]",
    )
    text = text.replace("home: [0.5, 0.3, 0.1, 0.0]", "home: [500, 300, 100, 90]")
    text = text.replace("xyz: [0, 0, 0.05]", "xyz: [0, 0, 50]").replace(
        "finger_width: 0.01", "finger_width: 10"
    )
    (tmp_path / "cell.yaml").write_text(text)
    arm = build_cell_model(load_world(tmp_path / "cell.yaml")).arms["gantry"]
    assert arm.home is not None
    np.testing.assert_allclose(arm.home, [0.5, 0.3, 0.1, math.pi / 2])
