"""bench/results.json holds every figure issue #3 asks for, as numbers."""

import json
import math

from tests.conftest import ROOT

KEYS = [
    "ik_ur_batch_us_per_pose",
    "ik_ur_single_us",
    "ik_ur_success",
    "ik_numeric_median_ms",
    "ik_numeric_warm_us",
    "ik_numeric_success",
    "peer_rtb_ik_lm_us",
    "peer_rtb_ik_lm_success",
    "peer_ikpy_ms",
    "cartesian_1m_ik_ms",
    "cartesian_1m_checked_ms",
    "collision_state_us",
    "plan_dualarm_median_ms",
    "plan_dualarm_success",
    "timing_50wp_ms",
    "peer_toppra_1000_ms",
    "timing_duration_ratio_vs_toppra",
]


def test_results_have_every_figure() -> None:
    results = json.loads((ROOT / "bench" / "results.json").read_text())
    missing = [k for k in KEYS if k not in results]
    assert not missing, f"run `make bench`: missing {missing}"
    assert all(isinstance(results[k], float | int) and math.isfinite(results[k]) for k in KEYS)
