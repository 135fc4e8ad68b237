"""Drivers by the name a cell file gives them (``driver: {kind: sim}``): a plain dict.

The UR driver joins as ``"ur_rtde"``; its vendor library is imported only when it is used.
The lab bench's GRBL controllers join as ``"lab"`` (pyserial imported when it configures).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from cellengine.drivers.base import Driver
from cellengine.drivers.fault import DriverRefused
from cellengine.drivers.lab import LabBenchDriver
from cellengine.drivers.sim import SimDriver
from cellengine.drivers.ur_rtde import UrDriver
from cellengine.errors import known
from cellengine.info.cell import Cell
from cellengine.info.objects import Objects

# the UR driver imports its vendor library only when it configures
DRIVERS: dict[str, type[Driver]] = {"sim": SimDriver, "ur_rtde": UrDriver, "lab": LabBenchDriver}


def make_driver(
    cell: Cell,
    joints: Mapping[str, Sequence[str]],
    *,
    objects: Objects | None = None,
    kind: str | None = None,
    **options: Any,
) -> Driver:
    """The driver the cell names (or ``kind``, e.g. from ``--driver``), unconfigured.

    ``joints``: each robot's joint names (the cell's q is them one robot after the other);
    ``options`` go to the driver class (for ``sim``: realtime, lag, q0, ...).
    """
    name = kind if kind is not None else cell.driver.kind
    cls = DRIVERS.get(name)
    if cls is None:
        raise DriverRefused(name, f"no driver '{name}' is available" + known(DRIVERS))
    if name == "sim" and cell.driver.kind == "sim":
        options = {"mass_noise": cell.driver.mass_noise, **options}
    return cls(cell, joints, objects=objects, **options)
