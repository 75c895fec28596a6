"""Inverse dynamics: finite differences against known trajectories, the root residual's
sign and scale (standing on the floor needs nothing, held 20 cm up needs the body's
weight, free fall needs nothing), the support wrench against MuJoCo's own Jacobians, and
real walks."""

import mujoco
import numpy as np
from scipy.spatial.transform import Rotation

from controller import to_qpos
from controller.body import body_figures
from controller.checks.dynamics import (
    finite_differences,
    lowpass_qpos,
    raw_inverse_with_contacts,
    root_residual,
    unwrap_hinges,
)
from controller.config import DEFAULT
from controller.qpos import joint_layout


def _still(model, n=20, lift_m=0.0):
    qpos = np.tile(model.qpos0, (n, 1))
    qpos[:, 2] += lift_m
    return qpos


def test_standing_still_on_the_floor_needs_little_residual(model02):
    result = root_residual(model02, _still(model02), fps=120.0)
    np.testing.assert_allclose(result.needed_force_bw, 1.0, rtol=1e-6)  # it needs its weight
    assert np.all(result.support_points > 0)
    # ... which the floor supplies; what remains is the rest pose's centre of mass standing
    # 2 cm behind the heels' contact points (measured 0.006 body weights, 0.010 torque).
    assert result.force_bw.max() < 0.02
    assert result.torque_bwh.max() < 0.02


def test_the_same_posture_lifted_20_cm_needs_the_body_weight_upwards(model02):
    result = root_residual(model02, _still(model02, lift_m=0.20), fps=120.0)
    assert np.all(result.support_points == 0)
    weight = body_figures(model02).weight_n
    np.testing.assert_allclose(result.residual_force_n / weight,
                               np.tile([0.0, 0.0, 1.0], (20, 1)), atol=1e-6)
    np.testing.assert_allclose(result.force_bw, 1.0, rtol=1e-6)


def test_free_fall_needs_no_external_force(model02):
    """A body dropping at g from 1 m up: gravity alone does it (checks the sign of the
    finite-difference acceleration against MuJoCo's gravity)."""
    fps = 120.0
    t = np.arange(30) / fps
    qpos = _still(model02, 30, lift_m=1.0)
    qpos[:, 2] -= 0.5 * 9.81 * t ** 2
    result = root_residual(model02, qpos, fps, lowpass_hz=None)
    assert result.force_bw.max() < 1e-6
    assert result.torque_bwh.max() < 1e-6


def test_mujoco_soft_contacts_give_no_support_to_a_resting_foot(model02):
    """Why the residual does not use plain mj_inverse with contacts: standing exactly on
    the floor, MuJoCo's soft contact pushes with nothing (the residual would be the whole
    weight); 1 mm in, it pushes with most of it."""
    weight = body_figures(model02).weight_n
    on_floor = raw_inverse_with_contacts(model02, _still(model02), 120.0) / weight
    np.testing.assert_allclose(on_floor[:, 2], 1.0, atol=1e-6)
    sunk = raw_inverse_with_contacts(model02, _still(model02, lift_m=-0.001), 120.0) / weight
    assert 0.3 < sunk[5, 2] < 0.99


def test_finite_differences_of_known_motion(model02):
    fps = 100.0
    n = 50
    t = np.arange(n) / fps
    layout = joint_layout(model02)
    qpos = _still(model02, n, lift_m=0.5)
    qpos[:, 0] = 0.3 * t  # constant velocity along x
    omega = np.array([0.0, 0.0, 2.0])  # turning about z at 2 rad/s
    xyzw = Rotation.from_rotvec(t[:, None] * omega).as_quat()
    qpos[:, 3:7] = np.concatenate([xyzw[:, 3:], xyzw[:, :3]], axis=1)
    knee = layout.qpos_address[layout.names.index("ltibia.rx")]
    knee_dof = layout.dof_address[layout.names.index("ltibia.rx")]
    qpos[:, knee] = 0.5 + 0.2 * np.sin(3.0 * t)
    qvel, qacc = finite_differences(model02, qpos, fps)
    inner = slice(1, -1)
    np.testing.assert_allclose(qvel[:, 0], 0.3, atol=1e-12)
    np.testing.assert_allclose(qvel[:, 3:6], np.tile(omega, (n, 1)), atol=1e-9)
    np.testing.assert_allclose(qacc[:, :6], 0.0, atol=1e-7)
    np.testing.assert_allclose(qvel[inner, knee_dof], 0.6 * np.cos(3.0 * t[inner]), atol=1e-3)
    np.testing.assert_allclose(qacc[inner, knee_dof], -1.8 * np.sin(3.0 * t[inner]),
                               atol=1e-3)


