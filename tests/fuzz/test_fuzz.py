"""Fuzz target (#19): hostile X3D Transforms and geometry, URDF meshes and journal entries,
each loaded by the real engine in a subprocess, which must end by itself with exit 0, 1 or 2
and no traceback (tests/fuzz/target.py).

In `make test` each target tries a few derandomized examples (the same ones every run);
`make fuzz` (CELLENGINE_FUZZ=long) tries many random ones, and hypothesis keeps any failure
in .hypothesis/ to try first next time. CELLENGINE_FUZZ_EXAMPLES=N sets the count of either.
"""

from __future__ import annotations

import os
import re
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, Phase, event, given, settings
from hypothesis import strategies as st

from tests.conftest import CELLS, DATA
from tests.fuzz.strategies import (
    apply_edits,
    journal_edits,
    scales,
    stl_files,
    transform_attributes,
    transform_fields,
    x3d_geometry,
)
from tests.fuzz.target import Outcome, assert_clean, cellengine, load_cell

_SLOW_OK = [HealthCheck.too_slow, HealthCheck.data_too_large, HealthCheck.large_base_example]
# CI: the same examples every run, a failure reported as found (shrinking a subprocess's
# input takes minutes); a long run shrinks it, and keeps it in .hypothesis/ for the next
settings.register_profile(
    "fuzz-ci", max_examples=15, derandomize=True, database=None, deadline=None,
    suppress_health_check=_SLOW_OK, phases=[Phase.explicit, Phase.generate],
)  # fmt: skip
settings.register_profile(
    "fuzz-long", max_examples=500, deadline=None, suppress_health_check=_SLOW_OK
)
_LONG = os.environ.get("CELLENGINE_FUZZ") == "long"
_EXAMPLES = os.environ.get("CELLENGINE_FUZZ_EXAMPLES")


def fuzz(ci_examples: int) -> settings:
    """The profile of this run: in CI ``ci_examples`` (a load costs about 1 s, a resume 3),
    else the long profile's; CELLENGINE_FUZZ_EXAMPLES overrides either."""
    count = int(_EXAMPLES) if _EXAMPLES else None if _LONG else ci_examples
    profile = settings.get_profile("fuzz-long" if _LONG else "fuzz-ci")
    return settings(profile, max_examples=count) if count else profile


TIMEOUT = 60.0  # s: a load takes about 1 s; a shared CI machine may be slow, a hang is not
RESUME_TIMEOUT = 120.0  # s: a resume compiles the plan (3 s) and runs what is left


def judged(outcome: Outcome, shown_input: str) -> None:
    """Assert a clean end; count exit codes (pytest --hypothesis-show-statistics shows how
    many inputs got past the loaders: exit 0)."""
    event(f"exit {outcome.code}: {_gist(outcome)}")
    assert_clean(outcome, shown_input)


def _gist(outcome: Outcome) -> str:
    """The first problem printed, without its place, names and numbers."""
    lines = [ln for ln in (outcome.stdout + outcome.stderr).splitlines() if ln.strip()]
    first = lines[0].split(": ", 1)[-1] if lines else ""
    return re.sub(r"'[^']*'|\"[^\"]*\"|[-+]?\d[\w.+-]*", "_", first)[:70]


def shown(data: bytes | str, limit: int = 4000) -> str:
    text = data.decode(errors="backslashreplace") if isinstance(data, bytes) else data
    return text if len(text) <= limit else text[:limit] + f"... ({len(text)} characters)"


# ------------------------------------------------------------------------------------- X3D

X3D_CASE = DATA / "bad" / "x3d_bad_rotation_text"  # a routing platform, its X3D replaced
ELEMENTS = {  # DEF: the translation and geometry of a sound platform (mm)
    "Conn": ("0 5 0", '<Box size="44 63 44"/>'),
    "G1": ("100 5 0", '<Box size="10 60 24"/>'),
    "G2": ("200 5 0", '<Box size="10 60 24"/>'),
    "CA": ("0 5 -80", '<Box size="10 70 54"/>'),
    "CB": ("120 5 -80", '<Box size="10 70 54"/>'),
}


