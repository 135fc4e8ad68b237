import math
from pathlib import Path

import numpy as np
import pytest

from cellengine.errors import InputError
from cellengine.info.cell import MAX_ROBOTS
from cellengine.info.load import load_cell

CELL = """\
name: two_arms
units: {length: mm, angle: deg}
robots:
  left:
    model: ur5e
    base: {xyz: [0, 350, 0], rpy: [0, 0, 90]}
    tool: gripper
    home: [0, -90, 90, -90, -90, 0]
  right:
    model: ur5e
    base: {xyz: [0, -350, 0]}
    tool: gripper
tools:
  gripper:
    kind: parallel_gripper
    tcp: {xyz: [0, 0, 200]}
    finger_width: 20
    jaw: {open: 60, slide: 7, grasp: 4}
obstacles:
  table: {box: [1400, 1400, 20], pose: {xyz: [500, 0, -10]}}
driver: {kind: sim}
"""


def load(write, text: str):
    return load_cell(write("cell.yaml", text))[0]


def errors(write, text: str) -> list[str]:
    with pytest.raises(InputError) as e:
        load(write, text)
    return [str(p).split("cell.yaml", 1)[1] for p in e.value.problems]


def test_units_converted_once_at_load(write) -> None:
    cell = load(write, CELL)
    left = cell.robots["left"]
    assert left.base.xyz == pytest.approx((0.0, 0.35, 0.0))
    assert left.base.rpy == pytest.approx((0.0, 0.0, math.pi / 2))
    assert left.home == pytest.approx((0, -math.pi / 2, math.pi / 2, -math.pi / 2, -math.pi / 2, 0))
    tool = cell.tools["gripper"]
    assert tool.tcp.xyz == pytest.approx((0, 0, 0.2))
    assert tool.jaw == pytest.approx({"open": 0.06, "slide": 0.007, "grasp": 0.004})
    assert cell.obstacles["table"].box == pytest.approx((1.4, 1.4, 0.02))
    np.testing.assert_allclose(left.base.matrix()[:3, 3], [0, 0.35, 0])


def test_models_are_immutable(write) -> None:
    cell = load(write, CELL)
    with pytest.raises(Exception, match="frozen"):
        cell.robots["left"].tool = "x"  # type: ignore[misc]


def test_unknown_tool_lists_known(write) -> None:
    text = CELL.replace("tool: gripper", "tool: grip", 1)
    assert errors(write, text) == [":7:11: robots.left.tool: unknown tool 'grip'; known: gripper"]


def test_unknown_model_lists_builtins(write) -> None:
    text = CELL.replace(
        "model: ur5e\n    base: {xyz: [0, -350", "model: ur7\n    base: {xyz: [0, -350"
    )
    assert errors(write, text) == [
        ":10:12: robots.right.model: unknown robot model 'ur7'; known: ur10e, ur3e, ur5, ur5e; "
        "or give {urdf: path, tip: link}"
    ]


def test_home_needs_six_angles(write) -> None:
    text = CELL.replace("home: [0, -90, 90, -90, -90, 0]", "home: [0, -90, 90]")
    assert errors(write, text) == [":8:11: robots.left.home: a ur5e has 6 joints, got 3 angles"]


def test_unknown_key_and_bad_values(write) -> None:
    text = CELL.replace("finger_width: 20", "finger_widht: 20").replace(
        "{kind: sim}", "{kind: simulated}"
    )
    assert errors(write, text) == [
        ":17:5: tools.gripper: unknown key 'finger_widht'; known: dwell, finger_thickness, "
        "finger_width, fingers, grasp, jaw, kind, load_cell, mass, mesh, shape, slot, tcp",
        ":21:16: driver.kind: unknown kind 'simulated'; known: lab, sim, ur_rtde",
    ]


def test_missing_required(write) -> None:
    text = CELL.replace("    model: ur5e\n    base: {xyz: [0, 350", "    base: {xyz: [0, 350")
    assert errors(write, text) == [":5:5: robots.left: missing required key 'model'"]


def test_units_must_be_known(write) -> None:
    text = CELL.replace("length: mm", "length: inch")
    assert errors(write, text) == [":2:17: units.length: must be 'm', 'cm' or 'mm', got 'inch'"]


def test_ur_rtde_driver_needs_every_arm(write) -> None:
    text = CELL.replace("{kind: sim}", "{kind: ur_rtde, arms: {left: 192.168.1.10, top: 10.0.0.1}}")
    assert errors(write, text) == [
        ":21:52: driver.arms.top: unknown robot 'top'; known: left, right",
        ":21:31: driver.arms: no address for robot 'right'",
    ]


def test_bad_ip(write) -> None:
    text = CELL.replace(
        "{kind: sim}", "{kind: ur_rtde, arms: {left: 192.168.1.300, right: 10.0.0.1}}"
    )
    assert errors(write, text) == [
        ":21:38: driver.arms.left: not a valid IPv4 address, got '192.168.1.300'"
    ]


