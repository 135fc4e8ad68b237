"""Untrusted file references: resolved inside the cell's folder, read with size caps."""

from __future__ import annotations

import errno
import hashlib
import os
import re
import stat
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from contextvars import ContextVar
from pathlib import Path

from cellengine.errors import InputError

# Caps per kind of file, in bytes. Real CAD exports are large; YAML written by people is not.
MAX_BYTES = {
    "yaml": 1 << 20,
    "xml": 64 << 20,
    "x3d": 64 << 20,
    "csv": 8 << 20,
    "urdf": 16 << 20,
    "mesh": 64 << 20,
    "image": 64 << 20,  # a camera's picture (PNG, JPEG, ...)
}

# Opening a FIFO for reading waits for a writer; without blocking it opens, and is refused.
_NONBLOCK = getattr(os, "O_NONBLOCK", 0)

_SCHEME = re.compile(r"^[A-Za-z][A-Za-z0-9+.-]*:")


def resolve_inside(
    root: Path, ref: str, file: Path | str, line: int | None = None, col: int | None = None
) -> Path:
    """Resolve ``ref`` (written in ``file``) against ``root``'s folder; refuse anything
    outside it, any URL scheme, and symlinks leading out."""
    where = (file, line, col)
    if not isinstance(ref, str) or not ref.strip():
        raise InputError.at("empty file reference", *where)
    if _SCHEME.match(ref) and not re.match(r"^[A-Za-z]:[\\/]", ref):
        raise InputError.at(
            f"file reference '{ref}' is a URL; only paths inside the cell folder are allowed",
            *where,
        )
    if "\0" in ref:  # YAML's "\0" escape; no file system takes it
        raise InputError.at(f"file reference {_shown(ref)} contains a NUL character", *where)
    try:
        base = real(root)
        target = real(base / ref)
        if not target.is_relative_to(base):
            link = Path(os.path.normpath(base / ref)).is_relative_to(base)
            how = "is a link that leads" if link else "points"
            raise InputError.at(
                f"file reference {_shown(ref)} {how} outside the cell folder", *where
            )
        try:
            mode = target.stat().st_mode
        except (FileNotFoundError, NotADirectoryError):
            raise InputError.at(
                f"file {_shown(ref)} not found (looked for {target})", *where
            ) from None
    except OSError as e:  # a name too long for the file system, a loop of links
        raise InputError.at(
            f"file reference {_shown(ref)} cannot be used: {reason(e)}", *where
        ) from None
    if stat.S_ISDIR(mode):
        raise InputError.at(f"file reference {_shown(ref)} is a folder, not a file", *where)
    if not stat.S_ISREG(mode):
        raise InputError.at(
            f"file reference {_shown(ref)} is {special(mode)}, not a regular file", *where
        )
    return target


def real(path: Path) -> Path:
    """``path`` with its links followed, as ``Path.resolve()``; but a loop of links is left
    for opening the file to report (as OSError ELOOP), where Python 3.11's resolve raises
    RuntimeError."""
    return Path(os.path.realpath(path))


def reason(e: OSError) -> str:
    """Why the system refused a path, in a user's words."""
    return "a loop of symbolic links" if e.errno == errno.ELOOP else str(e.strerror or e)


def special(mode: int) -> str:
    """What a file that is not a regular file is, for messages."""
    if stat.S_ISDIR(mode):
        return "a folder"
    if stat.S_ISFIFO(mode):
        return "a named pipe (FIFO)"
    if stat.S_ISSOCK(mode):
        return "a socket"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    return "a special file"


def _shown(ref: str) -> str:
    return repr(ref) if len(ref) <= 80 else repr(ref[:77] + "...")


def read_capped(
    path: Path,
    kind: str,
    file: Path | str | None = None,
    line: int | None = None,
    col: int | None = None,
) -> bytes:
    """Read a whole regular file, refusing before reading anything else (a FIFO would block,
    a device never end) or a file larger than its kind's cap."""
    cap = MAX_BYTES[kind]
    # at the place that names the file, naming it; else at the file itself
    where, name = ((file, line, col), f" '{path}'") if file else ((path,), "")
    try:
        fd = os.open(path, os.O_RDONLY | _NONBLOCK)
    except OSError as e:
        raise InputError.at(f"cannot read{name}: {reason(e)}", *where) from None
    try:
        st = os.fstat(fd)  # of what was opened: a file swapped in since cannot slip through
        if not stat.S_ISREG(st.st_mode):
            what = f"{special(st.st_mode)}, not a regular file"
            raise InputError.at(f"'{path}' is {what}" if file else what, *where)
        if st.st_size > cap:
            raise InputError.at(
                f"file is {st.st_size} bytes, more than the {cap}-byte limit for {kind} files",
                path,
            )
        with open(fd, "rb", closefd=False) as f:  # (io.open refuses a folder's fd)
            data = f.read(cap + 1)
    finally:
        os.close(fd)
    if len(data) > cap:  # grew while reading
        raise InputError.at(f"file is more than the {cap}-byte limit for {kind} files", path)
    if _recordings.get():
        noted({real(path): hashlib.sha256(data).hexdigest()})
    return data


# What the open recordings have seen read: each file's real path and content digest.
Reads = dict[Path, str]
_recordings: ContextVar[tuple[Reads, ...]] = ContextVar("recordings", default=())


@contextmanager
def recording() -> Iterator[Reads]:
    """Every file read (by :func:`read_capped`) inside the block, with the digest of what
    was read: what a result computed there depends on (a compile cache's key). Nested
    recordings each see the reads of the blocks inside them."""
    reads: Reads = {}
    token = _recordings.set((*_recordings.get(), reads))
    try:
        yield reads
    finally:
        _recordings.reset(token)


def noted(reads: Mapping[Path, str]) -> None:
    """Count ``reads`` as read in every open recording: a loader's cached result (a cell
    loaded once for several plans) notes again the files it read when it was built."""
    for r in _recordings.get():
        r.update(reads)
