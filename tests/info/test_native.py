"""Native platforms: X3D poses + element models + mapping, checked against hand arithmetic."""

from __future__ import annotations

import shutil
from pathlib import Path
from types import MappingProxyType

import numpy as np
import pytest

from cellengine.arrays import Mat
from cellengine.errors import InputError
from cellengine.geometry import pose, rot_z, transform
from cellengine.info.mapcsv import MapRow
from cellengine.info.mesh import Mesh
from cellengine.info.models_xml import load_models
from cellengine.info.native import assemble, load_native_platform
from cellengine.info.platform import Platform
from cellengine.info.x3d import X3DNode, X3DScene

DATA = Path(__file__).parents[1] / "data" / "platforms" / "native"

# Every child of the fixture's root Transform (scale 0.001, rotation 0 0.707107 0.707107 π)
# maps (x, y, z) mm to (-x, z, y) mm, and the y-up -> z-up turn Rx(+90°) maps (a, b, c) to
# (a, -c, b): together (x, y, z) mm -> (-x, -y, z) / 1000 m, and axes turn by diag(-1, -1, 1).
FLIP = np.diag([-1.0, -1.0, 1.0])


def load(folder: Path = DATA, up: str = "y", T: Mat | None = None) -> Platform:
    return load_native_platform(
        "holder",
        np.eye(4) if T is None else T,
        folder / "platform.x3d",
        folder / "models.xml",
        folder / "map.csv",
        folder,
        "z" if up == "z" else "y",
    )


def in_platform(p: Platform, element: str, keypoint: str) -> Mat:
    e = p.elements[element]
    return e.T_platform_element @ e.keypoints[keypoint].T_element_keypoint


def test_elements_in_map_order_with_names_models_and_sources() -> None:
    p = load()
    # the mapped elements in map order, then the CAD parts no row names, as obstacles
    assert list(p.elements) == ["guide1", "guide2", "comb_a", "Base"]
    g = p.elements["guide2"]
    assert (g.name, g.model) == ("guide2", "guide_u")
    assert list(g.keypoints) == ["slot", "entry"]
    assert dict(g.dimensions) == pytest.approx(
        {"length": 0.010, "width": 0.024, "height": 0.060, "gap": 0.010}
    )
    assert g.source is not None
    assert (Path(g.source.file).name, g.source.line) == ("map.csv", 3)
    base = p.elements["Base"]  # the root assembly's plate is in no map row
    assert (base.model, dict(base.keypoints), base.mesh is not None) == ("obstacle", {}, True)
    (warning,) = p.warnings
    assert (Path(warning.file or "").name, warning.line) == ("platform.x3d", base.source.line)
    assert warning.message == (
        "CAD part 'Base' is in no row of map.csv: it is checked as the obstacle "
        "'holder.Base'; give it a row (its model, or 'obstacle' or 'ignore')"
    )


def test_keypoints_through_the_blender_root_transform() -> None:
    p = load()
    # guide1: translation (100, 50, 5) mm -> origin (-0.1, -0.05, 0.005) m, axes FLIP;
    # slot (0, 0, 55) mm in the element -> (0, 0, 0.055) after FLIP -> (-0.1, -0.05, 0.060).
    np.testing.assert_allclose(
        p.elements["guide1"].T_platform_element, transform(FLIP, [-0.1, -0.05, 0.005]), atol=1e-6
    )
    np.testing.assert_allclose(
        in_platform(p, "guide1", "slot"), transform(FLIP, [-0.1, -0.05, 0.060]), atol=1e-6
    )
    # guide2: translation "200, 50, 5", turned 90° about its z (which stays z): axes
    # FLIP·Rz(90°). entry (-5, 0, 55) mm: Rz(90°) -> (0, -5, 55), FLIP -> (0, 5, 55),
    # + origin (-200, -50, 5) -> (-0.2, -0.045, 0.060) m. Its rpy (0, 0, 90°) adds another
    # quarter turn: FLIP·Rz(180°) = identity.
    np.testing.assert_allclose(
        p.elements["guide2"].T_platform_element[:3, :3], FLIP @ rot_z(np.pi / 2), atol=1e-6
    )
    np.testing.assert_allclose(
        in_platform(p, "guide2", "entry"), transform(np.eye(3), [-0.2, -0.045, 0.060]), atol=1e-6
    )
    # comb_a: (300, 100, 0) mm + tooth1 (5, 17, 80) mm -> (-0.305, -0.117, 0.080) m.
    np.testing.assert_allclose(
        in_platform(p, "comb_a", "tooth1")[:3, 3], [-0.305, -0.117, 0.080], atol=1e-6
    )


def test_mesh_is_in_the_element_frame_in_metres() -> None:
    mesh = load().elements["comb_a"].mesh
    assert mesh is not None
    np.testing.assert_allclose(mesh.extents, [0.010, 0.034, 0.065], atol=1e-9)
    np.testing.assert_allclose(mesh.bounds.mean(axis=0), [0, 0, 0], atol=1e-9)


