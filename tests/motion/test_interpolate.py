"""TCP interpolation: exact lines, arcs and slerp on known cases; step counts from the maximum
translation and rotation per step."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cellengine import geometry as g
from cellengine.motion import interpolate as itp


def rot_angle(R0: np.ndarray, R1: np.ndarray) -> float:
    return float(np.linalg.norm(g.log3(R0.T @ R1)))


# ----------------------------------------------------------------------------- slerp


def test_slerp_halfway_is_half_the_rotation() -> None:
    R1 = g.rot_z(math.pi / 2)
    half = g.slerp(np.eye(3), R1, 0.5)[0]
    np.testing.assert_allclose(half, g.rot_z(math.pi / 4), atol=1e-9)


def test_slerp_between_tilted_frames_at_constant_speed() -> None:
    R0 = g.rpy_to_matrix([0.3, -0.2, 1.0])
    R1 = R0 @ g.axis_angle_to_matrix([1.0, 2.0, -0.5], 1.2)
    Rs = g.slerp(R0, R1, np.linspace(0.0, 1.0, 7))
    np.testing.assert_allclose(Rs[0], R0, atol=1e-9)
    np.testing.assert_allclose(Rs[-1], R1, atol=1e-9)
    np.testing.assert_allclose(g.rotation_angles(Rs), np.full(6, 0.2), atol=1e-9)
    # the halfway rotation is the same angle from both ends
    assert rot_angle(R0, Rs[3]) == pytest.approx(rot_angle(Rs[3], R1), abs=1e-9)


def test_rotation_angles_of_tiny_steps_keep_their_digits() -> None:
    Rs = np.array([np.eye(3), g.rot_x(1e-9), g.rot_x(1e-9) @ g.rot_y(2e-9)])
    np.testing.assert_allclose(g.rotation_angles(Rs), [1e-9, 2e-9], rtol=1e-6)


# ----------------------------------------------------------------------------- lines


def test_a_1_m_line_in_1_mm_steps_has_1001_poses_at_equal_steps() -> None:
    R = g.rpy_to_matrix([math.pi, 0.0, 0.3])
    T0, T1 = g.transform(R, [0.2, 0.5, 0.3]), g.transform(R, [0.2, -0.5, 0.3])
    W = itp.line(T0, T1, max_translation=0.001)
    assert W.shape == (1001, 4, 4)
    np.testing.assert_array_equal(W[0], T0)
    np.testing.assert_array_equal(W[-1], T1)
    steps = np.linalg.norm(np.diff(W[:, :3, 3], axis=0), axis=1)
    np.testing.assert_allclose(steps, 0.001, atol=1e-9)
    np.testing.assert_allclose(W[:, :3, :3], np.broadcast_to(R, (1001, 3, 3)), atol=1e-9)
    np.testing.assert_allclose(W[:, 0, 3], 0.2, atol=1e-9)  # on the line


@pytest.mark.parametrize(
    ("length", "angle", "max_t", "max_r", "n"),
    [
        (1.0, 0.0, 0.001, 0.1, 1000),  # translation decides
        (0.01, math.pi / 2, 0.005, math.radians(2), 45),  # rotation decides: 90 / 2
        (0.3, 0.2, 0.1, 0.1, 3),  # 0.3 / 0.1 is 2.9999... in floats: still 3
        (0.0, 0.0, 0.005, 0.1, 1),  # no motion: one step
        (0.0101, 0.0, 0.005, 0.1, 3),
    ],
)
def test_step_counts_are_the_fewest_within_both_maxima(
    length: float, angle: float, max_t: float, max_r: float, n: int
) -> None:
    assert itp.steps(length, angle, max_t, max_r) == n
    T0 = np.eye(4)
    T1 = g.transform(g.rot_x(angle), [length, 0.0, 0.0])
    W = itp.line(T0, T1, max_t, max_r)
    assert len(W) == n + 1
    moved = np.linalg.norm(np.diff(W[:, :3, 3], axis=0), axis=1)
    turned = g.rotation_angles(W)
    assert moved.max() <= max_t + 1e-9 and turned.max() <= max_r + 1e-9
    if n > 1:  # one step fewer would break a maximum
        assert length / (n - 1) > max_t or angle / (n - 1) > max_r


def test_step_maxima_must_be_positive() -> None:
    with pytest.raises(ValueError, match="positive"):
        itp.line(np.eye(4), g.pose([1, 0, 0]), max_translation=0.0)


def test_polyline_joins_segments_once() -> None:
    Ts = [g.pose([0, 0, 0]), g.pose([0.1, 0, 0]), g.pose([0.1, 0.05, 0], [0, 0, 0.5])]
    W = itp.polyline(Ts, max_translation=0.01, max_rotation=0.1)
    assert len(W) == 1 + 10 + 5  # 10 steps, then max(5, ceil(0.5 / 0.1) = 5) steps
    np.testing.assert_array_equal(W[10], Ts[1])
    np.testing.assert_array_equal(W[-1], Ts[2])
    assert itp.polyline(np.array(Ts[:1])).shape == (1, 4, 4)


def test_concatenate_refuses_a_gap() -> None:
    a = itp.line(np.eye(4), g.pose([0.1, 0, 0]))
    b = itp.line(g.pose([0.2, 0, 0]), g.pose([0.3, 0, 0]))
    with pytest.raises(ValueError, match="does not start where"):
        itp.concatenate([a, b])


# ----------------------------------------------------------------------------- arcs


def test_circle_through_three_points_of_a_known_circle() -> None:
    centre, radius = np.array([0.4, -0.1, 0.25]), 0.15
    R = g.rpy_to_matrix([0.4, 0.7, -1.1])  # the circle's plane, tilted
    on = [centre + radius * R @ [math.cos(a), math.sin(a), 0.0] for a in (0.2, 1.0, 2.5)]
    circle, a1, a2 = itp.circle_through(*on)
    np.testing.assert_allclose(circle.centre, centre, atol=1e-9)
    assert circle.radius == pytest.approx(radius, abs=1e-9)
    np.testing.assert_allclose(circle.axis, R[:, 2], atol=1e-9)
    assert (a1, a2) == (pytest.approx(0.8, abs=1e-9), pytest.approx(2.3, abs=1e-9))
    np.testing.assert_allclose(circle.points([0.0, a1, a2]), on, atol=1e-9)


def test_circle_through_collinear_points_is_refused() -> None:
    with pytest.raises(ValueError, match="one line"):
        itp.circle_through([0, 0, 0], [1, 1, 1], [2, 2, 2])


def test_arc_through_a_half_circle() -> None:
    """From (1, 0) via (0, 1) to (-1, 0) about (0, 0, 0.3): a half turn of radius 1, pi m."""
    R0, R1 = np.eye(3), g.rot_z(0.5)
    T0, T1 = g.transform(R0, [1.0, 0.0, 0.3]), g.transform(R1, [-1.0, 0.0, 0.3])
    W = itp.arc_through(T0, [0.0, 1.0, 0.3], T1, max_translation=0.0125, max_rotation=1.0)
    n = math.ceil(math.pi / 0.0125)
    assert len(W) == n + 1 and n % 2 == 0
    r = np.linalg.norm(W[:, :2, 3], axis=1)
    np.testing.assert_allclose(r, 1.0, atol=1e-9)
    np.testing.assert_allclose(W[:, 2, 3], 0.3, atol=1e-9)
    np.testing.assert_allclose(np.diff(np.arctan2(W[:, 1, 3], W[:, 0, 3])), math.pi / n, atol=1e-9)
    np.testing.assert_array_equal(W[-1], T1)
    # orientation turns in step with the arc: halfway (at the via point), half the rotation
    np.testing.assert_allclose(W[n // 2][:3, 3], [0.0, 1.0, 0.3], atol=1e-9)
    np.testing.assert_allclose(W[n // 2][:3, :3], g.rot_z(0.25), atol=1e-9)
    np.testing.assert_allclose(g.rotation_angles(W), 0.5 / n, atol=1e-9)


def test_arc_about_an_axis_quarter_turn() -> None:
    T0 = g.pose([0.7, 0.0, 0.3], [math.pi, 0.0, 0.0])
    W = itp.arc_about(T0, [0.5, 0.0, 0.0], [0, 0, 1], math.pi / 2, max_translation=0.001)
    circle = itp.arc_circle(T0, [0.5, 0.0, 0.0], [0, 0, 1])
    assert circle.radius == pytest.approx(0.2, abs=1e-9)
    np.testing.assert_allclose(circle.centre, [0.5, 0.0, 0.3], atol=1e-9)
    assert len(W) == math.ceil(0.2 * math.pi / 2 / 0.001) + 1
    np.testing.assert_allclose(np.linalg.norm(W[:, :3, 3] - circle.centre, axis=1), 0.2, atol=1e-9)
    np.testing.assert_allclose(W[-1][:3, 3], [0.5, 0.2, 0.3], atol=1e-9)
    # turning with the arc: the end orientation is the start's turned a quarter about z
    np.testing.assert_allclose(W[-1][:3, :3], g.rot_z(math.pi / 2) @ T0[:3, :3], atol=1e-9)
    fixed = itp.arc_about(T0, [0.5, 0.0, 0.0], [0, 0, 1], math.pi / 2, turn=False)
    np.testing.assert_allclose(
        fixed[:, :3, :3], np.broadcast_to(T0[:3, :3], fixed[:, :3, :3].shape)
    )


def test_arc_about_an_axis_turning_by_a_share_of_the_angle() -> None:
    """turn=0.5 on a quarter turn: the same circle, the orientation turned by an eighth of a
    turn at the end, in step with the arc."""
    T0 = g.pose([0.7, 0.0, 0.3], [math.pi, 0.0, 0.0])
    W = itp.arc_about(T0, [0.5, 0.0, 0.0], [0, 0, 1], math.pi / 2, turn=0.5, max_translation=0.001)
    full = itp.arc_about(T0, [0.5, 0.0, 0.0], [0, 0, 1], math.pi / 2, max_translation=0.001)
    np.testing.assert_allclose(W[:, :3, 3], full[:, :3, 3], atol=1e-9)
    np.testing.assert_allclose(W[-1][:3, :3], g.rot_z(math.pi / 4) @ T0[:3, :3], atol=1e-9)
    n = len(W) - 1  # 315 steps: at step k, k / n of the eighth turn
    np.testing.assert_allclose(
        W[100][:3, :3], g.rot_z(math.pi / 4 * 100 / n) @ T0[:3, :3], atol=1e-9
    )


def test_arc_about_the_tcp_itself_turns_in_place_beyond_a_half_turn() -> None:
    T0 = g.pose([0.3, 0.2, 0.1])
    W = itp.arc_about(T0, T0[:3, 3], [0, 0, 1], 1.5 * math.pi, max_rotation=math.radians(5))
    assert len(W) == 54 + 1
    np.testing.assert_allclose(W[:, :3, 3], np.broadcast_to(T0[:3, 3], (55, 3)), atol=1e-9)
    np.testing.assert_allclose(W[-1][:3, :3], g.rot_z(1.5 * math.pi), atol=1e-9)
    np.testing.assert_allclose(g.rotation_angles(W), math.radians(5), atol=1e-9)


def test_step_lengths_count_rotation() -> None:
    W = np.array(
        [g.pose([0, 0, 0]), g.pose([0.003, 0.004, 0]), g.pose([0.003, 0.004, 0], [0, 0, 1])]
    )
    np.testing.assert_allclose(itp.step_lengths(W), [0.005, itp.ROTATION_LENGTH * 1.0], atol=1e-9)
