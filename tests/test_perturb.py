"""Seeded joint-angle offsets (upm.motion.perturb) on the real clips."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from upm.motion.dropouts import dropout_mask
from upm.motion.perturb import offset_joint_angles


@pytest.fixture(scope="module")
def start_of_16_15(catalog):
    # 16_15 begins with its left arm's marker dropout: exact zeros for its first frames
    return catalog.load("16_15").frames(0, 40)


@settings(max_examples=25, deadline=None)
@given(st.floats(0.0, 5.0), st.integers(0, 2**31))
def test_each_channel_moves_by_one_constant_and_zeros_stay(start_of_16_15, sigma_deg, seed):
    motion = start_of_16_15
    moved = offset_joint_angles(motion, sigma_deg, seed)
    before, after = motion.posture_deg, moved.posture_deg
    kept = dropout_mask(before) | np.all(before == 0.0, axis=0)
    assert dropout_mask(before).any() and np.all(after[kept] == before[kept])
    # one constant per channel over every other frame, an exact zero among them
    for channel in range(before.shape[1]):
        shift = (after - before)[~kept[:, channel], channel]
        assert shift.size == 0 or np.ptp(shift) < 1e-9
    np.testing.assert_array_equal(moved.root, motion.root)
    again = offset_joint_angles(motion, sigma_deg, seed)
    np.testing.assert_array_equal(again.posture_deg, after)
    if sigma_deg == 0.0:
        np.testing.assert_array_equal(after, before)


def test_offsets_follow_their_spread_and_seed(walk):
    moved = [offset_joint_angles(walk, 0.1, seed).posture_deg - walk.posture_deg
             for seed in (1, 2)]
    live = np.all(walk.posture_deg != 0.0, axis=0)
    first = moved[0][0, live]
    assert 0.05 < np.std(first) < 0.2 and np.abs(first).max() < 0.5
    assert not np.allclose(moved[0][0, live], moved[1][0, live])


def test_a_bad_spread_is_refused(walk):
    for sigma in (-0.1, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="standard deviation"):
            offset_joint_angles(walk, sigma, 0)


def test_a_zero_that_is_no_dropout_moves_with_its_channel(walk):
    # 02_01 has channels that pass through exactly zero for a frame: no dropout
    before = walk.posture_deg
    isolated = (before == 0.0) & ~dropout_mask(before) & ~np.all(before == 0.0, axis=0)
    assert isolated.any()
    after = offset_joint_angles(walk, 0.1, 1).posture_deg
    frame, channel = np.argwhere(isolated)[0]
    other = (frame + 1) % len(before)
    assert after[frame, channel] != 0.0
    assert after[frame, channel] - before[frame, channel] == pytest.approx(
        after[other, channel] - before[other, channel], abs=1e-9)


def test_a_moved_clip_keeps_its_marker_dropouts(catalog, start_of_16_15):
    import mujoco

    from controller.dropouts import fill_dropouts
    from controller.qpos import to_qpos
    from humanoid_xml import build_mjcf

    model = mujoco.MjModel.from_xml_string(build_mjcf(catalog.skeleton("16")))
    _, count = fill_dropouts(model, to_qpos(model, start_of_16_15))
    # the same (bone, frame) dropouts on the AMC channels as on the humanoid's hinges
    mask = dropout_mask(start_of_16_15.posture_deg)
    assert mask.reshape(len(mask), 21, 3).any(axis=2).sum() == count
    moved = offset_joint_angles(start_of_16_15, 0.1, 1)
    _, moved_count = fill_dropouts(model, to_qpos(model, moved))
    assert count >= 2 and moved_count == count

