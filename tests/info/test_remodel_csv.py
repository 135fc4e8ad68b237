"""REMODEL process files: the shared sample as parsed, and every mistake at file:row."""

from __future__ import annotations

from pathlib import Path

import pytest

from cellengine.errors import InputError, Problem
from cellengine.info.remodel_csv import (
    UNEXECUTED,
    CableRow,
    ConnectorRow,
    Operation,
    Spot,
    load_components,
    load_sequence,
)
from cellengine.info.remodel_harness import BranchXml, HarnessXml, PinnedCable, load_wiring
from tests.conftest import REMODEL

COMPONENTS_HEAD = "Type;Model;Reference;Label;Color;length;Diameter;x;y;z;Type\n"
SEQUENCE_HEAD = "Order;Type of operation;Label;Spot\n"
HEADER_NAMES = "Order, Type of operation, Label, Spot"
EC = "C2.1-C1.1 (two combs, connector end first) or C1.1.L (a comb, the arm)"
T = "J1.1-J2.1-J2.1 (the two guides to tape between, then the one to hold beside)"
ARMLESS = "only PC and EC spots name an arm;"


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
    cable = PinnedCable("CA1", 1, 1, None, None, 5)
    branch = BranchXml("Free", (cable,), 4)
    assert load_wiring(REMODEL / "WH_configuration.xml") == (
        (HarnessXml("1", "CON1", "B3.1", (branch,), 3),),
        [],
    )


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
        ("XX;CON1;J3.1", "unknown operation 'XX'; known: EC, PC, RC, T, TJ"),
        ("PC;CON1;J8.1.X", "unknown arm letter 'X' in 'J8.1.X'; known: L, R (left, right)"),
        ("EC;CON1;C2.1", f"EC names 2 combs, or 1 comb with an arm, e.g. {EC}; 'C2.1' names 1"),
        (
            "EC;CON1;C2.1.L-C1.1",
            f"EC names 2 combs, or 1 comb with an arm, e.g. {EC}; 'C2.1.L-C1.1' names 2 "
            "with an arm",
        ),
        ("T;WH1;J1.1-J2.1", f"T names 3 guides, e.g. {T}; 'J1.1-J2.1' names 2"),
        (
            "T;WH1;J1.1-J2.1-J2.1.L",
            f"'J2.1.L' in Spot 'J1.1-J2.1-J2.1.L': {ARMLESS} T writes e.g. {T}",
        ),
        ("TJ;WH1;J1.1", UNEXECUTED["TJ"]),
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
            f"'J3.1.L': {ARMLESS} RC writes e.g. J3.1-J4.1 (guides in routing order)",
        ),
        ("RC;;J3.1", "empty Label"),
    ],
)
def test_operation_errors_at_their_row(tmp_path: Path, row: str, message: str) -> None:
    text = SEQUENCE_HEAD + "1;EC;CON1;C2.1-C1.1\n2;PC;CON1;J8.1.L\n3;" + row + "\n"
    p = write(tmp_path, "Assembly_sequence.csv", text)
    assert problems(load_sequence, p) == [(message, 4)]


def test_operations_run_in_file_order_as_in_remodel_with_warnings(tmp_path: Path) -> None:
    text = SEQUENCE_HEAD + "2;pc;CON1; J8.1.r \n1;EC;CON1;C2.1 - C1.1\n1;RC;CON1;J3.1\n"
    warnings: list[Problem] = []
    p = write(tmp_path, "s.csv", text)
    ops = load_sequence(p, warnings)
    assert [(o.order, o.kind, o.row) for o in ops] == [(2, "PC", 2), (1, "EC", 3), (1, "RC", 4)]
    assert ops[1].spots == (Spot("C2", "1"), Spot("C1", "1"))
    assert ops[0].spots == (Spot("J8", "1", "right"),)
    ignored = "REMODEL ignores the Order column and runs the rows in file order; so does the import"
    assert [(w.message, w.line) for w in warnings] == [
        (f"Order 1 comes after Order 2 (row 2): {ignored}", 3),
        (f"Order 1 comes after Order 1 (row 3): {ignored}", 4),
        (
            "operation 'pc' is read as PC; REMODEL's planner compares operation types "
            "case-sensitively and would not run it",
            2,
        ),
    ]


