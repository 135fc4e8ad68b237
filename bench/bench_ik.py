"""Inverse kinematics on a UR5e: closed form, numerical (pinocchio), and the peers, on THE SAME
target poses.

Run: .venv/bin/python bench/bench_ik.py [--quick]   (prints the figures as JSON)

Targets: FK of 1000 configurations drawn uniformly within the built-in UR5e's limits
(+-2 pi, elbow +-pi), seed 2024; base -> tool0 (flange) in the controller's DH convention.
Seeds: the nominal seed is UR "home" (0, -pi/2, pi/2, -pi/2, -pi/2, 0) for every solver; a
warm seed is the target's own configuration plus N(0, 0.01 rad) per joint (the TCP 1-2 cm
away), the situation of a path's next waypoint.

Success is judged here, for every solver alike, by FK of its answer: position and rotation
error at most 1e-9 for the closed form, 1e-5 m / 1e-5 rad for the numerical solvers.

Goals (issue #3): closed form <= 4 us per pose in batches of 1000, <= 25 us for one pose,
100 % success with residual <= 1e-9; numerical >= 99.5 % success from the nominal seed,
median <= 0.3 ms from it, <= 40 us from a warm seed.

Peers: roboticstoolbox-python's `ik_LM` and `ik_NR` (C++) on a `DHRobot` built exactly like
`rtb.models.DH.UR5()` but with the UR5e's DH table and limits (its URDF models download data
at run time and fail offline; its UR5 is another arm, so it could not solve the same poses),
at tol = 5e-11 (its tol bounds E = e^T e / 2, so |e| <= 1e-5, our tolerance; its default 1e-6
only reaches about 1e-3), called on the robot's ETS (``robot.ik_LM`` rebuilds the ETS per call,
about 0.5 ms); ikpy 4 (scipy optimisation, full orientation) on the built-in URDF, on the first
100 targets only (about 10 ms each), with its accuracy reported.

Times are medians: each target is solved several times, the median per target taken, then the
median over targets (the batch: median over repeated batches). The garbage collector is off
while timing, as in timeit. Everything is seeded.
"""

from __future__ import annotations

import argparse
import gc
import json
import math
import statistics
import sys
import time
import warnings
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, TypeVar

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from cellengine.motion.numeric_ik import NumericIK  # noqa: E402
from cellengine.motion.ur_ik import UR_DH, UR_LOWER, UR_UPPER, URKinematics  # noqa: E402

Array = NDArray[np.float64]
R = TypeVar("R")

URDF = ROOT / "cellengine" / "motion" / "urdf" / "ur5e.urdf"
N_POSES = 1000
SEED = 2024
HOME = np.array([0.0, -math.pi / 2, math.pi / 2, -math.pi / 2, -math.pi / 2, 0.0])
WARM_NOISE = 0.01  # rad per joint
TOL = 1e-5  # m, rad: the numerical solvers' tolerance
EXACT = 1e-9  # the closed form's residual goal
RTB_TOL = 0.5 * TOL**2  # rtb's tol bounds E = |e|^2 / 2
N_IKPY = 100


# ---------------------------------------------------------------------- shared


def make_targets(kin: URKinematics, n: int) -> tuple[Array, Array, Array]:
    """(q (n, 6), T (n, 4, 4), warm seeds (n, 6)), all from one seeded generator."""
    rng = np.random.default_rng(SEED)
    q = rng.uniform(UR_LOWER, UR_UPPER, (n, 6))
    warm = q + rng.normal(0.0, WARM_NOISE, (n, 6))
    return q, kin.fk_batch(q), np.clip(warm, UR_LOWER, UR_UPPER)


def errors(kin: URKinematics, q: Array, T: Array) -> tuple[float, float]:
    """Position (m) and rotation (rad) error of FK(q) against T."""
    M = kin.fk(q)
    dp = float(np.linalg.norm(M[:3, 3] - T[:3, 3]))
    R = M[:3, :3].T @ T[:3, :3]
    skew = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    dr = math.atan2(float(np.linalg.norm(skew)) / 2.0, (float(np.trace(R)) - 1.0) / 2.0)
    return dp, dr


def time_each(solve: Callable[[int], R], n: int, repeats: int) -> tuple[float, list[R]]:
    """Median over targets of the per-target median time (s), and the first pass's answers."""
    solve(0)  # warm up imports and caches
    times = np.empty((repeats, n))
    answers: list[R] = []
    gc.disable()
    try:
        for r in range(repeats):
            for i in range(n):
                t0 = time.perf_counter()
                out = solve(i)
                times[r, i] = time.perf_counter() - t0
                if r == 0:
                    answers.append(out)
    finally:
        gc.enable()
    return float(np.median(np.median(times, axis=0))), answers


def success(kin: URKinematics, qs: Sequence[Array | None], T: Array, tol: float) -> float:
    ok = 0
    for q, Ti in zip(qs, T, strict=True):
        if q is not None and np.all(np.isfinite(q)) and max(errors(kin, q, Ti)) <= tol:
            ok += 1
    return ok / len(qs)


# ---------------------------------------------------------------------- ours


