"""`cellengine import remodel` of folders of REMODEL's later system (HARNESS.md): an ATC
platform, labels by letter class, harnesses of several cables with branches, the later
system's operations, and what REMODEL reads differently reported at file:line."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
import yaml

from cellengine.cli import main
from tests.conftest import REMODEL

SEQUENCE_HEAD = "Order;Type of operation;Label;Spot\n"
_CUBE = (
    '<Shape><IndexedFaceSet coordIndex="0 1 2 3 -1 4 7 6 5 -1 0 4 5 1 -1 1 5 6 2 -1 '
    '2 6 7 3 -1 3 7 4 0 -1"><Coordinate point="0 0 0 {x} 0 0 {x} {y} 0 0 {y} 0 '
    '0 0 {z} {x} 0 {z} {x} {y} {z} 0 {y} {z}"/></IndexedFaceSet></Shape>'
)


def _atc_x3d() -> str:
    """A tool changer as Blender exports one: a table (the root, mm scaled to m, turned
    y-up to z-up) with three slots on it."""
    slots = "".join(
        f'<Transform DEF="ID00000{i}" translation="{x} 0 800" rotation="0 0 1 0">'
        + _CUBE.format(x=10, y=34, z=65)
        + "</Transform>"
        for i, x in ((2, 0), (3, 150), (4, 300))
    )
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n<X3D version="3.0" profile="Immersive">'
        '<Scene><Transform DEF="ID000001" translation="0 0 0" scale="0.001 0.001 0.001" '
        'rotation="0.000000 0.707107 0.707107 3.141593">'
        + _CUBE.format(x=400, y=100, z=800)
        + slots
        + "</Transform></Scene></X3D>\n"
    )


@pytest.fixture
def src(tmp_path: Path) -> Path:
    """The shared sample with the later system's ATC platform, harnesses and rows."""
    folder = tmp_path / "src"
    shutil.copytree(REMODEL, folder)
    for f in folder.iterdir():
        f.chmod(0o644)
    # the sample's Jigs file has the later system's two tool changer stations already
    (folder / "ATC_cad.x3d").write_text(_atc_x3d())
    (folder / "ATC_ids.wri").write_text(
        "ID000001\tT1\t0000001\r\nID000002\tAgun\t0000301\r\n"
        "ID000003\tAgripper_right\t0000302\r\nID000004\tAgripper_left\t0000302\r\n"
    )
    with (folder / "Components_definition.csv").open("a") as f:
        f.write("Connector;LUM1;111;WH1;White;;;32.9;14.64;46.55;\r\n")
        for i, color in enumerate(("Yellow", "Green", "Blue"), start=2):
            f.write(f"Cable;;;CA{i};{color};520;2.1;;;;\r\n")
    (folder / "WH_configuration.xml").write_text(
        '<?xml version="1.0"?>\n<data>\n'
        '  <wiring_harness id="1" first_connector="CON1" tray="B3.1">\n'
        '    <end_connector label="Free"><cable Row1="1" Col1="1">CA1</cable></end_connector>\n'
        "  </wiring_harness>\n"
        '  <wiring_harness id="2" first_connector="WH1">\n'
        '    <end_connector label="GR11">\n'
        '      <cable Row1="1" Col1="0">CA2</cable>\n'
        '      <cable Row1="2" Col1="0" Row2="4" Col2="1">CA3</cable>\n'
        "    </end_connector>\n"
        '    <end_connector label="GR12"><cable Row1="0" Col1="0">CA4</cable></end_connector>\n'
        "  </wiring_harness>\n</data>\n"
    )
    return folder


def run(*args: str | Path) -> int:
    return main(["import", "remodel", *map(str, args)])


def sequence(src: Path, *rows: str) -> None:
    (src / "Assembly_sequence.csv").write_text(SEQUENCE_HEAD + "".join(r + "\n" for r in rows))


