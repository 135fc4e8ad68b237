"""The `emulated` fixture: the cable cell pointed at two free loopback addresses, and a list
the test puts the emulators it starts in (each killed at the end, whatever happened)."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.drivers.urcell import ur_cell
from tests.emulate.harness import Emulator, free_hosts


@pytest.fixture
def emulated(tmp_path: Path) -> Iterator[tuple[Path, list[str], list[Emulator]]]:
    hosts = free_hosts(2)
    started: list[Emulator] = []
    yield ur_cell(tmp_path, hosts), hosts, started
    for e in started:
        e.close()
