"""The UR driver's servo loop (issue #6): 60 s of servoJ streaming to two emulated
controllers through the real ur-rtde client, and the time from a fault's detection to both
arms stopped.

Run: .venv/bin/python bench/bench_ur_servo.py [--seconds 60]
The emulator (`cellengine emulate ur`) runs in its own process on two free loopback
addresses. Figures: the loop's achieved rate, the 50th / 99th / 99.9th percentiles of
|period - 2 ms|, and the stop latency after a protective stop injected mid-segment.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import shutil
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


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seconds", type=float, default=60.0)
    args = ap.parse_args()
    print(json.dumps(run(args.seconds), indent=2))


def run(seconds: float = 60.0) -> dict[str, float]:
    hosts = free_hosts(2)
    folder = Path(tempfile.mkdtemp()) / "cell"
    shutil.copytree(ROOT / "cells" / "cable_routing", folder)
    path = folder / "cell.yaml"
    driver_yaml = f"{{kind: ur_rtde, arms: {{left: {hosts[0]}, right: {hosts[1]}}}}}"
    path.write_text(path.read_text().replace("driver: {kind: sim}", f"driver: {driver_yaml}"))
    cell, _ = load_cell(path)
    joints = {
        "left": [f"left_j{i}" for i in range(6)],
        "right": [f"right_j{i}" for i in range(6)],
    }
    names = tuple(joints["left"] + joints["right"])
    q0 = ",".join(f"{v:.6f}" for v in HOME)
    emulator = Emulator(hosts, "--q0", f"{hosts[0]}={q0}", "--q0", f"{hosts[1]}={q0}")
    out: dict[str, float] = {}
    try:
        driver = UrDriver(cell, joints)
        driver.configure()
        driver.activate()
        traj = sine(seconds, names)
        t0 = time.perf_counter()
        driver.execute(CompiledSegment(Segment(0, "bench"), "split", traj, {}))
        wall = time.perf_counter() - t0
        periods = np.array(driver.periods)
        err = np.abs(periods - 0.002) * 1e3
        out.update(
            {
                "ur_servo_seconds": seconds,
                "ur_servo_wall_s": wall,
                "ur_servo_rate_hz": float(1.0 / periods.mean()),
                "ur_servo_period_error_p50_ms": float(np.percentile(err, 50)),
                "ur_servo_period_error_p99_ms": float(np.percentile(err, 99)),
                "ur_servo_period_error_p999_ms": float(np.percentile(err, 99.9)),
                "ur_servo_period_max_ms": float(periods.max() * 1e3),
            }
        )
        short = sine(6.0, names)
        emulator_fault_at = time.perf_counter() + 2.0

        def inject() -> None:
            time.sleep(max(0.0, emulator_fault_at - time.perf_counter()))
            emulator.fault(hosts[1], "protective_stop")

        threading.Thread(target=inject, daemon=True).start()
        with contextlib.suppress(DriverFault):  # the fault is the point
            driver.execute(CompiledSegment(Segment(0, "fault"), "split", short, {}))
        if driver.stop_latencies:
            out["ur_fault_to_stop_ms"] = driver.stop_latencies[-1] * 1e3
        driver.finalize()
    finally:
        emulator.close()
    return out


if __name__ == "__main__":
    main()
