"""Drivers: one interface and one lifecycle; the simulated cell by default.

- :mod:`.lifecycle`: the states and transitions every driver follows.
- :mod:`.base`: :class:`Driver`, the interface, with the shared checks.
- :mod:`.sim`: :class:`SimDriver`, the simulated cell (with fault injection for tests).
- :mod:`.record`: :class:`Recorder`, what was sent and what happened, as plain data.
- :mod:`.registry`: ``DRIVERS`` and :func:`make_driver`.
- :mod:`.play`: a whole Program on a driver, each event with its segment.
"""

from cellengine.drivers.base import Driver, GripperState
from cellengine.drivers.fault import DriverFault, DriverRefused, Fault
from cellengine.drivers.layout import CellLayout
from cellengine.drivers.lifecycle import LifecycleError, State
from cellengine.drivers.play import play, segment_events
from cellengine.drivers.record import Played, Recorder
from cellengine.drivers.registry import DRIVERS, make_driver
from cellengine.drivers.sim import SimDriver

__all__ = [
    "DRIVERS",
    "CellLayout",
    "Driver",
    "DriverFault",
    "DriverRefused",
    "Fault",
    "GripperState",
    "LifecycleError",
    "Played",
    "Recorder",
    "SimDriver",
    "State",
    "make_driver",
    "play",
    "segment_events",
]
