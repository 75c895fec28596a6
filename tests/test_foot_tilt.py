"""The swing foot kept at the reference's tilt (controller.balance.foot_tilt), on the real walk
02_01: the reference's own state asks for no change; a swing hip and knee moved by up to 10
degrees leave the foot pitched, and one step of the ankle's targets turns it back; a foot on
the floor is left alone."""

import mujoco
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from controller import to_qpos
from controller.balance.foot_tilt import SwingFootTilt

LEGS = {0: ("lfemur_rx", "lfemur_ry", "lfemur_rz", "ltibia_rx"),
        1: ("rfemur_rx", "rfemur_ry", "rfemur_rz", "rtibia_rx")}


@pytest.fixture(scope="module")
def setup(model02, walk):
    qpos = to_qpos(model02, walk)
    feet = [model02.body(name).id for name in ("lfoot", "rfoot")]
    return model02, qpos, feet, SwingFootTilt(model02, qpos, feet)


def _tilt(model, data, tilt, q, frame, side):
    """(tilt error, pitch error) of foot ``side`` in state ``q``, degrees: the angle of
    the reference's vertical from the vertical, and its part about the foot's own
    horizontal lateral axis (toes to ankle turned about z)."""
    data.qpos[:] = q
    mujoco.mj_kinematics(model, data)
    foot = tilt.foot_bodies[side]
    now = data.xmat[foot].reshape(3, 3) @ tilt.up[frame, side]
    toe = [b for b in range(model.nbody) if model.body_parentid[b] == foot][0]
    forward = data.xpos[toe] - data.xpos[foot]
    lateral = np.array([forward[1], -forward[0], 0.0]) / np.hypot(forward[0], forward[1])
    turn = np.cross(now, [0.0, 0.0, 1.0])
    return (np.degrees(np.arccos(np.clip(now[2], -1.0, 1.0))),
            np.degrees(np.arcsin(np.clip(abs(turn @ lateral), 0.0, 1.0))))


def test_the_reference_itself_asks_for_no_change(setup):
    model, qpos, feet, tilt = setup
    data = mujoco.MjData(model)
    for frame in range(0, qpos.shape[0], 37):
        data.qpos[:] = qpos[frame]
        mujoco.mj_kinematics(model, data)
        q_ref = qpos[frame].copy()
        tilt.adjust(data, frame, q_ref, (False, False))
        np.testing.assert_allclose(q_ref, qpos[frame], atol=1e-9)


def test_a_moved_swing_leg_is_turned_back_to_the_references_pitch(setup):
    model, qpos, feet, tilt = setup
    data = mujoco.MjData(model)
    rng = np.random.default_rng(7)
    before, after = [], []
    for frame in range(10, qpos.shape[0] - 10, 23):
        for side in (0, 1):
            q = qpos[frame].copy()
            leg = [model.joint(name).qposadr[0] for name in LEGS[side]]
            q[leg] += np.radians(rng.uniform(-10.0, 10.0, len(leg)))
            data.qpos[:] = q
            mujoco.mj_kinematics(model, data)
            q_ref = q.copy()
            touching = (side == 1, side == 0)  # the other foot stands
            tilt.adjust(data, frame, q_ref, touching)
            # only this foot's ankle targets change
            changed = np.flatnonzero(q_ref != q)
            assert set(changed) <= set(tilt.qpos_address[side])
            before.append(_tilt(model, data, tilt, q, frame, side))
            after.append(_tilt(model, data, tilt, q_ref, frame, side))
    before, after = np.array(before), np.array(after)
    assert before[:, 1].mean() > 3.0  # the moved legs did pitch the feet
    # the pitch (the ankle's flexion axis) is put back to first order ...
    assert np.all(after[:, 1] < 0.2 * before[:, 1] + 0.3)
    # ... and the whole tilt is smaller in every case (the ankle's second hinge is near
    # vertical in this skeleton: it cannot roll the foot much)
    assert np.all(after[:, 0] < before[:, 0])


def test_a_foot_on_the_floor_is_left_alone(setup):
    model, qpos, feet, tilt = setup
    data = mujoco.MjData(model)
    q = qpos[50].copy()
    q[[model.joint(name).qposadr[0] for name in LEGS[0] + LEGS[1]]] += np.radians(8.0)
    data.qpos[:] = q
    mujoco.mj_kinematics(model, data)
    q_ref = q.copy()
    tilt.adjust(data, 50, q_ref, (True, True))
    np.testing.assert_array_equal(q_ref, q)


@settings(max_examples=200, deadline=None)
@given(rotation=arrays(np.float64, 3, elements=st.floats(-3.0, 3.0)),
       up=arrays(np.float64, 3, elements=st.floats(-1.0, 1.0)),
       axes=arrays(np.float64, (2, 3), elements=st.floats(-1.0, 1.0)))
def test_the_compiled_ankle_turn_is_the_damped_least_squares(rotation, up, axes):
    """The compiled step (:func:`controller.balance.qp_kernels.tilt_ankle`) is the module's damped
    least squares, ``delta = (A^T A + damping I)^-1 A^T ((R up) x z)``, for any foot
    orientation ``R`` and hinge axes ``A`` (columns)."""
    from scipy.spatial.transform import Rotation

    from controller.balance.leg_kernels import tilt_ankle
    from controller.config import DEFAULT

    R = Rotation.from_rotvec(rotation).as_matrix()
    xaxis = np.zeros((5, 3))
    hinges, qadr = np.array([1, 3]), np.array([4, 2])
    xaxis[hinges] = axes
    damping = DEFAULT.foot_tilt.damping * np.eye(2)
    qpos = np.linspace(0.1, 0.7, 7)
    q = np.full(7, 9.0)
    tilt_ankle(R.ravel(), up, xaxis, hinges, damping, qpos, qadr, q)
    A = axes.T
    turn = np.cross(R @ up, [0.0, 0.0, 1.0])
    delta = np.linalg.solve(A.T @ A + damping, A.T @ turn)
    np.testing.assert_allclose(q[qadr], qpos[qadr] + delta, rtol=1e-9, atol=1e-9)
    untouched = np.setdiff1d(np.arange(7), qadr)
    assert np.all(q[untouched] == 9.0)
