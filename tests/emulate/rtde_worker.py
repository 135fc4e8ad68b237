"""A process that drives the real ur-rtde clients for the emulator's tests.

The tests never construct a client in their own process: the pybind11 constructors hold the
GIL and wait without a timeout, so a broken emulator would hang pytest. Instead this worker
reads one JSON request per line on stdin and answers one JSON line on the file descriptor
named on its command line (ur-rtde prints on stdout); the test side waits for each answer
with a deadline and kills the worker when it does not come (see harness.py).

Requests: {"op": "new", "name": N, "cls": "control"|"receive"|"io"|"dashboard", "host": H},
{"op": "call", "name": N, "method": M, "args": [...]}, and the loops that must run at 500 Hz
next to the client: "servo_sine", "speed", "kick".
"""

from __future__ import annotations

import json
import math
import os
import sys
import time
from typing import Any

import dashboard_client
import rtde_control
import rtde_io
import rtde_receive

CLASSES = {
    "control": rtde_control.RTDEControlInterface,
    "receive": rtde_receive.RTDEReceiveInterface,
    "io": rtde_io.RTDEIOInterface,
    "dashboard": dashboard_client.DashboardClient,
}
objects: dict[str, Any] = {}


def plain(value: Any) -> Any:
    """A client's return value as JSON."""
    if isinstance(value, bool | int | float | str) or value is None:
        return value
    try:
        return [plain(v) for v in value]
    except TypeError:
        return repr(value)


def servo_sine(req: dict[str, Any]) -> dict[str, Any]:
    """servoJ at 500 Hz for ``seconds``: joint ``joint`` follows q0 + A sin(2 pi f t)."""
    c, r = objects[req["control"]], objects[req["receive"]]
    q0, joint, amp, freq = req["q0"], req["joint"], req["amplitude"], req["frequency"]
    commanded, actual, target, periods = [], [], [], []
    start = last = time.perf_counter()
    for k in range(int(req["seconds"] * 500)):
        t_cycle = c.initPeriod()
        q = list(q0)
        q[joint] += amp * math.sin(2 * math.pi * freq * k * 0.002)
        if not c.servoJ(q, 0.0, 0.0, 0.002, req["lookahead"], req["gain"]):
            return {"ok": False, "error": f"servoJ returned False at cycle {k}"}
        commanded.append(q[joint])
        actual.append(r.getActualQ()[joint])
        target.append(r.getTargetQ()[joint])
        c.waitPeriod(t_cycle)
        now = time.perf_counter()
        periods.append(now - last)
        last = now
    stopped = c.servoStop(10.0)
    return {
        "ok": True,
        "value": {
            "commanded": commanded,
            "actual": actual,
            "target": target,
            "periods": periods[1:],
            "seconds": time.perf_counter() - start,
            "stopped": stopped,
        },
    }


def speed(req: dict[str, Any]) -> dict[str, Any]:
    """speedJ(qd, a) every cycle for ``seconds``, then what getActualQd says."""
    c, r = objects[req["control"]], objects[req["receive"]]
    end = time.perf_counter() + req["seconds"]
    while time.perf_counter() < end:
        t_cycle = c.initPeriod()
        if not c.speedJ(req["qd"], req["a"], 0.002):
            return {"ok": False, "error": "speedJ returned False"}
        c.waitPeriod(t_cycle)
    return {"ok": True, "value": {"qd": list(r.getActualQd()), "q": list(r.getActualQ())}}


def kick(req: dict[str, Any]) -> dict[str, Any]:
    """kickWatchdog at ``hz`` for ``seconds``; how many kicks returned True."""
    c = objects[req["control"]]
    good = 0
    n = int(req["seconds"] * req["hz"])
    for _ in range(n):
        good += bool(c.kickWatchdog())
        time.sleep(1.0 / req["hz"])
    return {"ok": True, "value": good}


def handle(req: dict[str, Any]) -> dict[str, Any]:
    op = req["op"]
    if op == "new":
        objects[req["name"]] = CLASSES[req["cls"]](req["host"], *req.get("args", []))
        return {"ok": True, "value": None}
    if op == "call":
        value = getattr(objects[req["name"]], req["method"])(*req.get("args", []))
        return {"ok": True, "value": plain(value)}
    loops = {"servo_sine": servo_sine, "speed": speed, "kick": kick}
    return loops[op](req)


def main() -> None:
    answers = os.fdopen(int(sys.argv[1]), "w", buffering=1)
    for line in sys.stdin:
        req = json.loads(line)
        try:
            reply = handle(req)
        except Exception as e:  # the client's exceptions are answers too
            reply = {"ok": False, "error": f"{type(e).__name__}: {e}"}
        answers.write(json.dumps(reply) + "\n")


if __name__ == "__main__":
    main()
