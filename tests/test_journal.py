"""The journal read back for ``--resume``: every value it would act on is checked, and a
damaged or edited entry is an error at its line, naming the field."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from cellengine.errors import InputError
from cellengine.journal import read_progress

START = {"entry": "start", "plan": "plan.yaml", "driver": "SimDriver"}
FINISHED = {
    "entry": "finished",
    "step": 0,
    "segment": 0,
    "label": "s0 PickCable",
    "q": [0.0, -1.57, 1.57, -1.57, -1.57, 0.0],
    "grippers": {"left": ["open", None], "right": ["grasp", "cable1"]},
}
MEASURED = {"entry": "measured", "step": 1, "object": "vial1", "arm": "left", "mass_kg": 0.03}


def _write(tmp_path: Path, *entries: dict[str, Any] | bytes) -> Path:
    path = tmp_path / "journal.jsonl"
    lines = [e if isinstance(e, bytes) else json.dumps(e).encode() for e in entries]
    path.write_bytes(b"".join(line + b"\n" for line in lines))
    return path


def error(tmp_path: Path, *entries: dict[str, Any] | bytes) -> str:
    path = _write(tmp_path, *entries)
    with pytest.raises(InputError) as e:
        read_progress(path)
    return str(e.value).replace(str(path), "journal.jsonl")


def test_a_good_journal_is_read(tmp_path: Path) -> None:
    progress = read_progress(_write(tmp_path, START, FINISHED, MEASURED))
    assert progress.labels == ("s0 PickCable",)
    assert progress.grippers == {"left": ("open", None), "right": ("grasp", "cable1")}
    assert progress.measured == {"vial1": 0.03}


def test_load_cell_zeros_are_kept_for_a_resumed_run_and_checked(tmp_path: Path) -> None:
    tared = {"entry": "tared", "load_cells": {"robot1": 0.0037}}
    assert read_progress(_write(tmp_path, START, tared, FINISHED)).tares == {"robot1": 0.0037}
    assert read_progress(_write(tmp_path, START, tared, START)).tares == {}  # a new run
    assert error(tmp_path, START, {**tared, "load_cells": {"robot1": "3.7 g"}}) == (
        "journal.jsonl:2: 'load_cells' must map arms to finite masses in kg (within 1000), "
        'got {"robot1": "3.7 g"}'
    )


def test_missing_field(tmp_path: Path) -> None:
    finished = {k: v for k, v in FINISHED.items() if k != "q"}
    assert error(tmp_path, START, finished) == (
        "journal.jsonl:2: 'q' is missing from this 'finished' entry"
    )


def test_wrong_types(tmp_path: Path) -> None:
    assert error(tmp_path, START, {**FINISHED, "segment": "0"}) == (
        "journal.jsonl:2: 'segment' must be a segment index (an integer from 0), got \"0\""
    )
    assert error(tmp_path, START, {**FINISHED, "segment": -1}) == (
        "journal.jsonl:2: 'segment' must be a segment index (an integer from 0), got -1"
    )
    assert error(tmp_path, START, {**FINISHED, "label": 5}) == (
        "journal.jsonl:2: 'label' must be a string, got 5"
    )
    assert error(tmp_path, START, {**FINISHED, "q": {"a": 1}}) == (
        "journal.jsonl:2: 'q' must be a list of joint values, got {\"a\": 1}"
    )
    assert error(tmp_path, START, {**FINISHED, "grippers": {"left": "open"}}) == (
        "journal.jsonl:2: 'grippers.left' must be [mode, holds] (each a name or null), got \"open\""
    )
    assert error(tmp_path, START, {**FINISHED, "grippers": [1]}) == (
        "journal.jsonl:2: 'grippers' must map each arm to [mode, holds], got [1]"
    )
    assert error(tmp_path, START, {**MEASURED, "object": None}) == (
        "journal.jsonl:2: 'object' must be a string, got null"
    )
    assert error(tmp_path, START, {"entry": "fault", "fault": "tracking"}) == (
        "journal.jsonl:2: 'fault' must be a mapping, got \"tracking\""
    )


@pytest.mark.parametrize(
    ("mass", "shown"),
    [("NaN", "nan"), ("-0.5", "-0.5"), ("0", "0"), ("1e308", "1e+308"), ("1e999", "inf")],
)
def test_masses_finite_and_in_range(tmp_path: Path, mass: str, shown: str) -> None:
    line = json.dumps({**MEASURED, "mass_kg": 0.25}).replace("0.25", mass).encode()
    assert error(tmp_path, START, FINISHED, line) == (
        f"journal.jsonl:3: 'mass_kg' must be a finite mass in kg (0 to 1000), got {shown}"
    )


def test_joint_values_finite(tmp_path: Path) -> None:
    line = json.dumps(FINISHED).replace("-1.57, 1.57", "-1.57, NaN").encode()
    assert error(tmp_path, START, line) == (
        "journal.jsonl:2: 'q[2]' must be a finite joint value (rad or m, at most 100 either "
        "way), got nan"
    )
    assert error(tmp_path, START, {**FINISHED, "q": [0.0, 1e300]}) == (
        "journal.jsonl:2: 'q[1]' must be a finite joint value (rad or m, at most 100 either "
        "way), got 1e+300"
    )
    assert error(tmp_path, START, {"entry": "fault", "fault": {"q": [0.0, True]}}) == (
        "journal.jsonl:2: 'fault.q[1]' must be a finite joint value (rad or m, at most 100 "
        "either way), got true"
    )


def test_integers_too_large_for_a_float(tmp_path: Path) -> None:
    """JSON integers have any number of digits (found by the fuzz target: OverflowError)."""
    digits = "1" + "0" * 399
    shown = digits[:37] + "..."
    assert error(tmp_path, START, {**FINISHED, "q": [0.0, 10**399]}) == (
        "journal.jsonl:2: 'q[1]' must be a finite joint value (rad or m, at most 100 either "
        f"way), got {shown}"
    )
    assert error(tmp_path, START, {**MEASURED, "mass_kg": -(10**399)}) == (
        f"journal.jsonl:2: 'mass_kg' must be a finite mass in kg (0 to 1000), got -{shown[:-4]}..."
    )


def test_run_identity_is_a_mapping_of_strings(tmp_path: Path) -> None:
    """resume compares it with the files (an AttributeError traceback after compiling a
    journal whose 'run' was a list: found by the fuzz target)."""
    assert error(tmp_path, {**START, "run": []}, FINISHED) == (
        "journal.jsonl:1: 'run' must map plan, cell, objects, execution and version to "
        "strings, got []"
    )
    assert error(tmp_path, {**START, "run": {"plan": 7}}, FINISHED) == (
        "journal.jsonl:1: 'run' must map plan, cell, objects, execution and version to "
        'strings, got {"plan": 7}'
    )


def test_fault_grippers(tmp_path: Path) -> None:
    fault = {"entry": "fault", "fault": {"q": [0.0], "grippers": [{"mode": "open"}]}}
    assert error(tmp_path, START, fault) == (
        "journal.jsonl:2: 'fault.grippers[0].arm' must be a string, got null"
    )
    # resume reads both (it ended in a KeyError traceback from `run --resume`)
    fault = {"entry": "fault", "fault": {"grippers": [{"arm": "left", "mode": "open"}]}}
    assert error(tmp_path, START, fault) == (
        "journal.jsonl:2: 'fault.grippers[0].holds' is missing from this 'fault' entry"
    )


def test_invalid_utf8_line(tmp_path: Path) -> None:
    assert error(tmp_path, START, b'{"entry": "end", "x": "\xff\xfe"}', FINISHED) == (
        "journal.jsonl:2: not a journal entry (not UTF-8 text)"
    )


def test_deep_nesting(tmp_path: Path) -> None:
    deep = b'{"entry": "end", "x": ' + b"[" * 10000 + b"]" * 10000 + b"}"
    assert error(tmp_path, START, deep) == (
        "journal.jsonl:2: not a journal entry (JSON nested too deeply)"
    )


def test_unknown_entry(tmp_path: Path) -> None:
    assert error(tmp_path, START, {"entry": ["finished"]}) == (
        'journal.jsonl:2: unknown journal entry ["finished"]; known: cycle, end, fault, '
        "finished, measured, recovery, replanned, resume, sent, start, tared, timing, tool"
    )


def test_a_torn_last_line_is_ignored_even_mid_character(tmp_path: Path) -> None:
    path = _write(tmp_path, START, FINISHED)
    with path.open("ab") as f:
        f.write(b'{"entry": "sent", "label": "caf\xc3')  # killed inside a character
    assert read_progress(path).labels == ("s0 PickCable",)


def test_a_segment_finished_out_of_order_is_refused(tmp_path: Path) -> None:
    """Skipping ahead would resume after segments that never ran; going back is a replanned
    or resumed run finishing one again."""
    again = [START, FINISHED, {**FINISHED, "segment": 1}, FINISHED]
    assert read_progress(_write(tmp_path, *again)).done == 1
    assert error(tmp_path, START, FINISHED, {**FINISHED, "segment": 7}) == (
        "journal.jsonl:3: segment 7 finished, but the run's journal has segments finished up to "
        "0 only"
    )
    assert error(tmp_path, START, {**FINISHED, "segment": 2}) == (
        "journal.jsonl:2: segment 2 finished before segment 0"
    )


def test_cycles_are_counts_and_a_cycle_starts_the_segments_again(tmp_path: Path) -> None:
    cycle = {"entry": "cycle", "cycle": 2, "of": 3}
    progress = read_progress(_write(tmp_path, {**START, "cycles": 3}, FINISHED, cycle))
    assert (progress.cycle, progress.cycles, progress.done) == (2, 3, 0)
    assert progress.q == tuple(FINISHED["q"])  # where the arms are when the cycle begins
    assert error(tmp_path, START, {**cycle, "cycle": 4}) == "journal.jsonl:2: cycle 4 of 3"
    assert error(tmp_path, {**START, "cycles": 0}) == (
        "journal.jsonl:1: 'cycles' must be a count of cycles (1 to 1000000), got 0"
    )
    assert error(tmp_path, START, {**cycle, "of": True}) == (
        "journal.jsonl:2: 'of' must be a count of cycles (1 to 1000000), got true"
    )
