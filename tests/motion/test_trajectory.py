"""The shared Trajectory type: construction checks, quintic sampling, resampling, JSON,
concatenation."""

from __future__ import annotations

import json

import numpy as np
import pytest

from cellengine.motion.trajectory import Trajectory, concatenate


def _poly_traj(times: np.ndarray) -> Trajectory:
    """Knots taken from a known quintic per joint, so sampling must reproduce it exactly."""
    c = np.array([[0.1, -0.2], [0.5, 0.3], [-0.4, 0.2], [0.3, -0.1], [-0.05, 0.02], [0.01, 0.0]])
    t = times[:, None]
    q = sum(c[k] * t**k for k in range(6))
    qd = sum(k * c[k] * t ** (k - 1) for k in range(1, 6))
    qdd = sum(k * (k - 1) * c[k] * t ** (k - 2) for k in range(2, 6))
    return Trajectory(("a", "b"), times, q, qd, qdd)


def _exact(t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    ref = _poly_traj(np.array([0.0, 10.0]))  # one segment: the quintic itself
    return (*ref.sample(t), ref.jerk(t))


def test_sample_reproduces_a_quintic_and_its_derivatives() -> None:
    traj = _poly_traj(np.array([0.0, 0.3, 1.0, 1.1, 2.5, 4.0]))
    ts = np.linspace(0.0, 4.0, 97)
    for got, want in zip((*traj.sample(ts), traj.jerk(ts)), _exact(ts), strict=True):
        np.testing.assert_allclose(got, want, atol=1e-9)


def test_sample_at_knots_returns_the_stored_state() -> None:
    traj = _poly_traj(np.array([0.0, 0.5, 1.5, 2.0]))
    q, qd, qdd = traj.sample(traj.t)
    np.testing.assert_allclose(q, traj.q, atol=1e-9)
    np.testing.assert_allclose(qd, traj.qd, atol=1e-9)
    np.testing.assert_allclose(qdd, traj.qdd, atol=1e-9)


def test_sample_scalar_shapes_and_clamping() -> None:
    traj = _poly_traj(np.array([0.0, 1.0, 2.0]))
    q, qd, qdd = traj.sample(0.5)
    assert q.shape == qd.shape == qdd.shape == (2,)
    q_end, qd_end, _ = traj.sample(99.0)
    np.testing.assert_allclose(q_end, traj.q[-1])
    np.testing.assert_allclose(qd_end, traj.qd[-1])
    np.testing.assert_allclose(traj.sample(-1.0)[0], traj.q[0])


def test_single_point_trajectory() -> None:
    traj = Trajectory(("a",), [0.0], [[1.0]], [[0.0]], [[0.0]])
    assert traj.duration == 0.0
    q, _, _ = traj.sample(np.array([0.0, 1.0]))
    np.testing.assert_allclose(q, [[1.0], [1.0]])
    assert traj.sample(3.0)[0].shape == (1,)


def test_arrays_are_copied_and_read_only() -> None:
    q = np.zeros((2, 1))
    traj = Trajectory(("a",), [0.0, 1.0], q, np.zeros((2, 1)), np.zeros((2, 1)))
    q[0, 0] = 5.0
    assert traj.q[0, 0] == 0.0
    with pytest.raises(ValueError):
        traj.q[0, 0] = 1.0
    with pytest.raises(AttributeError):
        traj.t = np.zeros(2)  # type: ignore[misc]


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"t": [0.0, 0.0]}, r"t must strictly increase; t\[1\] = 0.0 follows t\[0\] = 0.0"),
        ({"t": [1.0, 0.5]}, "strictly increase"),
        ({"t": [0.0, 1.0, 2.0]}, r"q has shape \(2, 2\); expected \(3, 2\)"),
        ({"qd": np.zeros((2, 3))}, r"qd has shape \(2, 3\); expected \(2, 2\)"),
        ({"qdd": np.zeros(4)}, "qdd must have 2 dimension"),
        ({"q": [[0.0, np.nan], [0.0, 0.0]]}, r"q holds a non-finite value at index \(0, 1\)"),
        ({"t": [0.0, np.inf]}, "t holds a non-finite value"),
        ({"t": []}, "at least one point"),
        ({"joint_names": ("a", "a")}, "joint_names repeats a"),
        ({"joint_names": ()}, "joint_names must be"),
        ({"q": [["x", 0.0], [0.0, 0.0]]}, "q must be numeric"),
    ],
)
def test_construction_names_what_is_wrong(kwargs: dict[str, object], message: str) -> None:
    args: dict[str, object] = {
        "joint_names": ("a", "b"),
        "t": [0.0, 1.0],
        "q": np.zeros((2, 2)),
        "qd": np.zeros((2, 2)),
        "qdd": np.zeros((2, 2)),
    }
    args.update(kwargs)
    with pytest.raises(ValueError, match=message):
        Trajectory(**args)  # type: ignore[arg-type]


