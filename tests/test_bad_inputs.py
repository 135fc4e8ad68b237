"""The malformed-input corpus: every folder under tests/data/bad/ is a small, complete cell
(or just the files one mistake needs) with one mistake in it. ``cellengine validate .`` run
inside the folder must print exactly the lines that ``expected.txt`` gives for it, each
problem at file:line:col (CSV: file:row), and exit 1. No case may end in a traceback.

``expected.txt`` holds, per case, a header ``== <case> <exit code>`` and the lines of
standard output. The folder's absolute path, which some messages give ("looked for ..."),
is written ``<case>``. Size caps are lowered for the ``*_size_cap`` cases rather than
committing large files.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from cellengine.cli import main
from cellengine.info import files

BAD = Path(__file__).resolve().parent / "data" / "bad"

# case -> (kind of file, cap in bytes) for the duration of the case
CAPS = {
    "yaml_size_cap": ("yaml", 256),
    "x3d_size_cap": ("x3d", 512),
    "models_size_cap": ("xml", 256),
    "map_size_cap": ("csv", 64),
}


def _expected() -> dict[str, tuple[int, list[str]]]:
    cases: dict[str, tuple[int, list[str]]] = {}
    lines: list[str] = []
    for line in (BAD / "expected.txt").read_text(encoding="utf-8").splitlines():
        if line.startswith("== "):
            _, name, code = line.split()
            assert name not in cases, f"{name} is listed twice in expected.txt"
            lines = []
            cases[name] = (int(code), lines)
        elif line:
            lines.append(line)
    return cases


EXPECTED = _expected()


def test_every_case_folder_has_its_expected_output() -> None:
    folders = sorted(p.name for p in BAD.iterdir() if p.is_dir())
    assert folders == sorted(EXPECTED)
    assert len(folders) >= 70
    assert set(CAPS) <= set(EXPECTED)


@pytest.mark.parametrize("case", sorted(EXPECTED))
def test_bad_input(
    case: str, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = BAD / case
    monkeypatch.chdir(folder)
    if case in CAPS:
        kind, cap = CAPS[case]
        monkeypatch.setitem(files.MAX_BYTES, kind, cap)
    code = main(["validate", "--no-compile", "."])  # the files; compiling is tested elsewhere
    out = capsys.readouterr().out.replace(str(folder), "<case>")
    exit_code, lines = EXPECTED[case]
    assert out.splitlines() == lines
    assert code == exit_code
