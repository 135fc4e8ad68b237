"""write_files: every file or none, no temporary left behind."""

from __future__ import annotations

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
