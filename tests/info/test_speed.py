"""speed and tcp_speed in cell.yaml and plan.yaml: one number or two fractions, a TCP speed
in the file's length unit per second."""

from __future__ import annotations

from pathlib import Path

from cellengine.info.load import load_cell
from cellengine.info.plan import parse_plan
from cellengine.info.speed import SpeedScaling, scaling
from cellengine.info.yamlio import parse_yaml
from tests.info.test_plan import PLAN

CELL = """\
name: c
units: {length: mm, angle: deg}
robots:
  left: {model: ur5e}
"""


def test_a_cell_s_speed_is_one_number_or_two_fractions(tmp_path: Path) -> None:
    path = tmp_path / "cell.yaml"
    path.write_text(CELL + "speed: 0.5\ntcp_speed: 250\n")
    cell, _ = load_cell(path)
    assert scaling(cell.speed) == SpeedScaling(velocity=0.5, acceleration=0.5)
    assert cell.tcp_speed == 0.25  # mm/s in a millimetre file, m/s once loaded
    path.write_text(CELL + "speed: {acceleration: 0.3}\n")
    cell, _ = load_cell(path)
    assert (scaling(cell.speed), cell.tcp_speed) == (SpeedScaling(acceleration=0.3), None)


def test_a_plan_s_speed_tcp_cap_and_return_home() -> None:
    plain = parse_plan(parse_yaml(PLAN, Path("plan.yaml")))
    assert (plain.speed, plain.tcp_speed, plain.return_home) == (None, None, False)
    text = PLAN.replace(
        "steps:", "units: {length: mm}\nspeed: 0.25\ntcp_speed: 100\nreturn_home: true\nsteps:"
    )
    plan = parse_plan(parse_yaml(text, Path("plan.yaml")))
    assert plan.speed == SpeedScaling(velocity=0.25, acceleration=0.25)
    assert (plan.tcp_speed, plan.return_home) == (0.1, True)
