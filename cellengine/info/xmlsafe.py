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

# Formats whose text may exceed libxml2's 10 MB per text node or attribute value: an X3D
# mesh's point and index lists (a 1M-vertex IndexedFaceSet is ~20 MB of numbers in one
# attribute). The file is within its byte cap (files.read_capped), which bounds what the
# lifted limit lets through.
LARGE_TEXT_KINDS = frozenset({"x3d"})
MAX_DEPTH = 256  # libxml2's element nesting limit without XML_PARSE_HUGE, kept with it
# libxml2's refusals of a text over its limit, which XML_PARSE_HUGE lifts
_TOO_LARGE = re.compile(r"Buffer size limit exceeded|huge text node|Huge input lookup")


def _parser(huge: bool = False) -> etree.XMLParser:
    return etree.XMLParser(
        resolve_entities=False,
        load_dtd=False,
        no_network=True,
        dtd_validation=False,
        huge_tree=huge,
        remove_blank_text=False,
    )


def parse_xml(path: Path, kind: str = "xml") -> etree._ElementTree:
    """Parse ``path``; every failure is an InputError at file:line:col."""
    data = read_capped(path, kind)
    try:
        tree = etree.ElementTree(etree.fromstring(data, _parser(), base_url=str(path)))
    except etree.XMLSyntaxError as e:
        if kind not in LARGE_TEXT_KINDS or not _TOO_LARGE.search(str(e.msg or e)):
            raise _syntax_error(e, data, path) from None
        tree = _parse_huge(data, path)
    _refuse_subset(tree, data, path)
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


def _parse_huge(data: bytes, path: Path) -> etree._ElementTree:
    """Parse again with libxml2's size limits lifted (XML_PARSE_HUGE). That also lifts its
    nesting limit (to 2048) and its checks on entity sizes: an internal DTD subset (where
    entities are declared) is refused before parsing, and the nesting is checked here."""
    subset = _INTERNAL_SUBSET.match(data)
    if subset:
        _refuse_entities(data, path)
        raise _subset_error(data, path, subset.end() - 1)
    try:
        tree = etree.ElementTree(etree.fromstring(data, _parser(huge=True), base_url=str(path)))
    except etree.XMLSyntaxError as e:
        raise _syntax_error(e, data, path) from None
    depth = 0
    for event, el in etree.iterwalk(tree, events=("start", "end")):
        depth += 1 if event == "start" else -1
        if depth > MAX_DEPTH:
            raise InputError.at(
                f"XML syntax error: elements nest more than {MAX_DEPTH} deep", path, el.sourceline
            )
    return tree


def _syntax_error(e: etree.XMLSyntaxError, data: bytes, path: Path) -> InputError:
    # An entity that is declared but not loaded (XXE) or refused for its size (billion
    # laughs) fails the parse: say why, where it is declared.
    _refuse_entities(data, path)
    line, col = e.position if e.position else (None, None)
    msg = " ".join(str(e.msg or e).split(f", line {line}")[0].split())  # one line
    for pattern, readable in _REWRITES:
        msg = pattern.sub(readable, msg)
    return InputError.at(f"XML syntax error: {msg}", path, line, col)


def _refuse_subset(tree: etree._ElementTree, data: bytes, path: Path) -> None:
    dtd = tree.docinfo.internalDTD
    if dtd is None:
        return
    for ent in dtd.iterentities():
        _refuse_entities(data, path)
        raise _entity_error(str(ent.name), path, _doctype_line(data), None)
    subset = _INTERNAL_SUBSET.match(data)
    if subset:
        raise _subset_error(data, path, subset.end() - 1)


def _subset_error(data: bytes, path: Path, at: int) -> InputError:
    line, col = _position(data, at)
    return InputError.at(
        "XML internal DTD subsets are not allowed (their declarations change what the "
        "elements say); remove the part of the DOCTYPE in [ ]",
        path,
        line,
        col,
    )


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