def test_hinges_are_unwrapped_before_differencing(model02):
    layout = joint_layout(model02)
    column = layout.qpos_address[0]
    qpos = _still(model02, 5)
    qpos[:, column] = [3.10, 3.13, -3.13, -3.10, -3.07]  # crossing +-pi at 0.03 rad/frame
    unwrapped = unwrap_hinges(model02, qpos)
    np.testing.assert_allclose(np.diff(unwrapped[:, column]), 0.03, atol=0.02)
    qvel, _ = finite_differences(model02, qpos, 1.0)
    assert np.abs(qvel[:, layout.dof_address[0]]).max() < 0.05


def test_support_wrench_matches_mujoco_jacobians(model02, walk):
    """The contact columns use [f, (p - x) x f] in the world frame; MuJoCo's point
    Jacobian gives the free joint J^T f with its rotation in the root's frame."""
    data = mujoco.MjData(model02)
    data.qpos[:] = to_qpos(model02, walk)[100]
    mujoco.mj_kinematics(model02, data)
    mujoco.mj_comPos(model02, data)
    body = mujoco.mj_name2id(model02, mujoco.mjtObj.mjOBJ_BODY, "lfoot")
    point = data.xpos[body] + np.array([0.05, -0.02, -0.04])
    force = np.array([10.0, -20.0, 300.0])
    jacp = np.zeros((3, model02.nv))
    mujoco.mj_jac(model02, data, jacp, None, point, body)
    generalised = jacp[:, :6].T @ force
    rotation = data.xmat[1].reshape(3, 3)
    np.testing.assert_allclose(generalised[:3], force, atol=1e-9)
    np.testing.assert_allclose(rotation @ generalised[3:],
                               np.cross(point - data.xpos[1], force), atol=1e-9)


def test_real_walks_need_little_hand_of_god(catalog, all_motions):
    """With the 12 Hz filter, a real walk needs on average a few percent of its weight
    beyond what the floor gives (02_01: 0.044); unfiltered, mocap noise twice
    differentiated asks for ten times that (0.41)."""
    from humanoid_xml import catalog_model_path, load_model

    model = load_model(catalog_model_path(catalog, "02_01"))
    walk = all_motions["02_01"]
    qpos = to_qpos(model, walk)
    filtered = root_residual(model, qpos, walk.fps)
    raw = root_residual(model, qpos, walk.fps, lowpass_hz=None)
    assert filtered.force_bw.mean() < 0.1
    assert np.median(filtered.force_bw) < 0.05
    assert raw.force_bw.mean() > 4 * filtered.force_bw.mean()
    assert abs(filtered.needed_force_n[:, 2].mean() / filtered.weight_n - 1.0) < 0.05
    summary = filtered.summary(slice(100, 140))
    assert 0 <= summary["residual_force_bw_mean"] <= summary["residual_force_bw_peak"]
    assert DEFAULT.residual.support_distance_m == 0.05


def test_lowpass_keeps_quaternions_unit_and_hemisphere_flips_harmless(model02, walk):
    qpos = to_qpos(model02, walk)[:60]
    flipped = qpos.copy()
    flipped[::2, 3:7] *= -1.0  # the same rotations, alternating signs
    a = lowpass_qpos(model02, qpos, walk.fps)
    b = lowpass_qpos(model02, flipped, walk.fps)
    np.testing.assert_allclose(np.linalg.norm(a[:, 3:7], axis=1), 1.0)
    np.testing.assert_allclose(np.abs(np.sum(a[:, 3:7] * b[:, 3:7], axis=1)), 1.0, atol=1e-9)
    assert np.abs(a[:, :3] - qpos[:, :3]).max() < 0.02  # a walk's root moves little above 12 Hz


def test_root_residual_refuses_non_finite_motion(model02):
    import pytest

    from controller.checks.dynamics import root_residual
    from upm.core.errors import UsageError

    qpos = np.tile(model02.qpos0, (5, 1))
    qpos[2, 7] = np.inf
    with pytest.raises(UsageError, match="NaN or infinite"):
        root_residual(model02, qpos, fps=120.0)
    qpos[2, 7] = 0.0
    qpos[2, 0] = 1e300  # a finite root position whose accelerations overflow
    with pytest.raises(UsageError, match="overflow|NaN or infinite"):
        root_residual(model02, qpos, fps=120.0)
