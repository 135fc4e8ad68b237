"""Parsing untrusted XML with lxml: no DTD loading, no entities, no network.

A DOCTYPE naming a remote DTD (as CAD exporters write) is accepted and never fetched;
an internal subset (``<!DOCTYPE x [ ... ]>``) is refused: its ENTITY declarations (XXE,
billion laughs) expand text, and its ATTLIST defaults give every element attributes a
reader of the element does not see (libxml2 applies them).
"""

from __future__ import annotations

import re
from pathlib import Path

from lxml import etree

from cellengine.errors import InputError
from cellengine.info.files import read_capped


def _parser() -> etree.XMLParser:
    return etree.XMLParser(
        resolve_entities=False,
        load_dtd=False,
        no_network=True,
        dtd_validation=False,
        huge_tree=False,
        remove_blank_text=False,
    )


def parse_xml(path: Path, kind: str = "xml") -> etree._ElementTree:
    """Parse ``path``; every failure is an InputError at file:line:col."""
    data = read_capped(path, kind)
    try:
        tree = etree.ElementTree(etree.fromstring(data, _parser(), base_url=str(path)))
    except etree.XMLSyntaxError as e:
        # An entity that is declared but not loaded (XXE) or refused for its size (billion
        # laughs) fails the parse: say why, where it is declared.
        _refuse_entities(data, path)
        line, col = e.position if e.position else (None, None)
        msg = " ".join(str(e.msg or e).split(f", line {line}")[0].split())  # one line
        for pattern, readable in _REWRITES:
            msg = pattern.sub(readable, msg)
        raise InputError.at(f"XML syntax error: {msg}", path, line, col) from None
    dtd = tree.docinfo.internalDTD
    if dtd is not None:
        for ent in dtd.iterentities():
            _refuse_entities(data, path)
            raise _entity_error(str(ent.name), path, _doctype_line(data), None)
        subset = _INTERNAL_SUBSET.match(data)
        if subset:
            line, col = _position(data, subset.end() - 1)
            raise InputError.at(
                "XML internal DTD subsets are not allowed (their declarations change what the "
                "elements say); remove the part of the DOCTYPE in [ ]",
                path,
                line,
                col,
            )
    for node in tree.iter(etree.Entity):
        raise InputError.at(
            f"XML entity reference '{node.text}' is not allowed", path, node.sourceline
        )
    return tree


# An <!ENTITY declaration (general or parameter) inside a DOCTYPE's internal subset.
_ENTITY_DECL = re.compile(rb"<!DOCTYPE[^\[>]*\[.*?(<!ENTITY\s+(?:%\s+)?([^\s>]+))", re.S)

# The prolog up to a DOCTYPE's internal subset '[': an XML declaration, comments and
# processing instructions, then <!DOCTYPE name [SYSTEM "..." | PUBLIC "..." "..."] [
_QUOTED = rb"""(?:"[^"]*"|'[^']*')"""
_INTERNAL_SUBSET = re.compile(
    rb"(?:\xef\xbb\xbf)?\s*(?:<\?.*?\?>\s*|<!--.*?-->\s*)*<!DOCTYPE\s+[^\s\[>]+"
    rb"(?:\s+(?:SYSTEM\s+" + _QUOTED + rb"|PUBLIC\s+" + _QUOTED + rb"\s+" + _QUOTED + rb"))?"
    rb"\s*\[",
    re.S,
)

_REWRITES = [  # libxml2's messages that name its own API
    (re.compile(r"^Excessive depth in document: (\d+).*"), r"elements nest more than \1 deep"),
    (re.compile(r"^Huge input lookup.*|^xmlSAX2Characters: huge text node.*"), "text too large"),
]


def _refuse_entities(data: bytes, path: Path) -> None:
    m = _ENTITY_DECL.search(data)
    if m:
        line, col = _position(data, m.start(1))
        name = m.group(2).decode("utf-8", "replace")
        raise _entity_error(name, path, line, col)


def _entity_error(name: str, path: Path, line: int | None, col: int | None) -> InputError:
    return InputError.at(
        f"XML entity declarations are not allowed (found '{name}'); "
        "remove the DOCTYPE's internal subset",
        path,
        line,
        col,
    )


def _position(data: bytes, i: int) -> tuple[int, int]:
    """(line, column) of byte ``i`` (columns in bytes, as libxml2's; a BOM is not one)."""
    start = data.rfind(b"\n", 0, i) + 1
    if start == 0 and data.startswith(b"\xef\xbb\xbf"):
        start = 3
    return data.count(b"\n", 0, i) + 1, i - start + 1


def _doctype_line(data: bytes) -> int | None:
    i = data.find(b"<!DOCTYPE")
    return data.count(b"\n", 0, i) + 1 if i >= 0 else None
