"""The run folder: nothing written outside it through a planted link, a folder that is a link
or a file refused, one command at a time, a full file system an error (no traceback)."""

from __future__ import annotations

import errno
import os
from pathlib import Path

import pytest

from cellengine.cli import main
from cellengine.errors import InputError
from cellengine.outfiles import write_files
from cellengine.runfolder import check, open_append, using
from tests.conftest import CELLS

PLAN = CELLS / "cable_routing" / "plan_straight.yaml"


def _run(out: Path, capsys: pytest.CaptureFixture[str]) -> tuple[int, str]:
    code = main(["run", str(PLAN), "--out", str(out), "-q"])
    return code, capsys.readouterr().err


def test_a_planted_journal_link_is_refused_and_its_target_untouched(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    victim = tmp_path / "victim.txt"
    victim.write_text("keep me")
    out = tmp_path / "out"
    out.mkdir()
    (out / "journal.jsonl").symlink_to(victim)
    code, text = _run(out, capsys)
    assert code == 1
    assert text == (
        f"{out / 'journal.jsonl'}: a link in the run folder: it holds only what cellengine "
        "writes; remove the link\n"
    )
    assert victim.read_text() == "keep me"
    assert sorted(p.name for p in out.iterdir()) == ["journal.jsonl"]  # nothing written


def test_a_run_folder_that_is_a_link_or_a_file_is_refused(tmp_path: Path) -> None:
    real = tmp_path / "real"
    real.mkdir()
    (tmp_path / "link").symlink_to(real)
    (tmp_path / "file").write_text("")
    with pytest.raises(InputError) as e:
        check(tmp_path / "link")
    assert str(e.value) == f"{tmp_path / 'link'}: the run folder is a link; give a real folder"
    with pytest.raises(InputError) as e:
        check(tmp_path / "file")
    assert str(e.value) == f"{tmp_path / 'file'}: the run folder is a file, not a folder"


def test_temporary_files_are_not_predictable_and_no_link_is_followed(tmp_path: Path) -> None:
    """The old fixed temporary name, planted as a link, is never written through (the folder
    check refuses the link; without it, mkstemp's names would not meet it)."""
    victim = tmp_path / "victim.txt"
    victim.write_text("keep me")
    out = tmp_path / "out"
    out.mkdir()
    (out / ".report.json.tmp").symlink_to(victim)
    with pytest.raises(InputError, match="a link in the run folder"):
        write_files(out, {"report.json": "{}"})
    assert victim.read_text() == "keep me"
    (out / ".report.json.tmp").unlink()
    (out / "journal.jsonl").symlink_to(victim)
    with pytest.raises(InputError) as e:
        open_append(out / "journal.jsonl")
    assert str(e.value) == f"{out / 'journal.jsonl'}: cannot open journal.jsonl: it is a link"


def test_a_second_command_into_a_folder_in_use_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out"
    with using(out):  # as another process's run would hold it
        code = main(["plan", str(PLAN), "--out", str(out), "-q"])
    assert code == 1
    assert capsys.readouterr().err == (
        f"{out}: another cellengine command is writing this run folder; wait for it to end or "
        "give another --out\n"
    )
    assert sorted(p.name for p in out.iterdir()) == [".lock"]
    assert main(["plan", str(PLAN), "--out", str(out), "-q"]) == 0  # released


def test_a_full_file_system_is_an_error_and_leaves_no_temporaries(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    def full(fd: int) -> None:
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(os, "fsync", full)
    with pytest.raises(InputError) as e:
        write_files(tmp_path, {"a.json": "{}", "b.json": "{}"})
    assert str(e.value) == f"{tmp_path}: cannot write the run folder: No space left on device"
    assert list(tmp_path.iterdir()) == []
