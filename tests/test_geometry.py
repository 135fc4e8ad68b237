import math

import numpy as np

from cellengine import geometry as g


def test_rpy_is_urdf_convention() -> None:
    # R = Rz(yaw) Ry(pitch) Rx(roll): roll 90 deg then yaw 90 deg maps x->y, y->z, z->x.
    R = g.rpy_to_matrix([math.pi / 2, 0.0, math.pi / 2])
    np.testing.assert_allclose(R @ [1, 0, 0], [0, 1, 0], atol=1e-12)
    np.testing.assert_allclose(R @ [0, 1, 0], [0, 0, 1], atol=1e-12)
    np.testing.assert_allclose(R @ [0, 0, 1], [1, 0, 0], atol=1e-12)


def test_rpy_round_trip_and_singularity() -> None:
    for rpy in ([0.1, -0.2, 0.3], [-3.0, 1.2, 2.5], [0.4, math.pi / 2, 0.0]):
        R = g.rpy_to_matrix(rpy)
        np.testing.assert_allclose(g.rpy_to_matrix(g.matrix_to_rpy(R)), R, atol=1e-12)


def test_axis_angle() -> None:
    R = g.axis_angle_to_matrix([0, 0, 2], math.pi / 2)  # axis need not be unit length
    np.testing.assert_allclose(R @ [1, 0, 0], [0, 1, 0], atol=1e-12)
    np.testing.assert_array_equal(g.axis_angle_to_matrix([0, 0, 0], 0.0), np.eye(3))


def test_inverse() -> None:
    T = g.pose([1, 2, 3], [0.3, -0.2, 1.0])
    np.testing.assert_allclose(T @ g.inverse(T), np.eye(4), atol=1e-12)
