"""The compile cache: an entry used only while its files are unchanged and it checks out."""

from __future__ import annotations

import json
import os
import time
from pathlib import Path

import pytest

import cellengine.cache as cache_module
from cellengine.cache import Cache, default_folder, engine_fingerprint
from cellengine.info.files import read_capped, real, recording

REQUEST = {"command": "validate", "plan": "plan.yaml"}


def _stored(tmp_path: Path, text: str = "a: 1\n") -> tuple[Cache, Path]:
    f = tmp_path / "cell" / "cell.yaml"
    f.parent.mkdir(exist_ok=True)
    f.write_text(text)
    with recording() as reads:
        read_capped(f, "yaml")
    cache = Cache(tmp_path / "cache")
    cache.store(REQUEST, reads, {"ok": True}, {"out": b"x" * 1000})
    return cache, f


def _entry(cache: Cache) -> Path:
    (entry,) = cache.folder.glob("*/*.json")
    return entry


def test_a_stored_result_is_found_with_its_blobs(tmp_path: Path) -> None:
    cache, _ = _stored(tmp_path)
    hit = cache.lookup(REQUEST, blobs=("out",))
    assert hit is not None and hit.result == {"ok": True} and hit.blobs == {"out": b"x" * 1000}
    assert cache.lookup({**REQUEST, "plan": "other.yaml"}) is None


def test_a_changed_or_missing_file_is_a_miss(tmp_path: Path) -> None:
    cache, f = _stored(tmp_path)
    f.write_text("a: 2\n")
    assert cache.lookup(REQUEST) is None
    f.write_text("a: 1\n")  # the same content again: the same result
    assert cache.lookup(REQUEST) is not None
    f.unlink()
    assert cache.lookup(REQUEST) is None


def test_a_corrupt_entry_or_blob_is_a_miss(tmp_path: Path) -> None:
    cache, _ = _stored(tmp_path)
    entry = _entry(cache)
    data = json.loads(entry.read_text())
    data["body"]["result"]["ok"] = False  # edited without its checksum
    entry.write_text(json.dumps(data))
    assert cache.lookup(REQUEST) is None
    entry.write_bytes(b"\x00garbage")
    assert cache.lookup(REQUEST) is None

    cache, _ = _stored(tmp_path)
    (blob,) = cache.folder.glob("*/*.out.z")
    blob.write_bytes(blob.read_bytes()[:-3])
    assert cache.lookup(REQUEST) is not None  # the result alone does not need the blob
    assert cache.lookup(REQUEST, blobs=("out",)) is None


def test_a_foreign_entry_is_a_miss(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    cache, _ = _stored(tmp_path)
    other = {**REQUEST, "plan": "other.yaml"}
    cache.store(other, {}, {"ok": False})
    # another request's entry (checksum and all) put where this request's is looked for
    (mine,) = [e for e in cache.folder.glob("*/*.json") if "other.yaml" not in e.read_text()]
    (theirs,) = [e for e in cache.folder.glob("*/*.json") if e != mine]
    mine.write_bytes(theirs.read_bytes())
    assert cache.lookup(REQUEST) is None

    cache, _ = _stored(tmp_path)
    monkeypatch.setattr(cache_module, "engine_fingerprint", lambda: "another engine")
    assert cache.lookup(REQUEST) is None


def test_recording_sees_every_read_and_nests(tmp_path: Path) -> None:
    a, b = tmp_path / "a.yaml", tmp_path / "b.yaml"
    a.write_text("a: 1\n")
    b.write_text("b: 1\n")
    with recording() as outer:
        read_capped(a, "yaml")
        with recording() as inner:
            read_capped(b, "yaml")
    assert set(inner) == {real(b)}
    assert set(outer) == {real(a), real(b)}
    assert outer[real(a)] == cache_module._file_digest(a)


def test_an_unwritable_folder_is_said_once(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("")
    cache = Cache(blocker / "cache")  # a folder under a file cannot be made
    cache.store(REQUEST, {}, {})
    cache.store(REQUEST, {}, {})
    err = capsys.readouterr().err
    assert err.count("warning: the compile cache in") == 1
    assert cache.lookup(REQUEST) is None


def test_the_folder_and_the_engine(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("CELLENGINE_CACHE_DIR", str(tmp_path))
    assert default_folder() == tmp_path
    monkeypatch.delenv("CELLENGINE_CACHE_DIR")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert default_folder() == tmp_path / "xdg" / "cellengine"
    assert len(engine_fingerprint()) == 64


def _fill(folder: Path, n: int, blob: int) -> list[dict[str, str]]:
    """n entries, each with a blob of ``blob`` bytes (compressed to about that: random
    bytes), the first stored first and last used first."""
    requests = [{"command": "plan", "plan": f"p{k}.yaml"} for k in range(n)]
    cache = Cache(folder)
    cache._trimmed = True  # filled without trimming
    for k, r in enumerate(requests):
        cache.store(r, {}, {"k": k}, {"out": os.urandom(blob)})
        entry = cache._path(r)
        os.utime(entry, (time.time() - 1000 + k, time.time() - 1000 + k))
    return requests


def test_past_its_size_the_least_recently_used_entries_go(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    folder = tmp_path / "cache"
    requests = _fill(folder, 10, 100_000)  # about 1 MB
    assert Cache(folder).lookup(requests[0], ("out",)) is not None  # used now: the newest
    dead = folder / "00" / ".tmp-died"
    dead.parent.mkdir(exist_ok=True)
    dead.write_bytes(b"half")
    then = time.time() - 2 * cache_module.TMP_AGE
    os.utime(dead, (then, then))
    monkeypatch.setenv(cache_module.MAX_ENV, "0.5")  # 524 288 bytes: down to 419 430
    cache = Cache(folder)
    cache.store({"command": "validate", "plan": "new.yaml"}, {}, {"new": True})
    kept = [k for k, r in enumerate(requests) if cache.lookup(r, ("out",)) is not None]
    assert kept == [0, 7, 8, 9]  # the one just used and the three last stored
    assert not dead.exists()
    blobs = list(folder.glob("*/*.z"))
    assert len(blobs) == 4  # each entry's blob went with it
    assert all((p.parent / (p.name.split(".")[0] + ".json")).exists() for p in blobs)
    sizes = sum(p.stat().st_size for p in folder.glob("*/*"))
    assert sizes <= 0.8 * 0.5 * (1 << 20) + 10_000  # and the entry just stored


def test_under_its_size_nothing_goes_and_a_bad_size_is_the_default(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    folder = tmp_path / "cache"
    requests = _fill(folder, 3, 1000)
    for bad in ("nan", "inf"):
        monkeypatch.setenv(cache_module.MAX_ENV, bad)
        assert cache_module.max_bytes() == cache_module.DEFAULT_MAX_MB << 20
    monkeypatch.setenv(cache_module.MAX_ENV, "a lot")
    assert cache_module.max_bytes() == cache_module.DEFAULT_MAX_MB << 20
    cache = Cache(folder)
    cache.store({"command": "validate", "plan": "new.yaml"}, {}, {"new": True})
    assert all(cache.lookup(r, ("out",)) is not None for r in requests)
