"""Parsing untrusted XML with lxml: no DTD loading, no entities, no network.

A DOCTYPE naming a remote DTD (as CAD exporters write) is accepted and never fetched;
any ENTITY declaration (XXE, billion laughs) is refused.
"""

from __future__ import annotations

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
        line, col = e.position if e.position else (None, None)
        msg = str(e.msg or e).split(f", line {line}")[0]
        raise InputError.at(f"XML syntax error: {msg}", path, line, col) from None
    dtd = tree.docinfo.internalDTD
    if dtd is not None:
        for ent in dtd.iterentities():
            raise InputError.at(
                f"XML entity declarations are not allowed (found '{ent.name}'); "
                "remove the DOCTYPE's internal subset",
                path,
                _doctype_line(data),
            )
    for node in tree.iter(etree.Entity):
        raise InputError.at(
            f"XML entity reference '{node.text}' is not allowed", path, node.sourceline
        )
    return tree


def _doctype_line(data: bytes) -> int | None:
    i = data.find(b"<!DOCTYPE")
    return data.count(b"\n", 0, i) + 1 if i >= 0 else None
