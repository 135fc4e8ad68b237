"""The lab extensions of the file formats: zones in cell.yaml, where containers stand in
objects.yaml, tool grasp and load cell, the simulated load cell's noise."""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import pytest

from cellengine.drivers.registry import make_driver
from cellengine.errors import InputError
from cellengine.info.load import load_cell, load_plan, load_world
from tests.conftest import CELLS

ZONES = """\
zones:
  bench_left:  {min: [0, 0, 0], max: [600, 350, 400], robots: [left]}
  shared:      {min: [0, -100, 0], max: [600, 100, 400], robots: [left, right]}
"""


def _cell(tmp_path: Path, extra: str) -> Path:
    folder = tmp_path / "cell"
    shutil.copytree(CELLS / "cable_routing", folder)
    path = folder / "cell.yaml"
    path.write_text(path.read_text() + extra)
    return path


def test_zones_load_in_metres_and_contain_points(tmp_path: Path) -> None:
    cell, _ = load_cell(_cell(tmp_path, ZONES))
    shared = cell.zones["shared"]
    assert shared.min == pytest.approx((0.0, -0.1, 0.0))
    assert shared.robots == ("left", "right")
    assert shared.contains((0.3, 0.0, 0.1))
    assert not shared.contains((0.3, 0.2, 0.1))
    assert cell.zones["bench_left"].contains((0.6, 0.35, 0.4))  # faces included


def test_zone_errors_name_the_line(tmp_path: Path) -> None:
    bad = """\
zones:
  a: {min: [0, 0, 0], max: [600, 350, 400], robots: [left, middle]}
  b: {min: [0, 0, 500], max: [600, 350, 400], robots: [left]}
"""
    path = _cell(tmp_path, bad)
    lines = path.read_text().splitlines()
    line_a = lines.index(bad.splitlines()[1]) + 1
    with pytest.raises(InputError) as e:
        load_cell(path)
    got = [str(p).split("cell.yaml", 1)[1] for p in e.value.problems]
    assert got == [f":{line_a + 1}:6: zones.b: each of min's x, y, z must be below max's"]
    path.write_text(path.read_text().replace("min: [0, 0, 500]", "min: [0, 0, 0]"))
    with pytest.raises(InputError) as e:
        load_cell(path)
    got = [str(p).split("cell.yaml", 1)[1] for p in e.value.problems]
    col = lines[line_a - 1].index("middle") + 1
    assert got == [
        f":{line_a}:{col}: zones.a.robots[1]: unknown robot 'middle'; known: left, right"
    ]


def _objects(folder: Path, at: str) -> Path:
    path = folder / "objects.yaml"
    path.write_text(
        path.read_text()
        + "containers:\n"
        + f"  vial1: {{kind: vial, diameter: 28, height: 60, mass: 30, at: {at}}}\n"
    )
    return path


def test_a_container_stands_at_a_keypoint(tmp_path: Path) -> None:
    cell = _cell(tmp_path, "")
    world = load_world(cell, _objects(cell.parent, "holder.comb_a.slot"))
    assert world.container("vial1").at == "holder.comb_a.slot"
    assert world.container("vial1").mass == pytest.approx(0.03)


def test_a_container_at_an_unknown_keypoint_is_refused_at_its_line(tmp_path: Path) -> None:
    cell = _cell(tmp_path, "")
    objects = _objects(cell.parent, "holder.comb_z")
    last = objects.read_text().splitlines()[-1]
    line, col = len(objects.read_text().splitlines()), last.index("holder.comb_z") + 1
    with pytest.raises(InputError) as e:
        load_world(cell, objects)
    (problem,) = e.value.problems
    assert str(problem).split("objects.yaml", 1)[1] == (
        f":{line}:{col}: containers.vial1.at: unknown element 'holder.comb_z'; known: "
        "comb_a, comb_b"
    )


