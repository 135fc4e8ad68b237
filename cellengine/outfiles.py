"""Writing a set of output files all or nothing: each goes to a temporary file beside its
final one, and only when every file is on disk are they renamed into place (a rename within
one folder is atomic, and replaces a link rather than writing through it), so a failure part
way leaves no half-written or mismatched files. The folder is a checked run folder
(:mod:`cellengine.runfolder`); temporary names are mkstemp's (created with O_EXCL)."""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterable, Mapping
from pathlib import Path

from cellengine.errors import InputError, Problem
from cellengine.runfolder import check


def _file_mode() -> int:
    """The mode open() gives a new file: 0666 less the process's umask."""
    mask = os.umask(0)
    os.umask(mask)
    return 0o666 & ~mask


def write_files(out_dir: Path, files: Mapping[str, str | Iterable[str]]) -> dict[str, Path]:
    """Write ``files`` (file name -> UTF-8 text, or its pieces: a long text need not be
    whole in memory) into ``out_dir`` (made if needed); return each name's path."""
    check(out_dir)
    mode = _file_mode()
    staged: list[tuple[Path, Path]] = []
    try:
        for name, text in files.items():
            fd, tmp_name = tempfile.mkstemp(prefix=f".{name}.", suffix=".tmp", dir=out_dir)
            staged.append((Path(tmp_name), out_dir / name))
            os.fchmod(fd, mode)  # mkstemp's 0600 would keep the report from the cell's team
            with os.fdopen(fd, "w", encoding="utf-8") as f:
                f.writelines([text] if isinstance(text, str) else text)
                f.flush()
                os.fsync(f.fileno())
        for tmp, final in staged:
            tmp.replace(final)
    except BaseException as e:
        for tmp, _ in staged:
            tmp.unlink(missing_ok=True)
        if isinstance(e, OSError):  # a full or read-only file system
            raise InputError(
                Problem(f"cannot write the run folder: {e.strerror}", str(out_dir))
            ) from None
        raise
    return {final.name: final for _, final in staged}
