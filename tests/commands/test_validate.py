import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from cellengine.cli import main
from tests.conftest import ROOT

CELL = """\
name: bench
robots:
  left: {model: ur5e, base: {xyz: [0, 0.35, 0]}}
  right: {model: ur5e, base: {xyz: [0, -0.35, 0]}}
"""
OBJECTS = "containers:\n  vial1: {kind: vial, diameter: 0.028, height: 0.06, mass: 0.03}\n"
PLAN = "cell: cell.yaml\nobjects: objects.yaml\nsteps:\n  - {skill: Weigh, object: vial1}\n"


@pytest.fixture
def cell_dir(tmp_path: Path) -> Path:
    (tmp_path / "cell.yaml").write_text(CELL)
    (tmp_path / "objects.yaml").write_text(OBJECTS)
    (tmp_path / "plan.yaml").write_text(PLAN)
    (tmp_path / ".hidden").mkdir()
    (tmp_path / ".hidden" / "ci.yaml").write_text("on: push\n")
    (tmp_path / "other.yaml").write_text("just: data\n")  # not ours: skipped in folders
    return tmp_path


def test_folder_passes(
    cell_dir: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(cell_dir)
    assert main(["validate", "--no-compile", "."]) == 0
    out = capsys.readouterr()
    assert out.out.splitlines() == [
        "cell.yaml: ok (cell)",
        "objects.yaml: ok (objects)",
        "plan.yaml: ok (plan)",
    ]
    assert out.err == "3 file(s) checked, 0 with problems\n"


def test_explicit_unknown_file_fails(
    cell_dir: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(cell_dir)
    assert main(["validate", "other.yaml"]) == 1
    assert capsys.readouterr().out == (
        "other.yaml:1:1: cannot tell what this file is: a cell has 'robots', objects have "
        "'cables', 'harnesses' or 'containers', a plan has 'steps'\n"
    )


def test_formats(
    cell_dir: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(cell_dir)
    (cell_dir / "plan.yaml").write_text(PLAN.replace("object: vial1", "object: vial2"))
    assert main(["validate", "--no-compile", "plan.yaml", "cell.yaml", "--format", "github"]) == 1
    assert capsys.readouterr().out == (
        "::error file=plan.yaml,line=4,col=28::steps[0].object: unknown object 'vial2'; "
        "known: vial1\n"
    )
    assert main(["validate", "--no-compile", "plan.yaml", "cell.yaml", "--format", "json"]) == 1
    report = json.loads(capsys.readouterr().out)
    assert report["ok"] is False
    assert [(f["file"], f["kind"], f["ok"]) for f in report["files"]] == [
        ("plan.yaml", "plan", False),
        ("cell.yaml", "cell", True),
    ]
    assert report["files"][0]["problems"] == [
        {
            "file": "plan.yaml",
            "line": 4,
            "col": 28,
            "message": "steps[0].object: unknown object 'vial2'; known: vial1",
        }
    ]


def test_broken_cell_reported_once(
    cell_dir: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(cell_dir)
    (cell_dir / "cell.yaml").write_text(CELL.replace("ur5e,", "ur6,", 1))
    assert main(["validate", "--no-compile", "."]) == 1
    out = capsys.readouterr()
    assert out.out.splitlines() == [
        "cell.yaml:3:17: robots.left.model: unknown robot model 'ur6'; known: ur10e, ur3e, "
        "ur5, ur5e; or give {urdf: path, tip: link}",
        "objects.yaml: ok (objects)",
        "plan.yaml: not checked: it uses files with problems above",
    ]
    assert out.err == "3 file(s) checked, 2 with problems\n"


def test_usage_errors_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["validate", str(tmp_path / "nope.yaml")]) == 2
    assert capsys.readouterr().err == f"{tmp_path}/nope.yaml: no such file or folder\n"
    with pytest.raises(SystemExit) as e:
        main(["validate", "--format", "xml", str(tmp_path)])
    assert e.value.code == 2


def test_robot_models_are_built(
    cell_dir: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A URDF robot whose tip is not a link fails validation, not only a later run."""
    monkeypatch.chdir(cell_dir)
    (cell_dir / "arm.urdf").write_text(
        '<robot name="a"><link name="base"/><link name="l1"/>'
        '<joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>'
        '<axis xyz="0 0 1"/><limit lower="-1" upper="1" velocity="1" effort="1"/></joint>'
        "</robot>"
    )
    (cell_dir / "cell.yaml").write_text(
        CELL.replace("right: {model: ur5e,", "right: {model: {urdf: arm.urdf, tip: l9},")
    )
    assert main(["validate", "cell.yaml"]) == 1
    assert capsys.readouterr().out == (
        "cell.yaml:4:40: robots.right.model.tip: unknown link 'l9' in arm.urdf; known: base, l1\n"
    )


def validate_in_subprocess(folder: Path, *args: str) -> subprocess.CompletedProcess[str]:
    """`cellengine validate` in a fresh process with a timeout: a hang fails, not hangs."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run(
        [sys.executable, "-m", "cellengine", "validate", "--no-compile", *args],
        cwd=folder,
        env=env,
        capture_output=True,
        text=True,
        timeout=60,
    )


def test_folder_skips_what_is_not_a_regular_file(cell_dir: Path) -> None:
    """A FIFO named *.yaml would block the open forever; a folder named x.yaml is no file."""
    os.mkfifo(cell_dir / "fifo.yaml")
    (cell_dir / "x.yaml").mkdir()
    result = validate_in_subprocess(cell_dir, ".")
    assert result.stdout.splitlines() == [
        "cell.yaml: ok (cell)",
        "objects.yaml: ok (objects)",
        "plan.yaml: ok (plan)",
    ]
    assert (result.returncode, result.stderr) == (0, "3 file(s) checked, 0 with problems\n")


def test_a_named_fifo_or_device_is_an_error(cell_dir: Path) -> None:
    os.mkfifo(cell_dir / "fifo.yaml")
    result = validate_in_subprocess(cell_dir, "fifo.yaml", "/dev/null")
    assert result.stdout.splitlines() == [
        "fifo.yaml: a named pipe (FIFO), not a regular file",
        "/dev/null: a device, not a regular file",
    ]
    assert result.returncode == 1


def test_symlink_loops_are_errors_at_the_file(
    cell_dir: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(cell_dir)
    (cell_dir / "loop1.yaml").symlink_to("loop2.yaml")
    (cell_dir / "loop2.yaml").symlink_to("loop1.yaml")
    assert main(["validate", "--no-compile", "."]) == 1
    assert capsys.readouterr().out.splitlines() == [
        "cell.yaml: ok (cell)",
        "loop1.yaml: cannot read: a loop of symbolic links",
        "loop2.yaml: cannot read: a loop of symbolic links",
        "objects.yaml: ok (objects)",
        "plan.yaml: ok (plan)",
    ]
    assert main(["validate", "loop1.yaml"]) == 1  # named: an error, not "no such file"
    assert capsys.readouterr().out == "loop1.yaml: cannot read: a loop of symbolic links\n"


def test_references_to_a_symlink_loop_or_a_fifo(cell_dir: Path) -> None:
    (cell_dir / "loop.yaml").symlink_to("loop.yaml")
    os.mkfifo(cell_dir / "fifo.yaml")
    (cell_dir / "plan.yaml").write_text(PLAN.replace("cell.yaml", "loop.yaml"))
    result = validate_in_subprocess(cell_dir, "plan.yaml")
    assert result.stdout.splitlines() == [
        "plan.yaml:1:7: file reference 'loop.yaml' cannot be used: a loop of symbolic links",
    ]
    (cell_dir / "plan.yaml").write_text(PLAN.replace("objects.yaml", "fifo.yaml"))
    result = validate_in_subprocess(cell_dir, "plan.yaml")
    assert result.stdout.splitlines() == [
        "plan.yaml:2:10: file reference 'fifo.yaml' is a named pipe (FIFO), not a regular file",
    ]
    assert result.returncode == 1


def test_plan_and_show_name_a_fifo_for_what_it_is(cell_dir: Path) -> None:
    """Not "no such file" (exit 2): the file is there, and is not one."""
    os.mkfifo(cell_dir / "fifo.yaml")
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    for argv in (["plan", "fifo.yaml", "-q", "--out", "out"], ["show", "fifo.yaml"]):
        result = subprocess.run(
            [sys.executable, "-m", "cellengine", *argv],
            cwd=cell_dir,
            env=env,
            capture_output=True,
            text=True,
            timeout=60,
        )
        assert result.stderr == "fifo.yaml: a named pipe (FIFO), not a regular file\n"
        assert result.returncode == 1


def test_control_characters_from_files_are_escaped(
    cell_dir: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A key can carry ESC (terminal colours) and a newline starting a GitHub workflow
    command: every message shows them escaped, one problem per line."""
    monkeypatch.chdir(cell_dir)
    (cell_dir / "cell.yaml").write_text(CELL + '"\\e[31mred\\n::error::x": 1\n')
    assert main(["validate", "--no-compile", "cell.yaml"]) == 1
    assert capsys.readouterr().out == (
        "cell.yaml:5:1: unknown key '\\x1b[31mred\\n::error::x'; known: camera, clearance, "
        "driver, name, obstacles, platforms, robots, speed, tcp_speed, tools, units, "
        "work_clearance, zones\n"
    )
    assert main(["validate", "--no-compile", "cell.yaml", "--format", "github"]) == 1
    assert capsys.readouterr().out == (
        "::error file=cell.yaml,line=5,col=1::unknown key '\\x1b[31mred\\n::error::x'; known: "
        "camera, clearance, driver, name, obstacles, platforms, robots, speed, tcp_speed, tools, "
        "units, work_clearance, zones\n"
    )
    assert main(["validate", "--no-compile", "cell.yaml", "--format", "json"]) == 1
    problem = json.loads(capsys.readouterr().out)["files"][0]["problems"][0]
    assert problem["message"].startswith("unknown key '\x1b[31mred\n::error::x'")  # the data


def test_file_names_are_escaped(
    cell_dir: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(cell_dir)
    (cell_dir / "cell.yaml").rename(cell_dir / "cell\x1b[2J\n::error::x.yaml")
    assert main(["validate", "--no-compile", "cell\x1b[2J\n::error::x.yaml"]) == 0
    assert capsys.readouterr().out == "cell\\x1b[2J\\n::error::x.yaml: ok (cell)\n"


def test_warnings_in_every_format(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A CAD part no map row names: a warning, once (the plan repeats its cell's), and the
    files still pass."""
    monkeypatch.chdir(ROOT / "tests" / "data" / "bad" / "x3d_unmapped_part")
    message = (
        "CAD part 'Stray' is in no row of map.csv: it is checked as the obstacle "
        "'routing.Stray'; give it a row (its model, or 'obstacle' or 'ignore')"
    )
    assert main(["validate", "--no-compile", "cell.yaml", "--format", "github"]) == 0
    assert capsys.readouterr().out == (f"::warning file=routing/routing.x3d,line=15::{message}\n")
    assert main(["validate", "--no-compile", "cell.yaml", "--format", "json"]) == 0
    (entry,) = json.loads(capsys.readouterr().out)["files"]
    assert (entry["ok"], entry["warnings"]) == (
        True,
        [{"file": "routing/routing.x3d", "line": 15, "col": None, "message": message}],
    )


def test_an_arm_without_home_is_named_at_its_robot(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    shutil.copytree(ROOT / "cells" / "cable_routing", tmp_path / "cell")
    monkeypatch.chdir(tmp_path / "cell")
    text = Path("cell.yaml").read_text()
    i = text.index("    home:", text.index("  right:"))
    Path("cell.yaml").write_text(text[:i] + text[text.index("\n", i) + 1 :])
    assert main(["validate", "plan_straight.yaml"]) == 1
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith("cell.yaml:")
    assert out[0].endswith(
        ": robots.right.home is not given: a program needs every arm's start configuration"
    )
