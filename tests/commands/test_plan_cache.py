"""`cellengine plan` and the compile cache: the same files give the same outputs without a
compile; a changed file, a changed option or a damaged entry compiles again."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

import cellengine.pipeline
from cellengine.cli import main
from tests.conftest import CELLS

OUTPUTS = ("trajectory.json", "report.json", "report.html")


@pytest.fixture
def cell(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    shutil.copytree(CELLS / "cable_routing", tmp_path / "cell")
    monkeypatch.chdir(tmp_path / "cell")
    return tmp_path / "cell"


def _counting(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    calls: list[int] = []
    original = cellengine.pipeline.compile_plan

    def counted(*args, **kwargs):  # type: ignore[no-untyped-def]
        calls.append(1)
        return original(*args, **kwargs)

    monkeypatch.setattr(cellengine.pipeline, "compile_plan", counted)
    return calls


def _plan(capsys: pytest.CaptureFixture[str], out: str, *options: str) -> list[str]:
    assert main(["plan", "plan_straight.yaml", "--out", out, "-q", *options]) == 0
    return capsys.readouterr().out.splitlines()


def _texts(out: str) -> list[bytes]:
    return [(Path(out) / name).read_bytes() for name in OUTPUTS]


def test_the_same_files_give_the_same_outputs_without_compiling(
    cell: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    calls = _counting(monkeypatch)
    _plan(capsys, "one")
    assert main(["plan", "plan_straight.yaml", "--out", "two"]) == 0
    assert len(calls) == 1
    out = capsys.readouterr().out.splitlines()
    assert out[0].endswith("s of motion (split) (from the compile cache)")
    assert out[1] == "report: two/report.html"
    assert _texts("one") == _texts("two")

    _plan(capsys, "three", "--execution", "sync")  # another option: compiled
    assert len(calls) == 2
    _plan(capsys, "four", "--no-cache")
    assert len(calls) == 3
    assert _texts("four")[0] == _texts("one")[0]


def test_a_changed_file_or_a_damaged_entry_compiles_again(
    cell: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    calls = _counting(monkeypatch)
    _plan(capsys, "one")
    # the cache folder is the test's own (conftest), found from the environment
    folder = Path(os.environ["CELLENGINE_CACHE_DIR"])
    (blob,) = folder.glob("*/*.trajectory.json.z")
    blob.write_bytes(blob.read_bytes()[:100])
    _plan(capsys, "two")
    assert len(calls) == 2
    assert _texts("two")[0] == _texts("one")[0]  # (the report has the compile's own time)

    _plan(capsys, "three")
    assert len(calls) == 2
    objects = cell / "objects.yaml"
    objects.write_text(objects.read_text().replace("color: grey", "color: black"))
    _plan(capsys, "four")
    assert len(calls) == 3
