"""The compile cache: a result reused while every file it was computed from is unchanged.

An entry is found by its request (what was asked: the command, its options, the plan's path
and the working folder) and the engine's fingerprint, and holds the content digest of every
file read to compute it (:func:`cellengine.info.files.recording`), like a depfile. It is
used only when those files still have those digests, so a moved guide recompiles the plans
of its cell and no other. Entries are checked, never trusted: one that does not parse, whose
own checksum does not match, or that was made for another request or engine, is a miss.
The folder must be as trusted as the cell files themselves (an entry is a compiled program).

The folder is kept under $CELLENGINE_CACHE_MAX_MB (default 2048): a command that stores
entries first removes the least recently used ones (a hit counts as a use) down to 80 % of
that, as ccache does, so a CI that keeps the folder between runs does not see it grow
without end (each engine change, another plan path or --out, is another entry).
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import math
import os
import sys
import tempfile
import time
import zlib
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cache
from importlib import metadata
from pathlib import Path
from typing import Any

from cellengine import __version__
from cellengine.info.files import Reads

CACHE_ENV = "CELLENGINE_CACHE_DIR"
MAX_ENV = "CELLENGINE_CACHE_MAX_MB"
DEFAULT_MAX_MB = 2048
TMP_AGE = 3600.0  # s: a temporary file this old is a write that died, not one in progress
FORMAT = "cellengine.cache/1"
MAX_ENTRY_BYTES = 16 << 20  # an entry's JSON (blobs are apart); larger is not ours
# the libraries whose behaviour a compiled program depends on
LIBRARIES = ("pin", "coal", "ompl", "ruckig", "numpy", "trimesh", "lxml", "pydantic", "PyYAML")


def default_folder() -> Path:
    """$CELLENGINE_CACHE_DIR, else $XDG_CACHE_HOME/cellengine, else ~/.cache/cellengine."""
    if env := os.environ.get(CACHE_ENV):
        return Path(env)
    xdg = os.environ.get("XDG_CACHE_HOME")
    return (Path(xdg) if xdg else Path.home() / ".cache") / "cellengine"


@cache
def engine_fingerprint() -> str:
    """The engine's files (its modules, the skills, the robot models it ships), the skill
    families installed and the libraries' versions: any change is another engine."""
    h = hashlib.sha256(__version__.encode())
    root = Path(__file__).resolve().parent
    for folder, dirs, files in os.walk(root, followlinks=True):  # skills/ is a link
        dirs[:] = sorted(d for d in dirs if d != "__pycache__")
        for name in sorted(files):
            path = Path(folder, name)
            h.update(str(path.relative_to(root)).encode())
            h.update(hashlib.sha256(path.read_bytes()).digest())
    for ep in sorted(metadata.entry_points(group="cellengine.skills"), key=lambda e: e.name):
        dist = f"{ep.dist.name} {ep.dist.version}" if ep.dist else ""
        h.update(f"{ep.name}={ep.value} {dist}".encode())
    for name in LIBRARIES:
        try:
            h.update(f"{name}=={metadata.version(name)}".encode())
        except metadata.PackageNotFoundError:
            h.update(f"{name} absent".encode())
    return h.hexdigest()


@dataclass(frozen=True)
class Hit:
    """A usable entry: its result and, by name, the blobs stored with it."""

    result: dict[str, Any]
    blobs: dict[str, bytes]


