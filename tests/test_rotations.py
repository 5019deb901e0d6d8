"""The frame and angle conventions stated in docs/theory.md section 1."""

import math

import numpy as np
import pytest

from inserr.core.rotations import (
    body_to_nav,
    euler_from_dcm,
    heading_of,
    log_so3,
    rot_axis,
    rot_x,
    rot_y,
    rot_z,
    skew,
)
from inserr.schemes.turntable import table_dcm

E, N, U = np.eye(3)


def test_heading_is_clockwise_from_north():
    # Heading 90 deg: the forward (y) axis points east, the right (x) axis south.
    c = body_to_nav(math.radians(90), 0.0, 0.0)
    assert np.allclose(c @ [0, 1, 0], E)
    assert np.allclose(c @ [1, 0, 0], -N)
    assert heading_of(c) == pytest.approx(math.radians(90))


def test_pitch_nose_up_and_roll_right_wing_down_are_positive():
    c = body_to_nav(0.0, math.radians(10), 0.0)
    assert (c @ [0, 1, 0])[2] == pytest.approx(math.sin(math.radians(10)))  # nose up
    c = body_to_nav(0.0, 0.0, math.radians(10))
    assert (c @ [1, 0, 0])[2] == pytest.approx(-math.sin(math.radians(10)))  # right wing down


def test_euler_round_trip():
    rng = np.random.default_rng(0)
    for _ in range(50):
        h, p, r = rng.uniform(0, 2 * math.pi), rng.uniform(-1.4, 1.4), rng.uniform(-3, 3)
        h2, p2, r2 = euler_from_dcm(body_to_nav(h, p, r))
        assert (h2, p2, r2) == pytest.approx((h, p, r), abs=1e-12)


def test_table_angle_is_right_handed_and_lowers_imu_heading():
    # Level vehicle at heading 30 deg, table at +40 deg (counter-clockwise from above):
    # the IMU heading is 30 - 40 = -10 deg.
    c = body_to_nav(math.radians(30), 0.0, 0.0) @ table_dcm(math.radians(40), 0.0)
    assert heading_of(c) == pytest.approx(math.radians(350))


def test_rotation_matrix_conventions():
    v = np.array([0.3, -1.2, 2.0])
    w = np.array([1.0, 0.5, -0.7])
    assert np.allclose(skew(v) @ w, np.cross(v, w))
    assert np.allclose(rot_z(math.pi / 2) @ E, N)  # right-hand turn about up
    axis = np.array([1.0, 2.0, 2.0]) / 3.0
    r = rot_axis(axis, 0.7)
    assert np.allclose(log_so3(r), 0.7 * axis)
    assert np.allclose(r @ r.T, np.eye(3)) and np.linalg.det(r) == pytest.approx(1.0)


def test_batched_heading_rotations_equal_the_matrix_products():
    """The composition's row/column forms of ``rot_z(h) @ M`` and ``M @ rot_z(a)`` (no
    matrix product per time) against the products of :func:`rot_z` matrices, for a
    general (not orthogonal, not symmetric) M: a swapped sign or a transposed rotation
    is an O(1) difference."""
    from inserr.core.rotations import rot_z_times
    from inserr.schemes.composition import _times_rot_z

    rng = np.random.default_rng(11)
    angles = rng.uniform(-10.0, 10.0, size=50)
    m = rng.normal(size=(3, 3))
    ms = rng.normal(size=(50, 3, 3))
    left = np.array([rot_z(h) @ m for h in angles])
    right = np.array([mm @ rot_z(a) for mm, a in zip(ms, angles, strict=True)])
    # Same products, different order of additions: a few ulp.
    np.testing.assert_allclose(rot_z_times(angles, m), left, rtol=0, atol=1e-14)
    np.testing.assert_allclose(_times_rot_z(ms, angles), right, rtol=0, atol=1e-14)


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_coordinate_rotations_are_the_exponential_of_the_cross_product_matrix(axis):
    """rot_x/rot_y/rot_z (built entry by entry from one sine and cosine) against
    ``expm(angle [e x])`` computed by scipy, scalar and batched angles, and against
    Rodrigues' formula of rot_axis: a transposed or mislabelled axis is O(1)."""
    from scipy.linalg import expm

    fn = (rot_x, rot_y, rot_z)[axis]
    e = np.eye(3)[axis]
    angles = np.array([-7.0, -1.2, 0.0, 0.3, 2.5, 6.0])
    batch = fn(angles)
    assert batch.shape == (6, 3, 3) and fn(0.3).shape == (3, 3)
    for a, c in zip(angles, batch, strict=True):
        # expm to ~1e-15 for |angle| <= 7: 1e-13 leaves room.
        np.testing.assert_allclose(c, expm(a * skew(e)), rtol=0, atol=1e-13)
        np.testing.assert_allclose(fn(a), c, rtol=0, atol=0)
    np.testing.assert_allclose(batch, rot_axis(e, angles), rtol=0, atol=1e-15)
