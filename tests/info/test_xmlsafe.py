"""parse_xml, which every XML format (X3D, models.xml, URDF, SRDF, REMODEL files) goes
through: a DOCTYPE naming a remote DTD is accepted; any internal subset is refused at the
'[' that opens it, whatever the prolog before it."""

from __future__ import annotations

from pathlib import Path

import pytest

from cellengine.errors import InputError
from cellengine.info.xmlsafe import parse_xml

REFUSED = (
    "XML internal DTD subsets are not allowed (their declarations change what the elements "
    "say); remove the part of the DOCTYPE in [ ]"
)


def _parse(tmp_path: Path, text: str) -> str:
    path = tmp_path / "a.xml"
    path.write_text(text, encoding="utf-8")
    try:
        root = parse_xml(path).getroot()
    except InputError as e:
        return str(e).replace(str(path), "a.xml")
    return str(dict(root.attrib))


def test_a_remote_dtd_is_accepted_and_not_fetched(tmp_path: Path) -> None:
    text = (
        '<?xml version="1.0"?>\n<!DOCTYPE X3D PUBLIC "ISO//Web3D//DTD X3D 3.0//EN" '
        '"http://www.web3d.org/specifications/x3d-3.0.dtd">\n<X3D version="3.0"/>'
    )
    assert _parse(tmp_path, text) == "{'version': '3.0'}"


@pytest.mark.parametrize(
    ("text", "where"),
    [
        ('<!DOCTYPE a [<!ATTLIST a t CDATA "9">]><a/>', "1:13"),
        ('<?xml version="1.0"?>\n<!-- [x] -->\n<!DOCTYPE a SYSTEM "a.dtd" [\n]>\n<a/>', "3:28"),
        ("<!DOCTYPE a PUBLIC 'p' 's'[<!ELEMENT a ANY>]><a/>", "1:27"),
        ("\ufeff<!DOCTYPE a []><a/>", "1:13"),
    ],
)
def test_an_internal_subset_is_refused_where_it_opens(
    tmp_path: Path, text: str, where: str
) -> None:
    assert _parse(tmp_path, text) == f"a.xml:{where}: {REFUSED}"


def test_an_attribute_default_never_reaches_the_reader(tmp_path: Path) -> None:
    # libxml2 would give <a> the default: the reader of the element sees no t
    text = '<!DOCTYPE a [<!ATTLIST a t CDATA "9999">]>\n<a/>'
    assert _parse(tmp_path, text).endswith(REFUSED)
