"""`cellengine emulate grbl [--count N] [--set I:N=V] [--fault I@T:KIND] [--log FILE]`:
emulated GRBL 1.1 controllers on pseudo-terminals, for tests of the lab driver; and
`cellengine emulate loadcell [--load G] [--zero G] [--noise G] [--fault 0@T:KIND]`: an
emulated serial load cell.

Each prints ``cellengine emulate KIND: ready: PTY [PTY ...]`` (the paths a host opens as
it would /dev/ttyACM0) and serves them until SIGTERM. See cellengine/emulate/grbl.py and
loadcell.py for what is emulated.
"""

from __future__ import annotations

import argparse
import re
import signal
import sys
from pathlib import Path
from typing import Any

from cellengine.errors import Problem, UsageError


def add_serial(kinds: Any) -> None:
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
    c = kinds.add_parser(
        "loadcell",
        help="a serial load cell (HX711 on an Arduino) on a pseudo-terminal",
        description="Emulate a serial load cell printing one reading (g) a line, 10 a "
        "second, with noise. Prints 'ready' and the terminal's path; stops on SIGTERM.",
    )
    c.add_argument("--load", type=float, default=0.0, help="g on the cell (default 0)")
    c.add_argument("--zero", type=float, default=3.7, help="g it reads empty (default 3.7)")
    c.add_argument("--noise", type=float, default=0.2, help="g standard deviation (0.2)")
    c.add_argument("--seed", type=int, default=0, help="the noise's seed (default 0)")
    _fault_and_log(c, "T s after it starts: silence, garbage, lost", "line it printed")
    c.set_defaults(run=run_loadcell)
    d = kinds.add_parser(
        "dynamixel",
        help="a Dynamixel bus (Protocol 2.0, XL430-W250 servos) on a pseudo-terminal",
        description="Emulate a Dynamixel bus with XL430-W250 servos: ping, read, write, "
        "sync write, CRC-16. Prints 'ready' and the terminal's path; stops on SIGTERM.",
    )
    d.add_argument("--id", type=int, action="append", default=[], help="a servo's id (1..)")
    _fault_and_log(d, "T s after it is first written to: stuck, overload, lost", "packet it took")
    d.set_defaults(run=run_dynamixel)


def _fault_and_log(p: Any, faults: str, logged: str) -> None:
    """A one-device emulator's --fault and --log."""
    p.add_argument("--fault", action="append", default=[], metavar="0@T:KIND", help=faults)
    p.add_argument("--log", type=Path, help=f"append every {logged} here (JSON lines)")


def _usage(message: str, kind: str = "grbl") -> UsageError:
    return UsageError(Problem(message, f"cellengine emulate {kind}"))


def run(args: argparse.Namespace) -> int:
    from cellengine.emulate.grbl import Grbl
    from cellengine.emulate.serial_pty import open_port

    if not 1 <= args.count <= 8:
        raise _usage(f"--count {args.count}: from 1 to 8 controllers")
    grbls = [Grbl() for _ in range(args.count)]
    ports = [open_port(g) for g in grbls]
    for spec in args.set:
        m = re.fullmatch(r"(\d+):\$?(\d+)=([-+]?\d*\.?\d+)", spec)
        if m is None or int(m[1]) >= args.count:
            raise _usage(f"--set '{spec}': not I:N=V for a controller I below {args.count}")
        grbls[int(m[1])].settings[int(m[2])] = float(m[3])
    for spec in args.fault:
        (fault,) = _faults([spec], args.count, ("lost", *Grbl().faults))
        ports[int(spec.split("@", 1)[0])].faults.append(fault)
    return _serve("grbl", ports, args.log)


def run_loadcell(args: argparse.Namespace) -> int:
    from cellengine.emulate.loadcell import LoadCellEmulator
    from cellengine.emulate.serial_pty import open_port

    device = LoadCellEmulator(args.load, args.zero, args.noise, args.seed)
    port = open_port(device)
    port.faults += _faults(args.fault, 1, ("lost", *device.faults), "loadcell")
    return _serve("loadcell", [port], args.log)


def run_dynamixel(args: argparse.Namespace) -> int:
    from cellengine.emulate.dynamixel import DynamixelBus, Servo
    from cellengine.emulate.serial_pty import open_port

    ids = args.id or [1]
    if any(not 0 <= i <= 252 for i in ids) or len(set(ids)) != len(ids):
        raise _usage(f"--id {ids}: distinct ids from 0 to 252", "dynamixel")
    bus = DynamixelBus({i: Servo(i) for i in ids})
    port = open_port(bus)
    port.faults += _faults(args.fault, 1, ("lost", *bus.faults), "dynamixel")
    return _serve("dynamixel", [port], args.log)


def _faults(
    specs: list[str], count: int, kinds: tuple[str, ...], what: str = "grbl"
) -> list[tuple[float, str]]:
    out = []
    for spec in specs:
        m = re.fullmatch(r"(\d+)@(\d*\.?\d+):(\w+)", spec)
        if m is None or int(m[1]) >= count or m[3] not in kinds:
            raise _usage(
                f"--fault '{spec}': not I@T:KIND for a device I below {count} and KIND one "
                f"of {', '.join(kinds)}",
                what,
            )
        out.append((float(m[2]), m[3]))
    return out


def _serve(what: str, ports: list[Any], log_path: Path | None) -> int:
    from cellengine.emulate.serial_pty import ready_line, serve

    stop = [False]
    signal.signal(signal.SIGTERM, lambda *_: stop.__setitem__(0, True))
    print(ready_line(what, ports), flush=True)
    log = None if log_path is None else log_path.open("a", encoding="utf-8")
    try:
        serve(ports, stop, log)
    except KeyboardInterrupt:
        pass
    finally:
        if log is not None:
            log.close()
    print(f"cellengine emulate {what}: stopped", file=sys.stderr)
    return 0
