"""Shared fixtures: paths to the reference cells and the REMODEL sample."""

from __future__ import annotations

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
CELLS = ROOT / "cells"
DATA = Path(__file__).resolve().parent / "data"
REMODEL = ROOT.parent / "shared" / "remodel"


@pytest.fixture
def write(tmp_path: Path):
    """Write a text file under tmp_path and return its path."""

    def _write(name: str, text: str) -> Path:
        p = tmp_path / name
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(text)
        return p

    return _write