def test_tool_grasp_and_load_cell_default_to_a_plain_top_gripper(tmp_path: Path) -> None:
    cell, _ = load_cell(_cell(tmp_path, ""))
    tool = cell.tools["cable_gripper"]
    assert (tool.grasp, tool.load_cell) == ("top", False)


def test_the_simulated_load_cell_takes_the_cells_noise(tmp_path: Path) -> None:
    path = _cell(tmp_path, "")
    # cell.yaml gives no mass unit: kg
    path.write_text(path.read_text().replace("{kind: sim}", "{kind: sim, mass_noise: 0.0005}"))
    cell, _ = load_cell(path)
    assert cell.driver.kind == "sim" and cell.driver.mass_noise == pytest.approx(0.0005)
    joints = {"left": [f"l{i}" for i in range(6)], "right": [f"r{i}" for i in range(6)]}
    driver = make_driver(cell, joints)
    assert driver.mass_noise == pytest.approx(0.0005)  # type: ignore[attr-defined]


def test_a_plan_checks_where_its_objects_stand(tmp_path: Path) -> None:
    cell = _cell(tmp_path, "")
    objects = _objects(cell.parent, "holder.comb_z")
    plan = cell.parent / "plan_straight.yaml"
    with pytest.raises(InputError) as e:
        load_plan(plan)
    (problem,) = e.value.problems
    assert problem.file == str(objects)
    assert "containers.vial1.at: unknown element 'holder.comb_z'" in problem.message


def test_zone_places_must_be_keypoints(tmp_path: Path) -> None:
    extra = """\
zones:
  shared:
    min: [0, -100, 0]
    max: [600, 100, 400]
    robots: [left, right]
    handovers: [holder.comb_a.slot]
    cooperation: [holder.comb_q]
"""
    path = _cell(tmp_path, extra)
    line = path.read_text().splitlines().index("    cooperation: [holder.comb_q]") + 1
    with pytest.raises(InputError) as e:
        load_world(path)
    (problem,) = e.value.problems
    assert str(problem).split("cell.yaml", 1)[1] == (
        f":{line}:19: zones.shared.cooperation[0]: unknown element 'holder.comb_q'; known: "
        "comb_a, comb_b"
    )
    path.write_text(path.read_text().replace("holder.comb_q", "holder.comb_b"))
    zone = load_world(path).cell.zones["shared"]
    assert (zone.handovers, zone.cooperation) == (("holder.comb_a.slot",), ("holder.comb_b",))


def test_the_ur_driver_options_load_and_are_checked(tmp_path: Path) -> None:
    path = _cell(tmp_path, "")
    ur = (
        "{kind: ur_rtde, arms: {left: 127.0.0.2, right: 127.0.0.3}, "
        "servo: {gain: 500, lookahead: 0.05}, tracking_tolerance: 2, "
        "gripper_io: {open: [], slide: [0], grasp: [0, 1]}}"
    )
    path.write_text(path.read_text().replace("{kind: sim}", ur))
    cell, _ = load_cell(path)
    assert cell.driver.kind == "ur_rtde"
    assert (cell.driver.servo.gain, cell.driver.servo.lookahead) == (500.0, 0.05)
    assert cell.driver.tracking_tolerance == pytest.approx(math.radians(2))
    assert cell.driver.gripper_io == {"open": (), "slide": (0,), "grasp": (0, 1)}
    line = next(i for i, s in enumerate(path.read_text().splitlines(), 1) if "ur_rtde" in s)
    path.write_text(path.read_text().replace("grasp: [0, 1]", "squeeze: [0, 1]"))
    with pytest.raises(InputError) as e:
        load_cell(path)
    (problem,) = e.value.problems
    assert problem.line == line
    assert problem.message == (
        "driver.gripper_io.squeeze: no tool has a jaw mode 'squeeze'; known: grasp, open, slide"
    )
    path.write_text(path.read_text().replace("gain: 500", "gain: 5000"))
    with pytest.raises(InputError) as e:
        load_cell(path)
    messages = [p.message for p in e.value.problems]
    assert "driver.servo.gain: must be less than or equal to 2000, got 5000" in messages
