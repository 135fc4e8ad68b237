"""`cellengine import remodel`: the shared sample becomes a cell, objects and plan that
validate; every mistake is reported at its file and row, and a failed import writes nothing."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from importlib import resources
from pathlib import Path

import numpy as np
import pytest
import yaml

from cellengine.cli import main
from cellengine.commands.import_remodel import schema_line
from cellengine.info import files
from cellengine.info.load import load_cell, load_objects, load_world
from tests.conftest import REMODEL

ROOT = Path(__file__).resolve().parents[2]
ROBOTS = ROOT / "tests" / "data" / "remodel_import" / "robots.yaml"
SCHEMAS = Path(str(resources.files("cellengine.schemas"))).resolve()
SEQUENCE_HEAD = "Order;Type of operation;Label;Spot\n"


@pytest.fixture
def src(tmp_path: Path) -> Path:
    """The shared sample, copied as it is (tests change their copy, never the sample)."""
    folder = tmp_path / "src"
    shutil.copytree(REMODEL, folder)
    for f in folder.iterdir():
        f.chmod(0o644)  # the shared copy is read-only
    return folder


def run(*args: str | Path) -> int:
    return main(["import", "remodel", *map(str, args)])


def read(path: Path) -> dict:  # type: ignore[type-arg]
    data = yaml.safe_load(path.read_text())
    assert isinstance(data, dict)
    return data


def errors(capsys: pytest.CaptureFixture[str]) -> list[str]:
    return capsys.readouterr().err.splitlines()


def sequence(src: Path, *rows: str) -> None:
    (src / "Assembly_sequence.csv").write_text(SEQUENCE_HEAD + "".join(r + "\n" for r in rows))


def leftovers(tmp_path: Path) -> list[str]:
    return sorted(p.name for p in tmp_path.iterdir() if p.name.startswith("."))


# --- the sample --------------------------------------------------------------------------


def test_sample_plan_steps(src: Path, tmp_path: Path) -> None:
    dest = tmp_path / "cell"
    assert run(src, dest) == 0
    plan = read(dest / "plan.yaml")
    assert plan == {
        "cell": "cell.yaml",
        "objects": "objects.yaml",
        "steps": [
            {"skill": "PickCable", "cable": "CA1", "from": ["combs.C2.1", "combs.C1.1"]},
            {"skill": "PlaceConnector", "cable": "CA1", "guide": "platform.J8.1", "arm": "left"},
            {
                "skill": "RouteCable",
                "cable": "CA1",
                "guides": ["platform.J3.1", "platform.J4.1", "platform.J1.1", "platform.J2.1"],
            },
        ],
    }
    text = (dest / "plan.yaml").read_text()
    assert "# row 3: PC CON1 J8.1.L; connector CON1 is on cable CA1 (WH_configuration.xml)" in text


def test_sample_objects(src: Path, tmp_path: Path) -> None:
    dest = tmp_path / "cell"
    assert run(src, dest) == 0
    cable = load_objects(dest / "objects.yaml").cables["CA1"]
    assert cable.length == pytest.approx(0.5)
    assert cable.diameter == pytest.approx(0.0051)
    assert cable.color == "Grey"
    assert cable.connector is not None
    assert cable.connector.type == "VGA"
    # width = x, height = y, length = z (along the cable)
    assert cable.connector.width == pytest.approx(0.0329)
    assert cable.connector.height == pytest.approx(0.01464)
    assert cable.connector.length == pytest.approx(0.04655)
    assert read(dest / "objects.yaml")["units"] == {"length": "mm", "mass": "g"}


def test_sample_validates_and_platform_files_are_copied(
    src: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    dest = tmp_path / "cell"
    assert run(src, dest) == 0
    out = capsys.readouterr()
    assert out.out.splitlines()[-2:] == [
        f"{dest}: cell.yaml (platforms combs, platform), objects.yaml (1 cable), "
        "plan.yaml (3 steps)",
        f"not compiled: `cellengine validate {dest}` compiles the plan",
    ]
    assert out.err == ""  # every spot within both arms' reach
    assert main(["validate", "--no-compile", str(dest)]) == 0
    cell = read(dest / "cell.yaml")
    assert cell["platforms"]["combs"] == {
        "pose": {"xyz": [0, 0, 0], "rpy": [0, 0, 0]},
        "format": "remodel",
        "cad": "combs/combs_cad.x3d",
        "ids": "combs/combs_ids.wri",
        "models": "Jigs_definition_v2.xml",
    }
    for rel in (
        cell["platforms"]["platform"]["cad"],
        "combs/combs_ids.wri",
        "Jigs_definition_v2.xml",
    ):
        name = Path(rel).name
        assert (dest / rel).read_bytes() == (src / name).read_bytes()
    assert leftovers(tmp_path) == []  # the staging folder is gone


def test_default_robots_in_mm_and_deg(src: Path, tmp_path: Path) -> None:
    dest = tmp_path / "my cell"
    assert run(src, dest) == 0
    cell, _ = load_cell(dest / "cell.yaml")
    assert cell.name == "my_cell"
    assert list(cell.robots) == ["left", "right"]
    assert cell.robots["left"].model == "ur5e"
    assert cell.robots["left"].base.xyz == pytest.approx((0, 0.35, 0))
    assert cell.robots["right"].base.xyz == pytest.approx((0, -0.35, 0))
    assert cell.robots["right"].home == pytest.approx(np.radians([0, -90, 90, -90, -90, 0]))
    assert cell.tools["cable_gripper"].jaw["slide"] == pytest.approx(0.007)
    assert cell.driver.kind == "sim"
    assert read(dest / "cell.yaml")["units"] == {"length": "mm", "angle": "deg"}
    # the engine's default clearance, written out where a user sees it
    assert read(dest / "cell.yaml")["clearance"] == 10
    assert cell.clearance == pytest.approx(0.010)


def test_every_file_starts_with_its_schema_line(src: Path, tmp_path: Path) -> None:
    dest = tmp_path / "cell"
    assert run(src, dest) == 0
    for kind in ("cell", "objects", "plan"):
        first = (dest / f"{kind}.yaml").read_text().splitlines()[0]
        head, _, ref = first.partition("$schema=")
        assert head == "# yaml-language-server: "
        # relative to DEST, even outside the checkout: the cell and the checkout may move
        assert not ref.startswith("/") and ref.endswith(f"/schemas/{kind}.schema.json")
        assert (dest / ref).resolve() == SCHEMAS / f"{kind}.schema.json"


def test_schema_line_is_relative_inside_the_checkout() -> None:
    """Relative from where the package's schemas are (in a worktree they may be another
    checkout's: the virtual environment's editable install)."""
    assert schema_line("plan", SCHEMAS.parent / "cells" / "imported") == [
        "# yaml-language-server: $schema=../../schemas/plan.schema.json"
    ]


def test_spots_out_of_reach_are_warnings_at_their_rows(
    src: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Platforms 2 m out: the files are written (they are valid), and each spot no arm
    reaches is named at its row, saying the plan cannot run and what to check."""
    dest = tmp_path / "cell"
    assert run(src, dest, "--pose=2000 0 0 0 0 0") == 0
    assert (dest / "plan.yaml").is_file()
    seq = src / "Assembly_sequence.csv"
    tail = "(the tool coming down its z): the plan cannot run; check --pose"
    assert errors(capsys) == [
        f"{seq}:2: warning: no arm reaches combs.C2.1 {tail}",
        f"{seq}:2: warning: no arm reaches combs.C1.1 {tail}",
        f"{seq}:3: warning: no arm reaches platform.J8.1 {tail}",
        *(
            f"{seq}:4: warning: no arm reaches platform.{j}.1 {tail}"
            for j in ("J3", "J4", "J1", "J2")
        ),
    ]


