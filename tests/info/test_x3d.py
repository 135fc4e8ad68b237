"""The X3D loader. Every expected pose and vertex below was worked out by hand (in the
comments), not recomputed with the loader's own code."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from cellengine.errors import InputError
from cellengine.info import x3d
from cellengine.info.x3d import X3DScene, load_x3d

DATA = Path(__file__).parents[1] / "data" / "x3d"
from tests.conftest import REMODEL, ROOT  # noqa: E402

Q = 1.5707963267948966  # pi/2, as an exporter would write it

# Rx(+90°), the y-up to z-up turn: (x, y, z) -> (x, -z, y)
RX90 = np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])
RZ90 = np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]])
RZ180 = np.diag([-1.0, -1, 1])


def scene_xml(body: str) -> str:
    return f'<?xml version="1.0" encoding="UTF-8"?>\n<X3D>\n<Scene>\n{body}\n</Scene>\n</X3D>\n'


def write(folder: Path, name: str, body: str) -> Path:
    path = folder / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(scene_xml(body))
    return path


def load(tmp_path: Path, body: str, up: str = "z") -> X3DScene:
    return load_x3d(write(tmp_path, "scene.x3d", body), tmp_path, up)  # type: ignore[arg-type]


def error(tmp_path: Path, body: str, name: str = "scene.x3d") -> tuple[str, int | None]:
    path = write(tmp_path, name, body)
    with pytest.raises(InputError) as e:
        load_x3d(path, tmp_path)
    (p,) = e.value.problems
    assert p.file == str(path)
    return p.message, p.line


def origin(scene: X3DScene, name: str) -> np.ndarray:
    return scene.nodes[name].T_scene_node[:3, 3]


def rotation(scene: X3DScene, name: str) -> np.ndarray:
    return scene.nodes[name].T_scene_node[:3, :3]


# --- composing poses ------------------------------------------------------------------------


def test_translation_and_rotation_chain(tmp_path: Path) -> None:
    s = load(
        tmp_path,
        f"""<Transform DEF="A" translation="1 0 0" rotation="0 0 1 {Q}">
              <Transform DEF="B" translation="0 2 0" rotation="0 0 1 {Q}">
                <Transform DEF="C" translation="3 0 0"/>
              </Transform>
            </Transform>""",
    )
    # A: at (1,0,0), Rz90. B: (1,0,0) + Rz90 (0,2,0) = (-1,0,0), Rz180.
    # C: (-1,0,0) + Rz180 (3,0,0) = (-4,0,0), Rz180.
    assert list(s.nodes) == ["A", "B", "C"]
    np.testing.assert_allclose(origin(s, "A"), [1, 0, 0], atol=1e-9)
    np.testing.assert_allclose(origin(s, "B"), [-1, 0, 0], atol=1e-9)
    np.testing.assert_allclose(origin(s, "C"), [-4, 0, 0], atol=1e-9)
    np.testing.assert_allclose(rotation(s, "A"), RZ90, atol=1e-9)
    np.testing.assert_allclose(rotation(s, "C"), RZ180, atol=1e-9)
    np.testing.assert_allclose(s.nodes["C"].T_scene_node[3], [0, 0, 0, 1])


def test_scale_center_and_scale_orientation(tmp_path: Path) -> None:
    s = load(
        tmp_path,
        f"""<Transform DEF="N" translation="1 0 0" center="0 1 0" rotation="0 0 1 {Q}"
                       scale="2 1 1" scaleOrientation="0 0 1 {Q}">
              <Shape><TriangleSet><Coordinate point="0 0 0  0 1 0  1 1 1"/></TriangleSet></Shape>
              <Transform DEF="K" translation="1 0 0"/>
            </Transform>""",
    )
    # SR S SR^-1 with SR = Rz90 scales world y by 2: diag(1,2,1); L = Rz90 diag(1,2,1) maps
    # v -> (-2 vy, vx, vz). P' = t + c + L (P - c).
    # N's origin: (1,1,0) + L (0,-1,0) = (1,1,0) + (2,0,0) = (3,1,0); orientation Rz90 only.
    np.testing.assert_allclose(origin(s, "N"), [3, 1, 0], atol=1e-9)
    np.testing.assert_allclose(rotation(s, "N"), RZ90, atol=1e-9)
    # K: (1,1,0) + L (1,-1,0) = (1,1,0) + (2,1,0) = (3,2,0); still Rz90 (frames stay rigid).
    np.testing.assert_allclose(origin(s, "K"), [3, 2, 0], atol=1e-9)
    np.testing.assert_allclose(rotation(s, "K"), RZ90, atol=1e-9)
    # Vertices: (1,1,1) -> world (1,1,0) + L (1,0,1) = (1,2,1); in N's frame
    # Rz90^T ((1,2,1) - (3,1,0)) = Rz(-90) (-2,1,1) = (1,2,1). (0,1,0) -> world (1,1,0)
    # -> Rz(-90) (-2,0,0) = (0,2,0). The scale shows in the mesh, not in the frame.
    mesh = s.nodes["N"].mesh
    assert mesh is not None
    np.testing.assert_allclose(mesh.vertices, [[0, 0, 0], [0, 2, 0], [1, 2, 1]], atol=1e-9)
    np.testing.assert_array_equal(mesh.faces, [[0, 1, 2]])


def test_scale_orientation_changes_where_children_go(tmp_path: Path) -> None:
    s = load(
        tmp_path,
        f"""<Transform DEF="N" translation="1 0 0" center="0 1 0" rotation="0 0 1 {Q}"
                       scale="2 1 1"><Transform DEF="K" translation="1 0 0"/></Transform>""",
    )
    # Without scaleOrientation L = Rz90 diag(2,1,1): K at (1,1,0) + Rz90 (2,-1,0) = (2,3,0).
    np.testing.assert_allclose(origin(s, "K"), [2, 3, 0], atol=1e-9)


def test_root_scaled_to_metres(tmp_path: Path) -> None:
    body = """<Transform DEF="root" scale="0.001 0.001 0.001">
                <Transform DEF="part" translation="100 200 300">
                  <Shape><Box size="10 20 30"/></Shape>
                </Transform>
              </Transform>"""
    s = load(tmp_path, body)
    np.testing.assert_allclose(origin(s, "part"), [0.1, 0.2, 0.3], atol=1e-9)
    np.testing.assert_allclose(rotation(s, "part"), np.eye(3), atol=1e-9)
    mesh = s.nodes["part"].mesh
    assert mesh is not None
    np.testing.assert_allclose(mesh.bounds, [[-0.005, -0.01, -0.015], [0.005, 0.01, 0.015]])
    assert s.nodes["root"].mesh is None


def test_y_up_turned_to_z_up(tmp_path: Path) -> None:
    body = f'<Transform DEF="P" translation="1 2 3" rotation="0 1 0 {Q}"/>'
    # Rx90 maps (1,2,3) to (1,-3,2). Rx90 Ry90 = [[0,0,1],[1,0,0],[0,1,0]]: the node's y,
    # X3D's up, becomes the platform's z.
    s = load_x3d(write(tmp_path, "y.x3d", body), tmp_path)
    np.testing.assert_allclose(origin(s, "P"), [1, -3, 2], atol=1e-9)
    np.testing.assert_allclose(rotation(s, "P"), [[0, 0, 1], [1, 0, 0], [0, 1, 0]], atol=1e-9)
    z = load_x3d(write(tmp_path, "z.x3d", body), tmp_path, up="z")
    np.testing.assert_allclose(origin(z, "P"), [1, 2, 3], atol=1e-9)
    np.testing.assert_allclose(rotation(z, "P"), [[0, 0, 1], [0, 1, 0], [-1, 0, 0]], atol=1e-9)


def test_meshes_are_in_the_node_frame_whatever_the_up_axis(tmp_path: Path) -> None:
    body = '<Transform DEF="P" translation="1 2 3"><Shape><Box size="1 2 3"/></Shape></Transform>'
    s = load(tmp_path, body, up="y")
    mesh = s.nodes["P"].mesh
    assert mesh is not None
    np.testing.assert_allclose(mesh.extents, [1, 2, 3])
    np.testing.assert_allclose(rotation(s, "P"), RX90, atol=1e-9)


def test_unnamed_transforms_fold_into_the_named_ancestor(tmp_path: Path) -> None:
    s = load(
        tmp_path,
        """<Group DEF="G"><Transform translation="5 0 0" scale="2 2 2">
             <Shape><Box size="1 1 1"/></Shape></Transform></Group>
           <Shape><Box size="4 4 4"/></Shape>""",
    )
    assert list(s.nodes) == ["G"]
    mesh = s.nodes["G"].mesh
    assert mesh is not None
    # The unit box scaled 2 and moved 5 along x: x in [4, 6], y and z in [-1, 1].
    np.testing.assert_allclose(mesh.bounds, [[4, -1, -1], [6, 1, 1]])
    # Geometry under no named node is kept, in the platform frame.
    assert s.mesh is not None
    np.testing.assert_allclose(s.mesh.bounds, [[-2, -2, -2], [2, 2, 2]])


# --- real exporters -------------------------------------------------------------------------


def test_blender_style_file(monkeypatch: pytest.MonkeyPatch) -> None:
    def no_network(*args: object) -> None:
        raise AssertionError("the loader opened a network connection")

    monkeypatch.setattr(socket.socket, "connect", no_network)
    s = load_x3d(DATA / "blender.x3d", DATA)
    assert list(s.nodes) == ["ID0001", "ID0002"]
    n = s.nodes["ID0002"]
    assert (n.file, n.line) == (str(DATA / "blender.x3d"), 15)
    # The root turns pi about (0,1,1)/sqrt2: (x,y,z) -> (-x,z,y); then Rx90: (x,-z,y).
    # (100,50,5) mm -> (0.1,0.05,0.005) -> (-0.1,0.005,0.05) -> (-0.1,-0.05,0.005).
    np.testing.assert_allclose(origin(s, "ID0002"), [-0.1, -0.05, 0.005], atol=1e-6)
    np.testing.assert_allclose(rotation(s, "ID0002"), RZ180, atol=1e-6)
    np.testing.assert_allclose(rotation(s, "ID0001"), RZ180, atol=1e-6)
    mesh = n.mesh
    assert mesh is not None
    # The quad and the pentagon (no trailing -1), fanned; millimetres scaled to metres.
    np.testing.assert_array_equal(
        mesh.faces, [[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7], [4, 7, 8]]
    )
    np.testing.assert_allclose(mesh.vertices[6], [0.012, 0.010, 0.004], atol=1e-9)
    np.testing.assert_allclose(mesh.vertices[2], [0.010, 0.020, 0.0], atol=1e-9)
    assert s.nodes["ID0001"].mesh is None


def test_freecad_style_file() -> None:
    s = load_x3d(DATA / "freecad.x3d", DATA)
    assert list(s.nodes) == ["Body", "Pad", "Pocket"]
    # rotation "0 0 0 0" is no rotation; (0,0,10) y-up -> (0,-10,0) z-up.
    np.testing.assert_allclose(origin(s, "Pad"), [0, -10, 0], atol=1e-9)
    np.testing.assert_allclose(rotation(s, "Pad"), RX90, atol=1e-9)
    np.testing.assert_allclose(origin(s, "Pocket"), [2, 0, 0], atol=1e-9)
    pad, pocket = s.nodes["Pad"].mesh, s.nodes["Pocket"].mesh
    assert pad is not None and pocket is not None
    # The edges' IndexedLineSet adds nothing; the Coordinate USE'd by id is the same triangle.
    np.testing.assert_array_equal(pad.faces, [[0, 1, 2]])
    np.testing.assert_allclose(pocket.vertices, [[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    assert s.nodes["Body"].mesh is None


def test_remodel_platform_poses() -> None:
    s = load_x3d(REMODEL / "platform_cad.x3d", REMODEL, meshes=False)
    assert list(s.nodes) == ["ID0001", "ID0002", "ID0009", "ID0003", "ID0004", "ID0005"]
    # Root: scale 0.001 and (x,y,z) -> (-x,z,y); the y-up turn then (x,-z,y): (-x,-y,z) mm/1000.
    np.testing.assert_allclose(origin(s, "ID0002"), [-0.4820001, -0.14533, 0.005], atol=1e-6)
    np.testing.assert_allclose(origin(s, "ID0004"), [-0.318000001, -0.14533, 0.005], atol=1e-6)
    np.testing.assert_allclose(rotation(s, "ID0004"), RZ180, atol=1e-6)
    assert s.nodes["ID0002"].line == 34  # where its start tag begins
    assert s.nodes["ID0004"].mesh is None


def test_remodel_platform_sample_has_damaged_geometry() -> None:
    # The shared sample was cut short: a number ran into the next one. Found and reported.
    with pytest.raises(InputError) as e:
        load_x3d(REMODEL / "platform_cad.x3d", REMODEL)
    (p,) = e.value.problems
    assert (p.line, p.message) == (
        45,
        "Coordinate 'coords_ME_J1': point must be x y z triples of numbers, "
        "got '16.0735072.688004' (item 211 of 348)",
    )


def test_bad_geometry_skip_drops_only_the_bad_nodes_mesh(tmp_path: Path) -> None:
    body = (
        '<Transform DEF="good" translation="1 0 0"><Shape><Box size="2 2 2"/></Shape></Transform>\n'
        '<Transform DEF="bad" translation="0 1 0"><Shape><Box size="2 2 2"/></Shape>\n'
        '<Shape><IndexedFaceSet coordIndex="0 1 5"><Coordinate point="0 0 0 1 0 0 0 1 0"/>'
        "</IndexedFaceSet></Shape></Transform>"
    )
    path = write(tmp_path, "scene.x3d", body)
    s = load_x3d(path, tmp_path, "z", bad_geometry="skip")
    assert s.nodes["good"].mesh is not None and s.nodes["good"].mesh_problem is None
    bad = s.nodes["bad"]
    np.testing.assert_allclose(bad.T_scene_node[:3, 3], [0, 1, 0])
    assert bad.mesh is None  # never half a mesh: its sound Box is dropped too
    assert bad.mesh_problem is not None
    assert (bad.mesh_problem.line, bad.mesh_problem.message) == (
        6,
        "IndexedFaceSet: coordIndex refers to point 5, but there are 3 points (0..2)",
    )
    with pytest.raises(InputError):  # the default refuses it
        load_x3d(path, tmp_path, "z")


def test_remodel_combs_with_meshes() -> None:
    s = load_x3d(REMODEL / "combs_cad.x3d", REMODEL)
    # (458, 23, 3) mm -> (-0.458, -0.023, 0.003) m, as for the platform.
    np.testing.assert_allclose(origin(s, "ID000002"), [-0.458, -0.023, 0.003], atol=1e-6)
    base = s.nodes["ID000001"].mesh
    assert base is not None
    # The comb base plate, 600 x 282 x 3 mm in its own (rigid, unscaled) frame.
    np.testing.assert_allclose(base.bounds, [[0, 0, 0], [0.6, 0.282, 0.003]], atol=1e-6)


# --- DEF / USE ------------------------------------------------------------------------------


def test_use_instantiates_geometry_but_no_names(tmp_path: Path) -> None:
    s = load(
        tmp_path,
        """<Group DEF="Board">
             <Transform DEF="Peg" translation="1 0 0"><Shape><Box/></Shape></Transform>
             <Transform DEF="Slot2" translation="5 0 0"><Transform USE="Peg"/></Transform>
           </Group>""",
    )
    assert list(s.nodes) == ["Board", "Peg", "Slot2"]
    np.testing.assert_allclose(origin(s, "Peg"), [1, 0, 0])
    slot = s.nodes["Slot2"].mesh
    assert slot is not None
    # The default 2x2x2 box, 1 along x from Slot2's origin.
    np.testing.assert_allclose(slot.bounds, [[0, -1, -1], [2, 1, 1]])
    assert s.nodes["Board"].mesh is None


def test_use_of_unknown_name(tmp_path: Path) -> None:
    message, line = error(
        tmp_path, '<Transform DEF="Peg"/>\n<Group DEF="G">\n<Transform USE="Pge"/>\n</Group>'
    )
    assert (message, line) == ("USE 'Pge' names no DEF or id in this file; did you mean 'Peg'?", 6)


def test_use_of_another_kind_of_node(tmp_path: Path) -> None:
    body = (
        '<Shape><IndexedFaceSet coordIndex="0 0 0"><Coordinate DEF="c" point="0 0 0"/>'
        '</IndexedFaceSet></Shape>\n<Transform USE="c"/>'
    )
    message, line = error(tmp_path, body)
    assert (message, line) == ("Transform USE 'c' names a Coordinate (line 4)", 5)


def test_use_inside_its_own_definition(tmp_path: Path) -> None:
    message, line = error(tmp_path, '<Group DEF="G">\n<Group USE="G"/>\n</Group>')
    assert (message, line) == ("USE 'G' is inside the node it names (line 4)", 5)


def test_duplicate_names(tmp_path: Path) -> None:
    path = tmp_path / "scene.x3d"
    message, line = error(tmp_path, '<Group DEF="A"/>\n<Transform id="A"/>')
    assert (message, line) == (f"duplicate name 'A' (first defined at {path}:4)", 5)


def test_lines_are_where_start_tags_begin(tmp_path: Path) -> None:
    # libxml2 would say 5 and 8, where the start tags end.
    body = '<Group\n DEF="A"/>\n<!-- <Group DEF="A"/> -->\n<Transform\n id="A"\n/>'
    message, line = error(tmp_path, body)
    assert (message, line) == (
        f"duplicate name 'A' (first defined at {tmp_path / 'scene.x3d'}:4)",
        7,
    )


def test_use_repetition_is_capped(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(x3d, "MAX_VISITS", 30)
    body = '<Group DEF="a"><Shape><Box/></Shape></Group>' + "".join(
        f'<Group DEF="{b}">' + f'<Group USE="{a}"/>' * 4 + "</Group>"
        for a, b in zip("abcd", "bcde", strict=True)
    )
    message, _ = error(tmp_path, body)
    assert (
        message == "the scene expands to more than 30 nodes (DEF/USE or Inline repeated too often)"
    )


def test_geometry_is_capped(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(x3d, "MAX_TRIANGLES", 20)
    body = '<Group DEF="a"><Shape><Box/></Shape></Group>\n<Group USE="a"/>'  # 12 + 12 triangles
    assert error(tmp_path, body) == ("the scene has more than 20 triangles or vertices", 4)


# --- Inline ---------------------------------------------------------------------------------


def test_inline_inside_the_folder() -> None:
    cell = DATA / "cell"
    s = load_x3d(cell / "main.x3d", cell, up="z")
    assert list(s.nodes) == ["Mount", "Pin", "Screw"]
    # Mount (0,0,1); Pin (1,0,0) under it: (1,0,1); Screw (0,2,0) under Pin: (1,2,1).
    np.testing.assert_allclose(origin(s, "Pin"), [1, 0, 1])
    np.testing.assert_allclose(origin(s, "Screw"), [1, 2, 1])
    assert s.nodes["Mount"].file == str(cell / "main.x3d")
    assert s.nodes["Pin"].file == str(cell / "parts" / "part.x3d")
    assert s.nodes["Screw"].file == str(cell / "parts" / "screw.x3d")  # relative to part.x3d
    assert (s.nodes["Pin"].line, s.nodes["Screw"].line) == (4, 4)
    screw = s.nodes["Screw"].mesh
    assert screw is not None
    np.testing.assert_allclose(np.linalg.norm(screw.vertices, axis=1), 0.5)
    assert s.nodes["Mount"].mesh is None


def test_inline_outside_the_folder_is_refused(tmp_path: Path) -> None:
    cell = tmp_path / "cell"
    write(tmp_path, "outside.x3d", '<Transform DEF="X"/>')
    message, line = error(cell, '<Inline url="../outside.x3d"/>')
    assert (message, line) == (
        f"Inline url '../outside.x3d' points outside the cell folder {cell.resolve()}",
        4,
    )


@pytest.mark.parametrize(
    "url", ["webots://robots/arm.x3d", "http://example.com/a.x3d", "file:///etc/a.x3d"]
)
def test_inline_url_with_a_scheme_is_refused(tmp_path: Path, url: str) -> None:
    message, line = error(tmp_path, f"<Group>\n<Inline url='\"{url}\"'/>\n</Group>")
    assert (message, line) == (
        f"Inline url '{url}' is a URL; only files inside the cell folder "
        f"{tmp_path.resolve()} are allowed",
        5,
    )


def test_inline_cycle_is_refused(tmp_path: Path) -> None:
    a = write(tmp_path, "a.x3d", '<Inline url="b.x3d"/>')
    b = write(tmp_path, "b.x3d", '<Group>\n<Inline url="a.x3d"/>\n</Group>')
    with pytest.raises(InputError) as e:
        load_x3d(a, tmp_path)
    (p,) = e.value.problems
    assert (p.message, p.file, p.line) == (
        "Inline 'a.x3d' includes itself (a.x3d -> b.x3d -> a.x3d)",
        str(b.resolve()),
        5,
    )


def test_inline_depth(tmp_path: Path) -> None:
    for i in range(1, 10):
        write(
            tmp_path,
            f"d{i}.x3d",
            f'<Transform DEF="n{i}" translation="1 0 0"><Inline url="d{i + 1}.x3d"/></Transform>',
        )
    write(tmp_path, "d10.x3d", '<Transform DEF="n10"/>')
    # d2 -> ... -> d10 is 8 levels of Inline below d2: allowed; n10 sits 8 x 1 along x.
    s = load_x3d(tmp_path / "d2.x3d", tmp_path, up="z")
    np.testing.assert_allclose(origin(s, "n10"), [8, 0, 0])
    with pytest.raises(InputError) as e:
        load_x3d(tmp_path / "d1.x3d", tmp_path)
    assert e.value.problems[0].message == "Inline 'd10.x3d' nests files more than 8 deep"
    assert e.value.problems[0].file == str((tmp_path / "d9.x3d").resolve())


def test_inline_missing_file(tmp_path: Path) -> None:
    message, line = error(tmp_path, '<Inline url=\'"gone.x3d" "also_gone.x3d"\'/>')
    assert message == f"file 'gone.x3d' not found (looked for {tmp_path.resolve() / 'gone.x3d'})"
    assert line == 4


def test_inline_url_too_long(tmp_path: Path) -> None:
    url = "a" * 300
    assert error(tmp_path, f'<Inline url="{url}"/>') == (
        f"Inline url '{url[:57]}...' cannot be read: File name too long",
        4,
    )


def test_inline_symlink_loop(tmp_path: Path) -> None:
    (tmp_path / "loop.x3d").symlink_to("loop.x3d")
    message, line = error(tmp_path, '<Group>\n<Inline url="loop.x3d"/>\n</Group>')
    assert (message, line) == (
        "file reference 'loop.x3d' cannot be used: a loop of symbolic links",
        5,
    )


def test_inline_of_a_fifo_is_refused_without_opening_it(tmp_path: Path) -> None:
    """In a subprocess with a timeout: opening a FIFO waits for a writer forever."""
    os.mkfifo(tmp_path / "pipe.x3d")
    path = write(tmp_path, "scene.x3d", '<Inline url="pipe.x3d"/>')
    code = (
        "import sys; from pathlib import Path; from cellengine.info.x3d import load_x3d\n"
        f"load_x3d(Path({str(path)!r}), Path({str(tmp_path)!r}))"
    )
    result = subprocess.run(
        [sys.executable, "-c", code],
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert result.stderr.splitlines()[-1] == (
        f"cellengine.errors.InputError: {path}:4:1: file reference 'pipe.x3d' is a named pipe "
        "(FIFO), not a regular file"
    )


def test_an_inlined_file_is_parsed_once(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    parsed: list[str] = []
    parse = x3d.parse_xml
    monkeypatch.setattr(x3d, "parse_xml", lambda p, **kw: parsed.append(p.name) or parse(p, **kw))
    write(tmp_path, "leaf.x3d", "<Shape><Box/></Shape>")
    write(tmp_path, "mid.x3d", '<Inline url="leaf.x3d"/>' * 3)
    s = load(tmp_path, '<Transform translation="1 0 0"><Inline url="mid.x3d"/></Transform>' * 4)
    assert sorted(parsed) == ["leaf.x3d", "mid.x3d", "scene.x3d"]
    assert s.mesh is not None and len(s.mesh.faces) == 4 * 3 * 12  # every instance, boxes


def test_inline_instances_are_capped(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(x3d, "MAX_INLINES", 10)
    write(tmp_path, "leaf.x3d", "<Shape><Box/></Shape>")
    write(tmp_path, "mid.x3d", '<Inline url="leaf.x3d"/>\n' * 3)
    with pytest.raises(InputError) as e:
        load(tmp_path, '<Inline url="mid.x3d"/>\n' * 3)
    (p,) = e.value.problems
    # scene: mid (1), leaf x3 (4), mid (5), leaf x3 (8), mid (9), leaf (10), leaf (11): refused
    assert (p.message, Path(p.file or "").name, p.line, p.col) == (
        "the scene has more than 10 Inlines (files Inlined again and again)",
        "mid.x3d",
        5,
        1,
    )


# --- geometry -------------------------------------------------------------------------------


def test_primitives(tmp_path: Path) -> None:
    s = load(
        tmp_path,
        """<Transform DEF="box"><Shape><Box size="1 2 3"/></Shape></Transform>
           <Transform DEF="unit"><Shape><Box/></Shape></Transform>
           <Transform DEF="cyl"><Shape><Cylinder radius="0.5" height="3"/></Shape></Transform>
           <Transform DEF="cone"><Shape><Cone bottomRadius="1" height="2"/></Shape></Transform>
           <Transform DEF="ball"><Shape><Sphere radius="2"/></Shape></Transform>""",
    )
    meshes = {k: n.mesh for k, n in s.nodes.items()}
    assert all(m is not None for m in meshes.values())
    np.testing.assert_allclose(meshes["box"].extents, [1, 2, 3])  # type: ignore[union-attr]
    np.testing.assert_allclose(meshes["unit"].bounds, [[-1, -1, -1], [1, 1, 1]])  # type: ignore[union-attr]
    # Cylinders and cones stand along y, centred on the origin.
    np.testing.assert_allclose(
        meshes["cyl"].bounds, [[-0.5, -1.5, -0.5], [0.5, 1.5, 0.5]], atol=1e-9
    )  # type: ignore[union-attr]
    cone = meshes["cone"]
    assert cone is not None
    np.testing.assert_allclose(cone.bounds, [[-1, -1, -1], [1, 1, 1]], atol=1e-9)
    apex = cone.vertices[np.argmax(cone.vertices[:, 1])]
    np.testing.assert_allclose(apex, [0, 1, 0], atol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(meshes["ball"].vertices, axis=1), 2.0)  # type: ignore[union-attr]


@pytest.mark.parametrize(
    ("index", "faces"),
    [
        ("0 1 2 3 -1 4 5 6 7 -1", [[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]]),  # all quads
        ("0 1 2 3 -1 4 5 6 7", [[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]]),  # no last -1
        ("0 1 2 -1 5 6 7 -1", [[0, 1, 2], [5, 6, 7]]),  # all triangles
        ("0 1 -1 2 3 4 -1 -1 0 1 2 3 4", [[2, 3, 4], [0, 1, 2], [0, 2, 3], [0, 3, 4]]),  # mixed
    ],
)
def test_face_sets_are_fanned(tmp_path: Path, index: str, faces: list[list[int]]) -> None:
    points = " ".join(f"{i} 0 0" for i in range(8))
    s = load(
        tmp_path,
        f"""<Group DEF="G"><Shape><IndexedFaceSet coordIndex="{index}">
             <Coordinate point="{points}"/></IndexedFaceSet></Shape></Group>""",
    )
    mesh = s.nodes["G"].mesh
    assert mesh is not None
    np.testing.assert_array_equal(mesh.faces, faces)


def test_indexed_triangle_set_and_ccw(tmp_path: Path) -> None:
    s = load(
        tmp_path,
        """<Group DEF="G"><Shape><IndexedTriangleSet index="0 1 2 2 1 3" ccw="false">
             <Coordinate point="0 0 0 1 0 0 0 1 0 1 1 0"/></IndexedTriangleSet></Shape></Group>""",
    )
    mesh = s.nodes["G"].mesh
    assert mesh is not None
    np.testing.assert_array_equal(mesh.faces, [[2, 1, 0], [3, 1, 2]])


def test_shapes_of_one_node_are_concatenated(tmp_path: Path) -> None:
    s = load(
        tmp_path,
        """<Group DEF="G">
             <Shape><TriangleSet><Coordinate point="0 0 0 1 0 0 0 1 0"/></TriangleSet></Shape>
             <Shape><TriangleSet><Coordinate point="0 0 5 1 0 5 0 1 5"/></TriangleSet></Shape>
           </Group>""",
    )
    mesh = s.nodes["G"].mesh
    assert mesh is not None
    np.testing.assert_array_equal(mesh.faces, [[0, 1, 2], [3, 4, 5]])
    np.testing.assert_allclose(mesh.vertices[3], [0, 0, 5])


def test_switch_keeps_the_chosen_child(tmp_path: Path) -> None:
    s = load(
        tmp_path,
        """<Switch whichChoice="1"><Transform DEF="a"/><Transform DEF="b"/></Switch>
           <Switch><Transform DEF="c"/></Switch>""",
    )
    assert list(s.nodes) == ["b"]


def test_non_geometry_nodes_are_ignored(tmp_path: Path) -> None:
    s = load(
        tmp_path,
        """<WorldInfo title="t"/><Viewpoint DEF="v" position="0 0 5"/>
           <DirectionalLight direction="0 -1 0"/>
           <Transform DEF="T"><Shape><Appearance><Material/></Appearance><Box/></Shape></Transform>
           <!-- a comment -->""",
    )
    assert list(s.nodes) == ["T"]


# --- errors ---------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("attrs", "message"),
    [
        ('translation="1 2"', "Transform 'ID0002': translation must be 3 numbers, got '1 2'"),
        ('rotation="0 1 0 x"', "Transform 'ID0002': rotation must be 4 numbers, got '0 1 0 x'"),
        ('scale="1 1 nan"', "Transform 'ID0002': scale must be 3 numbers, got '1 1 nan'"),
        ('center=" "', "Transform 'ID0002': center must be 3 numbers, got ' '"),
    ],
)
def test_bad_transform_numbers(tmp_path: Path, attrs: str, message: str) -> None:
    assert error(tmp_path, f'<Group>\n<Transform DEF="ID0002"\n {attrs}/>\n</Group>') == (
        message,
        5,
    )


def test_bad_geometry_numbers(tmp_path: Path) -> None:
    points = '<Coordinate point="0 0 0 1 0 0 0 1 0"/>'
    body = f'<Shape>\n<IndexedFaceSet coordIndex="0 1 a -1">{points}</IndexedFaceSet>\n</Shape>'
    assert error(tmp_path, body) == (
        "IndexedFaceSet: coordIndex must be integers, got 'a' (item 3 of 4)",
        5,
    )
    body = (
        '<Shape><IndexedFaceSet coordIndex="0 1 2">\n'
        '<Coordinate DEF="c" point="0 0 0 1 0"/></IndexedFaceSet></Shape>'
    )
    assert error(tmp_path, body) == (
        "Coordinate 'c': point must be x y z triples of numbers, got 5 numbers",
        5,
    )
    body = '<Shape><Box size="1 0 1"/></Shape>'
    assert error(tmp_path, body) == ("Box: size must be 3 positive numbers, got '1 0 1'", 4)


def test_index_out_of_range(tmp_path: Path) -> None:
    body = (
        '<Shape>\n<IndexedFaceSet DEF="f" coordIndex="0 1 2 3 -1 0 7 1">'
        '<Coordinate point="0 0 0 1 0 0 0 1 0 1 1 0"/></IndexedFaceSet></Shape>'
    )
    assert error(tmp_path, body) == (
        "IndexedFaceSet 'f': coordIndex refers to point 7, but there are 4 points (0..3)",
        5,
    )


def test_unsupported_geometry(tmp_path: Path) -> None:
    body = '<Transform DEF="T"><Shape>\n<Extrusion crossSection="0 0 1 0 1 1"/></Shape></Transform>'
    assert error(tmp_path, body) == (
        "unsupported geometry node 'Extrusion'; supported: Box, Cone, Cylinder, IndexedFaceSet, "
        "IndexedTriangleSet, Sphere, TriangleSet",
        5,
    )


def test_unsupported_node_around_geometry(tmp_path: Path) -> None:
    body = "<Billboard>\n<Shape><Box/></Shape></Billboard>"
    assert error(tmp_path, body) == (
        "unsupported node 'Billboard' around geometry; supported grouping nodes: "
        "Anchor, Collision, Group, StaticGroup, Switch, Transform",
        4,
    )


def test_not_x3d(tmp_path: Path) -> None:
    path = tmp_path / "scene.x3d"
    path.write_text("<html>\n<body/>\n</html>")
    with pytest.raises(InputError) as e:
        load_x3d(path, tmp_path)
    assert str(e.value.problems[0].message) == "the root element must be X3D, got 'html'"
    path.write_text("<X3D>\n<head/>\n</X3D>")
    with pytest.raises(InputError) as e:
        load_x3d(path, tmp_path)
    assert (e.value.problems[0].message, e.value.problems[0].line) == (
        "X3D has no Scene element",
        1,
    )


def _grid_mesh(path: Path, side: int, prolog: str = "", nested: int = 0) -> None:
    """A flat side x side grid of vertices (mm) in one IndexedFaceSet, two triangles per
    square, after ``prolog`` (a DOCTYPE), then ``nested`` Groups one in another."""
    i = np.arange(side * side).reshape(side, side)
    a, b, c, d = i[:-1, :-1].ravel(), i[:-1, 1:].ravel(), i[1:, 1:].ravel(), i[1:, :-1].ravel()
    minus = np.full_like(a, -1)
    index = np.column_stack([a, b, c, minus, a, c, d, minus]).ravel()
    y, x = np.divmod(np.arange(side * side), side)
    points = np.column_stack([x, y, np.zeros_like(x)]).ravel()
    with path.open("w") as f:
        f.write(f'{prolog}<X3D><Scene><Transform scale="0.001 0.001 0.001">')
        f.write('<Shape><IndexedFaceSet coordIndex="')
        f.write(" ".join(map(str, index.tolist())))
        f.write('"><Coordinate point="')
        f.write(" ".join(map(str, points.tolist())))
        f.write('"/></IndexedFaceSet></Shape></Transform>')
        f.write(f"{'<Group>' * nested}{'</Group>' * nested}</Scene></X3D>\n")


def test_a_mesh_over_libxml2s_10_mb_text_limit_loads(tmp_path: Path) -> None:
    """Issue 19: a 56 MB X3D (under the 64 MB cap) of one 980k-vertex IndexedFaceSet was
    refused with libxml2's 'Buffer size limit exceeded': its coordIndex is ~37 MB of text.
    ~6 s (half of it writing the file)."""
    path = tmp_path / "big.x3d"
    _grid_mesh(path, 990)
    assert 10e6 < path.stat().st_size < 64 * 2**20
    mesh = load_x3d(path, tmp_path, "z").mesh
    assert mesh is not None
    assert len(mesh.vertices) == 990 * 990
    assert len(mesh.faces) == 2 * 989 * 989
    assert np.allclose(mesh.vertices.max(axis=0), [0.989, 0.989, 0.0])


@pytest.mark.parametrize(
    ("prolog", "nested", "message"),
    [
        (
            '<!DOCTYPE X3D [<!ENTITY e "x">]>',
            0,
            "XML entity declarations are not allowed (found 'e'); remove the DOCTYPE's "
            "internal subset",
        ),
        (
            '<!DOCTYPE X3D [<!ATTLIST Transform translation CDATA "9 9 9">]>',
            0,
            "XML internal DTD subsets are not allowed (their declarations change what the "
            "elements say); remove the part of the DOCTYPE in [ ]",
        ),
        ("", 300, "XML syntax error: elements nest more than 256 deep"),
    ],
)
def test_a_large_text_lifts_no_other_limit(
    tmp_path: Path, prolog: str, nested: int, message: str
) -> None:
    """Parsed with libxml2's size limits lifted (XML_PARSE_HUGE, which also lifts its
    nesting limit and entity checks), a file is still refused an internal DTD subset and
    nesting deeper than 256."""
    path = tmp_path / "big.x3d"
    _grid_mesh(path, 700, prolog, nested)  # a coordIndex of ~17 MB, before the nesting
    with pytest.raises(InputError) as e:
        load_x3d(path, tmp_path, "z")
    (p,) = e.value.problems
    assert p.message == message
    assert p.line == 1
