"""Motions into qpos and back: root frame change, wrapped hinges, round trips."""

import mujoco
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from controller import from_qpos, posture_to_ctrl, to_qpos
from controller.qpos import qpos_to_root, root_to_qpos
from humanoid_xml import build_mjcf
from humanoid_xml.frames import ASF_TO_MJ
from upm.motion.kinematics import forward_kinematics
from upm.motion.skeleton import joint_dof_index
from upm.ops.angles import angle_diff_deg
from upm.ops.rotations import euler_to_matrix


def _joint_qpos(model, qpos, name):
    j = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)
    return qpos[:, model.jnt_qposadr[j]]


def test_to_qpos_maps_root_and_hinges(model02, walk):
    qpos = to_qpos(model02, walk)
    assert qpos.shape == (walk.n_frames, model02.nq)
    np.testing.assert_allclose(qpos[:, :3], walk.root[:, :3] @ ASF_TO_MJ.T)
    assert np.all(qpos[:, 2] > 0.8)  # the root stands about a metre above the floor (z up)
    np.testing.assert_allclose(np.linalg.norm(qpos[:, 3:7], axis=1), 1.0)
    for joint, axis in (("lfemur", "rx"), ("ltibia", "rx"), ("lhumerus", "rz")):
        np.testing.assert_allclose(_joint_qpos(model02, qpos, f"{joint}_{axis}"),
                                   np.deg2rad(walk.posture_deg[:, joint_dof_index(joint, axis)]))


def test_unwrapped_angles_are_wrapped(catalog, all_motions):
    """135_06's root rx runs past 1251 degrees and 131_04's thumbs past 900: qpos holds the
    same rotations, hinges within [-pi, pi)."""
    motion = all_motions["135_06"]
    assert np.abs(motion.root[:, 3:]).max() > 720
    model = mujoco.MjModel.from_xml_string(build_mjcf(motion.skeleton))
    qpos = to_qpos(model, motion)
    hinges = qpos[:, 7:]
    assert hinges.min() >= -np.pi and hinges.max() < np.pi
    back = from_qpos(model, qpos, motion.skeleton, fps=motion.fps)
    np.testing.assert_allclose(forward_kinematics(back), forward_kinematics(motion), atol=1e-9)


def test_round_trip_motion_qpos_motion(model02, all_motions):
    for name in ("02_01", "02_05", "02_07"):
        motion = all_motions[name]
        back = from_qpos(model02, to_qpos(model02, motion), motion.skeleton, fps=motion.fps)
        assert back.fps == motion.fps and back.n_frames == motion.n_frames
        np.testing.assert_allclose(forward_kinematics(back), forward_kinematics(motion),
                                   atol=1e-9)
        declared = motion.skeleton.declared
        assert np.abs(angle_diff_deg(back.posture_deg, motion.posture_deg)[:, declared]).max() \
            < 1e-9
        assert np.all(back.posture_deg[:, ~declared] == 0)


def test_round_trip_qpos_motion_qpos(model02, walk):
    qpos = to_qpos(model02, walk)
    again = to_qpos(model02, from_qpos(model02, qpos, walk.skeleton))
    np.testing.assert_allclose(again, qpos, atol=1e-12)


@settings(max_examples=60, deadline=None)
@given(arrays(float, (5, 3), elements=st.floats(-1000, 1000)),
       st.sampled_from(["XYZ", "ZYX", "YXZ"]))
def test_root_rotation_round_trip(angles, order):
    root = np.concatenate([np.zeros((5, 3)), angles], axis=1)
    free = root_to_qpos(root, order)
    assert np.all(free[:, 3] >= 0)
    back = qpos_to_root(free, order)
    assert np.all((back[:, 3:] >= -180) & (back[:, 3:] < 180))
    np.testing.assert_allclose(euler_to_matrix(back[:, 3:], order),
                               euler_to_matrix(angles, order), atol=1e-9)


def test_root_quaternion_is_the_conjugated_rotation():
    root = np.array([[0.1, 0.9, -0.3, 20.0, -35.0, 110.0]])
    free = root_to_qpos(root)
    matrix = np.zeros(9)
    mujoco.mju_quat2Mat(matrix, free[0, 3:])
    expected = ASF_TO_MJ @ euler_to_matrix(root[0, 3:], "XYZ") @ ASF_TO_MJ.T
    np.testing.assert_allclose(matrix.reshape(3, 3), expected, atol=1e-12)


def test_posture_is_a_control_vector(model02, walk):
    ctrl = posture_to_ctrl(model02, walk.posture_deg)
    assert ctrl.shape == (walk.n_frames, model02.nu)
    qpos = to_qpos(model02, walk)
    np.testing.assert_allclose(ctrl, qpos[:, model02.jnt_qposadr[model02.actuator_trnid[:, 0]]])
    assert posture_to_ctrl(model02, walk.posture_deg[0]).shape == (model02.nu,)


def test_wrong_qpos_shape_is_an_error(model02, walk):
    with pytest.raises(ValueError, match="qpos must have shape"):
        from_qpos(model02, np.zeros((3, model02.nq + 1)), walk.skeleton)


def test_a_model_without_posture_hinges_is_refused(walk):
    model = mujoco.MjModel.from_xml_string(
        "<mujoco><worldbody><body><freejoint/><geom size='0.1'/>"
        "<body><joint name='elbow' type='hinge'/><geom size='0.1'/></body>"
        "</body></worldbody></mujoco>")
    with pytest.raises(ValueError, match="not a posture DOF"):
        to_qpos(model, walk)
