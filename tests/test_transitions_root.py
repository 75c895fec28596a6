"""The root across a transition: the paper's velocity blend, heading alignment (a clip
turned 90 degrees), no jumps in position or orientation, other subjects' scale."""

import numpy as np
import pytest

from tests.transition_data import PAIRS, pair
from upm.motion.kinematics import forward_kinematics
from upm.ops.angles import wrap_deg
from upm.ops.rotations import axis_rotation, continuous_euler_deg, euler_to_matrix
from upm.transitions import match_clip, transition
from upm.transitions.root import heading_deg, leg_length_m
from upm.transitions.slerp import rotation_angle_deg


def turned(motion, angle_deg):
    """The motion turned about the vertical through the origin: positions and orientation."""
    order = motion.skeleton.root_axis_order
    turn = axis_rotation(angle_deg, "Y")
    root = motion.root.copy()
    root[:, :3] = motion.root[:, :3] @ turn.T
    matrices = turn @ euler_to_matrix(motion.root[:, 3:], order)
    root[:, 3:] = continuous_euler_deg(matrices, order, motion.root[0, 3:])
    return motion.replace(root=root)


def root_matrices(motion):
    return euler_to_matrix(motion.root[:, 3:], motion.skeleton.root_axis_order)


@pytest.mark.parametrize("theta", [-170.0, -90.0, 0.0, 45.0, 180.0])
def test_heading_is_the_turn_about_the_vertical(theta):
    tilt = axis_rotation(25.0, "X") @ axis_rotation(-10.0, "Z")  # about horizontal axes
    assert float(wrap_deg(heading_deg(axis_rotation(theta, "Y")) - theta)) == pytest.approx(0)
    assert float(wrap_deg(heading_deg(axis_rotation(theta, "Y") @ axis_rotation(25.0, "X"))
                          - theta)) == pytest.approx(0, abs=1e-9)
    # A tilt about a horizontal axis with both components has a small twist of its own
    # (swing-twist); the heading moves with the vertical turn, exactly.
    base = float(heading_deg(tilt))
    assert float(wrap_deg(heading_deg(axis_rotation(theta, "Y") @ tilt) - base - theta)) == \
        pytest.approx(0, abs=1e-9)


def test_a_clip_facing_90_degrees_away_is_turned_back(data_dir):
    before, after = pair(data_dir, 0)
    away = turned(after, 90.0)
    straight = transition("linear", before, after, 20)
    result = transition("linear", before, away, 20)
    assert float(wrap_deg(result.heading_turn_deg - straight.heading_turn_deg + 90.0)) == \
        pytest.approx(0, abs=1e-9)
    np.testing.assert_allclose(root_matrices(result.motion), root_matrices(straight.motion),
                               atol=1e-9)
    np.testing.assert_allclose(forward_kinematics(result.motion),
                               forward_kinematics(straight.motion), atol=1e-9)
    # Clip 2's heading at B continues clip 1's at A.
    r = root_matrices(result.motion)
    assert float(wrap_deg(heading_deg(r[result.b_index]) - heading_deg(r[result.a_index]))) == \
        pytest.approx(0, abs=1e-9)


def test_without_alignment_the_clip_keeps_its_heading(data_dir):
    before, after = pair(data_dir, 0)
    away = turned(after, 90.0)
    result = transition("linear", before, away, 20, align_heading=False)
    assert result.heading_turn_deg == 0.0
    np.testing.assert_allclose(root_matrices(result.motion)[result.b_index:], root_matrices(away),
                               atol=1e-9)


