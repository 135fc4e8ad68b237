"""`cellengine emulate grbl [--count N] [--set I:N=V] [--fault I@T:KIND] [--log FILE]`:
emulated GRBL 1.1 controllers on pseudo-terminals, for tests of the lab driver.

Prints ``cellengine emulate grbl: ready: PTY [PTY ...]`` (the paths a host opens as it
would /dev/ttyACM0) and serves them until SIGTERM. See cellengine/emulate/grbl.py for what
is emulated.
"""

from __future__ import annotations

import argparse
import re
import signal
import sys
from pathlib import Path
from typing import Any

from cellengine.errors import Problem, UsageError


def add_grbl(kinds: Any) -> None:
    p = kinds.add_parser(
        "grbl",
        help="GRBL 1.1 controllers on pseudo-terminals",
        description="Emulate GRBL 1.1 controllers (a cartesian robot's axes on an Arduino) "
        "on pseudo-terminals: character-counted streaming, a 15-block planner with "
        "acceleration, status reports, feed hold, reset, alarms, homing. Prints 'ready' and "
        "the terminals' paths; stops on SIGTERM.",
    )
    p.add_argument("--count", type=int, default=1, help="how many controllers (default 1)")
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="I:N=V",
        help="controller I's setting $N (e.g. 0:$110=3000 or 0:110=3000)",
    )
    p.add_argument(
        "--fault",
        action="append",
        default=[],
        metavar="I@T:KIND",
        help="controller I, T s after the first byte it got: alarm1 (a hard limit), lost "
        "(the port goes away), error (the next line answered error:24)",
    )
    p.add_argument("--log", type=Path, help="append every line executed here (JSON lines)")
    p.set_defaults(run=run)


def _usage(message: str) -> UsageError:
    return UsageError(Problem(message, "cellengine emulate grbl"))


def run(args: argparse.Namespace) -> int:
    from cellengine.emulate.grbl import Grbl
    from cellengine.emulate.grbl_pty import FAULTS, open_port, ready_line, serve

    if not 1 <= args.count <= 8:
        raise _usage(f"--count {args.count}: from 1 to 8 controllers")
    ports = [open_port(Grbl()) for _ in range(args.count)]
    for spec in args.set:
        m = re.fullmatch(r"(\d+):\$?(\d+)=([-+]?\d*\.?\d+)", spec)
        if m is None or int(m[1]) >= args.count:
            raise _usage(f"--set '{spec}': not I:N=V for a controller I below {args.count}")
        ports[int(m[1])].grbl.settings[int(m[2])] = float(m[3])
    for spec in args.fault:
        m = re.fullmatch(r"(\d+)@(\d*\.?\d+):(\w+)", spec)
        if m is None or int(m[1]) >= args.count or m[3] not in FAULTS:
            raise _usage(
                f"--fault '{spec}': not I@T:KIND for a controller I below {args.count} and "
                f"KIND one of {', '.join(FAULTS)}"
            )
        ports[int(m[1])].faults.append((float(m[2]), m[3]))
    stop = [False]
    signal.signal(signal.SIGTERM, lambda *_: stop.__setitem__(0, True))
    print(ready_line(ports), flush=True)
    log = None if args.log is None else args.log.open("a", encoding="utf-8")
    try:
        serve(ports, stop, log)
    except KeyboardInterrupt:
        pass
    finally:
        if log is not None:
            log.close()
    print("cellengine emulate grbl: stopped", file=sys.stderr)
    return 0
