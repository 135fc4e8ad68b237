"""The element-model XML: units converted once, keypoint poses, and errors at file:line:col."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from cellengine.errors import InputError
from cellengine.geometry import rot_x, rot_z
from cellengine.info.models_xml import load_models

DATA = Path(__file__).parents[1] / "data" / "platforms" / "native"


def write(tmp_path: Path, text: str) -> Path:
    p = tmp_path / "models.xml"
    p.write_text(text)
    return p


def error(path: Path) -> tuple[str, int | None, int | None]:
    with pytest.raises(InputError) as e:
        load_models(path)
    p = e.value.problems[0]
    assert p.file == str(path)
    return p.message, p.line, p.col


def test_fixture_in_metres_and_radians_in_document_order() -> None:
    models = load_models(DATA / "models.xml")
    assert list(models) == ["guide_u", "comb"]
    g = models["guide_u"]
    assert dict(g.dimensions) == pytest.approx(
        {"length": 0.010, "width": 0.024, "height": 0.060, "gap": 0.010}
    )
    assert list(g.dimensions) == ["length", "width", "height", "gap"]
    assert list(g.keypoints) == ["slot", "entry"]
    slot = g.keypoints["slot"].T_element_keypoint
    np.testing.assert_allclose(slot[:3, 3], [0, 0, 0.055])
    np.testing.assert_allclose(slot[:3, :3], np.eye(3), atol=1e-9)
    # rpy="0 0 90" in degrees: a quarter turn about z.
    entry = g.keypoints["entry"].T_element_keypoint
    np.testing.assert_allclose(entry[:3, 3], [-0.005, 0, 0.055])
    np.testing.assert_allclose(entry[:3, :3], rot_z(np.pi / 2), atol=1e-9)
    assert g.source.line == 4
    assert not entry.flags.writeable


def test_rpy_is_optional_and_defaults_are_metres_and_radians(tmp_path: Path) -> None:
    p = write(
        tmp_path,
        '<elements><element model="m">'
        '<keypoint name="a" xyz="1 2 3"/><keypoint name="b" xyz="0 0 0" rpy="1.5 0 0"/>'
        '<dimension name="d" value="2.5e-1"/></element></elements>',
    )
    m = load_models(p)["m"]
    np.testing.assert_allclose(m.keypoints["a"].T_element_keypoint[:3, 3], [1, 2, 3])
    np.testing.assert_allclose(m.keypoints["b"].T_element_keypoint[:3, :3], rot_x(1.5))
    assert m.dimensions["d"] == 0.25


@pytest.mark.parametrize(
    ("child", "message"),
    [
        ('<dimension name="gap" value="0"/>', "dimension 'gap': 0 is not a size (more than 0, "
         "at most 100 m)"),
        ('<dimension name="gap" value="-10"/>', "dimension 'gap': -10 is not a size (more than "
         "0, at most 100 m)"),
        ('<dimension name="gap" value="1e300"/>', "dimension 'gap': 1e300 is not a size (more "
         "than 0, at most 100 m)"),
        ('<keypoint name="k" xyz="0 0 1e6"/>', "keypoint 'k': xyz '0 0 1e6' is beyond 100 m of "
         "its element"),
    ],
)  # fmt: skip
def test_sizes_are_positive_and_everything_within_100_m(
    tmp_path: Path, child: str, message: str
) -> None:
    p = write(tmp_path, f'<elements><element model="m">{child}</element></elements>')
    with pytest.raises(InputError) as e:
        load_models(p)
    assert e.value.problems[0].message == message


def test_centimetres(tmp_path: Path) -> None:
    p = write(
        tmp_path,
        '<elements units="cm"><element model="m"><keypoint name="a" xyz="1 2 3"/>'
        "</element></elements>",
    )
    xyz = load_models(p)["m"].keypoints["a"].T_element_keypoint[:3, 3]
    np.testing.assert_allclose(xyz, [0.01, 0.02, 0.03])


def test_schema_violation_bad_number(tmp_path: Path) -> None:
    p = write(
        tmp_path,
        '<elements units="mm">\n'
        '  <element model="a">\n'
        '    <dimension name="gap" value="1O"/>\n'
        "  </element>\n"
        "</elements>\n",
    )
    assert error(p) == ("<dimension> attribute 'value': '1O' is not a number", 3, 27)


def test_schema_violation_unknown_units(tmp_path: Path) -> None:
    p = write(tmp_path, '<elements units="inch"><element model="a"/></elements>')
    assert error(p) == (
        "<elements> attribute 'units': 'inch' is not one of m, mm, cm",
        1,
        11,
    )


def test_schema_violation_wrong_count_of_numbers(tmp_path: Path) -> None:
    p = write(
        tmp_path,
        '<elements>\n<element model="a">\n  <keypoint name="k" xyz="1 2"/>\n'
        "</element>\n</elements>",
    )
    # One problem, not a second one repeating it for the whole list.
    with pytest.raises(InputError) as e:
        load_models(p)
    assert [str(x.message) for x in e.value.problems] == [
        "<keypoint> attribute 'xyz': '1 2' has 2 numbers; expected 3 separated by spaces"
    ]
    assert (e.value.problems[0].line, e.value.problems[0].col) == (3, 22)


def test_schema_violation_infinity_and_dotted_name(tmp_path: Path) -> None:
    p = write(
        tmp_path,
        '<elements><element model="a"><dimension name="g" value="INF"/></element></elements>',
    )
    assert error(p)[0] == "<dimension> attribute 'value': 'INF' is not a finite number"
    p = write(
        tmp_path,
        '<elements><element model="a"><keypoint name="k.1" xyz="0 0 0"/></element></elements>',
    )
    assert error(p)[0] == (
        "<keypoint> attribute 'name': 'k.1' is not a name: use no dots or spaces "
        "(plans write platform.element.keypoint)"
    )


def test_overflow_is_refused(tmp_path: Path) -> None:
    p = write(
        tmp_path,
        '<elements>\n<element model="a">\n  <keypoint name="k" xyz="0 1e999 0"/>\n'
        "</element>\n</elements>",
    )
    assert error(p) == ("<keypoint> attribute 'xyz': '0 1e999 0' is out of range", 3, 22)


def test_schema_violation_unknown_tag_and_attribute(tmp_path: Path) -> None:
    p = write(
        tmp_path, '<elements>\n<element model="a">\n  <slot name="k"/>\n</element>\n</elements>'
    )
    assert error(p) == ("<slot>: unexpected element; expected dimension, keypoint", 3, 3)
    p = write(tmp_path, '<elements><element model="a" colour="red"/></elements>')
    assert error(p) == (
        "<element>: attribute 'colour' is not allowed",
        1,
        30,
    )


def test_schema_violation_missing_attribute_and_wrong_root(tmp_path: Path) -> None:
    p = write(
        tmp_path, '<elements>\n  <element model="a"><keypoint name="k"/></element>\n</elements>'
    )
    assert error(p) == ("<keypoint>: attribute 'xyz' is required but missing", 2, 22)
    p = write(tmp_path, "<data/>")
    assert error(p) == (
        "<data>: this is not an element-model file; expected the root element <elements>",
        1,
        1,
    )


def test_duplicate_model_names_the_first(tmp_path: Path) -> None:
    p = write(
        tmp_path,
        '<elements>\n  <element model="a"/>\n  <element model="b"/>\n  <element model="a"/>\n'
        "</elements>",
    )
    assert error(p) == ("duplicate model 'a' (first defined at line 2)", 4, 12)


def test_duplicate_keypoint_and_dimension_within_one_element(tmp_path: Path) -> None:
    p = write(
        tmp_path,
        '<elements>\n<element model="a">\n  <keypoint name="k" xyz="0 0 0"/>\n'
        '  <keypoint name="k" xyz="0 0 1"/>\n</element>\n</elements>',
    )
    assert error(p) == ("duplicate keypoint 'k' (first defined at line 3)", 4, 13)
    p = write(
        tmp_path,
        '<elements>\n<element model="a">\n  <dimension name="h" value="1"/>\n'
        '  <dimension name="h" value="2"/>\n</element>\n</elements>',
    )
    assert error(p) == ("duplicate dimension 'h' (first defined at line 3)", 4, 14)


def test_same_keypoint_name_in_two_models_is_fine(tmp_path: Path) -> None:
    p = write(
        tmp_path,
        '<elements><element model="a"><keypoint name="k" xyz="0 0 0"/></element>'
        '<element model="b"><keypoint name="k" xyz="0 0 0"/></element></elements>',
    )
    assert list(load_models(p)) == ["a", "b"]


def test_entities_are_refused(tmp_path: Path) -> None:
    p = write(
        tmp_path,
        '<!DOCTYPE elements [<!ENTITY x "1">]>\n<elements><element model="&x;"/></elements>',
    )
    with pytest.raises(InputError, match="entit"):
        load_models(p)
