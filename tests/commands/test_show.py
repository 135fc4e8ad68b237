import json
import math
import shutil
from pathlib import Path

import pytest

from cellengine.cli import main
from tests.conftest import CELLS
from tests.test_reach import moved_cell

# routing.guide2 is Blender's Guide_U_001 at (150, 260, 10) mm turned +90 deg about Blender z.
# Blender's root rotation and the y-up -> z-up turn map (x, y, z) -> (-x, -y, z); the platform
# pose (280, -210, 0) mm, yaw 180 deg, maps that back to (x + 280, y - 210, z): (430, 50, 10).
# The slot is 55 mm above the element origin: (430, 50, 65) mm, yaw 180 + 180 + 90 = 90 deg.


def test_json_in_metres_and_radians(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["show", str(CELLS / "cable_routing" / "cell.yaml"), "--json"]) == 0
    keypoints = json.loads(capsys.readouterr().out)["keypoints"]
    kp = keypoints["routing.guide2.slot"]
    # Blender writes the root rotation as 0.707107 and 3.141593: about 5e-8 m off
    assert kp["xyz"] == pytest.approx([0.43, 0.05, 0.065], abs=1e-6)
    assert kp["rpy"] == pytest.approx([0.0, 0.0, math.pi / 2], abs=1e-6)
    assert {k.split(".")[1] for k in keypoints if k.startswith("routing.")} == {
        "connector",
        *(f"guide{i}" for i in range(1, 8)),
    }


def test_table_in_mm_and_degrees(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["show", str(CELLS / "cable_routing")]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].split() == [
        "keypoint",
        "x",
        "mm",
        "y",
        "mm",
        "z",
        "mm",
        "roll",
        "deg",
        "pitch",
        "deg",
        "yaw",
        "deg",
    ]
    row = next(line for line in lines if line.startswith("routing.guide2.slot "))
    assert row.split()[1:] == ["430.00", "50.00", "65.00", "0.00", "0.00", "90.00"]


def test_missing_cell_is_usage_error(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["show", "no/such/cell.yaml"]) == 2
    assert capsys.readouterr().err == "no/such/cell.yaml: no such cell file\n"


def test_names_from_files_are_escaped(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    cell = tmp_path / "cell"
    shutil.copytree(CELLS / "cable_routing", cell)
    csv = cell / "routing" / "map.csv"
    csv.write_text(csv.read_text().replace(",connector\n", ",conn\x1b[31m\n"))
    assert main(["show", str(cell)]) == 0
    rows = [ln for ln in capsys.readouterr().out.splitlines() if "conn" in ln]
    assert [r.split()[0] for r in rows] == [
        "routing.conn\\x1b[31m.slot",
        "routing.conn\\x1b[31m.exit",
    ]


def test_errors_are_escaped(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "cell.yaml").write_text('name: "a\\e[2J\\n::error::x"\nrobots: {}\n')
    assert main(["show", str(tmp_path)]) == 1
    err = capsys.readouterr().err.replace(str(tmp_path), "<dir>")
    assert err.splitlines() == [
        "<dir>/cell.yaml:1:7: name: 'a\\x1b[2J\\n::error::x' is not a valid name: use letters, "
        "digits, '_' and '-', starting with a letter or '_'",
        "<dir>/cell.yaml:2:9: robots: must have at least 1 item, got 0",
    ]


def test_html_page_in_the_working_folder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(["show", str(CELLS / "cable_routing"), "--html"]) == 0
    assert capsys.readouterr().out == "cable_routing.html: 15 keypoints: 15 reached by every arm\n"
    page = (tmp_path / "cable_routing.html").read_text(encoding="utf-8")
    assert "<title>cellengine show: cable_routing</title>" in page
    assert '"reach":{"holder.comb_a.slot":["left","right"]' in page
    assert [p.name for p in tmp_path.iterdir()] == ["cable_routing.html"]  # no temporary left


def test_html_page_where_asked(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    cell = moved_cell(tmp_path / "cell")
    out = tmp_path / "page.html"
    out.write_text("old")
    assert main(["show", str(cell), "--html", str(out)]) == 0
    assert capsys.readouterr().out == (
        f"{out}: 15 keypoints: 2 reached by every arm, 7 by left only, 6 by no arm\n"
    )
    assert out.read_text(encoding="utf-8").startswith("<!DOCTYPE html>")


def test_html_page_in_a_missing_folder(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "no" / "page.html"
    assert main(["show", str(CELLS / "cable_routing"), "--html", str(out)]) == 1
    assert capsys.readouterr().err == (
        f"{out}: cannot write the cell page: No such file or directory\n"
    )


def test_json_and_html_are_one_or_the_other(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as e:
        main(["show", str(CELLS / "cable_routing"), "--json", "--html"])
    assert e.value.code == 2
    assert capsys.readouterr().err.splitlines()[-1] == (
        "cellengine show: error: argument --html: not allowed with argument --json"
    )
