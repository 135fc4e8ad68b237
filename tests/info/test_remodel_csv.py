"""REMODEL process files: the shared sample as parsed, and every mistake at file:row."""

from __future__ import annotations

from pathlib import Path

import pytest

from cellengine.errors import InputError
from cellengine.info.remodel_csv import (
    CableRow,
    ConnectorRow,
    HarnessCable,
    Operation,
    Spot,
    load_components,
    load_harness,
    load_sequence,
)
from tests.conftest import REMODEL

COMPONENTS_HEAD = "Type;Model;Reference;Label;Color;length;Diameter;x;y;z;Type\n"
SEQUENCE_HEAD = "Order;Type of operation;Label;Spot\n"
HEADER_NAMES = "Order, Type of operation, Label, Spot"


def write(tmp_path: Path, name: str, text: str | bytes) -> Path:
    p = tmp_path / name
    p.write_bytes(text.encode() if isinstance(text, str) else text)
    return p


def problems(load: object, path: Path) -> list[tuple[str, int | None]]:
    with pytest.raises(InputError) as e:
        load(path)  # type: ignore[operator]
    for p in e.value.problems:
        assert p.file == str(path)
        assert p.col is None
    return [(p.message, p.line) for p in e.value.problems]


# --- the shared sample -------------------------------------------------------------------


def test_sample_components() -> None:
    c = load_components(REMODEL / "Components_definition.csv")
    # x 32.9 across the VGA shell, y 14.64 its thickness, z 46.55 along the cable
    assert c.connectors == {"CON1": ConnectorRow("CON1", "VGA", 46.55, 32.9, 14.64, "Grey", 2)}
    assert c.cables == {"CA1": CableRow("CA1", 500, 5.1, "Grey", 3)}
    assert isinstance(c.cables["CA1"].length, int)  # written back as 500, not 500.0


def test_sample_sequence() -> None:
    assert load_sequence(REMODEL / "Assembly_sequence.csv") == (
        Operation(1, "EC", "CON1", "C2.1-C1.1", (Spot("C2", "1"), Spot("C1", "1")), 2),
        Operation(2, "PC", "CON1", "J8.1.L", (Spot("J8", "1", "left"),), 3),
        Operation(
            3,
            "RC",
            "CON1",
            "J3.1-J4.1-J1.1-J2.1",
            (Spot("J3", "1"), Spot("J4", "1"), Spot("J1", "1"), Spot("J2", "1")),
            4,
        ),
    )


def test_sample_harness() -> None:
    assert load_harness(REMODEL / "WH_configuration.xml") == (HarnessCable("CA1", "CON1", None, 5),)


# --- reading the tables ------------------------------------------------------------------


def test_bom_cp1252_decimal_comma_blank_lines_and_spaced_header(tmp_path: Path) -> None:
    text = (
        "\ufeffType ; Model;Reference;LABEL;Color;Length;diameter;x;y;z;Type\r\n\r\n"
        "Cable;;;CA1;Gr\u00fcn;650;5,5;;;;\r\n"
    )
    p = write(tmp_path, "c.csv", text.encode("utf-8"))
    assert load_components(p).cables["CA1"] == CableRow("CA1", 650, 5.5, "Gr\u00fcn", 3)
    # Excel on Windows saves "CSV (semicolon)" as Windows-1252
    p = write(tmp_path, "c.csv", text.removeprefix("\ufeff").encode("cp1252"))
    assert load_components(p).cables["CA1"].color == "Gr\u00fcn"


def test_empty_file(tmp_path: Path) -> None:
    assert problems(load_sequence, write(tmp_path, "s.csv", "\n")) == [
        ("empty file; expected a ';'-separated header with " + HEADER_NAMES, 1)
    ]


def test_missing_column_is_at_the_header(tmp_path: Path) -> None:
    p = write(tmp_path, "s.csv", "\n" + "Order;Type of operation;Label\n1;EC;CON1\n")
    assert problems(load_sequence, p) == [
        ("missing column 'Spot'; the header has: Order, Type of operation, Label", 2)
    ]
    p = write(tmp_path, "s.csv", "Order,Type of operation,Label,Spot\n")
    msg = problems(load_sequence, p)[0][0]
    assert msg.endswith("(is the file ';'-separated?)")


def test_every_bad_row_length_is_reported(tmp_path: Path) -> None:
    p = write(tmp_path, "s.csv", SEQUENCE_HEAD + "1;EC;CON1\n2;PC;CON1;J8.1.L\n3;RC;CON1;J3.1;\n")
    assert problems(load_sequence, p) == [
        ("expected 4 ';'-separated cells as in the header, found 3", 2),
        ("expected 4 ';'-separated cells as in the header, found 5", 4),
    ]


def test_malformed_quotes(tmp_path: Path) -> None:
    p = write(tmp_path, "s.csv", SEQUENCE_HEAD + '1;EC;"CON1"x;C2.1-C1.1\n')
    ((msg, row),) = problems(load_sequence, p)
    assert msg.startswith("malformed CSV") and row == 2


