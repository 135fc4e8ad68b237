"""Emulated serial devices served on pseudo-terminals in a thread of the test process."""

from __future__ import annotations

import threading
from collections.abc import Iterator
from contextlib import contextmanager

from cellengine.emulate.serial_pty import Device, Port, open_port, serve


@contextmanager
def served(*devices: Device) -> Iterator[list[Port]]:
    """Each device on its own pty, served until the block ends."""
    ports = [open_port(d) for d in devices]
    stop = [False]
    thread = threading.Thread(target=serve, args=(ports, stop), daemon=True)
    thread.start()
    try:
        yield ports
    finally:
        stop[0] = True
        thread.join(timeout=2)
