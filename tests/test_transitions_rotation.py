"""Rotation helpers added for the transitions: Euler angles back from matrices (both
Tait-Bryan solutions, continuous along time), quaternions, rotation log and exp."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from upm.ops.rotations import (
    continuous_euler_deg,
    euler_to_matrix,
    matrix_to_euler_deg,
    matrix_to_quaternion,
    rotation_exp,
    rotation_log,
)

ORDERS = ["XYZ", "ZYX", "YZX", "XZY", "YXZ", "ZXY"]
angles = st.floats(-400, 400, allow_nan=False)


@settings(max_examples=200, deadline=None)
@given(angles, angles, angles, st.sampled_from(ORDERS))
def test_euler_round_trip(ax, ay, az, order):
    m = euler_to_matrix([ax, ay, az], order)
    back = matrix_to_euler_deg(m, order)
    np.testing.assert_allclose(euler_to_matrix(back, order), m, atol=1e-9)
    # With the original as the reference, the original comes back (away from gimbal lock).
    middle = {"X": ax, "Y": ay, "Z": az}[order[1]]
    if abs(np.cos(np.radians(middle))) > 1e-3:
        np.testing.assert_allclose(matrix_to_euler_deg(m, order, near_deg=[ax, ay, az]),
                                   [ax, ay, az], atol=1e-6)


def test_continuous_euler_through_gimbal_lock_and_full_turns():
    """A smooth path that turns 720 degrees about y and tilts through the XYZ order's
    singular middle angle: angles continue without 360-degree or branch jumps."""
    t = np.linspace(0, 1, 2001)
    path = Rotation.from_euler("y", 720 * t[:, None], degrees=True) * Rotation.from_euler(
        "x", 100 * np.sin(np.pi * t)[:, None], degrees=True)
    matrices = path.as_matrix()
    angles = continuous_euler_deg(matrices, "XYZ", [0.0, 0.0, 0.0])
    np.testing.assert_allclose(euler_to_matrix(angles, "XYZ"), matrices, atol=1e-9)
    steps = np.abs(np.diff(angles, axis=0))
    # Away from the lock (|ry| not within 2 degrees of 90) every step is small.
    cos_middle = np.abs(np.cos(np.radians(angles[1:, 1])))
    assert steps[cos_middle > np.sin(np.radians(2.0))].max() < 5.0
    assert angles[-1, 1] == pytest.approx(0.0, abs=1e-6) or abs(angles[-1, 1]) > 300


def test_continuous_euler_reproduces_continuous_data(walk):
    start = walk.root[0, 3:]
    angles = continuous_euler_deg(euler_to_matrix(walk.root[:, 3:], "XYZ"), "XYZ", start)
    np.testing.assert_allclose(angles, walk.root[:, 3:], atol=1e-9)


@settings(max_examples=60, deadline=None)
@given(st.sampled_from(ORDERS), st.integers(0, 2**32 - 1), st.sampled_from([1.0, 10.0, 60.0]))
def test_continuous_euler_in_every_order(order, seed, step_deg):
    """Random paths in each rotation order, with whole turns in the start: the angles
    give back every rotation and move less than 180 degrees a frame, from within 180
    degrees of the start; a smooth path away from gimbal lock comes back as given,
    shifted by whole turns (large random steps may take the other branch, nearer)."""
    rng = np.random.default_rng(seed)
    middle = "XYZ".index(order[1])
    path = np.cumsum(rng.normal(0.0, step_deg, (40, 3)), axis=0)
    path[:, middle] = 60.0 * np.sin(np.linspace(0.0, 3.0, 40) + rng.uniform(0, 6))
    matrices = euler_to_matrix(path, order)
    start = path[0] + 360.0 * rng.integers(-2, 3, 3) + rng.normal(0.0, 5.0, 3)
    angles = continuous_euler_deg(matrices, order, start)
    np.testing.assert_allclose(euler_to_matrix(angles, order), matrices, atol=1e-9)
    assert np.all(np.abs(angles[0] - start) < 180.0)
    assert np.all(np.abs(np.diff(angles, axis=0)) < 180.0)
    if step_deg < 60.0:  # small steps: the very same path, whole turns apart
        turns = (angles - path) / 360.0
        np.testing.assert_allclose(turns, np.round(turns), atol=1e-9)
        np.testing.assert_allclose(angles - angles[0], path - path[0], atol=1e-9)


def test_quaternion_log_exp_agree_with_scipy():
    rotations = Rotation.random(500, random_state=11)
    m = rotations.as_matrix()
    q = rotations.as_quat(scalar_first=True)
    q = np.where(q[:, :1] < 0, -q, q)
    np.testing.assert_allclose(matrix_to_quaternion(m), q, atol=1e-12)
    np.testing.assert_allclose(rotation_log(m), rotations.as_rotvec(), atol=1e-9)
    np.testing.assert_allclose(rotation_exp(rotations.as_rotvec()), m, atol=1e-12)
    half_turns = np.array([np.diag([-1.0, 1.0, -1.0]), np.diag([1.0, -1.0, -1.0])])
    np.testing.assert_allclose(rotation_exp(rotation_log(half_turns)), half_turns, atol=1e-12)
    np.testing.assert_allclose(rotation_exp(np.zeros((2, 3))), np.eye(3)[None].repeat(2, 0))


@pytest.mark.parametrize("order", ORDERS)
def test_euler_is_the_principal_solution_scipy_gives(order):
    # Closed form against scipy's intrinsic-from-extrinsic conversion: the same principal
    # solution (middle angle in [-90, 90]) away from gimbal lock ...
    rng = np.random.default_rng(3)
    m = Rotation.random(500, random_state=rng).as_matrix()
    ours = matrix_to_euler_deg(m, order)
    theirs = Rotation.from_matrix(m).as_euler(order.lower(), degrees=True)
    index = {"X": 0, "Y": 1, "Z": 2}
    for k, axis in enumerate(order):
        np.testing.assert_allclose(ours[:, index[axis]], theirs[:, k], atol=1e-8)
    # ... and near and at it, angles that rebuild the rotation to float precision.
    near = rng.uniform(-180, 180, (40, 3))
    near[:, index[order[1]]] = 90.0 - np.concatenate([10.0 ** -np.arange(1, 13), np.zeros(28)])
    m = euler_to_matrix(near, order)
    np.testing.assert_allclose(euler_to_matrix(matrix_to_euler_deg(m, order), order), m,
                               atol=1e-12)
