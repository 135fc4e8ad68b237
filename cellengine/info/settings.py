"""Values set over what a cell's files say, for the loads inside a block: the variants of a
sweep (``cellengine sweep``) without a copy of the files for each.

A setting names the kind of file ("cell", "objects" or "plan"), a key path into its YAML
(``("platforms", "routing", "elements", "guide3", "xyz")``; list items by index) and a
value written as in that file, in its units. It replaces the value there, or adds the key
(and the maps above it) where the file has none; the file's own checks then see it as if
written, and a problem with it is reported at the key's place in the file (or the nearest
enclosing one written there).
"""

from __future__ import annotations

import copy
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from contextvars import ContextVar
from typing import Any

from cellengine.info.platform import Platform
from cellengine.info.yamlio import Loc, YamlDoc

KINDS = ("cell", "objects", "plan")
Setting = tuple[str, tuple[str | int, ...], Any]  # kind, key path, value

_settings: ContextVar[tuple[Setting, ...]] = ContextVar("settings", default=())


@contextmanager
def settings(values: Sequence[Setting]) -> Iterator[None]:
    """``values`` set over the files loaded inside the block."""
    token = _settings.set(tuple(values))
    try:
        yield
    finally:
        _settings.reset(token)


def overlaid(doc: YamlDoc, kind: str) -> YamlDoc:
    """``doc`` (a file of ``kind``) with the settings of the block it is loaded in."""
    mine = [(loc, value) for k, loc, value in _settings.get() if k == kind]
    if not mine:
        return doc
    data = copy.deepcopy(doc.data) if doc.data is not None else {}
    for loc, value in mine:
        data = _set(doc, data, loc, value)
    return YamlDoc(doc.file, data, doc.values, doc.keys)


def _set(doc: YamlDoc, data: Any, loc: Loc, value: Any) -> Any:
    if not isinstance(data, dict):
        raise doc.error("a setting needs a map here; the file has something else", ())
    node = data
    for i, key in enumerate(loc):
        last = i == len(loc) - 1
        if isinstance(node, list) and isinstance(key, int) and 0 <= key < len(node):
            if last:
                node[key] = value
            node = node[key]
        elif isinstance(node, dict):
            if last:
                node[key] = value
            node = node.setdefault(key, {})
        else:
            what = f"a list of {len(node)}" if isinstance(node, list) else f"'{node}'"
            raise doc.error(
                f"setting '{dotted(loc)}': '{dotted(loc[:i])}' is {what} in the file, "
                f"which has no '{key}'",
                loc[:i],
            )
    return data


def dotted(loc: Loc) -> str:
    return ".".join(str(k) for k in loc)


def parse_key(text: str, platforms: Mapping[str, Platform] | None = None) -> tuple[str, Loc]:
    """``cell:robots.right.base.xyz`` (a file kind, a dotted key path; list items by
    index) or ``routing.guide3.move`` (a platform's element: a shift in the cell's frame,
    or its ``xyz`` or ``rpy`` in the platform's; cell.yaml's ``platforms.P.elements.E``)
    into a setting's kind and key path."""
    kind, sep, rest = text.partition(":")
    if sep and kind in KINDS:
        parts: list[str | int] = [int(p) if p.isdigit() else p for p in rest.split(".")]
        if not rest or not all(str(p) for p in parts):
            raise ValueError(f"'{text}': write {kind}:key.path")
        return kind, tuple(parts)
    if sep:
        raise ValueError(f"'{text}': the file is one of {', '.join(KINDS)}, not '{kind}'")
    bits = text.split(".")
    if len(bits) == 3 and bits[2] in ("xyz", "rpy", "move") and all(bits):
        if platforms is not None and bits[0] not in platforms:
            known = ", ".join(sorted(platforms)) or "none"
            raise ValueError(f"'{text}': no platform '{bits[0]}' in the cell (it has {known})")
        if platforms is not None and bits[1] not in platforms[bits[0]].elements:
            known = ", ".join(platforms[bits[0]].elements)
            raise ValueError(f"'{text}': no element '{bits[1]}' on '{bits[0]}' (it has {known})")
        return "cell", ("platforms", bits[0], "elements", bits[1], bits[2])
    raise ValueError(
        f"'{text}': write PLATFORM.ELEMENT.move (or .xyz, .rpy), or cell:KEY, objects:KEY, plan:KEY"
    )