class Cache:
    """The entries under ``folder``."""

    def __init__(self, folder: Path) -> None:
        self.folder = folder
        self._unwritable = False  # said once
        self._trimmed = False  # once per process: a walk of the folder is not free

    def lookup(self, request: Mapping[str, Any], blobs: tuple[str, ...] = ()) -> Hit | None:
        """The entry for ``request`` when every file it read is unchanged and it checks out
        (with ``blobs``, each of them too); else None."""
        path = self._path(request)
        try:
            entry = json.loads(_read(path, MAX_ENTRY_BYTES))
            body = entry["body"]
            if entry["check"] != _digest(body) or body["format"] != FORMAT:
                return None
            if body["request"] != _canonical(request) or body["engine"] != engine_fingerprint():
                return None  # another request hashed alike, or another engine's
            if any(_file_digest(Path(f)) != d for f, d in body["reads"].items()):
                return None
            got = {}
            for name in blobs:
                data = zlib.decompress(_read(path.with_suffix(f".{name}.z"), None))
                if hashlib.sha256(data).hexdigest() != body["blobs"][name]:
                    return None
                got[name] = data
            _touch(path)
            return Hit(dict(body["result"]), got)
        except (OSError, ValueError, KeyError, TypeError, AttributeError, zlib.error):
            return None  # absent, unreadable, foreign or corrupt: compiled again

    def store(
        self,
        request: Mapping[str, Any],
        reads: Reads,
        result: Mapping[str, Any],
        blobs: Mapping[str, bytes] | None = None,
    ) -> None:
        """Keep ``result`` (JSON data) for ``request``, computed from the files ``reads``.
        A cache that cannot be written is said once and otherwise ignored."""
        path = self._path(request)
        blobs = blobs or {}
        body = {
            "format": FORMAT,
            "request": _canonical(request),
            "engine": engine_fingerprint(),
            "reads": {str(f): d for f, d in sorted(reads.items()) if not _engines(f)},
            "result": result,
            "blobs": {n: hashlib.sha256(b).hexdigest() for n, b in blobs.items()},
        }
        try:
            if not self._trimmed:
                self._trimmed = True
                trim(self.folder, max_bytes())
            path.parent.mkdir(parents=True, exist_ok=True)
            for name, data in blobs.items():  # before the entry that vouches for them
                _write(path.with_suffix(f".{name}.z"), zlib.compress(data, 1))
            _write(path, json.dumps({"check": _digest(body), "body": body}).encode())
        except OSError as e:
            if not self._unwritable:
                self._unwritable = True
                print(
                    f"warning: the compile cache in {self.folder} is not written: {e}",
                    file=sys.stderr,
                )

    def _path(self, request: Mapping[str, Any]) -> Path:
        key = hashlib.sha256(json.dumps(_canonical(request)).encode()).hexdigest()
        return self.folder / key[:2] / f"{key}.json"


def max_bytes() -> int:
    """$CELLENGINE_CACHE_MAX_MB in bytes (a bad value is the default: a cache setting
    never stops a compile)."""
    try:
        mb = float(os.environ.get(MAX_ENV, DEFAULT_MAX_MB))
    except ValueError:
        mb = DEFAULT_MAX_MB
    if not math.isfinite(mb):  # "nan", "inf"
        mb = DEFAULT_MAX_MB
    return int(max(mb, 0.0) * (1 << 20))


def trim(folder: Path, limit: int) -> None:
    """Past ``limit`` bytes, remove whole entries (the JSON and its blobs), least recently
    used first, down to 80 % of it; and temporary files left by writes that died."""
    entries: dict[Path, list[Path]] = {}
    total, now = 0, time.time()
    for path in folder.glob("??/*"):
        try:
            st = path.stat()
        except OSError:
            continue
        if path.name.startswith(".tmp-"):
            if now - st.st_mtime > TMP_AGE:
                with contextlib.suppress(OSError):  # trimming never stops a store
                    path.unlink()
            continue
        total += st.st_size
        entries.setdefault(path.with_name(path.name.split(".", 1)[0] + ".json"), []).append(path)
    if total <= limit:
        return
    for entry in sorted(entries, key=_used):
        for path in entries[entry]:
            try:
                size = path.stat().st_size
                path.unlink()
                total -= size
            except OSError:
                continue
        if total <= 0.8 * limit:
            return


def _used(entry: Path) -> float:
    try:
        return entry.stat().st_mtime
    except OSError:
        return 0.0  # blobs without their entry: unusable, first to go


def _touch(path: Path) -> None:
    with contextlib.suppress(OSError):  # a read-only cache is still a cache
        os.utime(path)


def _engines(path: Path) -> bool:
    """Whether ``path`` is one of the engine's own files (a robot model it ships): the
    fingerprint covers it, and another machine's engine has it elsewhere."""
    return any(path.is_relative_to(root) for root in _engine_roots())


def _engine_roots() -> tuple[Path, ...]:
    package = Path(__file__).resolve().parent
    return (package, (package / "skills").resolve())


def _canonical(request: Mapping[str, Any]) -> Any:
    return json.loads(json.dumps(request, sort_keys=True))


def _digest(body: Any) -> str:
    return hashlib.sha256(json.dumps(body, sort_keys=True).encode()).hexdigest()


def _file_digest(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        while chunk := f.read(1 << 20):
            h.update(chunk)
    return h.hexdigest()


def _read(path: Path, cap: int | None) -> bytes:
    with open(path, "rb") as f:
        data = f.read() if cap is None else f.read(cap + 1)
    if cap is not None and len(data) > cap:
        raise ValueError("entry too large")
    return data


def _write(path: Path, data: bytes) -> None:
    """All or nothing: a reader never sees half an entry."""
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".tmp-")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
