"""How well a servo loop kept its period: the achieved rate and the percentiles of the
period error |measured period - nominal period|, from every period a driver measured, and
the time from each fault's detection to every arm's stop command. For the journal, the run's
report and the benchmark."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np


def servo_timing(
    periods: Sequence[float], nominal: float, stop_latencies: Sequence[float] = ()
) -> dict[str, Any]:
    """JSON-ready figures (ms, Hz) of the measured ``periods`` (s) against ``nominal`` (s)."""
    p = np.asarray(periods, dtype=np.float64)
    out: dict[str, Any] = {"ticks": int(p.size), "nominal_period_ms": nominal * 1e3}
    if p.size:
        err = np.abs(p - nominal) * 1e3
        out |= {
            "rate_hz": round(float(1.0 / p.mean()), 3),
            "period_error_ms": {
                "p50": round(float(np.percentile(err, 50)), 4),
                "p99": round(float(np.percentile(err, 99)), 4),
                "p99.9": round(float(np.percentile(err, 99.9)), 4),
                "max": round(float(err.max()), 4),
            },
        }
    out["stop_commands_ms"] = [round(s * 1e3, 3) for s in stop_latencies]
    return out


def describe(timing: dict[str, Any]) -> str:
    """One line for the terminal."""
    if not timing.get("ticks"):
        return "servo loop: no ticks"
    e = timing["period_error_ms"]
    return (
        f"servo loop: {timing['rate_hz']:.1f} Hz over {timing['ticks']} ticks, period error "
        f"p50 / p99 / p99.9 / max {e['p50']:.3f} / {e['p99']:.3f} / {e['p99.9']:.3f} / "
        f"{e['max']:.3f} ms"
    )
