"""Marker dropouts (upm.motion.dropouts): found and filled on the real clips, in transitions, and
the same on the humanoid's hinges as on the AMC channels."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from upm.motion.dropouts import DROPOUT_JUMP_DEG, dropout_mask, fill_dropouts, joint_runs
from upm.motion.skeleton import JOINTS
from upm.transitions import transition


def test_every_clip_is_left_without_dropouts_and_changed_only_there(all_motions):
    with_dropouts = 0
    for name, motion in all_motions.items():
        before = motion.posture_deg
        mask = dropout_mask(before)
        filled, count = fill_dropouts(before)
        assert not dropout_mask(filled).any(), name
        np.testing.assert_array_equal(filled[~mask], before[~mask])
        assert count == mask.reshape(len(mask), 21, 3).any(axis=2).sum(), name
        with_dropouts += count > 0
        # each filled run lies between the frames around it (holds the one at an end)
        for channels, runs in joint_runs(before):
            for start, stop in runs:
                around = before[[i for i in (start - 1, stop) if 0 <= i < len(before)],
                                channels]
                run = filled[start:stop, channels]
                assert np.all(run >= around.min(axis=0) - 1e-9), name
                assert np.all(run <= around.max(axis=0) + 1e-9), name
    # 02_03 (left toes), 05_01 (right foot), 16_15 (left arm) and 05_16 (right knee)
    assert with_dropouts >= 4


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 20), st.integers(1, 8), st.integers(0, 2**31 - 1))
def test_a_zero_run_between_far_frames_is_filled_by_interpolation(start, length, seed):
    rng = np.random.default_rng(seed)
    posture = rng.uniform(DROPOUT_JUMP_DEG + 1, 170, size=(40, 63)) * rng.choice([-1, 1], 63)
    joint = int(rng.integers(0, 21))
    stop = min(start + length, 40)
    posture[start:stop, 3 * joint:3 * joint + 3] = 0.0
    filled, count = fill_dropouts(posture)
    assert count == stop - start
    rest = np.ones(posture.shape, dtype=bool)
    rest[start:stop, 3 * joint:3 * joint + 3] = False
    np.testing.assert_array_equal(filled[rest], posture[rest])
    channels = slice(3 * joint, 3 * joint + 3)
    before = posture[start - 1, channels] if start > 0 else posture[stop, channels]
    after = posture[stop, channels] if stop < 40 else posture[start - 1, channels]
    for k, frame in enumerate(range(start, stop)):
        w = (k + 1) / (stop - start + 1)
        np.testing.assert_allclose(filled[frame, channels], (1 - w) * before + w * after)


def test_a_transition_into_16_15_does_not_swing_the_arm_to_its_dropout(catalog):
    # 16_15 starts with its left arm's markers lost (exact zeros, then 76 degrees away):
    # B taken from those frames swung the arm down through the window and back in a frame
    before, after = catalog.load("02_01").frames(0, 200), catalog.load("16_15").frames(0, 100)
    raw_count = fill_dropouts(after.posture_deg)[1]
    step = transition("linear", before, after, 20)
    assert step.diagnostics["dropouts_filled"] == raw_count >= 2
    posture = step.motion.posture_deg
    assert not dropout_mask(posture).any()
    np.testing.assert_allclose(posture[step.window.stop:],
                               fill_dropouts(after.posture_deg)[0])
    lhumerus = slice(3 * JOINTS.index("lhumerus"), 3 * JOINTS.index("lhumerus") + 3)
    around_end = posture[step.window.stop - 3:step.window.stop + 10, lhumerus]
    assert np.abs(np.diff(around_end, axis=0)).max() < 10.0
    # the clip as read jumps by tens of degrees from its dropout
    assert np.abs(np.diff(after.posture_deg[:10, lhumerus], axis=0)).max() > 40.0


def test_the_humanoid_fill_matches_the_posture_fill(catalog):
    import mujoco

    from controller.dropouts import fill_dropouts as fill_hinges
    from controller.qpos import to_qpos
    from humanoid_xml import build_mjcf

    model = mujoco.MjModel.from_xml_string(build_mjcf(catalog.skeleton("16")))
    motion = catalog.load("16_15").frames(0, 40)
    hinges, count = fill_hinges(model, to_qpos(model, motion))
    posture, posture_count = fill_dropouts(motion.posture_deg)
    assert count == posture_count > 0
    np.testing.assert_allclose(hinges, to_qpos(model, motion.replace(posture_deg=posture)),
                               atol=1e-12)


@pytest.mark.parametrize("shape", [(0, 63), (1, 63)])
def test_empty_and_single_frames_have_nothing_to_fill(shape):
    posture = np.zeros(shape)
    filled, count = fill_dropouts(posture)
    assert count == 0 and filled.shape == shape