def test_a_step_s_arm_that_does_not_reach_its_spot(
    src: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Without --pose the platforms are at the origin; J8.1's step names the left arm.
    Moved 700 mm to -y (out of the left arm's reach, within the right's), only that step's
    arm is told of, with the advice to place the platforms."""
    dest = tmp_path / "cell"
    assert run(src, dest, "--pose=platform=0 -700 0 0 0 0") == 0
    seq = src / "Assembly_sequence.csv"
    assert errors(capsys) == [
        f"{seq}:3: warning: arm left does not reach platform.J8.1 (the tool coming down its z): "
        "the plan cannot run; check --pose"
    ]


def test_arms_auto_leaves_the_placing_arm_to_the_engine(
    src: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The same placement with --arms auto: J8.1's step says arm: auto and why, and the
    right arm reaching it is enough (no warning)."""
    dest = tmp_path / "cell"
    assert run(src, dest, "--pose=platform=0 -700 0 0 0 0", "--arms", "auto") == 0
    assert errors(capsys) == []
    (place,) = [s for s in read(dest / "plan.yaml")["steps"] if s["skill"] == "PlaceConnector"]
    assert place["arm"] == "auto"
    text = (dest / "plan.yaml").read_text()
    assert "; the engine chooses the arm, not the spot's left (--arms auto)\n" in text


# --- --robots, --pose, --name ------------------------------------------------------------


def test_robots_from_a_cell_keep_its_units_and_driver(src: Path, tmp_path: Path) -> None:
    dest = tmp_path / "cell"
    pose = "0.4 -0.1 0 0 0 3.14159"
    assert run(src, dest, "--robots", ROBOTS, "--pose", pose, "--name", "lab") == 0
    raw = read(dest / "cell.yaml")
    assert raw["units"] == {"length": "m", "angle": "rad"}
    assert set(raw) == {"name", "units", "robots", "tools", "platforms", "driver"}  # no obstacles
    assert raw["platforms"]["platform"]["pose"] == {"xyz": [0.4, -0.1, 0], "rpy": [0, 0, 3.14159]}
    cell, _ = load_cell(dest / "cell.yaml")
    assert cell.name == "lab"
    assert cell.robots["left"].model == "ur10e"
    assert cell.robots["left"].base.xyz == pytest.approx((0, 0.4, 0.02))
    assert cell.driver.kind == "ur_rtde"
    assert cell.platforms["combs"].pose.xyz == pytest.approx((0.4, -0.1, 0))
    assert main(["validate", "--no-compile", str(dest)]) == 0


def test_pose_for_all_and_for_one_platform(src: Path, tmp_path: Path) -> None:
    dest = tmp_path / "cell"
    args = ["--pose", "-400 0 10 0 0 180", "--pose", "combs=100,-200,0,0,0,90.5"]
    assert run(src, dest, *args) == 0
    platforms = read(dest / "cell.yaml")["platforms"]
    assert platforms["platform"]["pose"] == {"xyz": [-400, 0, 10], "rpy": [0, 0, 180]}
    assert platforms["combs"]["pose"] == {"xyz": [100, -200, 0], "rpy": [0, 0, 90.5]}
    cell, _ = load_cell(dest / "cell.yaml")
    assert cell.platforms["platform"].pose.rpy == pytest.approx((0, 0, np.pi))
    # J3.1 is (-323, -156.33, 112.25) mm in the platform frame (tests/info/test_remodel.py)
    T = load_world(dest / "cell.yaml").pose("platform.J3.1")
    np.testing.assert_allclose(T[:3, 3], [-0.4 + 0.323, 0.15633, 0.01 + 0.11225], atol=1e-6)


def test_bad_pose_and_name_are_usage_errors(
    src: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    dest = tmp_path / "cell"
    for bad in (["--pose", "1 2 3"], ["--pose", "x=1 2 3 4 5 six"], ["--name", "a.b"]):
        with pytest.raises(SystemExit) as e:
            run(src, dest, *bad)
        assert e.value.code == 2
    assert "expected [NAME=]\"x y z roll pitch yaw\" (6 numbers), got '1 2 3'" in (
        capsys.readouterr().err
    )
    assert run(src, dest, "--pose", "board=0 0 0 0 0 0") == 2
    assert errors(capsys) == [f"{src}: --pose: unknown platform 'board'; known: combs, platform"]
    assert not dest.exists()


def test_urdf_robots_are_refused_at_their_line(
    tmp_path: Path, src: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "arm.urdf").write_text("<robot name='a'/>")
    robots = tmp_path / "robots.yaml"
    robots.write_text("name: c\nrobots:\n  left:\n    model: {urdf: arm.urdf, tip: tool0}\n")
    assert run(src, tmp_path / "cell", "--robots", robots) == 1
    assert errors(capsys) == [
        f"{robots}:4:12: robots.left.model: a URDF robot cannot be imported yet; copy the "
        "URDF into DEST and edit cell.yaml by hand"
    ]


def test_arm_letter_needs_a_robot_of_that_name(
    src: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    robots = tmp_path / "robots.yaml"
    robots.write_text(
        "name: c\nrobots:\n  a: {model: ur5e, base: {xyz: [0, 0.35, 0]}}\n"
        "  b: {model: ur5e, base: {xyz: [0, -0.35, 0]}}\n"
    )
    monkeypatch.chdir(tmp_path)
    assert run(src, tmp_path / "cell", "--robots", robots) == 1
    assert errors(capsys) == [
        "src/Assembly_sequence.csv:3: Spot 'J8.1.L' names robot 'left', which robots.yaml "
        "does not have; known: a, b"
    ]
    # with --arms auto the letter names no robot: the engine chooses among a and b
    assert run(src, tmp_path / "cell", "--robots", robots, "--arms", "auto") == 0
    place = [s for s in read(tmp_path / "cell" / "plan.yaml")["steps"] if "guide" in s]
    assert [s["arm"] for s in place] == ["auto"]


# --- labels and cables -------------------------------------------------------------------


def test_label_may_name_the_cable(src: Path, tmp_path: Path) -> None:
    sequence(src, "1;EC;CA1;C2.1-C1.1", "2;RC;CA1;J3.1")
    assert run(src, tmp_path / "cell") == 0
    text = (tmp_path / "cell" / "plan.yaml").read_text()
    assert "# row 2: EC CA1 C2.1-C1.1; CA1 is a cable" in text


def test_without_harness_the_only_cable(src: Path, tmp_path: Path) -> None:
    (src / "WH_configuration.xml").unlink()
    assert run(src, tmp_path / "cell") == 0
    text = (tmp_path / "cell" / "plan.yaml").read_text()
    assert (
        "connector CON1 is taken to be on CA1, the only cable in Components_definition.csv" in text
    )
    assert read(tmp_path / "cell" / "objects.yaml")["cables"]["CA1"]["connector"]["type"] == "VGA"


def test_without_harness_two_cables_is_an_error(
    src: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    (src / "WH_configuration.xml").unlink()
    with (src / "Components_definition.csv").open("a") as f:
        f.write("Cable;;;CA2;Red;600;4;;;;\r\n")  # long enough to lie in both combs
    monkeypatch.chdir(src)
    assert run(src, tmp_path / "cell") == 1
    message = (
        "cannot tell which cable connector 'CON1' is on: there is no WH_configuration.xml, "
        "and Components_definition.csv has 2 cables; known: CA1, CA2"
    )
    assert errors(capsys) == [f"Assembly_sequence.csv:{row}: {message}" for row in (2, 3, 4)]


def test_unknown_label_names_the_row(
    src: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    sequence(src, "1;EC;CON1;C2.1-C1.1", "2;RC;CON9;J3.1")
    monkeypatch.chdir(src)
    assert run(src, tmp_path / "cell") == 1
    assert errors(capsys) == [
        "Assembly_sequence.csv:3: unknown Label 'CON9': not a connector or cable of "
        "Components_definition.csv nor a branch of WH_configuration.xml; known: CA1, CON1"
    ]


# --- errors at the row, and nothing written ----------------------------------------------


def test_unknown_operation(
    src: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    sequence(src, "1;EC;CON1;C2.1-C1.1", "2;PC;CON1;J8.1.L", "3;XX;CON1;J3.1")
    monkeypatch.chdir(src)
    assert run(src, tmp_path / "cell") == 1
    assert errors(capsys) == [
        "Assembly_sequence.csv:4: unknown operation 'XX'; known: EC, PC, RC, T, TJ"
    ]
    assert not (tmp_path / "cell").exists()


def test_unknown_element_label(
    src: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    sequence(src, "1;EC;CON1;C9.1-C1.1")
    monkeypatch.chdir(src)
    assert run(src, tmp_path / "cell") == 1
    assert errors(capsys) == [
        "Assembly_sequence.csv:2: unknown label 'C9' in Spot 'C9.1-C1.1'; "
        "known: C1, C2, J1, J2, J3, J4, J8"
    ]


def test_bad_arm_letter(
    src: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    sequence(src, "1;EC;CON1;C2.1-C1.1", "2;PC;CON1;J8.1.B")
    monkeypatch.chdir(src)
    assert run(src, tmp_path / "cell") == 1
    assert errors(capsys) == [
        "Assembly_sequence.csv:3: unknown arm letter 'B' in 'J8.1.B'; known: L, R (left, right)"
    ]


def test_unknown_guide_fails_validation_at_its_row_and_writes_nothing(
    src: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    sequence(src, "1;EC;CON1;C2.1-C1.1", "2;RC;CON1;J3.1-J4.2")
    dest = tmp_path / "cell"
    monkeypatch.chdir(src)
    assert run(src, dest) == 1
    assert errors(capsys) == [
        "Assembly_sequence.csv:3: unknown keypoint 'platform.J4.2'; known: 1",
        f"{dest}: nothing was written: the imported cell does not validate",
    ]
    assert not dest.exists()
    assert leftovers(tmp_path) == []


def test_bad_platform_file_is_reported_in_src_and_dest_is_untouched(
    src: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    with (src / "platform_ids.wri").open("a") as f:
        f.write("ID0099\tJ9\t0011\r\n")  # line 7: no such DEF in platform_cad.x3d
    dest = tmp_path / "cell"
    dest.mkdir()
    (dest / "notes.txt").write_text("mine")
    assert run(src, dest) == 1
    problems = errors(capsys)
    # reported in the SRC file a user would fix, not in the staged copy
    assert problems[0].startswith(f"{src}/platform_ids.wri:7: unknown CAD name 'ID0099'")
    assert problems[1:] == [f"{dest}: nothing was written: the imported cell does not validate"]
    assert sorted(p.name for p in dest.iterdir()) == ["notes.txt"]
    assert leftovers(tmp_path) == []


def test_existing_files_need_force(
    src: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    dest = tmp_path / "cell"
    dest.mkdir()
    (dest / "plan.yaml").write_text("old")
    (dest / "notes.txt").write_text("mine")
    assert run(src, dest) == 2
    assert errors(capsys) == [f"{dest}: would overwrite plan.yaml; give --force to overwrite"]
    assert (dest / "plan.yaml").read_text() == "old"
    assert run(src, dest, "--force") == 0
    assert read(dest / "plan.yaml")["steps"][0]["skill"] == "PickCable"
    assert (dest / "notes.txt").read_text() == "mine"
    assert main(["validate", "--no-compile", str(dest)]) == 0


def test_failed_import_with_force_keeps_the_old_files(src: Path, tmp_path: Path) -> None:
    dest = tmp_path / "cell"
    assert run(src, dest) == 0
    before = {p: p.read_bytes() for p in dest.rglob("*") if p.is_file()}
    sequence(src, "1;EC;CON1;C2.1-C1.1", "2;RC;CON1;J3.9")  # no guide 9: fails validation
    assert run(src, dest, "--force") == 1
    assert {p: p.read_bytes() for p in dest.rglob("*") if p.is_file()} == before
    assert leftovers(tmp_path) == []


# --- platform files that are no plain files ----------------------------------------------


def import_in_subprocess(src: Path, dest: Path) -> subprocess.CompletedProcess[str]:
    """The import in a fresh process with a timeout: a FIFO or device fails, not hangs."""
    return subprocess.run(
        [sys.executable, "-m", "cellengine", "import", "remodel", str(src), str(dest)],
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        capture_output=True,
        text=True,
        timeout=120,
    )


def test_link_leading_outside_src_is_refused_before_anything_is_copied(
    src: Path, tmp_path: Path
) -> None:
    """A link to /dev/zero was copied until the disk was full, before any validation. Here
    the link leads to a FIFO outside: were it followed, the import would wait, not fill the
    disk, and time out."""
    os.mkfifo(tmp_path / "pipe")
    (src / "platform_cad.x3d").unlink()
    (src / "platform_cad.x3d").symlink_to(tmp_path / "pipe")
    dest = tmp_path / "cell"
    result = import_in_subprocess(src, dest)
    assert result.stderr.splitlines() == [
        f"{src}/platform_cad.x3d: is a link that leads outside the REMODEL folder; copy the "
        "file itself into it"
    ]
    assert result.returncode == 1
    assert not dest.exists()
    assert leftovers(tmp_path) == []


def test_fifo_and_folder_in_src_are_refused(src: Path, tmp_path: Path) -> None:
    (src / "combs_ids.wri").unlink()
    os.mkfifo(src / "combs_ids.wri")
    (src / "platform_cad.x3d").unlink()
    (src / "platform_cad.x3d").mkdir()
    result = import_in_subprocess(src, tmp_path / "cell")
    assert result.stderr.splitlines() == [
        f"{src}/combs_ids.wri: a named pipe (FIFO), not a regular file",
        f"{src}/platform_cad.x3d: a folder, not a regular file",
    ]
    assert result.returncode == 1
    assert leftovers(tmp_path) == []


def test_link_inside_src_is_copied_as_a_file(src: Path, tmp_path: Path) -> None:
    (src / "cad").mkdir()
    (src / "platform_cad.x3d").rename(src / "cad" / "platform.x3d")
    (src / "platform_cad.x3d").symlink_to("cad/platform.x3d")
    dest = tmp_path / "cell"
    assert run(src, dest) == 0
    copy = dest / "platform" / "platform_cad.x3d"
    assert not copy.is_symlink()
    assert copy.read_bytes() == (src / "cad" / "platform.x3d").read_bytes()


def test_platform_files_over_the_readers_size_cap_are_refused(
    src: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setitem(files.MAX_BYTES, "x3d", 50_000)
    size = (src / "combs_cad.x3d").stat().st_size
    assert run(src, tmp_path / "cell") == 1
    assert errors(capsys) == [
        f"{src}/combs_cad.x3d: file is {size} bytes, more than the 50000-byte limit for x3d files"
    ]
    assert leftovers(tmp_path) == []


def test_missing_src_files(src: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert run(tmp_path / "nowhere", tmp_path / "cell") == 2
    (src / "combs_ids.wri").unlink()
    assert run(src, tmp_path / "cell") == 1
    (src / "Assembly_sequence.csv").unlink()
    errs = errors(capsys)
    assert errs[0] == f"{tmp_path / 'nowhere'}: no such folder"
    assert errs[1] == (
        f"{src / 'combs_cad.x3d'}: no combs_ids.wri next to it: a platform is a "
        "<name>_cad.x3d and <name>_ids.wri pair"
    )
    (src / "combs_cad.x3d").unlink()
    assert run(src, tmp_path / "cell") == 1
    assert errors(capsys) == [f"{src}: no Assembly_sequence.csv in the REMODEL folder"]


def harness(src: Path, body: str) -> None:
    (src / "WH_configuration.xml").write_text(f"<data>\n{body}\n</data>\n")


def test_harness_cable_must_be_a_component(
    src: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    harness(src, '<wiring_harness first_connector="CON1"><cable>CA9</cable></wiring_harness>')
    sequence(src, "1;EC;CON1;C2.1-C1.1")
    monkeypatch.chdir(src)
    assert run(src, tmp_path / "cell") == 1
    assert errors(capsys) == [
        "WH_configuration.xml:2: cable 'CA9' is not defined in Components_definition.csv; "
        "known: CA1"
    ]


def test_a_connector_with_several_cables_is_a_harness(
    src: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    with (src / "Components_definition.csv").open("a") as f:
        f.write("Cable;;;CA2;Red;600;4;;;;\r\n")
    harness(
        src,
        '<wiring_harness first_connector="CON1"><end_connector label="Free">'
        "<cable>CA1</cable><cable>CA2</cable></end_connector></wiring_harness>",
    )
    sequence(src, "1;EC;CON1;C2.1-C1.1")
    monkeypatch.chdir(src)
    assert run(src, tmp_path / "cell") == 1
    no_row = (
        "has no Row1: REMODEL orders a harness's cables at its first connector by Row1 "
        "(0 at the bottom)"
    )
    assert errors(capsys) == [
        f"WH_configuration.xml:2: cable CA1 {no_row}",
        f"WH_configuration.xml:2: cable CA2 {no_row}",
    ]
    harness(
        src,
        '<wiring_harness first_connector="CON1"><end_connector label="GR1">'
        '<cable Row1="1" Col1="0">CA1</cable></end_connector><end_connector label="GR2">'
        '<cable Row1="0" Col1="0">CA2</cable></end_connector></wiring_harness>',
    )
    sequence(src, "1;EC;CA2;C2.1-C1.1")
    assert run(src, tmp_path / "cell") == 1
    assert errors(capsys) == [
        "Assembly_sequence.csv:2: CA2 is a cable of harness CON1 (WH_configuration.xml); name "
        "the harness's connector CON1, or (RC) one of its branches; known: GR1, GR2"
    ]
    sequence(src, "1;EC;CON1;C2.1-C1.1", "2;PC;CON1;J8.1.L", "3;RC;CON1;J3.1-J4.1")
    assert run(src, tmp_path / "cell") == 0
    objects = read(tmp_path / "cell" / "objects.yaml")
    assert "cables" not in objects
    assert objects["harnesses"] == {
        "CON1": {
            "connector": {"type": "VGA", "length": 46.55, "width": 32.9, "height": 14.64},
            "color": "Grey",
            "cables": {
                "CA1": {"length": 500, "diameter": 5.1, "color": "Grey", "pin": [1, 0]},
                "CA2": {"length": 600, "diameter": 4, "color": "Red", "pin": [0, 0]},
            },
            "branches": {"GR1": {"cables": ["CA1"]}, "GR2": {"cables": ["CA2"]}},
        }
    }
    steps = read(tmp_path / "cell" / "plan.yaml")["steps"]
    assert [(s["skill"], s["cable"]) for s in steps] == [
        ("PickCable", "CON1"),
        ("PlaceConnector", "CON1"),
        ("RouteCable", "CON1"),
    ]
    sequence(
        src, "1;EC;CON1;C2.1-C1.1", "2;RC;GR2;J3.1", "3;PC;GR1;J8.1.L", "4;T;CON1;J3.1-J4.1-J4.1"
    )
    assert run(src, tmp_path / "cell2") == 1
    assert errors(capsys) == [
        "Assembly_sequence.csv:3: RC GR2 J3.1: GR2's cables leave the connector below CA1, "
        "still to be routed: REMODEL lays those aside in their harness's separation guide "
        "J<id>S first, and the harness has no id (WH_configuration.xml line 2)",
        "Assembly_sequence.csv:4: GR1 is a branch of harness CON1 (WH_configuration.xml); PC "
        "names the harness's connector, CON1",
    ]


def test_problems_of_every_file_together(
    src: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    with (src / "Components_definition.csv").open("a") as f:
        f.write("Cable;;;CA2;Red;;4;;;;\r\n")
    sequence(src, "1;EC;CON1;C2.1", "2;ZZ;CON1;J3.1")
    monkeypatch.chdir(src)
    assert run(src, tmp_path / "cell") == 1
    assert errors(capsys) == [
        "Components_definition.csv:4: empty length of cable CA2",
        "Assembly_sequence.csv:2: EC names 2 combs, or 1 comb with an arm, e.g. C2.1-C1.1 "
        "(two combs, connector end first) or C1.1.L (a comb, the arm); 'C2.1' names 1",
        "Assembly_sequence.csv:3: unknown operation 'ZZ'; known: EC, PC, RC, T, TJ",
    ]
