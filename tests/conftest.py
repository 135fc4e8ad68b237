"""Shared fixtures: paths to the reference cells, DESIGN.md and the REMODEL sample."""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
CELLS = ROOT / "cells"
DATA = Path(__file__).resolve().parent / "data"


def _shared() -> Path:
    """The team's shared folder for DESIGN.md (the contract): $CELLENGINE_SHARED, or the nearest
    'shared' folder beside the checkout or one of its parents, or the copy in tests/data."""
    if "CELLENGINE_SHARED" in os.environ:
        return Path(os.environ["CELLENGINE_SHARED"])
    for parent in ROOT.parents:
        if (parent / "shared" / "DESIGN.md").is_file():
            return parent / "shared"
    return DATA / "shared"


SHARED = _shared()
# The REMODEL sample the tests read: a copy in tests/data, so that a checkout alone passes.
REMODEL = DATA / "shared" / "remodel"


@pytest.fixture
def write(tmp_path: Path) -> Callable[[str, str], Path]:
    """Write a text file under tmp_path and return its path."""

    def _write(name: str, text: str) -> Path:
        p = tmp_path / name
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(text)
        return p

    return _write


@pytest.fixture(autouse=True)
def _compile_cache(
    tmp_path_factory: pytest.TempPathFactory, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Each test its own compile cache: no outcome leaks from one test into another (a test
    that patches the engine must see it compile), and none into the user's ~/.cache."""
    monkeypatch.setenv("CELLENGINE_CACHE_DIR", str(tmp_path_factory.mktemp("cache")))
