"""`cellengine sweep`: variants of a plan's files compiled into one table; bad variants
refused before anything compiles; the cache and the workers give the same rows."""

from __future__ import annotations

import csv
import json
import shutil
from pathlib import Path

import pytest

import cellengine.sweep
from cellengine.cli import main
from tests.conftest import CELLS

SHORT = (
    "plan_straight.yaml:15:5: steps[2] RouteCable routing.guide3: cable 'cable1' is too short "
    "for the route: this guide needs 366.9 mm (288.5 mm laid from the connector's rear face to "
    "the approach point, R_cable 68.0 mm slid past it, 1.4 mm pulled to tension, 9.0 mm for "
    "the fingers to hold) but the cable is 350.0 mm long"
)
VARY = ["--vary", "routing.guide3.xyz=[[-150, -380, 10]]"]
VARY += ["--vary", "objects:cables.cable1.length=[650, 350]"]


@pytest.fixture
def cell(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    shutil.copytree(CELLS / "cable_routing", tmp_path / "cell")
    monkeypatch.chdir(tmp_path / "cell")
    return tmp_path / "cell"


def _counting(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    calls: list[int] = []
    original = cellengine.sweep.evaluate

    def counted(task):  # type: ignore[no-untyped-def]
        calls.append(1)
        return original(task)

    monkeypatch.setattr(cellengine.sweep, "evaluate", counted)
    return calls


def _rows(text: str) -> list[dict[str, str]]:
    return list(csv.DictReader(text.splitlines()))


def test_every_combination_is_a_row(
    cell: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    assert main(["sweep", "plan_straight.yaml", *VARY, "-j", "2"]) == 0
    out = capsys.readouterr()
    assert out.err == "2 variant(s), 1 feasible\n"
    rows = _rows(out.out)
    assert list(rows[0]) == [
        "variant",
        "routing.guide3.xyz",
        "objects:cables.cable1.length",
        "feasible",
        "cycle_time_s",
        "arm_clearance_m",
        "environment_clearance_m",
        "problem",
    ]
    ok, short = rows
    assert (ok["variant"], ok["routing.guide3.xyz"], ok["objects:cables.cable1.length"]) == (
        "v1",
        "[-150, -380, 10]",
        "650",
    )
    assert ok["feasible"] == "true" and ok["problem"] == ""
    assert 20.0 < float(ok["cycle_time_s"]) < 40.0
    assert float(ok["arm_clearance_m"]) >= 0.010  # the cell's clearance, kept
    assert (short["feasible"], short["cycle_time_s"], short["problem"]) == ("false", "", SHORT)

    # again, from the cache: nothing compiled, the same table; as JSON to a file
    calls = _counting(monkeypatch)
    assert main(["sweep", "plan_straight.yaml", *VARY, "-j", "1", "--out", "t.json"]) == 0
    assert calls == []
    table = json.loads((cell / "t.json").read_text())
    assert [r["feasible"] for r in table] == [True, False]
    assert table[0]["cycle_time_s"] == pytest.approx(float(ok["cycle_time_s"]), abs=1e-6)
    assert table[1]["problem"] == SHORT
    assert capsys.readouterr().err == "2 variant(s), 1 feasible: t.json\n"


def test_a_variant_its_files_refuse_is_a_row(
    cell: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (cell / "variants.yaml").write_text(
        "- {name: near, 'routing.guide3.xyz': [-150, -372, 10]}\n"
        "- {name: turned, 'routing.guide3.rpy': [0, 0, 0]}\n"
    )
    assert main(["sweep", "plan_straight.yaml", "--variants", "variants.yaml", "-j", "1"]) == 0
    near, turned = _rows(capsys.readouterr().out)
    assert (near["variant"], turned["variant"]) == ("near", "turned")
    assert near["feasible"] == "true"
    assert turned["feasible"] == "false"
    assert turned["problem"].startswith(
        "plan_straight.yaml:17:46: steps[2].guides[2]: routing.guide3's slot runs across the route"
    )


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--vary", "tabel.guide3.xyz=[[0, 0, 0]]"],
         "--vary tabel.guide3.xyz: 'tabel.guide3.xyz': no platform 'tabel' in the cell "
         "(it has holder, routing)"),
        (["--vary", "routing.guide3.xyz=3"],
         "--vary routing.guide3.xyz: the values are a YAML list of at least one, not '3'"),
        (["--vary", "routing.guide3.xyz"],
         "--vary routing.guide3.xyz: write KEY=[value, value, ...]"),
        (["--vary", "routing.guideX.xyz=[[0, 0, 0]]"],
         "--vary routing.guideX.xyz: 'routing.guideX.xyz': no element 'guideX' on 'routing' "
         "(it has connector, guide1, guide2, guide3, guide4, guide5, guide6, guide7, plate)"),
    ],
)  # fmt: skip
def test_bad_keys_and_values_are_named(
    cell: Path, capsys: pytest.CaptureFixture[str], args: list[str], message: str
) -> None:
    assert main(["sweep", "plan_straight.yaml", *args]) == 1
    assert capsys.readouterr().err == message + "\n"


def test_a_bad_key_in_a_variants_file_is_at_its_line(
    cell: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (cell / "variants.yaml").write_text("- name: a\n  routing.guide3: [0, 0, 0]\n")
    assert main(["sweep", "plan_straight.yaml", "--variants", "variants.yaml"]) == 1
    assert capsys.readouterr().err == (
        "variants.yaml:2:3: 'routing.guide3': write PLATFORM.ELEMENT.move (or .xyz, .rpy), "
        "or cell:KEY, objects:KEY, plan:KEY\n"
    )