def test_an_atc_platform_with_its_own_table_t1_imports(src: Path, tmp_path: Path) -> None:
    """T1 is on the platform and the ATC: REMODEL keys tables by CAD id, never by label."""
    assert run(src, tmp_path / "cell") == 0
    cell = yaml.safe_load((tmp_path / "cell" / "cell.yaml").read_text())
    assert sorted(cell["platforms"]) == ["ATC", "combs", "platform"]
    from cellengine.info.load import load_world

    world = load_world(tmp_path / "cell" / "cell.yaml")
    slot = world.platforms["ATC"].elements["Agun"]
    assert sorted(slot.keypoints) == ["tool_base", "tool_end"]
    gripper = world.platforms["ATC"].elements["Agripper_left"]
    assert sorted(gripper.keypoints) == ["gripper_nail", "tool_base", "tool_end"]
    assert gripper.dimensions["finger_length"] == pytest.approx(0.040, abs=1e-9)
    # each station's tool, with its slot at the station's tool_base and REMODEL's approach
    # (out 70 mm along x, back 50 mm plus the tool along z; the bare flange back 50 mm)
    tools = cell["tools"]
    assert sorted(tools) == ["cable_gripper", "gripper_left", "gripper_right", "gun"]
    assert tools["gun"]["kind"] == "taping_gun" and tools["gun"]["dwell"] == 3.0
    assert tools["gun"]["slot"] == {
        "at": "ATC.Agun.tool_base",
        "exit": [[70, 0, 0], [70, 0, -150]],
        "retreat": [[0, 0, -50]],
    }
    assert tools["gun"]["tcp"] == {"xyz": [100, -55, 86], "rpy": [0, pytest.approx(89.95437), 0]}
    assert tools["gripper_left"]["slot"]["exit"] == [[70, 0, 0], [70, 0, -315]]
    assert tools["gripper_left"]["tcp"] == {"xyz": [0, 0, 240], "rpy": [0, 0, 0]}
    assert tools["gripper_left"]["fingers"] == tools["cable_gripper"]["fingers"]
    assert {r: cell["robots"][r]["tool"] for r in cell["robots"]} == {
        "left": "gripper_left",
        "right": "gripper_right",
    }
    assert world.slot("gun") == pytest.approx(world.pose("ATC.Agun.tool_base"), abs=1e-12)