def test_platform_file_outside_cell_folder(write, tmp_path: Path) -> None:
    from cellengine.info.load import load_world

    text = CELL + "platforms:\n  p: {cad: ../../etc/x.x3d, models: m.xml, map: m.csv}\n"
    with pytest.raises(InputError) as e:
        load_world(write("cell.yaml", text))
    assert str(e.value) == (
        f"{tmp_path}/cell.yaml:23:12: "
        "file reference '../../etc/x.x3d' points outside the cell folder"
    )


def test_platform_format_needs_its_files(write) -> None:
    text = CELL + "platforms:\n  p: {format: remodel, cad: a.x3d, models: m.xml, map: m.csv}\n"
    assert errors(write, text) == [":23:6: platforms.p: format 'remodel' needs 'ids'"]


def test_clearance_in_the_files_length_unit(write) -> None:
    assert load(write, CELL).clearance == pytest.approx(0.010)  # the default: 10 mm
    assert load(write, CELL + "clearance: 4\n").clearance == pytest.approx(0.004)
    metres = CELL.replace("units: {length: mm, angle: deg}", "units: {angle: deg}")
    metres = metres.replace("[1400, 1400, 20]", "[1.4, 1.4, 0.02]").replace(
        "500, 0, -10", "0.5, 0, -0.01"
    )
    metres = metres.replace("350", "0.35").replace("[0, 0, 200]", "[0, 0, 0.2]")
    metres = metres.replace("20\n", "0.02\n").replace("{open: 60, slide: 7, grasp: 4}", "{}")
    assert load(write, metres + "clearance: 0.02\n").clearance == pytest.approx(0.02)
    assert load(write, CELL + "clearance: 0\n").clearance == 0.0


def test_work_clearance_in_the_files_length_unit(write) -> None:
    """The cable skills' hands keep 5 mm from the fixtures they work beside unless the cell
    says otherwise; it must be more than 0 (a finger touching a guide wall it slides along
    is not planned)."""
    assert load(write, CELL).work_clearance == pytest.approx(0.005)
    assert load(write, CELL + "work_clearance: 3\n").work_clearance == pytest.approx(0.003)
    assert errors(write, CELL + "work_clearance: 0\n") == [
        ":22:17: work_clearance: must be greater than 0, got 0"
    ]


def test_negative_clearance_refused(write) -> None:
    assert errors(write, CELL + "clearance: -1\n") == [
        ":22:12: clearance: must be greater than or equal to 0, got -1"
    ]


def test_robot_count_is_bounded_before_any_robot_is_built(write) -> None:
    def ring(n: int) -> str:
        arms = "".join(f"  r{i}: {{model: ur5e, base: {{xyz: [{i}, 0, 0]}}}}\n" for i in range(n))
        return f"name: ring\nrobots:\n{arms}"

    assert len(load(write, ring(MAX_ROBOTS)).robots) == MAX_ROBOTS
    assert errors(write, ring(40)) == [
        ":3:3: robots: 40 robots, more than the 8 this engine plans for: its tasks take one or "
        "two arms, and checking every arm against every other grows with the cube of the count"
    ]


def test_huge_numbers_reach_the_range_checks(write) -> None:
    """YAML 1.2 reads 1e30 as a number (YAML 1.1 read a string): it gets the bound."""
    text = CELL.replace("finger_width: 20", "finger_width: 1e30")
    assert errors(write, text) == [
        ":17:19: tools.gripper.finger_width: must be between -100000 and 100000 mm (100 m), "
        "got 1e+30"
    ]
    text = CELL.replace("xyz: [0, -350, 0]", "xyz: [0, -1e300, 0]")
    assert errors(write, text) == [
        ":11:21: robots.right.base.xyz[1]: must be between -100000 and 100000 mm (100 m), "
        "got -1e+300"
    ]


def test_lengths_bounded_in_the_files_unit(write) -> None:
    at_limit = CELL.replace("xyz: [0, -350, 0]", "xyz: [0, -100000, 0]")
    assert load(write, at_limit).robots["right"].base.xyz == pytest.approx((0, -100, 0))
    metres = CELL.replace("length: mm", "length: m").replace("[0, -350, 0]", "[0, -101, 0]")
    mm = "(lengths are metres unless the file says `units: {length: mm}`)"
    assert f":11:21: robots.right.base.xyz[1]: must be between -100 and 100 m {mm}, got -101" in (
        errors(write, metres)
    )


def test_masses_bounded(write) -> None:
    text = CELL.replace("finger_width: 20", "finger_width: 20\n    mass: 1e308")
    assert errors(write, text) == [
        ":18:11: tools.gripper.mass: must be at most 1000 kg, got 1e+308"
    ]
    grams = text.replace("{length: mm, angle: deg}", "{length: mm, angle: deg, mass: g}")
    assert errors(write, grams.replace("1e308", "1000001")) == [
        ":18:11: tools.gripper.mass: must be at most 1e+06 g (1000 kg), got 1000001"
    ]