def test_up_z_skips_the_turn() -> None:
    # Only the root rotation: (100, 50, 5) mm -> (-100, 5, 50) mm.
    origin = load(up="z").elements["guide1"].T_platform_element[:3, 3]
    np.testing.assert_allclose(origin, [-0.1, 0.005, 0.05], atol=1e-6)


def test_platform_pose_is_kept_as_given() -> None:
    T = pose([0.45, 0.25, 0.0], [0.0, 0.0, 0.3])
    p = load(T=T)
    assert p.name == "holder"
    np.testing.assert_array_equal(p.T_cell_platform, T)
    assert not p.T_cell_platform.flags.writeable


def copy_fixture(tmp_path: Path, map_csv: str) -> Path:
    folder = tmp_path / "holder"
    shutil.copytree(DATA, folder)
    (folder / "map.csv").write_text(map_csv)
    return folder


def test_unknown_cad_name_at_the_map_row(tmp_path: Path) -> None:
    folder = copy_fixture(tmp_path, "cad_name,model,name\nG1,guide_u,guide1\nG9,guide_u,g9\n")
    with pytest.raises(InputError) as e:
        load(folder)
    (problem,) = e.value.problems
    assert (problem.file, problem.line) == (str(folder / "map.csv"), 3)
    assert problem.message == (
        "unknown CAD name 'G9' (no DEF of that name in platform.x3d); known: Base, C1, G1, G2"
    )


def test_unknown_model_at_the_map_row(tmp_path: Path) -> None:
    folder = copy_fixture(tmp_path, "cad_name,model,name\nG1,guide_v,guide1\n")
    with pytest.raises(InputError) as e:
        load(folder)
    (problem,) = e.value.problems
    assert (problem.file, problem.line) == (str(folder / "map.csv"), 2)
    assert problem.message == "unknown model 'guide_v' (not in models.xml); known: comb, guide_u"


def test_models_file_errors_come_through(tmp_path: Path) -> None:
    folder = copy_fixture(tmp_path, "cad_name,model,name\n")
    (folder / "models.xml").write_text('<elements units="mm">\n<element model="x" />\n<x/>')
    with pytest.raises(InputError) as e:
        load(folder)
    assert e.value.problems[0].file == str(folder / "models.xml")


def test_assemble_from_a_scene_built_by_hand() -> None:
    T_scene_a = pose([0.1, 0.2, 0.3], [0.0, 0.0, np.pi / 2])
    T_scene_a.setflags(write=False)
    scene = X3DScene(
        "hand.x3d",
        MappingProxyType(
            {
                "A": X3DNode("A", "hand.x3d", 3, T_scene_a, None),
                "B": X3DNode("B", "hand.x3d", 4, np.eye(4), None),
            }
        ),
    )
    models = load_models(DATA / "models.xml")
    p = assemble(
        "p",
        np.eye(4),
        scene,
        models,
        (MapRow("A", "comb", "c", 2),),
        DATA / "models.xml",
        DATA / "map.csv",
    )
    assert list(p.elements) == ["c"]
    e = p.elements["c"]
    assert e.T_platform_element is T_scene_a
    assert e.mesh is None
    # tooth1 (5, 17, 80) mm turned 90° about z -> (-17, 5, 80) mm, + (100, 200, 300) mm.
    T = e.T_platform_element @ e.keypoints["tooth1"].T_element_keypoint
    np.testing.assert_allclose(T[:3, 3], [0.083, 0.205, 0.380])


def test_obstacle_and_ignore_rows(tmp_path: Path) -> None:
    """A row with model 'obstacle' names the part an obstacle (no warning); 'ignore' leaves
    it out of the scene (a label, a part the cable passes through)."""
    folder = tmp_path / "p"
    shutil.copytree(DATA, folder)
    mapping = folder / "map.csv"
    mapping.write_text(mapping.read_text().rstrip("\n") + "\nBase,obstacle,plate\n")
    p = load(folder)
    assert (p.elements["plate"].model, p.warnings) == ("obstacle", ())
    assert "Base" not in p.elements
    mapping.write_text(mapping.read_text().replace("Base,obstacle,plate", "Base,ignore,base"))
    p = load(folder)
    assert list(p.elements) == ["guide1", "guide2", "comb_a"] and p.warnings == ()


def test_geometry_under_no_def_is_an_obstacle_too() -> None:
    """A Shape straight under the Scene (no DEF over it), and a DEF called 'unnamed' with
    geometry of its own: both obstacles, told apart in their warnings."""
    tri = Mesh(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]]), np.array([[0, 1, 2]]))
    scene = X3DScene(
        "hand.x3d",
        MappingProxyType({"unnamed": X3DNode("unnamed", "hand.x3d", 3, np.eye(4), tri)}),
        mesh=tri,
    )
    p = assemble("p", np.eye(4), scene, {}, (), DATA / "models.xml", DATA / "map.csv")
    assert list(p.elements) == ["unnamed", "unnamed_2"]
    assert [(w.line, w.message.split(" is in")[0]) for w in p.warnings] == [
        (3, "CAD part 'unnamed'"),
        (None, "geometry under no DEF"),
    ]
