"""Forward kinematics: Euler convention, hand-computed chains, real clips."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from scipy.spatial.transform import Rotation

from tests.asf_builder import make_asf
from upm import Motion, forward_kinematics, read_asf
from upm.motion.kinematics import global_transforms
from upm.motion.skeleton import joint_dof_index
from upm.ops.rotations import euler_to_matrix

WALKS = ("02_01", "02_02", "05_01", "16_15", "35_01")


@given(arrays(float, (4, 3), elements=st.floats(-720, 720)),
       st.sampled_from(["XYZ", "ZYX", "YZX", "XZY"]))
def test_euler_matches_scipy_extrinsic(angles, order):
    # Acclaim "XYZ": x applied first about fixed axes = scipy's extrinsic "xyz".
    ours = euler_to_matrix(angles, order)
    columns = ["XYZ".index(a) for a in order]
    theirs = Rotation.from_euler(order.lower(), angles[:, columns], degrees=True).as_matrix()
    np.testing.assert_allclose(ours, theirs, atol=1e-12)


def _skeleton(tmp_path, bones, hierarchy):
    path = tmp_path / "hand.asf"
    path.write_text(make_asf(bones, hierarchy, length_unit=0.0254))  # 1 unit = 1 m
    return read_asf(path)


def _pose(skeleton, values, root=(0, 0, 0, 0, 0, 0)):
    posture = np.zeros((1, 63))
    for (joint, axis), v in values.items():
        posture[0, joint_dof_index(joint, axis)] = v
    motion = Motion(skeleton, posture, np.array([root], dtype=float))
    positions = forward_kinematics(motion)[0]
    return {n: positions[i] for i, n in enumerate(skeleton.bone_names)}


def test_one_bone_by_hand(tmp_path):
    s = _skeleton(tmp_path, {"lowerback": {"direction": (1, 0, 0), "length": 2.0,
                                           "dof": ["rx", "ry", "rz"]}},
                  {"root": ["lowerback"]})
    assert s.length_to_m == pytest.approx(1.0)
    np.testing.assert_allclose(_pose(s, {})["lowerback"], [2, 0, 0], atol=1e-12)
    # rz = 90 turns +x into +y; a root at (1, 2, 3) carries it along.
    got = _pose(s, {("lowerback", "rz"): 90}, root=(1, 2, 3, 0, 0, 0))
    np.testing.assert_allclose(got["lowerback"], [1, 4, 3], atol=1e-12)
    # Root ry = 90 turns +x into -z.
    np.testing.assert_allclose(_pose(s, {}, root=(0, 0, 0, 0, 90, 0))["lowerback"],
                               [0, 0, -2], atol=1e-12)


def test_two_bones_with_an_axis_frame(tmp_path):
    # upperback hangs off lowerback; its axis frame is turned 90 deg about z, so its own
    # "rx" is a rotation about the world y axis.
    s = _skeleton(tmp_path, {
        "lowerback": {"direction": (0, 1, 0), "length": 1.0, "dof": ["rx", "ry", "rz"]},
        "upperback": {"direction": (1, 0, 0), "length": 2.0, "axis": (0, 0, 90),
                      "dof": ["rx", "ry", "rz"]},
    }, {"root": ["lowerback"], "lowerback": ["upperback"]})
    rest = _pose(s, {})
    np.testing.assert_allclose(rest["upperback"], [2, 1, 0], atol=1e-12)
    # local = C Rx(90) C^T with C = Rz(90): a rotation of +90 about C's x = world +y,
    # which turns +x into -z.
    got = _pose(s, {("upperback", "rx"): 90})
    np.testing.assert_allclose(got["upperback"], [0, 1, -2], atol=1e-12)
    # Bending lowerback by rx = 90 (about x) turns +y into +z and carries upperback.
    got = _pose(s, {("lowerback", "rx"): 90})
    np.testing.assert_allclose(got["lowerback"], [0, 0, 1], atol=1e-12)
    np.testing.assert_allclose(got["upperback"], [2, 0, 1], atol=1e-12)


def test_bone_lengths_constant_in_every_frame_of_every_clip(all_motions):
    for name, motion in all_motions.items():
        s = motion.skeleton
        positions = forward_kinematics(motion)
        segment = positions[:, 1:] - positions[:, s.parents[1:]]
        lengths = np.linalg.norm(segment, axis=-1)
        assert np.abs(lengths - s.lengths_m[1:]).max() < 1e-9, name


def test_walks_touch_the_floor(all_motions):
    for name in WALKS:
        motion = all_motions[name]
        s = motion.skeleton
        toes = [s.bone_index("ltoes"), s.bone_index("rtoes")]
        lowest = forward_kinematics(motion)[:, toes, 1].min(axis=1)
        assert -0.04 < lowest.min() < 0.04, name
        assert np.percentile(lowest, 5) < 0.03, name
        # and the pelvis stays at a walking height
        assert 0.8 < np.median(motion.root[:, 1]) < 1.15, name


def test_bone_lengths_constant_in_every_synthetic_frame(synthetic_catalog):
    for info in synthetic_catalog:
        motion = synthetic_catalog.load(info.name)
        s = motion.skeleton
        positions = forward_kinematics(motion)
        lengths = np.linalg.norm(positions[:, 1:] - positions[:, s.parents[1:]], axis=-1)
        assert np.abs(lengths - s.lengths_m[1:]).max() < 1e-9, info.name


def test_non_articulated_bones_follow_their_parent(synthetic_catalog):
    walk = synthetic_catalog.load("81_01")  # its wrists, fingers, thumbs and upperneck move
    assert np.abs(walk.extra_deg[:5]).max() > 1
    s = walk.skeleton
    rotations, _ = global_transforms(s, walk.posture_deg[:5], walk.root[:5])
    for bone in ("upperneck", "lwrist", "lfingers", "lhipjoint"):
        b = s.bone_index(bone)
        np.testing.assert_array_equal(rotations[:, b], rotations[:, s.parents[b]])


def test_batched_equals_per_frame(synthetic_catalog):
    walk = synthetic_catalog.load("82_01")
    batched = forward_kinematics(walk.frames(0, 7))
    single = np.stack([forward_kinematics(walk.frames(t, t + 1))[0] for t in range(7)])
    np.testing.assert_allclose(batched, single, atol=1e-14)