def test_resample_keeps_the_motion_and_the_end() -> None:
    traj = _poly_traj(np.array([0.0, 0.7, 2.0, 3.05]))
    res = traj.resample(0.1)
    assert res.t[0] == 0.0 and res.t[-1] == traj.t[-1]
    assert np.all(np.diff(res.t) > 0)
    assert len(res) == 32  # 0.0 .. 3.0 every 0.1, then the end at 3.05
    ts = np.linspace(0.0, 3.05, 200)
    np.testing.assert_allclose(res.sample(ts)[0], traj.sample(ts)[0], atol=1e-9)
    with pytest.raises(ValueError, match="dt must be"):
        traj.resample(0.0)


def test_json_rounds_to_the_decimals_asked() -> None:
    traj = _poly_traj(np.array([0.0, 0.123456789, 1.25]))
    data = traj.to_json(decimals=4)
    assert [p["time_from_start"] for p in data["points"]] == [0.0, 0.1235, 1.25]
    back = Trajectory.from_json(data)
    np.testing.assert_allclose(back.q, traj.q, atol=5e-5)
    assert np.abs(back.q - traj.q).max() > 0.0  # rounded, not the full value
    np.testing.assert_array_equal(back.q, np.round(traj.q, 4))


def test_resample_exact_multiple_does_not_duplicate_the_end() -> None:
    traj = _poly_traj(np.array([0.0, 1.0]))
    res = traj.resample(0.25)
    np.testing.assert_allclose(res.t, [0.0, 0.25, 0.5, 0.75, 1.0])


def test_json_round_trip_has_ros_semantics() -> None:
    traj = _poly_traj(np.array([0.0, 0.5, 1.25]))
    data = json.loads(json.dumps(traj.to_json()))
    assert data["joint_names"] == ["a", "b"]
    assert [p["time_from_start"] for p in data["points"]] == [0.0, 0.5, 1.25]
    assert set(data["points"][0]) == {"positions", "velocities", "accelerations", "time_from_start"}
    back = Trajectory.from_json(data)
    for a, b in ((back.t, traj.t), (back.q, traj.q), (back.qd, traj.qd), (back.qdd, traj.qdd)):
        np.testing.assert_array_equal(a, b)
    with pytest.raises(ValueError, match="not a trajectory"):
        Trajectory.from_json({"joint_names": ["a"]})


def _rest_move(q0: float, q1: float, duration: float) -> Trajectory:
    t = np.array([0.0, duration])
    q = np.array([[q0], [q1]])
    return Trajectory(("a",), t, q, np.zeros((2, 1)), np.zeros((2, 1)))


def test_concatenate_shifts_times_and_merges_the_junction() -> None:
    a = _rest_move(0.0, 1.0, 2.0)
    b = _rest_move(1.0, -1.0, 1.5).shifted(7.0)
    c = concatenate([a, b])
    np.testing.assert_allclose(c.t, [0.0, 2.0, 3.5])
    np.testing.assert_allclose(c.q[:, 0], [0.0, 1.0, -1.0])
    assert c.duration == pytest.approx(3.5)
    np.testing.assert_allclose(c.sample(2.75)[0], b.sample(7.75)[0])


