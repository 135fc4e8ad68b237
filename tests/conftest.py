"""Shared fixtures: paths to the reference cells and the REMODEL sample."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
CELLS = ROOT / "cells"
DATA = Path(__file__).resolve().parent / "data"


def _shared() -> Path:
    """The team's shared folder (DESIGN.md, the REMODEL sample): $CELLENGINE_SHARED, or the
    nearest 'shared' folder beside the checkout or one of its parents."""
    if "CELLENGINE_SHARED" in os.environ:
        return Path(os.environ["CELLENGINE_SHARED"])
    for parent in ROOT.parents:
        if (parent / "shared" / "remodel").is_dir():
            return parent / "shared"
    return ROOT.parent / "shared"


SHARED = _shared()
REMODEL = SHARED / "remodel"


@pytest.fixture
def write(tmp_path: Path):
    """Write a text file under tmp_path and return its path."""

    def _write(name: str, text: str) -> Path:
        p = tmp_path / name
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(text)
        return p

    return _write
