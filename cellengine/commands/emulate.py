"""`cellengine emulate ur --host ADDR [--host ADDR ...]`: emulated UR controllers for tests.

One emulated controller per loopback address, all in this process: the dashboard server
(29999), the script port (30003) and RTDE (30004) that ur-rtde's clients talk to, and a
simulated arm. See cellengine/emulate/ for what is emulated and how.

`cellengine emulate grbl [--count N]`: emulated GRBL 1.1 controllers (the lab bench's
cartesian axes) on pseudo-terminals (commands/emulate_serial.py).

`cellengine emulate camera CELL --out FILE`: a picture of the bench from the cell's camera
(commands/emulate_camera.py).
"""

from __future__ import annotations

import argparse
import ipaddress
import math
from pathlib import Path
from typing import Any

from cellengine.errors import Problem, UsageError


def add_parser(sub: Any, name: str) -> None:
    from cellengine.commands.emulate_camera import add_camera
    from cellengine.commands.emulate_serial import add_serial

    top = sub.add_parser(
        name,
        help="emulate robot controllers for tests: ur (on loopback addresses), grbl, "
        "loadcell and dynamixel (on pseudo-terminals); camera (a picture of the bench)",
        description="Emulate robot controllers in this process, for tests of the real "
        "drivers. Prints a line with 'ready' when they accept connections; stops on SIGTERM.",
    )
    kinds = top.add_subparsers(
        dest="robot", required=True, metavar="{ur,grbl,loadcell,dynamixel,camera}"
    )
    p = kinds.add_parser(
        "ur",
        help="Universal Robots controllers, one per loopback address",
        description="Emulate Universal Robots controllers, one per address, in this process: "
        "dashboard (29999), script port (30003), RTDE (30004) and a simulated arm. Prints a "
        "line with 'ready' when every controller accepts connections; stops on SIGTERM.",
    )
    add_serial(kinds)
    add_camera(kinds)
    p.add_argument(
        "--host",
        action="append",
        required=True,
        metavar="ADDR",
        help="an address to serve on "
        "(127.0.0.2, 127.0.0.3, ...: the ports are fixed, so one address per controller)",
    )
    p.add_argument(
        "--q0",
        action="append",
        default=[],
        metavar="HOST=q1,...,q6",
        help="an arm's starting joint angles in rad (default all zeros)",
    )
    p.add_argument(
        "--model",
        action="append",
        default=[],
        metavar="HOST=NAME",
        help="the robot model the dashboard reports: UR3, UR5 (default), UR10, UR16",
    )
    p.add_argument(
        "--fault",
        action="append",
        default=[],
        metavar="HOST@T:KIND",
        help="inject a fault T s after the first RTDE start: protective_stop, emergency_stop, "
        "frozen, drop, kill (or clear)",
    )
    p.add_argument(
        "--fault-socket",
        type=Path,
        metavar="PATH",
        help="a Unix socket taking lines 'HOST KIND' (KIND as for --fault, or clear)",
    )
    p.set_defaults(run=run)


def _usage(message: str) -> UsageError:
    return UsageError(Problem(message, "cellengine emulate"))


def _per_host(values: list[str], hosts: list[str], flag: str) -> dict[str, str]:
    out = {}
    for value in values:
        host, eq, rest = value.partition("=")
        if not eq or host not in hosts:
            raise _usage(f"{flag} '{value}': not HOST=... for one of the --host")
        out[host] = rest
    return out


def run(args: argparse.Namespace) -> int:
    from cellengine.emulate.faults import parse_flag
    from cellengine.emulate.process import serve

    hosts: list[str] = args.host
    for host in hosts:
        try:
            ipaddress.ip_address(host)
        except ValueError:
            raise _usage(f"--host '{host}' is not an IP address") from None
    if len(set(hosts)) != len(hosts):
        raise _usage("--host: an address given twice")
    q0 = {}
    for host, text in _per_host(args.q0, hosts, "--q0").items():
        try:
            q = [float(v) for v in text.split(",")]
        except ValueError:
            q = []
        if len(q) != 6 or not all(math.isfinite(v) for v in q):
            raise _usage(f"--q0 {host}: six joint angles in rad, not '{text}'")
        q0[host] = q
    models = {h: m.upper() for h, m in _per_host(args.model, hosts, "--model").items()}
    faults = []
    for spec in args.fault:
        try:
            fault = parse_flag(spec)
        except ValueError as e:
            raise _usage(f"--fault: {e}") from None
        if fault.host not in hosts:
            raise _usage(f"--fault '{spec}': {fault.host} is not one of the --host")
        faults.append(fault)
    return serve(hosts, q0, models, faults, args.fault_socket)
