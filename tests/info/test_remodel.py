"""REMODEL platforms: the shared sample's slot centres against hand arithmetic, a key turned
about all three axes, and errors at file:line for bad inputs."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from cellengine.arrays import Mat
from cellengine.errors import InputError
from cellengine.geometry import rot_x, rot_y, rot_z, transform
from cellengine.info.platform import Platform
from cellengine.info.remodel import IdsRow, load_ids, load_jigs, load_remodel_platform
from tests.conftest import REMODEL

JIGS = REMODEL / "Jigs_definition_v2.xml"
DATA = Path(__file__).parents[1] / "data" / "platforms" / "remodel"
MM = 1e-3
# Each sample X3D has a root Transform (scale 0.001, rotation 0 0.707107 0.707107 π) that
# maps a child's (x, y, z) mm to (-x, z, y) mm; the y-up -> z-up turn Rx(+90°) maps
# (a, b, c) to (a, -c, b). Together: (x, y, z) mm -> (-x, -y, z) / 1000 m, and the axes of
# an element that is not rotated inside the root turn by FLIP.
FLIP = np.diag([-1.0, -1.0, 1.0])


def keypoint(p: Platform, element: str, name: str) -> Mat:
    e = p.elements[element]
    return e.T_platform_element @ e.keypoints[name].T_element_keypoint


def slot(model: str, couple: str = "1") -> Mat:
    return load_jigs(JIGS)[model].keypoints[couple].T_element_keypoint


# --- the shared sample -----------------------------------------------------------------------


def test_sample_slot_centres_in_the_element_frame() -> None:
    # slot centre = key pos + (length/2, gap/2, height/2), all keys unrotated:
    # 0011: (0, 6, 80) + (10/2, 10/2, 54.5/2) = (5, 11, 107.25) mm
    np.testing.assert_allclose(slot("0011")[:3, 3], np.array([5, 11, 107.25]) * MM)
    # 0012 and 0013: (0, 6, 100) + (5, 5, 55/2) = (5, 11, 127.5) mm
    np.testing.assert_allclose(slot("0012")[:3, 3], np.array([5, 11, 127.5]) * MM)
    np.testing.assert_allclose(slot("0013")[:3, 3], np.array([5, 11, 127.5]) * MM)
    # 0014: (20, 4.5, 90) + (1.5/2, 4.5/2, 37/2) = (20.75, 6.75, 108.5) mm
    np.testing.assert_allclose(slot("0014")[:3, 3], np.array([20.75, 6.75, 108.5]) * MM)
    # comb 0000210: (0, 12, 65) + (5, 5, 30/2) = (5, 17, 80) mm
    np.testing.assert_allclose(slot("0000210")[:3, 3], np.array([5, 17, 80]) * MM)
    np.testing.assert_allclose(slot("0011")[:3, :3], np.eye(3))


def test_sample_models_dimensions_and_boxes_in_metres() -> None:
    models = load_jigs(JIGS)
    assert list(models) == ["0011", "0012", "0013", "0014", "0000210", "0000301", "0000302"]
    jig = models["0011"]
    assert jig.kind == "jig"
    assert dict(jig.dimensions) == pytest.approx(
        {"xdim": 0.010, "xcol1": 0.0, "xcol2": 0.010, "ydim": 0.030, "ycol1": -0.008,
         "ycol2": 0.022, "zdim": 0.100}
    )  # fmt: skip
    assert dict(jig.keypoints["1"].dimensions) == pytest.approx(
        {"length": 0.010, "gap": 0.010, "height": 0.0545, "height_corner": 0.0545,
         "xcol1": 0.0, "xcol2": 0.010, "ycol1": -0.014, "ycol2": 0.024}
    )  # fmt: skip
    body, box = jig.boxes
    # the body: x in [xcol1, xcol2] = [0, 10], y in [ycol1, ycol2] = [-8, 22], z in [0, 100] mm
    assert body.size == pytest.approx((0.010, 0.030, 0.100))
    np.testing.assert_allclose(body.T_element_box[:3, 3], [0.005, 0.007, 0.050])
    assert box.size == pytest.approx((0.0072, 0.0198, 0.010))
    np.testing.assert_allclose(box.T_element_box, transform(np.eye(3), [0.0184, 0, 0.055]))
    _, box = models["0012"].boxes  # yaw 0.2883 rad about its z
    np.testing.assert_allclose(
        box.T_element_box, transform(rot_z(0.2883), [0.01444, 0.00795, 0.055]), atol=1e-9
    )
    # the comb: only its body; its guide's collision box is all zeros
    (body,) = models["0000210"].boxes
    assert body.size == pytest.approx((0.010, 0.034, 0.065))


def test_sample_atc_stations_are_models_with_tool_keypoints() -> None:
    atc = load_jigs(JIGS)["0000302"]
    assert atc.kind == "ATC_station"
    assert list(atc.keypoints) == ["tool_base", "tool_end", "gripper_nail"]
    # tool_base: pos (25, -48, 115) mm, rot R = -1.57, P = 0, Y = -1.57.
    np.testing.assert_allclose(
        atc.keypoints["tool_base"].T_element_keypoint,
        transform(rot_x(-1.57) @ rot_z(-1.57), [0.025, -0.048, 0.115]),
    )
    assert atc.dimensions["finger_height"] == pytest.approx(0.125)
    assert atc.dimensions["tool_z"] == pytest.approx(0.265)


def board(tmp_path: Path) -> Platform:
    for name in ("platform_cad.x3d", "platform_ids.wri", "Jigs_definition_v2.xml"):
        shutil.copy(REMODEL / name, tmp_path / name)
    return load_remodel_platform(
        "board",
        np.eye(4),
        tmp_path / "platform_cad.x3d",
        tmp_path / "platform_ids.wri",
        tmp_path / "Jigs_definition_v2.xml",
        tmp_path,
        "y",
    )


def test_sample_board_slot_centres_in_the_platform_frame(tmp_path: Path) -> None:
    p = board(tmp_path)
    assert list(p.elements) == ["T1", "J1", "J2", "J3", "J4", "J8"]
    # J3 = ID0004 (model 0011): translation (318.000001, 145.330002, 5) mm inside the root,
    # slot (5, 11, 107.25) mm in its frame, both through (x, y, z) -> (-x, -y, z) / 1000:
    # (-(318.000001 + 5), -(145.330002 + 11), 5 + 107.25) / 1000 m.
    j3 = keypoint(p, "J3", "1")
    np.testing.assert_allclose(j3[:3, 3], [-0.323000001, -0.156330002, 0.11225], atol=1e-6)
    np.testing.assert_allclose(j3[:3, :3], FLIP, atol=1e-6)
    np.testing.assert_allclose(
        p.elements["J3"].T_platform_element[:3, 3], [-0.318000001, -0.145330002, 0.005], atol=1e-6
    )
    # J8 = ID0009 (model 0014): (213.250001, 145.300003, 5) + (20.75, 6.75, 108.5) mm.
    j8 = keypoint(p, "J8", "1")
    np.testing.assert_allclose(j8[:3, 3], [-0.234000001, -0.152050003, 0.1135], atol=1e-6)
    # J1 = ID0002: (482.0001, 145.330002, 5) + (5, 11, 107.25) mm.
    j1 = keypoint(p, "J1", "1")
    np.testing.assert_allclose(j1[:3, 3], [-0.4870001, -0.156330002, 0.11225], atol=1e-6)
    assert dict(p.elements["J3"].keypoints["1"].dimensions)["gap"] == pytest.approx(0.010)


def test_sample_damaged_meshes_are_dropped_for_modelled_elements(tmp_path: Path) -> None:
    """Three Coordinate lists of the sample hold glued numbers ('16.0735072.688004') and
    indices past their points: those jigs keep their poses, keypoints and Jigs boxes, lose
    the mesh, and say why; the tray T1, with no model, keeps its (sound) plate mesh."""
    p = board(tmp_path)
    j1 = p.elements["J1"]
    assert j1.mesh is None and len(j1.boxes) == 2
    assert j1.note == (
        f"its CAD mesh was dropped ({tmp_path}/platform_cad.x3d:45:9: Coordinate 'coords_ME_J1': "
        "point must be x y z triples of numbers, got '16.0735072.688004' (item 211 of 348))"
    )
    assert p.elements["T1"].mesh is not None
    # the plate spans 600 x 250 x 5 mm in its (scaled) frame
    assert p.elements["T1"].mesh.bounds[1] == pytest.approx([0.6, 0.25, 0.005], abs=1e-6)


def test_sample_tray_without_a_model_loads_with_a_note(tmp_path: Path) -> None:
    t1 = board(tmp_path).elements["T1"]
    assert t1.model == "0001"
    assert dict(t1.keypoints) == {}
    assert t1.note == "model '0001' is not defined in Jigs_definition_v2.xml"
    # ID0001 is the root Transform itself: its frame is the root's rotation after the turn.
    np.testing.assert_allclose(t1.T_platform_element, transform(FLIP), atol=1e-6)


def test_sample_combs_load_unchanged() -> None:
    p = load_remodel_platform(
        "combs",
        np.eye(4),
        REMODEL / "combs_cad.x3d",
        REMODEL / "combs_ids.wri",
        JIGS,
        REMODEL,
        "y",
    )
    assert list(p.elements) == ["T2", "C1", "C2"]
    assert p.elements["T2"].note == "model '0000201' is not defined in Jigs_definition_v2.xml"
    # C1 = ID000002: (458, 23, 3) + slot (5, 17, 80) mm -> (-463, -40, 83) / 1000.
    np.testing.assert_allclose(keypoint(p, "C1", "1")[:3, 3], [-0.463, -0.040, 0.083], atol=1e-6)
    # C2 = ID000003: (8.77, 23, 3) + (5, 17, 80) mm -> (-13.77, -40, 83) / 1000.
    np.testing.assert_allclose(keypoint(p, "C2", "1")[:3, 3], [-0.01377, -0.040, 0.083], atol=1e-6)
    c1 = p.elements["C1"]
    assert c1.mesh is not None and len(c1.boxes) == 1  # its body; the guide box is all zeros
    # The comb's mesh spans 10 x 34 x 95.004974 mm in its own frame.
    np.testing.assert_allclose(c1.mesh.extents, [0.010, 0.034, 0.095004974], atol=1e-9)
    assert c1.source is not None and c1.source.line == 2


# --- a small fixture: a key turned about all three axes ----------------------------------------


def fixture_platform(folder: Path = DATA) -> Platform:
    return load_remodel_platform(
        "board",
        np.eye(4),
        folder / "platform_cad.x3d",
        folder / "platform_ids.wri",
        folder / "Jigs_definition_v2.xml",
        folder,
        "z",
    )


def test_key_rotation_is_rotx_roty_rotz_about_moving_axes() -> None:
    p = fixture_platform()
    q = np.pi / 2
    key = p.elements["JA"].keypoints["1"].T_element_keypoint
    # Slot offset (10/2, 4/2, 20/2) = (5, 2, 10) mm, turned by RotX(90°)·RotY(90°)·RotZ(90°),
    # the rightmost first: RotZ (x, y, z) -> (-y, x, z) gives (-2, 5, 10); RotY
    # (x, y, z) -> (z, y, -x) gives (10, 5, 2); RotX (x, y, z) -> (x, -z, y) gives
    # (10, -2, 5); plus pos (10, 20, 30) -> (20, 18, 35) mm. (URDF's Rz·Ry·Rx would give
    # (20, 30, 35).)
    np.testing.assert_allclose(key[:3, 3], np.array([20, 18, 35]) * MM, atol=1e-9)
    # Columns are the images of the axes: x -> (0, 0, 1), y -> (0, -1, 0), z -> (1, 0, 0).
    R = np.array([[0, 0, 1], [0, -1, 0], [1, 0, 0]], dtype=float)
    np.testing.assert_allclose(key[:3, :3], R, atol=1e-9)
    np.testing.assert_allclose(key[:3, :3], rot_x(q) @ rot_y(q) @ rot_z(q), atol=1e-9)
    # JA = ID1 at (0.1, 0.2, 0) turned 90° about z: (20, 18, 35) mm -> (-18, 20, 35) mm.
    np.testing.assert_allclose(
        keypoint(p, "JA", "1")[:3, 3], [0.1 - 0.018, 0.2 + 0.020, 0.035], atol=1e-9
    )
    assert dict(p.elements["JA"].keypoints["1"].dimensions) == pytest.approx(
        {"length": 0.010, "gap": 0.004, "height": 0.020, "height_corner": 0.025}
    )


def test_fixture_boxes_keypoint_order_and_models_without_guides() -> None:
    p = fixture_platform()
    ja = p.elements["JA"]
    assert list(ja.keypoints) == ["1", "2"]
    # Guide 2's key sits at the origin: slot centre (1, 1, 1) mm.
    np.testing.assert_allclose(ja.keypoints["2"].T_element_keypoint[:3, 3], [0.001] * 3)
    (box,) = ja.boxes  # guide 2's all-zero box is skipped
    assert box.size == pytest.approx((0.002, 0.004, 0.006))
    np.testing.assert_allclose(
        box.T_element_box, transform(rot_z(np.pi / 2), [0.001, 0.002, 0.003]), atol=1e-9
    )
    bx = p.elements["BX"]
    assert (bx.model, dict(bx.keypoints), bx.note) == ("B1", {}, "")
    assert bx.dimensions["xdim"] == pytest.approx(0.1)
    assert p.elements["TR"].note == "model '0001' is not defined in Jigs_definition_v2.xml"


# --- errors ----------------------------------------------------------------------------------


def error(fn: object, *args: object) -> tuple[str, str | None, int | None, int | None]:
    with pytest.raises(InputError) as e:
        fn(*args)  # type: ignore[operator]
    p = e.value.problems[0]
    return p.message, p.file, p.line, p.col


def test_ids_rows(tmp_path: Path) -> None:
    p = tmp_path / "a_ids.wri"
    p.write_bytes(b"ID1\tJ1\t0011\n\nID2\tJ2\t0011\n")
    assert load_ids(p) == (IdsRow("ID1", "J1", "0011", 1), IdsRow("ID2", "J2", "0011", 3))


@pytest.mark.parametrize(
    ("text", "message", "line"),
    [
        (
            "ID1\tJ1\t0011\nID2 J2 0011\n",
            "expected 3 tab-separated fields (DEF, label, model), found 1: "
            "separate the fields with tabs",
            2,
        ),
        ("ID1\tJ1\t0011\tx\n", "expected 3 tab-separated fields (DEF, label, model), found 4", 1),
        ("ID1\t\t0011\n", "empty label", 1),
        (
            "ID1\tJ1\t0011\nID2\tJ2\t0011\nID3\tJ1\t0012\n",
            "duplicate label 'J1' (first at line 1)",
            3,
        ),
        ("ID1\tJ1\t0011\nID1\tJ2\t0011\n", "duplicate DEF 'ID1' (first at line 1)", 2),
        (
            "ID1\tJ.1\t0011\n",
            "label 'J.1' may not contain dots or spaces (plans write platform.element.keypoint)",
            1,
        ),
    ],
)
def test_ids_errors(tmp_path: Path, text: str, message: str, line: int) -> None:
    p = tmp_path / "a_ids.wri"
    p.write_text(text)
    assert error(load_ids, p) == (message, str(p), line, None)


def test_unknown_def_at_the_ids_row(tmp_path: Path) -> None:
    folder = tmp_path / "board"
    shutil.copytree(DATA, folder)
    (folder / "platform_ids.wri").write_text("ID1\tJA\tJ90\nID9\tJB\tJ90\n")
    assert error(fixture_platform, folder) == (
        "unknown CAD name 'ID9' (no DEF of that name in platform_cad.x3d); known: ID1, ID2, ID3",
        str(folder / "platform_ids.wri"),
        2,
        None,
    )


POSE = (
    '<pos name="x">0</pos><pos name="y">0</pos><pos name="z">0</pos>'
    '<rot name="R">0</rot><rot name="P">0</rot><rot name="Y">0</rot>'
)


def jigs(tmp_path: Path, body: str) -> Path:
    p = tmp_path / "Jigs_definition_v2.xml"
    p.write_text(f'<?xml version="1.0"?>\n<data>\n{body}\n</data>\n')
    return p


@pytest.mark.parametrize(
    ("body", "message", "line", "col"),
    [
        (  # a malformed number as text
            '<jig model="a">\n<guide couple="1">\n<key length="1" gap="1" height="1">\n'
            '<pos name="x">0</pos><pos name="y">6,5</pos><pos name="z">0</pos>\n'
            '<rot name="R">0</rot><rot name="P">0</rot><rot name="Y">0</rot>\n'
            "</key></guide></jig>",
            "<pos name=\"y\"> is '6,5'; expected a number in mm",
            6,
            22,
        ),
        (  # a malformed number as an attribute
            f'<jig model="a">\n<guide couple="1">\n<key length="10" gap="ten" height="1">'
            f"{POSE}</key></guide></jig>",
            "<key> attribute 'gap' is 'ten'; expected a number in mm",
            5,
            18,
        ),
        (
            f'<jig model="a" xdim="1e">\n<guide couple="1"><key length="1" gap="1" height="1">'
            f"{POSE}</key></guide></jig>",
            "<jig> attribute 'xdim' is '1e'; expected a number in mm",
            3,
            16,
        ),
        (
            f'<jig model="a" zdim="1e999">\n<guide couple="1"><key length="1" gap="1" height="1">'
            f"{POSE}</key></guide></jig>",
            "<jig> attribute 'zdim' is '1e999'; expected a number in mm",
            3,
            16,
        ),
        (  # an angle
            '<jig model="a">\n<guide couple="1">\n<key length="1" gap="1" height="1">\n'
            '<pos name="x">0</pos><pos name="y">0</pos><pos name="z">0</pos>\n'
            '<rot name="R">0</rot><rot name="P">nan</rot><rot name="Y">0</rot>\n'
            "</key></guide></jig>",
            "<rot name=\"P\"> is 'nan'; expected a number in radians",
            7,
            22,
        ),
        (
            '<clamp model="x"/>',
            "unexpected <clamp> in <data>; expected jig, comb, box or ATC_station",
            3,
            1,
        ),
        (
            '<jig model="a"><slot/></jig>',
            "unexpected <slot> in <jig>; expected guide",
            3,
            16,
        ),
        (
            f'<jig model="a"><guide couple="1"><key length="1" gap="1" height="1">{POSE}'
            '<pos name="w">1</pos></key></guide></jig>',
            "<pos> name is 'w'; expected one of x, y, z",
            3,
            None,
        ),
        (
            '<jig model="a"><guide couple="1"><key length="1" gap="1" height="1">'
            '<pos name="x">0</pos><pos name="y">0</pos><pos name="z">0</pos>'
            '<rot name="R">0</rot><rot name="P">0</rot></key></guide></jig>',
            '<key> has no <rot name="Y">',
            3,
            34,
        ),
        (
            f'<jig model="a"><guide couple="1"><key gap="1" height="1">{POSE}</key></guide></jig>',
            "<key> has no 'length' attribute (a length in mm)",
            3,
            34,
        ),
        (
            '<jig model="a"><guide couple="1"><collision xdim="1" ydim="1" zdim="1">'
            f"{POSE}</collision></guide></jig>",
            "<guide> has no <key>",
            3,
            16,
        ),
        (
            f'<jig model="a"><guide couple="0"><key length="1" gap="1" height="1">{POSE}'
            "</key></guide></jig>",
            "<guide> attribute 'couple' is '0'; expected its index 1, 2, ...",
            3,
            23,
        ),
        (
            f'<jig model="a"><guide couple="{"9" * 5000}"><key length="1" gap="1" height="1">'
            f"{POSE}</key></guide></jig>",
            f"<guide> attribute 'couple' is '{'9' * 40}...'; expected its index 1, 2, ...",
            3,
            23,
        ),
        (
            f'<jig model="a">\n<guide couple="1"><key length="1" gap="1" height="1">{POSE}'
            f'</key></guide>\n<guide couple="1"><key length="1" gap="1" height="1">{POSE}'
            "</key></guide></jig>",
            "duplicate guide couple '1' in model 'a' (first at line 4)",
            5,
            8,
        ),
        (
            '<jig model="0011"/>\n<comb model="0011"/>',
            "duplicate model '0011' (first defined at line 3)",
            4,
            7,
        ),
        ("<jig/>", "<jig> has no 'model' attribute", 3, 1),
        (
            f'<jig model="a"><guide couple="1" side="L"><key length="1" gap="1" height="1">'
            f"{POSE}</key></guide></jig>",
            "unexpected attribute 'side' on <guide>; expected couple",
            3,
            34,
        ),
        (
            f'<jig model="a"><guide couple="1"><key length="1" gap="1" height="1">{POSE}</key>'
            f'<collision xdim="-1" ydim="1" zdim="1">{POSE}</collision></guide></jig>',
            "<collision> attribute 'xdim' is negative",
            3,
            None,
        ),
    ],
)
def test_jigs_errors(tmp_path: Path, body: str, message: str, line: int, col: int | None) -> None:
    p = jigs(tmp_path, body)
    got = error(load_jigs, p)
    assert got[:3] == (message, str(p), line)
    if col is not None:
        assert got[3] == col


def test_jigs_root_must_be_data(tmp_path: Path) -> None:
    p = tmp_path / "j.xml"
    p.write_text("<jigs/>")
    assert error(load_jigs, p) == ("root element is <jigs>; expected <data>", str(p), 1, 1)