# --- components --------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("row", "message"),
    [
        ("Cable;;;CA1;Grey;;5.1;;;;", "empty length of cable CA1"),
        ("Cable;;;CA1;Grey;500;;;;;", "empty Diameter of cable CA1"),
        ("Cable;;;CA1;Grey;500;5.1x;;;;", "Diameter of cable CA1 '5.1x' is not a number"),
        ("Cable;;;CA1;Grey;0;5.1;;;;", "length of cable CA1 must be greater than 0, got 0"),
        ("Cable;;;CA1;Grey;inf;5.1;;;;", "length of cable CA1 must be greater than 0, got inf"),
        ("Connector;VGA;1;CON1;Grey;;;32.9;;46.55;", "empty y of connector CON1"),
        ("Connector;;1;CON1;Grey;;;32.9;14;46.55;", "empty Model (the type) of connector CON1"),
        ("Tape;;;T1;;;;;;;", "unknown component type 'Tape'; known: Cable, Connector"),
        ("Cable;;;;Grey;500;5.1;;;;", "empty Label"),
        (
            "Cable;;;CA 1;Grey;500;5.1;;;;",
            "Label 'CA 1' is not a valid name: use letters, digits, '_' and '-', starting "
            "with a letter or '_'",
        ),
    ],
)
def test_component_errors_at_their_row(tmp_path: Path, row: str, message: str) -> None:
    p = write(tmp_path, "c.csv", COMPONENTS_HEAD + "Cable;;;CA0;Grey;500;5.1;;;;\n" + row + "\n")
    assert problems(load_components, p) == [(message, 3)]


def test_duplicate_component_label(tmp_path: Path) -> None:
    rows = "Cable;;;CA1;;500;5;;;;\nConnector;VGA;;CA1;;;;1;2;3;\n"
    p = write(tmp_path, "c.csv", COMPONENTS_HEAD + rows)
    assert problems(load_components, p) == [("duplicate Label 'CA1' (first used in row 2)", 3)]


# --- assembly sequence -------------------------------------------------------------------


@pytest.mark.parametrize(
    ("row", "message"),
    [
        ("XX;CON1;J3.1", "unknown operation 'XX'; known: EC, PC, RC"),
        ("PC;CON1;J8.1.X", "unknown arm letter 'X' in 'J8.1.X'; known: L, R (left, right)"),
        ("EC;CON1;C2.1", "EC names 2 guides, e.g. C2.1-C1.1 (connector end first); 'C2.1' names 1"),
        (
            "PC;CON1;J8.1.L-J3.1",
            "PC names 1 guide, e.g. J8.1.L (guide, then L or R for the arm); 'J8.1.L-J3.1' names 2",
        ),
        ("RC;CON1;", "empty Spot; RC writes e.g. J3.1-J4.1 (guides in routing order)"),
        ("RC;CON1;J3.1--J4.1", "'' in Spot 'J3.1--J4.1' is not element.guide (e.g. J3.1)"),
        ("RC;CON1;J3", "'J3' is not element.guide (e.g. J3.1)"),
        ("PC;CON1;J8", "'J8' is not element.guide (e.g. J3.1) or element.guide.arm (e.g. J8.1.L)"),
        ("RC;CON1;J3.a", "guide 'a' of 'J3.a' is not a number"),
        (
            "RC;CON1;J3.1.L",
            "'J3.1.L': only PC spots name an arm; RC writes e.g. J3.1-J4.1 "
            "(guides in routing order)",
        ),
        ("RC;;J3.1", "empty Label"),
    ],
)
def test_operation_errors_at_their_row(tmp_path: Path, row: str, message: str) -> None:
    text = SEQUENCE_HEAD + "1;EC;CON1;C2.1-C1.1\n2;PC;CON1;J8.1.L\n3;" + row + "\n"
    p = write(tmp_path, "Assembly_sequence.csv", text)
    assert problems(load_sequence, p) == [(message, 4)]


def test_operations_sorted_by_order_lowercase_accepted_and_arm_r(tmp_path: Path) -> None:
    text = SEQUENCE_HEAD + "2;pc;CON1; J8.1.r \n1;EC;CON1;C2.1 - C1.1\n"
    ops = load_sequence(write(tmp_path, "s.csv", text))
    assert [(o.order, o.kind, o.row) for o in ops] == [(1, "EC", 3), (2, "PC", 2)]
    assert ops[0].spots == (Spot("C2", "1"), Spot("C1", "1"))
    assert ops[1].spots == (Spot("J8", "1", "right"),)


def test_order_must_be_unique_whole_numbers(tmp_path: Path) -> None:
    text = SEQUENCE_HEAD + "1;EC;CON1;C2.1-C1.1\n1;PC;CON1;J8.1.L\nthree;RC;CON1;J3.1\n"
    p = write(tmp_path, "s.csv", text)
    whole = "is not a whole number (of at most 9 digits)"
    assert problems(load_sequence, p) == [(f"Order 'three' {whole}", 4)]
    p = write(tmp_path, "s.csv", text.replace("three", "9" * 5000))  # int() refuses 4300+
    assert problems(load_sequence, p) == [(f"Order '{'9' * 20}...' {whole}", 4)]
    p = write(tmp_path, "s.csv", text.replace("three", "3"))
    assert problems(load_sequence, p) == [("duplicate Order 1 (first used in row 2)", 3)]


# --- wiring harness ----------------------------------------------------------------------


def test_harness_end_connectors_and_free_ends(tmp_path: Path) -> None:
    p = write(
        tmp_path,
        "WH_configuration.xml",
        '<data>\n<wiring_harness first_connector="CON1">\n'
        '<end_connector label="CON2"><cable>CA1</cable></end_connector>\n'
        '<end_connector label="free"><cable> CA2 </cable></end_connector>\n'
        "</wiring_harness>\n<wiring_harness><cable>CA3</cable></wiring_harness>\n</data>\n",
    )
    assert load_harness(p) == (
        HarnessCable("CA1", "CON1", "CON2", 3),
        HarnessCable("CA2", "CON1", None, 4),
        HarnessCable("CA3", None, None, 6),
    )


def test_harness_empty_cable(tmp_path: Path) -> None:
    p = write(tmp_path, "WH.xml", "<data>\n<wiring_harness>\n<cable/>\n</wiring_harness></data>")
    assert problems(load_harness, p) == [("empty <cable> (expected a cable label)", 3)]
