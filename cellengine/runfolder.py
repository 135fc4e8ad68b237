"""The run folder: what `plan` and `run` write goes there and nowhere else.

A run folder may come from anywhere (a cell bundle can ship a ``run/``), so it must be a real
folder, not a link, and hold no links: a planted ``journal.jsonl`` or temporary file linked
to a file elsewhere would have that file truncated and filled. Files are created with
O_EXCL (temporary names from mkstemp, not predictable) or opened with O_NOFOLLOW (the
journal), and a lock keeps a second command out while one writes the folder (flock:
released by the kernel when the process ends, however it ends).
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import os
from collections.abc import Iterator
from pathlib import Path
from typing import IO

from cellengine.errors import InputError, Problem

LOCK = ".lock"


@contextlib.contextmanager
def using(folder: Path) -> Iterator[Path]:
    """``folder`` checked (:func:`check`, made if missing) and locked against every other
    cellengine command while inside."""
    check(folder)
    fd = _open(folder / LOCK, os.O_RDWR | os.O_CREAT)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise _error(
                folder,
                "another cellengine command is writing this run folder; wait for it to end or "
                "give another --out",
            ) from None
        yield folder
    finally:
        os.close(fd)


def check(folder: Path) -> None:
    """``folder`` is a real folder (made if missing) holding no links."""
    if folder.is_symlink():
        raise _error(folder, "the run folder is a link; give a real folder")
    if folder.exists() and not folder.is_dir():
        raise _error(folder, "the run folder is a file, not a folder")
    try:
        folder.mkdir(parents=True, exist_ok=True)
        links = sorted(e.name for e in os.scandir(folder) if e.is_symlink())
    except OSError as e:
        raise _error(folder, f"cannot make or read the run folder: {e.strerror}") from None
    if links:
        raise _error(
            folder / links[0],
            "a link in the run folder: it holds only what cellengine writes; remove the link",
        )


def open_append(path: Path) -> IO[str]:
    """``path`` opened to append text, never through a link."""
    return os.fdopen(_open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT), "a", encoding="utf-8")


def _open(path: Path, flags: int) -> int:
    try:
        return os.open(path, flags | os.O_NOFOLLOW | os.O_CLOEXEC, 0o644)
    except OSError as e:
        why = "it is a link" if e.errno == errno.ELOOP else e.strerror
        raise _error(path, f"cannot open {path.name}: {why}") from None


def _error(path: Path, message: str) -> InputError:
    return InputError(Problem(message, str(path)))
