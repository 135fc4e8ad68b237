"""objects.yaml harnesses: groups in pin order, bundle diameters, a harness as one bundle."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from cellengine.info.load import load_objects
from cellengine.pipeline import compile_plan
from cellengine.world import RefError
from tests.helpers import routing_world

CELL = Path(__file__).resolve().parents[2] / "cells" / "cable_routing"
HARNESS = """
harnesses:
  WH1:
    connector: {type: VGA, length: 35, width: 31, height: 16}
    color: grey
    cables:
      CA3: {length: 660, diameter: 2.5, color: black, pin: [3, 1], mass: 20}
      CA1: {length: 650, diameter: 2.5, color: red, pin: [1, 1], mass: 20}
      CA2: {length: 640, diameter: 2.5, color: blue, pin: [2, 1], mass: 20}
    branches:
      GR11: {cables: [CA3, CA1]}
      GR12: {cables: [CA2]}
"""


def _objects(tmp_path: Path, text: str = HARNESS) -> Path:
    path = tmp_path / "objects.yaml"
    path.write_text("units: {length: mm, mass: g}" + text)
    return path


def test_groups_are_in_pin_order_and_bundles_pack(tmp_path: Path) -> None:
    harness = load_objects(_objects(tmp_path)).harnesses["WH1"]
    assert harness.in_order(harness.branches["GR11"].cables) == ("CA1", "CA3")
    assert harness.bundle_diameter(["CA2"]) == pytest.approx(0.0025, abs=1e-9)
    # two equal cables side by side: twice as wide; three: the packing's 2.1547
    assert harness.bundle_diameter(["CA1", "CA3"]) == pytest.approx(0.005, abs=1e-9)
    assert harness.bundle_diameter(["CA1", "CA2", "CA3"]) == pytest.approx(
        2.1547 * 0.0025, abs=1e-9
    )


def test_a_thick_cable_is_never_thinner_bundled(tmp_path: Path) -> None:
    text = HARNESS.replace("diameter: 2.5, color: black", "diameter: 9, color: black")
    harness = load_objects(_objects(tmp_path, text)).harnesses["WH1"]
    assert harness.bundle_diameter(["CA1", "CA3"]) >= 0.009 - 1e-9


def test_a_harness_is_a_cable_bundle_for_the_cable_skills(tmp_path: Path) -> None:
    objects = load_objects(_objects(tmp_path))
    bundle = objects.cable("WH1")
    assert bundle is not None and bundle.connector is not None
    assert bundle.length == pytest.approx(0.640, abs=1e-9)  # its shortest cable
    assert bundle.diameter == pytest.approx(2.1547 * 0.0025, abs=1e-9)
    assert bundle.mass == pytest.approx(0.060, abs=1e-9)
    branch = objects.cable("GR11")
    assert branch is not None and branch.diameter == pytest.approx(0.005, abs=1e-9)
    assert objects.cable_names() == ["WH1", "GR11", "GR12"]
    assert objects.cables_of("GR11") == ("CA1", "CA3") and objects.branch_of("GR12") is not None


def test_an_unknown_cable_lists_harnesses_too() -> None:
    world = routing_world()
    with pytest.raises(RefError, match="unknown cable 'WH9'; known: cable1"):
        world.cable("WH9")


def test_a_harness_is_picked_placed_and_routed_as_one_bundle(tmp_path: Path) -> None:
    cell = tmp_path / "cell"
    shutil.copytree(CELL, cell)
    with (cell / "objects.yaml").open("a") as f:
        f.write(HARNESS)
    plan = (cell / "plan_straight.yaml").read_text().replace("cable: cable1", "cable: WH1")
    (cell / "plan_h.yaml").write_text(plan)
    compiled = compile_plan(cell / "plan_h.yaml")
    held = {e.event.holds for e in compiled.program.events}
    assert "WH1" in held and "cable1" not in held
    labels = [s.segment.label for s in compiled.program.segments]
    assert any(label.startswith("RouteCable routing.guide3") for label in labels)


def test_a_file_of_harnesses_alone_is_objects(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from cellengine.cli import main

    path = _objects(tmp_path)
    assert main(["validate", str(path)]) == 0
    assert capsys.readouterr().out == f"{path}: ok (objects)\n"