def bench_closed_form(kin: URKinematics, T: Array, repeats: int) -> dict[str, float]:
    n = len(T)
    kin.ik_batch(T, HOME)
    batch_times = []
    gc.disable()
    try:
        for _ in range(repeats * 10):
            t0 = time.perf_counter()
            qb, okb = kin.ik_batch(T, HOME)
            batch_times.append(time.perf_counter() - t0)
    finally:
        gc.enable()
    single, qs = time_each(lambda i: kin.ik(T[i], HOME), n, repeats)
    same = all(
        (q is None and not okb[i]) or (q is not None and okb[i] and np.allclose(q, qb[i]))
        for i, q in enumerate(qs)
    )
    worst = max(max(errors(kin, q, T[i])) for i, q in enumerate(qs) if q is not None)
    return {
        "ik_ur_batch_us_per_pose": statistics.median(batch_times) / n * 1e6,
        "ik_ur_single_us": single * 1e6,
        "ik_ur_success": min(success(kin, qs, T, EXACT), success(kin, list(qb), T, EXACT)),
        "ik_ur_worst_residual": worst,
        "ik_ur_batch_equals_single": float(same),
    }


def bench_numeric(kin: URKinematics, T: Array, warm: Array, repeats: int) -> dict[str, float]:
    model = pin.buildModelFromUrdf(str(URDF))
    ik = NumericIK(model, "tool0", nominal=HOME, tol_pos=TOL, tol_rot=TOL)
    targets = [pin.SE3(t) for t in T]
    n = len(T)
    cold, res = time_each(lambda i: ik.solve(targets[i]), n, repeats)
    hot, res_w = time_each(lambda i: ik.solve(targets[i], warm[i]), n, repeats)
    qs = [r.q if r.success else None for r in res]
    qw = [r.q if r.success else None for r in res_w]
    return {
        "ik_numeric_median_ms": cold * 1e3,
        "ik_numeric_success": success(kin, qs, T, TOL),
        "ik_numeric_mean_iterations": statistics.mean(r.iterations for r in res),
        "ik_numeric_first_attempt": statistics.mean(r.attempts == 1 for r in res),
        "ik_numeric_warm_us": hot * 1e6,
        "ik_numeric_warm_success": success(kin, qw, T, TOL),
    }


# ---------------------------------------------------------------------- peers


def rtb_ur5e() -> Any:
    """A DHRobot made as rtb.models.DH.UR5() makes the UR5, with the UR5e's numbers."""
    import roboticstoolbox as rtb

    dh = UR_DH["ur5e"]
    links = [
        rtb.RevoluteDH(d=dh.d[i], a=dh.a[i], alpha=dh.alpha[i], qlim=[UR_LOWER[i], UR_UPPER[i]])
        for i in range(6)
    ]
    return rtb.DHRobot(links, name="UR5e")


def bench_rtb(kin: URKinematics, T: Array, warm: Array, repeats: int) -> dict[str, float]:
    robot = rtb_ur5e()
    assert np.allclose(robot.fkine(HOME).A, kin.fk(HOME), atol=1e-12), "rtb model != DH"
    # The robot's own ik_LM rebuilds its ETS on every call (about 0.5 ms); the ETS's methods
    # are the same C++ solver without that, so the peer is timed at its best.
    ets = robot.ets()
    out: dict[str, float] = {}
    for key, method in (("lm", ets.ik_LM), ("nr", ets.ik_NR)):
        cold, qs = time_each(_rtb_solver(method, T, None), len(T), repeats)
        hot, qw = time_each(_rtb_solver(method, T, warm), len(T), repeats)
        out[f"peer_rtb_ik_{key}_us"] = cold * 1e6
        out[f"peer_rtb_ik_{key}_success"] = success(kin, qs, T, TOL)
        out[f"peer_rtb_ik_{key}_warm_us"] = hot * 1e6
        out[f"peer_rtb_ik_{key}_warm_success"] = success(kin, qw, T, TOL)
    return out


def _rtb_solver(method: Any, T: Array, warm: Array | None) -> Callable[[int], Array | None]:
    """Target i from HOME (warm None) or from warm[i]; None when rtb reports failure."""

    def solve(i: int) -> Array | None:
        sol = method(T[i], q0=HOME if warm is None else warm[i], tol=RTB_TOL)
        return np.asarray(sol.q) if sol.success else None

    return solve


def bench_ikpy(kin: URKinematics, T: Array) -> dict[str, float]:
    from ikpy.chain import Chain

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # ikpy warns about the fixed links it keeps inactive
        chain = Chain.from_urdf_file(
            str(URDF),
            base_elements=["base", "shoulder_pan_joint"],
            active_links_mask=[False, *[True] * 6, False],
        )
    home = np.array([0.0, *HOME, 0.0])
    n = min(N_IKPY, len(T))

    def solve(i: int) -> Array:
        q = chain.inverse_kinematics_frame(T[i], initial_position=home, orientation_mode="all")
        return np.asarray(q)[1:7]

    t, qs = time_each(solve, n, 1)
    errs = np.array([errors(kin, q, T[i]) for i, q in enumerate(qs)])
    return {
        "peer_ikpy_ms": t * 1e3,
        "peer_ikpy_success": success(kin, list(qs), T[:n], TOL),
        "peer_ikpy_median_pos_err_m": float(np.median(errs[:, 0])),
        "peer_ikpy_median_rot_err_rad": float(np.median(errs[:, 1])),
    }


# ---------------------------------------------------------------------- entry points


def run(quick: bool = False) -> dict[str, float]:
    kin = URKinematics.from_name("ur5e")
    n = 200 if quick else N_POSES
    repeats = 1 if quick else 3
    _, T, warm = make_targets(kin, n)
    out: dict[str, float] = {}
    out.update(bench_closed_form(kin, T, repeats))
    out.update(bench_numeric(kin, T, warm, repeats))
    out.update(bench_rtb(kin, T, warm, repeats))
    out.update(bench_ikpy(kin, T[: 20 if quick else N_IKPY]))
    return out


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="200 poses, one pass")
    args = parser.parse_args()
    print(json.dumps(run(args.quick), indent=2))
