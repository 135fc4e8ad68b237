"""`cellengine validate --jobs N` and the compile cache: the same output as one process, a
killed worker reported for its plan alone, and plans compiled again only when their files
change."""

from __future__ import annotations

import os
import shutil
import signal
import time
from pathlib import Path

import pytest

from cellengine.cli import main
from cellengine.commands import validate
from tests.conftest import CELLS

TOO_SHORT = (
    "b/plan_straight.yaml:15:5: steps[2] RouteCable routing.guide3: cable 'cable1' is too "
    "short for the route: this guide needs 356.9 mm (278.5 mm laid from the connector's rear "
    "face to the approach point, R_cable 68.0 mm slid past it, 1.4 mm pulled to tension, "
    "9.0 mm for the fingers to hold) but the cable is 300.0 mm long"
)


@pytest.fixture
def cells(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """a/ and b/: the reference cell with its straight plan; b's cable is too short for it;
    c/ a plan whose cell does not parse."""
    for name in ("a", "b"):
        shutil.copytree(CELLS / "cable_routing", tmp_path / name)
        for plan in ("plan_one_turn.yaml", "plan_two_turns.yaml"):
            (tmp_path / name / plan).unlink()
    objects = tmp_path / "b" / "objects.yaml"
    objects.write_text(objects.read_text().replace("    length: 650 ", "    length: 300 "))
    (tmp_path / "c").mkdir()
    (tmp_path / "c" / "cell.yaml").write_text("robots: [\n")
    (tmp_path / "c" / "plan.yaml").write_text("cell: cell.yaml\nsteps: []\n")
    monkeypatch.chdir(tmp_path)
    return tmp_path


def _validate(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, list[str]]:
    code = main(["validate", *args, "a", "b", "c"])
    return code, capsys.readouterr().out.splitlines()


def _counting(monkeypatch: pytest.MonkeyPatch) -> list[str]:
    compiled: list[str] = []
    original = validate.Checker.compile

    def counted(self: validate.Checker, loaded):  # type: ignore[no-untyped-def]
        compiled.append(loaded.plan.file.parent.name)
        original(self, loaded)

    monkeypatch.setattr(validate.Checker, "compile", counted)
    return compiled


def test_two_workers_print_what_one_process_prints(
    cells: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    one = _validate(capsys, "--jobs", "1", "--no-cache")
    two = _validate(capsys, "--jobs", "2", "--no-cache")
    assert one == two
    code, out = two
    assert code == 1
    assert "a/plan_straight.yaml: ok (plan)" in out
    assert TOO_SHORT in out
    assert out[-1].startswith("c/plan.yaml")  # the broken cell did not stop the others
    assert out.index("a/cell.yaml: ok (cell)") < out.index(TOO_SHORT)  # the files' order


def test_a_killed_worker_is_its_plan_only(
    cells: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    original = validate.Checker.compile

    def dies_on_b(self: validate.Checker, loaded):  # type: ignore[no-untyped-def]
        if loaded.plan.file.parent.name == "b":
            os.kill(os.getpid(), signal.SIGKILL)
        original(self, loaded)

    monkeypatch.setattr(validate.Checker, "compile", dies_on_b)
    code, out = _validate(capsys, "--jobs", "2", "--no-cache")
    assert code == 1
    assert "b/plan_straight.yaml: not checked: its worker process was killed by SIGKILL" in out
    assert "a/plan_straight.yaml: ok (plan)" in out
    assert "b/cell.yaml: ok (cell)" in out  # the files after it, in the new worker


def test_the_cache_compiles_only_what_changed(
    cells: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    compiled = _counting(monkeypatch)
    first = _validate(capsys, "--jobs", "1")
    assert compiled == ["a", "b"]
    assert TOO_SHORT in first[1]
    assert _validate(capsys, "--jobs", "1") == first  # the failure too, from the cache
    assert compiled == ["a", "b"]

    x3d = cells / "a" / "routing" / "routing.x3d"  # guide3 2 mm along the route
    x3d.write_text(x3d.read_text().replace('"150.000000,370.000000,', '"150.000000,372.000000,'))
    assert _validate(capsys, "--jobs", "1") == first
    assert compiled == ["a", "b", "a"]
    _validate(capsys, "--jobs", "1", "--no-cache")
    assert compiled == ["a", "b", "a", "a", "b"]


def test_a_cache_folder_given_is_used(
    cells: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    compiled = _counting(monkeypatch)
    _validate(capsys, "-j", "1", "--cache-dir", "kept")
    _validate(capsys, "-j", "1", "--cache-dir", "kept")
    assert compiled == ["a", "b"]
    assert list((cells / "kept").glob("*/*.json"))


def test_jobs_must_be_positive(cells: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["validate", "--jobs", "0", "a"]) == 2
    assert capsys.readouterr().err == "--jobs must be at least 1, got 0\n"


def test_a_plan_past_the_timeout_is_said_and_the_rest_checked(
    cells: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    original = validate.Checker.compile

    def slow_on_b(self: validate.Checker, loaded):  # type: ignore[no-untyped-def]
        if loaded.plan.file.parent.name == "b":
            time.sleep(60)
        original(self, loaded)

    monkeypatch.setattr(validate.Checker, "compile", slow_on_b)
    code, out = _validate(capsys, "--jobs", "1", "--no-cache", "--timeout", "10")
    assert code == 1
    assert "b/plan_straight.yaml: not checked: it took longer than the 10 s allowed" in out
    assert "a/plan_straight.yaml: ok (plan)" in out


@pytest.mark.parametrize("value", ["0", "-1", "inf", "x"])
def test_the_timeout_is_seconds_above_0(
    cells: Path, capsys: pytest.CaptureFixture[str], value: str
) -> None:
    with pytest.raises(SystemExit) as e:
        main(["validate", "--timeout", value, "a"])
    assert e.value.code == 2
    assert "--timeout: " in capsys.readouterr().err
