import math

import numpy as np
import pinocchio as pin
import pytest

from cellengine import geometry as g


def test_rpy_is_urdf_convention() -> None:
    # R = Rz(yaw) Ry(pitch) Rx(roll): roll 90 deg then yaw 90 deg maps x->y, y->z, z->x.
    R = g.rpy_to_matrix([math.pi / 2, 0.0, math.pi / 2])
    np.testing.assert_allclose(R @ [1, 0, 0], [0, 1, 0], atol=1e-9)
    np.testing.assert_allclose(R @ [0, 1, 0], [0, 0, 1], atol=1e-9)
    np.testing.assert_allclose(R @ [0, 0, 1], [1, 0, 0], atol=1e-9)


def test_rpy_round_trip_and_singularity() -> None:
    for rpy in ([0.1, -0.2, 0.3], [-3.0, 1.2, 2.5], [0.4, math.pi / 2, 0.0]):
        R = g.rpy_to_matrix(rpy)
        np.testing.assert_allclose(g.rpy_to_matrix(g.matrix_to_rpy(R)), R, atol=1e-9)


def test_axis_angle() -> None:
    R = g.axis_angle_to_matrix([0, 0, 2], math.pi / 2)  # axis need not be unit length
    np.testing.assert_allclose(R @ [1, 0, 0], [0, 1, 0], atol=1e-9)
    np.testing.assert_array_equal(g.axis_angle_to_matrix([0, 0, 0], 0.0), np.eye(3))


def test_inverse() -> None:
    T = g.pose([1, 2, 3], [0.3, -0.2, 1.0])
    np.testing.assert_allclose(T @ g.inverse(T), np.eye(4), atol=1e-9)


# --- the functions geometry.py took over: against pinocchio and against their definitions


def _random_rotations(k: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    w = rng.normal(size=(k, 3))
    w *= rng.uniform(0.0, math.pi, size=(k, 1)) / np.linalg.norm(w, axis=1, keepdims=True)
    return np.array([g.exp3(v) for v in w])


def test_rpy_to_matrix_is_rz_ry_rx() -> None:
    for rpy in ([0.1, -0.2, 0.3], [-3.0, 1.2, 2.5], [0.4, math.pi / 2, 0.0]):
        r, p, y = rpy
        np.testing.assert_allclose(
            g.rpy_to_matrix(rpy), g.rot_z(y) @ g.rot_y(p) @ g.rot_x(r), atol=1e-9
        )


def test_skew_is_the_cross_product() -> None:
    v, u = np.array([0.3, -1.2, 2.0]), np.array([-0.5, 0.7, 0.1])
    np.testing.assert_allclose(g.skew(v) @ u, np.cross(v, u), atol=1e-9)
    np.testing.assert_array_equal(g.skew(v), -g.skew(v).T)


def test_exp3_log3_agree_with_rodrigues() -> None:
    w = np.array([0.2, -0.4, 0.9])
    angle = float(np.linalg.norm(w))
    np.testing.assert_allclose(g.exp3(w), g.axis_angle_to_matrix(w, angle), atol=1e-9)
    np.testing.assert_allclose(g.log3(g.exp3(w)), w, atol=1e-9)


def test_batched_exp_and_log_agree_with_pinocchio() -> None:
    Rs = _random_rotations(200)
    w = np.array([g.log3(R) for R in Rs])
    np.testing.assert_allclose(g.exp3_batch(w), Rs, atol=1e-9)
    np.testing.assert_allclose(g.log3_batch(Rs), w, atol=1e-9)
    np.testing.assert_array_equal(g.exp3_batch(np.zeros((2, 3))), np.stack([np.eye(3)] * 2))
    np.testing.assert_array_equal(g.log3_batch(np.stack([np.eye(3)])), np.zeros((1, 3)))
    # near pi (where the skew part vanishes) and tiny angles
    for angle in (math.pi - 1e-7, 1e-10):
        R = g.axis_angle_to_matrix([1.0, 2.0, -0.5], angle)
        np.testing.assert_allclose(g.log3_batch(R[None])[0], g.log3(R), atol=1e-9)


def test_slerp_and_rotation_angles() -> None:
    R0, R1 = _random_rotations(2, seed=3)
    total = g.rotation_angle(R0, R1)
    Rs = g.slerp(R0, R1, np.linspace(0.0, 1.0, 5))
    np.testing.assert_allclose(Rs[0], R0, atol=1e-9)
    np.testing.assert_allclose(Rs[-1], R1, atol=1e-9)
    np.testing.assert_allclose(g.rotation_angles(Rs), np.full(4, total / 4), atol=1e-9)
    # the angle between is the angle of R0^T R1, from the trace
    trace_angle = math.acos((np.trace(R0.T @ R1) - 1.0) / 2.0)
    assert g.rotation_angle(R0, R1) == pytest.approx(trace_angle, abs=1e-9)
    T0, T1 = g.transform(R0, [1.0, 2.0, 3.0]), g.transform(R1)
    assert g.rotation_angle(T0, T1) == g.rotation_angle(R0, R1)


def test_vector_angles_and_frames() -> None:
    assert g.angle_between([1, 0, 0], [0, 2, 0]) == pytest.approx(math.pi / 2, abs=1e-9)
    assert g.angle_between([1, 0, 0], [-1, 0, 0]) == pytest.approx(math.pi, abs=1e-9)
    up = np.array([0.0, 0.0, 1.0])
    assert g.signed_angle([1, 0, 0], [0, 1, 0], up) == pytest.approx(math.pi / 2, abs=1e-9)
    assert g.signed_angle([0, 1, 0], [1, 0, 0], up) == pytest.approx(-math.pi / 2, abs=1e-9)
    with pytest.raises(ValueError, match="zero vector"):
        g.unit([0.0, 0.0, 0.0])
    for z in (g.unit([0.3, -0.2, 0.9]), np.array([1.0, 0.0, 0.0])):
        x = g.any_perpendicular(z)
        assert abs(float(x @ z)) < 1e-9 and float(np.linalg.norm(x)) == pytest.approx(1.0)
        R = g.z_along(z)
        np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-9)
        np.testing.assert_allclose(R[:, 2], z, atol=1e-9)
        assert np.linalg.det(R) == pytest.approx(1.0)
    R = g.frame_yz(np.array([0.0, 1.0, 0.0]), np.array([0.0, 0.0, -1.0]))
    np.testing.assert_allclose(R, g.rot_y(math.pi), atol=1e-9)  # x = y x z = -x_cell


def test_inverse_and_transform_points_agree_with_pinocchio() -> None:
    T = g.pose([1, 2, 3], [0.3, -0.2, 1.0])
    np.testing.assert_allclose(g.inverse(T), pin.SE3(T).inverse().homogeneous, atol=1e-9)
    P = np.array([[0.1, 0.2, 0.3], [-1.0, 0.5, 2.0]])
    expected = np.array([pin.SE3(T).act(p) for p in P])
    np.testing.assert_allclose(g.transform_points(T, P), expected, atol=1e-9)


def test_cross_is_numpys_to_the_bit() -> None:
    rng = np.random.default_rng(7)
    axes = [*np.eye(3), *-np.eye(3), np.zeros(3)]  # signed zeros
    for a, b in [*rng.normal(size=(2000, 2, 3)), *((u, v) for u in axes for v in axes)]:
        assert g.cross(a, b).tobytes() == np.cross(a, b).tobytes()
    assert g.cross([1, 0, 0], [0, 1, 0]).tolist() == [0.0, 0.0, 1.0]
    with pytest.raises(ValueError):
        g.cross(np.eye(3), np.eye(3))  # arrays of vectors are numpy's