@st.composite
def x3d_documents(draw: st.DrawFn) -> str:
    """The platform's X3D, one or two elements' Transform fields and geometry hostile (and
    now and then the whole platform's): the others sound, so that a load goes on past them."""
    mm = {"scale": "0.001 0.001 0.001"}
    plate = draw(transform_fields()) if draw(st.integers(0, 3)) == 0 else mm
    chosen = draw(st.sets(st.sampled_from(list(ELEMENTS)), min_size=1, max_size=2))
    parts = []
    for name, (translation, box) in ELEMENTS.items():
        fields = {"translation": translation}
        if name in chosen:
            fields.update(draw(transform_fields()))
        geometry = draw(x3d_geometry()) if name in chosen else box
        parts.append(
            f'<Transform DEF="{name}"{transform_attributes(fields)}>'
            f"<Shape>{geometry}</Shape></Transform>"
        )
    body = "\n".join(parts)
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n<X3D version="3.0" profile="Immersive">\n'
        f'<Scene>\n<Transform DEF="Plate"{transform_attributes(plate)}>\n'
        f'<Shape><Box size="300 10 200"/></Shape>\n{body}\n</Transform>\n</Scene>\n</X3D>\n'
    )


@pytest.fixture(scope="module")
def scratch() -> Iterator[Path]:
    """A folder for the module's examples (hypothesis runs many examples per test call)."""
    with tempfile.TemporaryDirectory(prefix="cellengine-fuzz-") as d:
        yield Path(d)


def fresh(scratch: Path, source: Path) -> Path:
    """A new copy of ``source`` under ``scratch``."""
    target = Path(tempfile.mkdtemp(dir=scratch)) / "cell"
    shutil.copytree(source, target)
    return target


@fuzz(20)
@given(x3d=x3d_documents())
def test_x3d_transforms_and_geometry(scratch: Path, x3d: str) -> None:
    cell = fresh(scratch, X3D_CASE)
    (cell / "routing" / "routing.x3d").write_text(x3d)
    judged(load_cell(cell / "cell.yaml", TIMEOUT), shown(x3d))
    shutil.rmtree(cell.parent)


# ------------------------------------------------------------------------------------ URDF

MESH_CELL = DATA / "urdf" / "meshes"  # one arm whose link1 has a mesh by a relative path
LINK1_MESH = 'filename="../meshes/cube_mm.stl" scale="0.001 0.002 0.003"'


@fuzz(20)
@given(stl=stl_files, scale=st.none() | scales)
def test_urdf_meshes(scratch: Path, stl: bytes, scale: str | None) -> None:
    cell = fresh(scratch, MESH_CELL)
    urdf = cell / "arm_pkg" / "urdf" / "arm.urdf"
    text = urdf.read_text()
    assert LINK1_MESH in text
    if scale is not None:
        mesh = f'filename="../meshes/cube_mm.stl"{transform_attributes({"scale": scale})}'
        urdf.write_text(text.replace(LINK1_MESH, mesh))
    (cell / "arm_pkg" / "meshes" / "cube_mm.stl").write_bytes(stl)
    judged(load_cell(cell / "cell.yaml", TIMEOUT), f"scale: {scale!r}\n{shown(stl)}")
    shutil.rmtree(cell.parent)


# --------------------------------------------------------------------------------- journal

PLAN = CELLS / "cable_routing" / "plan_straight.yaml"


@pytest.fixture(scope="module")
def genuine_journal(scratch: Path) -> list[bytes]:
    """The journal of a whole run of PLAN on the simulated cell, line by line."""
    out = scratch / "genuine"
    assert_clean(cellengine(["run", str(PLAN), "--out", str(out), "-q"], RESUME_TIMEOUT))
    return (out / "journal.jsonl").read_bytes().splitlines()


@fuzz(10)
@given(cut=st.integers(1, 10**6), edits=journal_edits(), torn=st.booleans())
def test_resume_from_an_edited_journal(
    scratch: Path,
    genuine_journal: list[bytes],
    cut: int,
    edits: list[tuple[str, int, Any]],
    torn: bool,
) -> None:
    """A run stopped after ``cut`` lines (never its end), its journal edited, resumed."""
    lines = genuine_journal[: 1 + cut % (len(genuine_journal) - 1)]
    data = b"\n".join(apply_edits(lines, edits)) + (b"" if torn else b"\n")
    run_dir = Path(tempfile.mkdtemp(dir=scratch))
    (run_dir / "journal.jsonl").write_bytes(data)
    outcome = cellengine(["run", str(PLAN), "--resume", str(run_dir), "-q"], RESUME_TIMEOUT)
    judged(outcome, f"edits: {shown(repr(edits), 2000)}\njournal (its end):\n{shown(data[-4000:])}")
    shutil.rmtree(run_dir)
