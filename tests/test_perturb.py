"""Seeded joint-angle offsets (upm.perturb) on the real clips."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from upm.perturb import offset_joint_angles


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
    zero = before == 0.0
    assert zero.any() and np.all(after[zero] == 0.0)
    # one constant per channel over the frames where it is not zero
    for channel in range(before.shape[1]):
        shift = (after - before)[~zero[:, channel], channel]
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


def test_a_moved_clip_keeps_its_marker_dropouts(catalog, start_of_16_15):
    import mujoco

    from controller.dropouts import fill_dropouts
    from controller.qpos import to_qpos
    from humanoid_xml import build_mjcf

    model = mujoco.MjModel.from_xml_string(build_mjcf(catalog.skeleton("16")))
    _, count = fill_dropouts(model, to_qpos(model, start_of_16_15))
    moved = offset_joint_angles(start_of_16_15, 0.1, 1)
    _, moved_count = fill_dropouts(model, to_qpos(model, moved))
    assert count >= 2 and moved_count == count
