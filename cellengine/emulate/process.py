"""The emulator process: controllers from the command line's options, the loop, a line
containing ``ready`` on stdout (flushed) once every controller accepts connections, and a
clean exit 0 on SIGTERM or SIGINT."""

from __future__ import annotations

import sys
from collections.abc import Mapping, Sequence
from pathlib import Path

from cellengine.emulate.controller import Controller
from cellengine.emulate.faults import Fault
from cellengine.emulate.loop import Emulator, log
from cellengine.errors import EXIT_USAGE


def serve(
    hosts: Sequence[str],
    q0: Mapping[str, Sequence[float]],
    models: Mapping[str, str],
    faults: Sequence[Fault],
    fault_socket: Path | None,
) -> int:
    controllers = [Controller(h, q0.get(h, [0.0] * 6), models.get(h, "UR5"), log) for h in hosts]
    emulator = Emulator(controllers, list(faults), fault_socket)

    def ready() -> None:
        where = ", ".join(f"{h} (29999, 30003, 30004)" for h in hosts)
        extra = f"; faults on {fault_socket}" if fault_socket else ""
        print(f"cellengine emulate ur: ready: {where}{extra}", flush=True)

    try:
        return emulator.run(ready)
    except OSError as e:  # an address not local, a port taken
        emulator.close()
        print(f"cellengine emulate: cannot listen: {e}", file=sys.stderr)
        return EXIT_USAGE
