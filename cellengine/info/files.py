"""Untrusted file references: resolved inside the cell's folder, read with size caps."""

from __future__ import annotations

import os
import re
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
}

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
        base = root.resolve()
        target = (base / ref).resolve()
        if not target.is_relative_to(base):
            link = Path(os.path.normpath(base / ref)).is_relative_to(base)
            how = "is a link that leads" if link else "points"
            raise InputError.at(
                f"file reference {_shown(ref)} {how} outside the cell folder", *where
            )
        if target.is_dir():
            raise InputError.at(f"file reference {_shown(ref)} is a folder, not a file", *where)
        if not target.is_file():
            raise InputError.at(f"file {_shown(ref)} not found (looked for {target})", *where)
    except OSError as e:  # a name too long for the file system, a loop of links
        raise InputError.at(
            f"file reference {_shown(ref)} cannot be used: {e.strerror}", *where
        ) from None
    return target


def _shown(ref: str) -> str:
    return repr(ref) if len(ref) <= 80 else repr(ref[:77] + "...")


def read_capped(
    path: Path,
    kind: str,
    file: Path | str | None = None,
    line: int | None = None,
    col: int | None = None,
) -> bytes:
    """Read a whole file, refusing it before reading if it is larger than its kind's cap."""
    cap = MAX_BYTES[kind]
    try:
        size = path.stat().st_size
    except OSError as e:
        raise InputError.at(f"cannot read '{path}': {e.strerror}", file or path, line, col) from e
    if size > cap:
        raise InputError.at(
            f"file is {size} bytes, more than the {cap}-byte limit for {kind} files", path
        )
    with path.open("rb") as f:
        data = f.read(cap + 1)
    if len(data) > cap:  # grew while reading
        raise InputError.at(f"file is more than the {cap}-byte limit for {kind} files", path)
    return data