def test_the_later_system_s_rows(tmp_path: Path) -> None:
    text = SEQUENCE_HEAD + "1;EC;WH1;C1.1.R\n2;RC;GR11;J1.1-J2.1\n3;T;WH1;J1.1-J2.1-J2.1\n"
    ops = load_sequence(write(tmp_path, "s.csv", text))
    assert ops[0].spots == (Spot("C1", "1", "right"),)
    assert (ops[1].label, ops[1].kind) == ("GR11", "RC")
    assert ops[2].spots == (Spot("J1", "1"), Spot("J2", "1"), Spot("J2", "1"))


def test_order_must_be_whole_numbers(tmp_path: Path) -> None:
    text = SEQUENCE_HEAD + "1;EC;CON1;C2.1-C1.1\n1;PC;CON1;J8.1.L\nthree;RC;CON1;J3.1\n"
    p = write(tmp_path, "s.csv", text)
    whole = "is not a whole number (of at most 9 digits)"
    assert problems(load_sequence, p) == [(f"Order 'three' {whole}", 4)]
    p = write(tmp_path, "s.csv", text.replace("three", "9" * 5000))  # int() refuses 4300+
    assert problems(load_sequence, p) == [(f"Order '{'9' * 20}...' {whole}", 4)]


# --- wiring harness ----------------------------------------------------------------------


def test_harness_branches_pins_and_free_ends(tmp_path: Path) -> None:
    p = write(
        tmp_path,
        "WH_configuration.xml",
        '<data>\n<wiring_harness id="1" first_connector="WH1">\n'
        '<end_connector label="GR11"><cable Row1="1" Col1="0">CA1</cable>\n'
        '<cable Row1="0" Col1="0" Row2="3" Col2="1"> CA2 </cable></end_connector>\n'
        '<end_connector label="free"><cable Row1="2">CA3</cable></end_connector>\n'
        "</wiring_harness>\n<wiring_harness><cable>CA4</cable></wiring_harness>\n</data>\n",
    )
    harnesses, warnings = load_wiring(p)
    assert warnings == []
    wh1, loose = harnesses
    assert [(b.label, b.free, [c.cable for c in b.cables]) for b in wh1.branches] == [
        ("GR11", False, ["CA1", "CA2"]),
        ("free", True, ["CA3"]),
    ]
    assert wh1.cables[1] == PinnedCable("CA2", 0, 0, 3, 1, 4)
    assert (loose.id, loose.first, loose.branches[0].free) == (None, None, True)


def test_harness_mistakes_at_their_lines(tmp_path: Path) -> None:
    p = write(
        tmp_path,
        "WH.xml",
        "<data>\n"
        '<wiring_harness id="1" first_connector="WH1">\n'
        '<end_connector label="GR11"><cable Row1="x">CA1</cable><cable/></end_connector>\n'
        '<end_connector label="GR11"><cable Row1="0">CA1</cable></end_connector>\n'
        "<end_connector label='GR13'/><tape/>\n"
        "</wiring_harness>\n"
        '<wiring_harness id="1" first_connector="WH1"><cable Row1="0">CA9</cable>'
        '<cable Row1="0">CA8</cable></wiring_harness>\n'
        "<harness/>\n</data>",
    )
    assert problems(lambda path: load_wiring(path), p) == [
        ("<cable> Row1 is 'x'; expected a whole number (0, 1, ...)", 3),
        ("empty <cable> (expected a cable label)", 3),
        ("an <end_connector> with no <cable>: a branch has at least one", 5),
        ("unexpected <tape> in <wiring_harness>; expected end_connector or cable", 5),
        ("unexpected <harness> in <data>; expected wiring_harness", 8),
        ("end_connector label 'GR11' is used again (first at line 3)", 4),
        ("cable 'CA1' is used again (first at line 3)", 4),
        ("harness id '1' is used again (first at line 2)", 7),
        ("first_connector 'WH1' is used again (first at line 2)", 7),
        ("cable CA8 has the pins Row1=0 Col1=None of CA9", 7),
    ]


def test_a_long_harness_id_is_a_warning(tmp_path: Path) -> None:
    p = write(
        tmp_path,
        "WH.xml",
        '<data><wiring_harness id="12"><cable>CA1</cable></wiring_harness></data>',
    )
    _, warnings = load_wiring(p)
    assert [(w.message, w.line) for w in warnings] == [
        ("harness id '12': REMODEL's planner reads one character of it (WH1)", 1)
    ]
