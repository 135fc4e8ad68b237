"""Writing a set of output files all or nothing: each goes to a temporary name beside its
final one, and only when every file is on disk are they renamed into place (a rename within
one folder is atomic), so a failure part way leaves no half-written or mismatched files."""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path


def write_files(out_dir: Path, files: Mapping[str, str]) -> dict[str, Path]:
    """Write ``files`` (file name -> UTF-8 text) into ``out_dir`` (made if needed); return
    each name's path."""
    out_dir.mkdir(parents=True, exist_ok=True)
    staged: list[tuple[Path, Path]] = []
    try:
        for name, text in files.items():
            final = out_dir / name
            tmp = out_dir / f".{name}.tmp"
            staged.append((tmp, final))
            with tmp.open("w", encoding="utf-8") as f:
                f.write(text)
                f.flush()
                os.fsync(f.fileno())
    except BaseException:
        for tmp, _ in staged:
            tmp.unlink(missing_ok=True)
        raise
    for tmp, final in staged:
        tmp.replace(final)
    return {final.name: final for _, final in staged}
