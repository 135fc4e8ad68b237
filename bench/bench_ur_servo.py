"""The UR driver's servo loop (issue #6): 60 s of servoJ streaming to two emulated
controllers through the real ur-rtde client, and the time from a fault's detection to both
arms stopped.

Run: .venv/bin/python bench/bench_ur_servo.py [--seconds 60]
The emulator (`cellengine emulate ur`) runs in its own process on two free loopback
addresses, one process per arm. Figures: the loop's achieved rate, the 50th / 99th / 99.9th
percentiles of |period - 2 ms|; and for each fault kind, injected on one arm mid-segment:
from injection to detection, from detection to every arm's stop command sent, and from
detection to the healthy arm at rest (read by a receive client of the bench's own).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from cellengine.drivers.fault import DriverFault  # noqa: E402
from cellengine.drivers.ur_rtde import UrDriver  # noqa: E402
from cellengine.info.load import load_cell  # noqa: E402
from cellengine.motion.trajectory import Trajectory  # noqa: E402
from cellengine.program import CompiledSegment, Segment  # noqa: E402
from tests.drivers.urcell import ur_cell  # noqa: E402
from tests.emulate.harness import Emulator, free_hosts  # noqa: E402

HOME = np.array([0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0])


def sine(seconds: float, names: tuple[str, ...]) -> Trajectory:
    """Every joint 0.2 rad about home at 0.25 Hz, starting and ending at rest (a ramp)."""
    t = np.arange(0.0, seconds + 1e-9, 0.01)
    w = 2 * np.pi * 0.25
    ramp = np.clip(t / 2.0, 0, 1) * np.clip((seconds - t) / 2.0, 0, 1)
    base = np.concatenate([HOME, HOME])
    q = base + 0.2 * (ramp * np.sin(w * t))[:, None]
    qd = np.gradient(q, t, axis=0)
    qdd = np.gradient(qd, t, axis=0)
    qd[[0, -1]] = 0.0
    qdd[[0, -1]] = 0.0
    return Trajectory(names, t, q, qd, qdd)


FAULTS = [  # (fault, arm that has it)
    ("protective_stop", "right"),
    ("emergency_stop", "left"),
    ("frozen", "right"),
    ("drop", "left"),
    ("kill", "right"),
]
REST_SPEED = 0.005  # rad/s: an arm slower than this on every joint stands


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--repeats", type=int, default=3, help="runs of each fault (0: none)")
    args = ap.parse_args()
    print(json.dumps(run(args.seconds, args.repeats), indent=2))


def _cell(hosts: list[str]) -> Path:
    return ur_cell(Path(tempfile.mkdtemp()), hosts) / "cell.yaml"


JOINTS = {"left": [f"left_j{i}" for i in range(6)], "right": [f"right_j{i}" for i in range(6)]}
NAMES = tuple(JOINTS["left"] + JOINTS["right"])


def _emulators(hosts: list[str]) -> list[Emulator]:
    """One emulator process per arm (so that killing one spares the other), at home."""
    q0 = ",".join(f"{v:.6f}" for v in HOME)
    return [Emulator([h], "--q0", f"{h}={q0}") for h in hosts]


def run(seconds: float = 60.0, repeats: int = 3) -> dict[str, float]:
    hosts = free_hosts(2)
    cell, _ = load_cell(_cell(hosts))
    emulators = _emulators(hosts)
    out: dict[str, float] = {}
    try:
        driver = UrDriver(cell, JOINTS)
        driver.configure()
        driver.activate()
        t0 = time.perf_counter()
        driver.execute(CompiledSegment(Segment(0, "bench"), "split", sine(seconds, NAMES), {}))
        wall = time.perf_counter() - t0
        timing = driver.timing()
        driver.finalize()
    finally:
        for e in emulators:
            e.close()
    err = timing["period_error_ms"]
    out.update(
        {
            "ur_servo_seconds": seconds,
            "ur_servo_wall_s": wall,
            "ur_servo_rate_hz": timing["rate_hz"],
            "ur_servo_period_error_p50_ms": err["p50"],
            "ur_servo_period_error_p99_ms": err["p99"],
            "ur_servo_period_error_p999_ms": err["p99.9"],
            "ur_servo_period_max_ms": timing["nominal_period_ms"] + err["max"],
        }
    )
    for kind, arm in FAULTS if repeats > 0 else ():
        runs = [fault_run(kind, arm) for _ in range(repeats)]
        for key in runs[0]:
            values = [r[key] for r in runs]
            out[f"ur_{kind}_{arm}_{key}_median"] = float(np.median(values))
            out[f"ur_{kind}_{arm}_{key}_max"] = float(np.max(values))
    stops = [v for k, v in out.items() if k.endswith("stop_commands_ms_max")]
    if stops:
        out["ur_fault_to_stop_ms"] = max(stops)
    return out


def fault_run(kind: str, arm: str) -> dict[str, float]:
    """A 6 s segment on fresh controllers, ``kind`` injected on ``arm`` 2 s in: from the
    injection to its detection, from detection to every arm's stop command, and from
    detection to the other arm standing (its speed at the fault, and 10 rad/s^2)."""
    hosts = free_hosts(2)
    cell, _ = load_cell(_cell(hosts))
    emulators = _emulators(hosts)
    i = ("left", "right").index(arm)
    import rtde_receive

    try:
        rcv = rtde_receive.RTDEReceiveInterface(hosts[1 - i])
        driver = UrDriver(cell, JOINTS)
        driver.configure()
        driver.activate()
        injected: list[float] = []

        def inject() -> None:
            time.sleep(2.0)
            injected.append(time.perf_counter())
            with contextlib.suppress(Exception):  # a killed emulator does not answer
                emulators[i].fault(hosts[i], kind, timeout=1.0)

        threading.Thread(target=inject, daemon=True).start()
        with contextlib.suppress(DriverFault):  # the fault is the point
            driver.execute(CompiledSegment(Segment(0, kind), "split", sine(6.0, NAMES), {}))
        detected = driver.detections[-1]
        while max(abs(v) for v in rcv.getActualQd()) > REST_SPEED:
            time.sleep(0.0005)
        rest = time.perf_counter()
        figures = {
            "detect_ms": (detected - injected[0]) * 1e3,
            "stop_commands_ms": driver.stop_latencies[-1] * 1e3,
            "other_at_rest_ms": (rest - detected) * 1e3,
        }
        driver.finalize()
        rcv.disconnect()
    finally:
        for e in emulators:
            e.close()
    return figures


if __name__ == "__main__":
    main()