@pytest.mark.parametrize("index", range(len(PAIRS)))
def test_velocity_blend_and_re_anchoring(data_dir, index):
    """Horizontal root: the first step out of A is clip 1's last step, the last step into
    B is clip 2's first (turned) step, the steps in between blend linearly (the paper's
    m(t)); clip 2 keeps its own path, turned, from where the window ends."""
    before, after = pair(data_dir, index)
    result = transition("linear", before, after, 20)
    xz = result.motion.root[:, [0, 2]]
    a, b = result.a_index, result.b_index
    steps = np.diff(xz[a - 1:b + 2], axis=0)  # A-1 -> A, A -> 1, ..., L -> B, B -> B+1
    v1, v2 = steps[0], steps[-1]
    np.testing.assert_allclose(steps[1], v1, atol=1e-12)
    np.testing.assert_allclose(steps[-2], v2, atol=1e-12)
    np.testing.assert_allclose(np.diff(steps[1:-1], 2, axis=0), 0, atol=1e-12)
    # Clip 2's own path, turned by the heading turn (and scaled for another subject).
    matched, _ = match_clip(before, after)  # resampled and scaled like the transition's
    turn = axis_rotation(result.heading_turn_deg, "Y")
    expected = (matched.root[:, :3] - matched.root[0, :3]) @ turn.T
    np.testing.assert_allclose(result.motion.root[b:, :3] - result.motion.root[b, :3],
                               expected, atol=1e-9)


@pytest.mark.parametrize("index", range(len(PAIRS)))
def test_root_never_jumps(data_dir, index):
    before, after = pair(data_dir, index)
    result = transition("linear", before, after, 20)
    motion, a, b = result.motion, result.a_index, result.b_index
    around = slice(a - 5, b + 6)
    # Horizontal speed in the window is a blend of v1 and v2: never faster than both.
    xz_steps = np.linalg.norm(np.diff(motion.root[around, [0, 2]], axis=0), axis=1)
    clip_steps = np.concatenate([
        np.linalg.norm(np.diff(motion.root[a - 5:a + 1, [0, 2]], axis=0), axis=1),
        np.linalg.norm(np.diff(motion.root[b:b + 6, [0, 2]], axis=0), axis=1)])
    assert xz_steps.max() <= clip_steps.max() + 1e-9
    # Height and orientation: steps no larger than the clips' own near the joins or the
    # even pace from A to B, with margin for the spline bending toward the key (measured
    # on these pairs: at most 1.5x).
    n = result.frames + 1
    height_steps = np.abs(np.diff(motion.root[around, 1]))
    clip_height = np.concatenate([np.abs(np.diff(motion.root[a - 5:a + 1, 1])),
                                  np.abs(np.diff(motion.root[b:b + 6, 1])),
                                  [abs(motion.root[b, 1] - motion.root[a, 1]) / n]])
    assert height_steps.max() <= 2.0 * clip_height.max() + 1e-3
    r = root_matrices(motion)
    turn_steps = rotation_angle_deg(r[around][:-1], r[around][1:])
    clip_turns = np.concatenate([rotation_angle_deg(r[a - 5:a], r[a - 4:a + 1]),
                                 rotation_angle_deg(r[b:b + 5], r[b + 1:b + 6]),
                                 [rotation_angle_deg(r[a], r[b]) / n]])
    assert turn_steps.max() <= 2.0 * clip_turns.max() + 0.1
    # The Euler angles written continue from A's without 360-degree jumps.
    assert np.abs(np.diff(motion.root[around, 3:], axis=0)).max() < 180.0


def test_key_height_is_the_alpha_point(data_dir):
    """Root height at the window's middle (odd L): linear interpolation at alpha."""
    before, after = pair(data_dir, 0)
    for alpha in (0.0, 0.3, 1.0):
        result = transition("linear", before, after, 21, alpha)
        ty = result.motion.root[:, 1]
        expected = ty[result.a_index] + alpha * (ty[result.b_index] - ty[result.a_index])
        assert ty[result.a_index + 11] == pytest.approx(expected, abs=1e-12)


def test_another_subject_is_scaled_by_leg_length(data_dir):
    before, after = pair(data_dir, 1)  # subject 05 into subject 16
    assert before.skeleton is not after.skeleton
    result = transition("linear", before, after, 20)
    scale = leg_length_m(before.skeleton) / leg_length_m(after.skeleton)
    assert result.diagnostics["root_scale"] == pytest.approx(scale)
    assert 0.9 < scale < 1.1 and scale != 1.0
    assert result.motion.skeleton is before.skeleton
    np.testing.assert_allclose(result.motion.root[result.b_index:, 1], after.root[:, 1] * scale)
    np.testing.assert_array_equal(result.motion.posture_deg[result.b_index:], after.posture_deg)
