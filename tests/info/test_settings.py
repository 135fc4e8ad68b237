"""Values set over a cell's files for a block's loads, and cell.yaml's element poses."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from cellengine.errors import InputError
from cellengine.info.load import load_plan, load_world
from cellengine.info.settings import overlaid, parse_key, settings
from cellengine.info.yamlio import parse_yaml
from tests.conftest import CELLS

PLATFORMS = load_world(CELLS / "cable_routing" / "cell.yaml").platforms


def test_keys_name_a_file_and_a_path() -> None:
    assert parse_key("routing.guide3.xyz", PLATFORMS) == (
        "cell",
        ("platforms", "routing", "elements", "guide3", "xyz"),
    )
    assert parse_key("objects:cables.cable1.length") == ("objects", ("cables", "cable1", "length"))
    assert parse_key("plan:steps.2.guides") == ("plan", ("steps", 2, "guides"))


@pytest.mark.parametrize(
    ("key", "message"),
    [
        ("table.guide3.xyz",
         "'table.guide3.xyz': no platform 'table' in the cell (it has holder, routing)"),
        ("routing.guideX.xyz",
         "'routing.guideX.xyz': no element 'guideX' on 'routing' (it has connector, guide1, "
         "guide2, guide3, guide4, guide5, guide6, guide7, plate)"),
        ("robot:base", "'robot:base': the file is one of cell, objects, plan, not 'robot'"),
        ("cell:", "'cell:': write cell:key.path"),
        ("routing.guide3",
         "'routing.guide3': write PLATFORM.ELEMENT.move (or .xyz, .rpy), or cell:KEY, "
         "objects:KEY, plan:KEY"),
    ],
)  # fmt: skip
def test_a_bad_key_says_how_to_write_one(key: str, message: str) -> None:
    with pytest.raises(ValueError) as e:
        parse_key(key, PLATFORMS)
    assert str(e.value) == message


def test_settings_replace_add_and_index() -> None:
    doc = parse_yaml("a: {b: 1}\nsteps: [{x: 1}, {x: 2}]\n", Path("plan.yaml"))
    sets = [("plan", ("a", "b"), 5), ("plan", ("c", "d"), [1, 2]), ("plan", ("steps", 1, "x"), 9)]
    with settings(sets):
        got = overlaid(doc, "plan")
        assert overlaid(doc, "cell") is doc  # another kind's file: as it is
    assert got.data == {"a": {"b": 5}, "c": {"d": [1, 2]}, "steps": [{"x": 1}, {"x": 9}]}
    assert doc.data == {"a": {"b": 1}, "steps": [{"x": 1}, {"x": 2}]}  # the file's own
    assert overlaid(doc, "plan") is doc  # outside the block


def test_a_setting_through_a_value_is_refused_where_it_is() -> None:
    doc = parse_yaml("a: 1\n", Path("plan.yaml"))
    with settings([("plan", ("a", "b", "c"), 5)]), pytest.raises(InputError) as e:
        overlaid(doc, "plan")
    assert str(e.value.problems[0]) == (
        "plan.yaml:1:4: setting 'a.b.c': 'a' is '1' in the file, which has no 'b'"
    )


@pytest.fixture
def cell(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    shutil.copytree(CELLS / "cable_routing", tmp_path / "cell")
    monkeypatch.chdir(tmp_path / "cell")
    return tmp_path / "cell"


def _guide3(world_plan: str = "plan_straight.yaml") -> np.ndarray:
    return (
        load_plan(Path(world_plan)).world.platforms["routing"].elements["guide3"].T_platform_element
    )


def test_an_element_pose_in_cell_yaml_moves_it_and_keeps_what_it_does_not_give(cell: Path) -> None:
    cad = _guide3()
    text = (cell / "cell.yaml").read_text()
    moved = text.replace(
        "models: routing/models.xml, map: routing/map.csv}",
        "models: routing/models.xml, map: routing/map.csv,\n"
        "             elements: {guide3: {xyz: [-150, -380, 10]}}}",
    )
    assert moved != text
    (cell / "cell.yaml").write_text(moved)
    T = _guide3()
    np.testing.assert_allclose(T[:3, 3], [-0.150, -0.380, 0.010], atol=1e-9)  # mm in the file
    np.testing.assert_allclose(T[:3, :3], cad[:3, :3], atol=1e-9)  # the CAD's rotation


def test_a_setting_moves_an_element_for_its_block_only(cell: Path) -> None:
    kind, loc = parse_key("routing.guide3.rpy")
    with settings([(kind, loc, [0, 0, 90])]):
        T = _guide3()
    np.testing.assert_allclose(T[:3, :3], [[0, -1, 0], [1, 0, 0], [0, 0, 1]], atol=1e-9)
    assert not np.allclose(_guide3()[:3, :3], T[:3, :3])


def test_an_unknown_element_is_named_with_the_known_ones(cell: Path) -> None:
    kind, loc = parse_key("routing.guideX.xyz")
    with settings([(kind, loc, [0, 0, 0])]), pytest.raises(InputError) as e:
        _guide3()
    assert str(e.value.problems[0]) == (
        "cell.yaml:44:13: unknown element 'routing.guideX'; known: connector, guide1, guide2, "
        "guide3, guide4, guide5, guide6, guide7, plate"
    )


def test_a_move_is_in_the_cell_frame(cell: Path) -> None:
    """routing is turned 180 deg in the cell: +10 mm in the cell's y is -10 in its own."""
    before = _guide3()
    kind, loc = parse_key("routing.guide3.move")
    with settings([(kind, loc, [0, 10, 0])]):
        after = _guide3()
    np.testing.assert_allclose(after[:3, 3] - before[:3, 3], [0, -0.010, 0], atol=1e-9)
    np.testing.assert_allclose(after[:3, :3], before[:3, :3], atol=1e-12)
