"""write_files: every file or none, no temporary left behind."""

from __future__ import annotations

import os
import stat
from pathlib import Path

import pytest

from cellengine.outfiles import write_files


def test_writes_every_file_and_returns_their_paths(tmp_path: Path) -> None:
    out = tmp_path / "run"
    paths = write_files(out, {"a.json": "{}\n", "b.html": "<p>é</p>"})
    assert paths == {"a.json": out / "a.json", "b.html": out / "b.html"}
    assert (out / "b.html").read_text(encoding="utf-8") == "<p>é</p>"
    assert sorted(p.name for p in out.iterdir()) == ["a.json", "b.html"]


def test_a_failure_leaves_the_old_files_and_no_temporaries(tmp_path: Path) -> None:
    (tmp_path / "a.json").write_text("old")
    bad = {"a.json": "new", "c.txt": 1}  # the second text is not a str: writing it fails
    with pytest.raises(TypeError):
        write_files(tmp_path, bad)  # type: ignore[dict-item]
    assert (tmp_path / "a.json").read_text() == "old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.json"]


@pytest.mark.parametrize(("umask", "mode"), [(0o022, 0o644), (0o077, 0o600)])
def test_files_get_the_mode_open_gives(tmp_path: Path, umask: int, mode: int) -> None:
    """Not mkstemp's 0600 always: a report is for the cell's team, and the umask decides, as
    for any file the user's tools write."""
    before = os.umask(umask)
    try:
        paths = write_files(tmp_path / "run", {"report.json": "{}"})
    finally:
        os.umask(before)
    assert stat.S_IMODE(paths["report.json"].stat().st_mode) == mode
