"""The balance controller's compiled per-step kernels (controller.balance.qp_kernels) are the numpy
formulas they replace: the reference between frames, the targets clipped into the joint
ranges, the desired acceleration, the capture-offset shift of the swing foot and the swing
leg's joint change, the applied torques within their range and the QP's inequalities
solved with (the watched torque bounds only)."""

import math

import numpy as np
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from controller.balance.leg_kernels import capture_shift, damped_least_squares, move_point
from controller.balance.qp_kernels import bound_constraints, watched_constraints
from controller.balance.step_kernels import (
    clip_targets,
    clip_torques,
    desired_acceleration,
    reference_at,
)

_finite = st.floats(-10.0, 10.0, allow_nan=False)


def _tight(got, want):
    np.testing.assert_allclose(got, want, rtol=1e-14, atol=1e-14)


@given(arrays(float, (3, 9), elements=_finite), arrays(float, (3, 8), elements=_finite),
       arrays(float, (3, 8), elements=_finite), st.integers(0, 1), st.floats(0.0, 1.0))
def test_reference_at_interpolates_and_normalises_the_root_quaternion(qpos, qvel, qacc, i, w):
    qpos[:, 3] += 20.0  # quaternions far from zero
    q, qd, qdd = np.empty(9), np.empty(8), np.empty(8)
    reference_at(qpos, qvel, qacc, i, w, q, qd, qdd)
    a, b = qpos[i], qpos[i + 1]
    want = (1 - w) * a + w * b
    qb = b[3:7] if a[3:7] @ b[3:7] >= 0 else -b[3:7]
    quat = (1 - w) * a[3:7] + w * qb
    want[3:7] = quat / np.linalg.norm(quat)
    _tight(q, want)
    assert math.isclose(np.linalg.norm(q[3:7]), 1.0, rel_tol=1e-12)
    _tight(qd, (1 - w) * qvel[i] + w * qvel[i + 1])
    _tight(qdd, (1 - w) * qacc[i] + w * qacc[i + 1])


@given(arrays(float, 7, elements=_finite))
def test_clip_targets_clips_hinges_and_stops_them(angles):
    hinge_q, hinge_v = np.array([2, 4, 6]), np.array([1, 3, 5])
    low, high = np.array([-1.0, 0.0, -2.0]), np.array([1.0, 0.5, 2.0])
    q, qd, qdd = angles.copy(), np.ones(6), np.full(6, 2.0)
    clip_targets(q, qd, qdd, hinge_q, hinge_v, low, high)
    want = angles.copy()
    want[hinge_q] = np.clip(angles[hinge_q], low, high)
    np.testing.assert_array_equal(q, want)
    clipped = (angles[hinge_q] < low) | (angles[hinge_q] > high)
    np.testing.assert_array_equal(qd[hinge_v], np.where(clipped, 0.0, 1.0))
    np.testing.assert_array_equal(qdd[hinge_v], np.where(clipped, 0.0, 2.0))
    np.testing.assert_array_equal(qd[[0, 2, 4]], 1.0)


@given(arrays(float, (5, 6), elements=st.floats(-100.0, 100.0, allow_nan=False)))
def test_desired_acceleration_is_the_pd_law_within_its_bound(rows):
    qdd_ref, kp, err, kd, qd_ref = rows
    qvel = np.zeros(6)
    qvel[0] = np.nan  # a diverged state stays visible
    out = np.empty(6)
    desired_acceleration(qdd_ref, kp, err, kd, qd_ref, qvel, 300.0, out)
    want = np.clip(qdd_ref + kp * err + kd * (qd_ref - qvel), -300.0, 300.0)
    np.testing.assert_allclose(out, want, rtol=1e-14, atol=1e-12)
    assert np.isnan(out[0])


@given(arrays(float, (6, 3), elements=st.floats(-2.0, 2.0, allow_nan=False)),
       st.floats(0.1, 0.5), st.floats(0.0, 1.0))
def test_capture_shift_is_the_capture_offset_difference(points, tc, gain):
    com, vel, ankle, ref_com, ref_vel, ref_ankle = points
    shift = capture_shift(com, vel, ankle, ref_com, ref_vel, ref_ankle, tc, gain, 0.25)
    want = gain * (((com - ankle) + tc * vel) - ((ref_com - ref_ankle) + tc * ref_vel))[:2]
    norm = np.linalg.norm(want)
    if norm > 0.25:
        want *= 0.25 / norm
    _tight(shift, want)
    assert np.linalg.norm(shift) <= 0.25 + 1e-12


def test_move_point_turns_the_chosen_joints_by_the_damped_least_squares():
    rng = np.random.default_rng(3)
    for rows in (2, 3):
        jacp = rng.normal(size=(3, 12)) * 0.3
        dofs, qadr = np.array([7, 8, 9, 11]), np.array([1, 4, 5, 9])
        move = rng.normal(size=rows) * 0.1
        q = rng.normal(size=10)
        want = q.copy()
        want[qadr] += damped_least_squares(np.ascontiguousarray(jacp[:rows, dofs]), move,
                                           0.05, math.radians(45))
        move_point(jacp, dofs, move, 0.05, math.radians(45), q, qadr)
        np.testing.assert_array_equal(q, want)


@given(arrays(float, 7, elements=st.floats(-500.0, 500.0, allow_nan=False)),
       arrays(float, 7, elements=st.floats(-200.0, 0.0)), st.integers(0, 6))
def test_clip_torques_is_np_clip(tau, low, nan_at):
    high = -low
    tau[nan_at] = np.nan  # a diverged plan stays visible
    got = clip_torques(tau, low, high)
    np.testing.assert_array_equal(got, np.clip(tau, low, high))


@given(arrays(float, (4, 9), elements=_finite), arrays(float, 4, elements=_finite),
       arrays(bool, 4), st.sampled_from([0, 4]))
def test_watched_constraints_are_the_columns_of_the_bounds_kept(T, t0, watched, nl):
    """The QP's inequalities are ``C^T x >= d``: ``lambda >= 0`` (the last ``nl`` unknowns)
    and ``low <= T x + t0 <= high``; the watched subset is exactly their columns for the
    forces and the watched hinges' two bounds, in the full matrix's order."""
    low, high = -np.arange(1.0, 5.0), np.arange(1.0, 5.0)
    C, d = bound_constraints(T, t0, low, high, nl)
    x = np.linspace(-1.0, 1.0, T.shape[1])
    tau = T @ x + t0
    np.testing.assert_allclose(C.T @ x - d, np.concatenate(
        [x[T.shape[1] - nl:], high - tau, tau - low]), rtol=1e-12, atol=1e-12)
    keep = np.concatenate([np.ones(nl, bool), watched, watched])
    Cs, ds = watched_constraints(T, t0, low, high, nl, watched)
    np.testing.assert_array_equal(Cs, C[:, keep])
    np.testing.assert_array_equal(ds, d[keep])
