"""The mapping CSV: rows in order, and every mistake reported at file:row."""

from __future__ import annotations

from pathlib import Path

import pytest

from cellengine.errors import InputError
from cellengine.info.mapcsv import MapRow, load_map

DATA = Path(__file__).parents[1] / "data" / "platforms" / "native"


def write(tmp_path: Path, text: str) -> Path:
    p = tmp_path / "map.csv"
    p.write_bytes(text.encode())
    return p


def error(path: Path) -> tuple[str, int | None]:
    with pytest.raises(InputError) as e:
        load_map(path)
    p = e.value.problems[0]
    assert p.file == str(path)
    assert p.col is None
    return p.message, p.line


def test_fixture() -> None:
    assert load_map(DATA / "map.csv") == (
        MapRow("G1", "guide_u", "guide1", 2),
        MapRow("G2", "guide_u", "guide2", 3),
        MapRow("C1", "comb", "comb_a", 4),
    )


def test_bom_crlf_spaces_and_blank_lines(tmp_path: Path) -> None:
    p = write(tmp_path, "\ufeffcad_name, model, name\r\n\r\n A , m , a \r\nB,m,b")
    assert load_map(p) == (MapRow("A", "m", "a", 3), MapRow("B", "m", "b", 4))


def test_header_only_is_no_rows(tmp_path: Path) -> None:
    assert load_map(write(tmp_path, "cad_name,model,name\n")) == ()


def test_wrong_header(tmp_path: Path) -> None:
    p = write(tmp_path, "def,model,name\nA,m,a\n")
    assert error(p) == ("header is 'def,model,name'; expected exactly 'cad_name,model,name'", 1)
    p = write(tmp_path, "name,model,cad_name\n")
    assert error(p)[1] == 1


def test_empty_file(tmp_path: Path) -> None:
    assert error(write(tmp_path, "")) == (
        "empty mapping file; expected the header cad_name,model,name",
        1,
    )


def test_wrong_column_count(tmp_path: Path) -> None:
    p = write(tmp_path, "cad_name,model,name\nA,m,a\nB,m\n")
    assert error(p) == ("expected 3 columns (cad_name,model,name), found 2", 3)
    p = write(tmp_path, "cad_name,model,name\nA,m,a,extra\n")
    assert error(p) == ("expected 3 columns (cad_name,model,name), found 4", 2)


def test_empty_field(tmp_path: Path) -> None:
    p = write(tmp_path, "cad_name,model,name\nA,m,a\n\nB, ,b\n")
    assert error(p) == ("empty model", 4)


def test_duplicate_cad_name_names_the_first_row(tmp_path: Path) -> None:
    p = write(tmp_path, "cad_name,model,name\nA,m,a\nB,m,b\nA,m,c\n")
    assert error(p) == ("duplicate cad_name 'A' (first used in row 2)", 4)


def test_duplicate_name_names_the_first_row(tmp_path: Path) -> None:
    p = write(tmp_path, "cad_name,model,name\nA,m,a\nB,m,b\nC,m,b\n")
    assert error(p) == ("duplicate name 'b' (first used in row 3)", 4)


def test_name_with_a_dot(tmp_path: Path) -> None:
    p = write(tmp_path, "cad_name,model,name\nA,m,guide.1\n")
    assert error(p) == (
        "name 'guide.1' may not contain dots or spaces (plans write platform.element.keypoint)",
        2,
    )


def test_rows_count_lines_of_quoted_multiline_fields(tmp_path: Path) -> None:
    p = write(tmp_path, 'cad_name,model,name\n"A\nB",m,a\nC,m,\n')
    assert error(p) == ("empty name", 4)


def test_unterminated_quote_and_bad_encoding(tmp_path: Path) -> None:
    p = write(tmp_path, 'cad_name,model,name\nA,m,a\n"B,m,b\n')
    message, line = error(p)
    assert message.startswith("malformed CSV: ")
    assert line == 3
    p = tmp_path / "latin1.csv"
    p.write_bytes(b"cad_name,model,name\nA,m,\xe9\n")
    assert error(p) == ("file is not valid UTF-8", 2)