def test_concatenate_takes_a_one_point_part_between_two_moves() -> None:
    """A segment that does not move (a single point) adds no knot and no time."""
    still = Trajectory(("a",), [4.0], [[1.0]], [[0.0]], [[0.0]])
    c = concatenate([_rest_move(0.0, 1.0, 2.0), still, _rest_move(1.0, 3.0, 1.0)])
    np.testing.assert_allclose(c.t, [0.0, 2.0, 3.0])
    np.testing.assert_allclose(c.q[:, 0], [0.0, 1.0, 3.0])
    with pytest.raises(ValueError, match="position of a jumps from 1 to 2"):
        concatenate([_rest_move(0.0, 1.0, 1.0), still, _rest_move(2.0, 0.0, 1.0)])


def test_concatenate_refuses_a_jump_or_other_joints() -> None:
    with pytest.raises(ValueError, match="position of a jumps from 1 to 2"):
        concatenate([_rest_move(0.0, 1.0, 1.0), _rest_move(2.0, 0.0, 1.0)])
    other = Trajectory(("b",), [0.0, 1.0], [[1.0], [0.0]], [[0.0], [0.0]], [[0.0], [0.0]])
    with pytest.raises(ValueError, match="part 1 has joints"):
        concatenate([_rest_move(0.0, 1.0, 1.0), other])
    with pytest.raises(ValueError, match="at least one"):
        concatenate([])


def _dense_worst(traj: Trajectory) -> tuple[np.ndarray, ...]:
    dense = np.linspace(traj.t[0], traj.t[-1], 100_001)
    _, qd, qdd = traj.sample(dense)
    seg = np.clip(np.searchsorted(traj.t, dense, side="right") - 1, 0, len(traj) - 2)
    out = []
    for values in (qd, qdd, traj.jerk(dense)):
        worst = np.zeros((len(traj) - 1, traj.dof))
        np.maximum.at(worst, seg, np.abs(values))
        out.append(worst)
    return tuple(out)


def test_peaks_bound_dense_samples_of_any_knots() -> None:
    rng = np.random.default_rng(3)
    times = np.cumsum(rng.uniform(0.01, 0.05, 40))
    state = [rng.normal(size=(40, 3)) * k for k in (1, 1, 10)]
    traj = Trajectory(("a", "b", "c"), times, *state)
    for bound, worst in zip(traj.peaks(), _dense_worst(traj), strict=True):
        assert bound.shape == (39, 3)
        assert np.all(worst <= bound * (1 + 1e-9) + 1e-9)


def test_peaks_are_tight_on_smooth_motion() -> None:
    t = np.cumsum(np.r_[0.0, np.full(60, 0.02)])[:, None]
    w = np.array([3.0, 5.0])
    traj = Trajectory(
        ("a", "b"), t[:, 0], np.sin(w * t), w * np.cos(w * t), -(w**2) * np.sin(w * t)
    )
    for bound, worst in zip(traj.peaks(), _dense_worst(traj), strict=True):
        assert np.all(worst <= bound + 1e-9)
        assert np.all(bound <= worst * (1 + 1e-3) + 1e-9)


@pytest.mark.parametrize("knots", [1, 2, 3, 7, 4096])
def test_trajectory_text_is_the_json_of_the_whole_body(knots: int) -> None:
    """Issue 19: trajectory.json is turned to text a slice of knots at a time (the body as
    Python lists took ~7 times the text); the text is the same."""
    from cellengine.pipeline import trajectory_json, trajectory_text
    from cellengine.program import CompiledSegment, GripperEvent, Program, Segment, TimedEvent

    traj = _poly_traj(np.linspace(0.0, 2.0, 7))
    program = Program(
        ("a", "b"),
        (CompiledSegment(Segment(0, "s"), "split", traj, {}),),
        (TimedEvent(1.0, GripperEvent("left", "grasp", "vial1")),),
    )
    text = trajectory_text(program, knots)
    assert text == json.dumps(trajectory_json(program))
    assert len(json.loads(text)["points"]) == 7