def test_a_jig_label_on_two_platforms_is_refused(
    src: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    with (src / "ATC_ids.wri").open("a") as f:
        f.write("ID000005\tJ3\t0000302\r\n")
    monkeypatch.chdir(src)
    assert run(src, tmp_path / "cell") == 1
    assert capsys.readouterr().err.splitlines() == [
        "platform_ids.wri:4: label 'J3' is also on platform 'ATC' (ATC_ids.wri line 5); "
        "spots name jigs by label alone"
    ]


def test_a_label_of_no_class_is_a_warning(
    src: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    ids = src / "ATC_ids.wri"
    ids.write_text(ids.read_text().replace("Agripper_left", "Gripper2"))
    monkeypatch.chdir(src)
    assert run(src, tmp_path / "cell") == 0
    assert (
        "ATC_ids.wri:4: warning: label 'Gripper2' starts with none of T (table), J (jig), B (box), "
        "C (comb), A (tool changer slot): REMODEL gives it no type, and no spot can name it"
    ) in capsys.readouterr().err.splitlines()


def test_a_harness_of_several_cables_with_branches(src: Path, tmp_path: Path) -> None:
    sequence(src, "1;EC;WH1;C2.1-C1.1", "2;PC;WH1;J8.1.L", "3;RC;GR11;J3.1-J4.1", "4;RC;GR12;J3.1")
    assert run(src, tmp_path / "cell") == 0
    objects = yaml.safe_load((tmp_path / "cell" / "objects.yaml").read_text())
    assert list(objects["cables"]) == ["CA1"]  # the one-cable harness, as before
    wh1 = objects["harnesses"]["WH1"]
    assert wh1["branches"] == {"GR11": {"cables": ["CA2", "CA3"]}, "GR12": {"cables": ["CA4"]}}
    assert wh1["cables"]["CA3"] == {
        "length": 520,
        "diameter": 2.1,
        "color": "Green",
        "pin": [2, 0],
        "end_pin": [4, 1],
    }
    assert "end_pin" not in wh1["cables"]["CA2"]
    steps = yaml.safe_load((tmp_path / "cell" / "plan.yaml").read_text())["steps"]
    assert [s["cable"] for s in steps] == ["WH1", "WH1", "GR11", "GR12"]


def test_a_bottom_branch_first_is_refused_at_its_row(
    src: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """REMODEL lays the top cables into the separation guide J<id>S first (case A1): a
    folder without one is refused at the row."""
    sequence(src, "1;EC;WH1;C2.1-C1.1", "2;PC;WH1;J8.1.L", "3;RC;GR12;J3.1")
    monkeypatch.chdir(src)
    assert run(src, tmp_path / "cell") == 1
    assert capsys.readouterr().err.splitlines()[0] == (
        "Assembly_sequence.csv:4: RC GR12 J3.1: GR12's cables leave the connector below CA2, "
        "CA3, still to be routed: REMODEL lays those aside in the separation guide J2S first, "
        "which no platform has (add it to a platform's ids file)"
    )
    assert not (tmp_path / "cell").exists()


def test_a_bottom_branch_first_lays_the_others_aside_in_its_separation_guide(
    src: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """With J2S on a platform, the bottom branch's RouteCable names it (separate_into) and
    the top branch, routed after it, is taken back from there by the engine (REMODEL's GCS)."""
    x3d = src / "ATC_cad.x3d"
    x3d.write_text(
        x3d.read_text().replace(
            "</Transform></Scene>",
            '<Transform DEF="ID000005" translation="150 0 100" rotation="0 0 1 0">'
            + _CUBE.format(x=10, y=24, z=60)
            + "</Transform></Transform></Scene>",
        )
    )
    jig = next(
        line.split("\t")[2].strip()
        for line in (src / "platform_ids.wri").read_text().splitlines()
        if line.split("\t")[1] == "J3"
    )
    with (src / "ATC_ids.wri").open("a") as f:
        f.write(f"ID000005\tJ2S\t{jig}\r\n")
    sequence(src, "1;EC;WH1;C2.1-C1.1", "2;PC;WH1;J8.1.L", "3;RC;GR12;J3.1", "4;RC;GR11;J3.1-J4.1")
    monkeypatch.chdir(src)
    assert run(src, tmp_path / "cell") == 0
    steps = yaml.safe_load((tmp_path / "cell" / "plan.yaml").read_text())["steps"]
    assert steps[2] == {
        "skill": "RouteCable",
        "cable": "GR12",
        "guides": ["platform.J3.1"],
        "separate_into": "ATC.J2S.1",
    }
    assert "separate_into" not in steps[3]


def test_later_rows_not_built_yet_are_refused_at_their_rows(
    src: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    sequence(
        src,
        "1;EC;WH1;C1.1.R",
        "2;PC;WH1;J8.1.R",
        "3;RC;GR11;J3.1-J4.1",
        "4;T;WH1;J3.1-J4.1-J4.1",
        "5;RC;WH3;J1.1",
    )
    monkeypatch.chdir(src)
    assert run(src, tmp_path / "cell") == 1
    not_yet = "is not built yet in this engine (issue #15)"
    assert capsys.readouterr().err.splitlines() == [
        f"Assembly_sequence.csv:2: EC WH1 C1.1.R: picking from one comb with one hand (the "
        f"later system's EC) {not_yet}",
        "Assembly_sequence.csv:6: unknown Label 'WH3': not a connector or cable of "
        "Components_definition.csv nor a branch of WH_configuration.xml; known: CA1, CA2, CA3, "
        "CA4, CON1, GR11, GR12, WH1",
    ]
    assert not (tmp_path / "cell").exists()


def test_a_taping_row_is_a_tape_step(
    src: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """T's spots: the two guides to tape between, then the one to hold beside (HARNESS.md
    1.7); the harness's cables laid between them by the rows before are taped."""
    sequence(
        src,
        "1;EC;WH1;C2.1-C1.1",
        "2;PC;WH1;J8.1.L",
        "3;RC;GR11;J3.1-J4.1",
        "4;T;WH1;J3.1-J4.1-J4.1",
    )
    monkeypatch.chdir(src)
    assert run(src, tmp_path / "cell") == 0
    steps = yaml.safe_load((tmp_path / "cell" / "plan.yaml").read_text())["steps"]
    assert steps[-1] == {
        "skill": "Tape",
        "cable": "WH1",
        "between": ["platform.J3.1", "platform.J4.1"],
        "hold": "platform.J4.1",
    }


def test_a_taping_row_before_its_cables_are_laid(
    src: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    sequence(src, "1;EC;WH1;C2.1-C1.1", "2;PC;WH1;J8.1.L", "3;T;WH1;J3.1-J4.1-J4.1")
    monkeypatch.chdir(src)
    assert run(src, tmp_path / "cell") == 1
    assert capsys.readouterr().err.splitlines()[0] == (
        "Assembly_sequence.csv:4: steps[2].cable: none of WH1's cables is routed before this "
        "step: tape it after the RouteCable that lays it"
    )


def test_a_connector_that_starts_no_harness(
    src: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    with (src / "Components_definition.csv").open("a") as f:
        f.write("Connector;MOL1;111;WH3;White;;;32.9;14.64;46.55;\r\n")
    sequence(src, "1;EC;WH3;C2.1-C1.1")
    monkeypatch.chdir(src)
    assert run(src, tmp_path / "cell") == 1
    assert capsys.readouterr().err.splitlines() == [
        "Assembly_sequence.csv:2: connector 'WH3' starts no harness in WH_configuration.xml "
        '(its harnesses start at CON1, WH1): add its <wiring_harness first_connector="WH3">'
    ]


def test_what_remodel_reads_otherwise_is_a_warning_at_its_line(
    src: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    sequence(src, "2;EC;CON1;C2.1-C1.1", "1;pc;CON1;J8.1.L", "3;RC;CON1;J3.1-J4.1")
    monkeypatch.chdir(src)
    assert run(src, tmp_path / "cell") == 0
    err = capsys.readouterr().err.splitlines()
    assert (
        "Assembly_sequence.csv:3: warning: Order 1 comes after Order 2 (row 2): REMODEL ignores "
        "the Order column and runs the rows in file order; so does the import"
    ) in err
    assert (
        "Assembly_sequence.csv:3: warning: operation 'pc' is read as PC; REMODEL's planner "
        "compares operation types case-sensitively and would not run it"
    ) in err
    steps = yaml.safe_load((tmp_path / "cell" / "plan.yaml").read_text())["steps"]
    assert [s["skill"] for s in steps] == ["PickCable", "PlaceConnector", "RouteCable"]


def test_a_jig_on_the_combs_platform_is_a_warning(
    src: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    ids = src / "combs_ids.wri"
    ids.write_text(ids.read_text().replace("\tC2\t", "\tJ9\t"))
    sequence(src, "1;EC;CON1;J9.1-C1.1")
    monkeypatch.chdir(src)
    assert run(src, tmp_path / "cell") == 0
    assert (
        "combs_ids.wri:3: warning: jig 'J9' is on platform 'combs': REMODEL takes only combs "
        "from combs_ids.wri; the import takes it where it is"
    ) in capsys.readouterr().err.splitlines()


def test_a_message_naming_a_copied_file_names_it_in_src(
    src: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    cad = src / "ATC_cad.x3d"
    cad.write_text(cad.read_text().replace('DEF="ID000003"', 'DEF="ID000002"'))
    monkeypatch.chdir(src)
    assert run(src, tmp_path / "cell") == 1
    err = capsys.readouterr().err
    assert f"(first defined at {src / 'ATC_cad.x3d'}:" in err
    assert ".import-" not in err  # nothing names the staging folder


def test_a_later_folder_imports_and_runs_on_the_simulated_cell(
    src: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Tried as a user would: the folder with its tool changer platform (placed out of the
    way), WH1's top branch routed first (separated from the rest), then the bottom one. The
    default gripper grasps at 4 mm, too wide for these 2.1 mm cables (the plan says so at its
    step); with a 2 mm grasp the plan runs to its end."""
    sequence(src, "1;EC;WH1;C2.1-C1.1", "2;PC;WH1;J8.1.L", "3;RC;GR11;J3.1-J4.1", "4;RC;GR12;J3.1")
    monkeypatch.chdir(src)
    dest = tmp_path / "cell"
    assert run(src, dest, "--pose=250 380 0 0 0 90", "--pose=ATC=-900 0 0 0 0 0") == 0
    cell = dest / "cell.yaml"
    assert cell.read_text().count("grasp: 4}") == 3  # the setup's gripper, and each arm's own
    cell.write_text(cell.read_text().replace("grasp: 4}", "grasp: 2}"))
    out = tmp_path / "run"
    assert main(["run", str(dest / "plan.yaml"), "--out", str(out), "-q"]) == 0
    journal = [line for line in (out / "journal.jsonl").read_text().splitlines() if line]
    assert '"entry": "end"' in journal[-1]
