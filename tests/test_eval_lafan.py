"""The LaFAN1 protocol's metrics and baselines (eval.lafan) on synthetic skeletons and
motions: NPSS of a window with itself is 0, L2Q ignores quaternion signs, L2P's
normalisation, the pooled NPSS is the benchmark's one weighted average, the interpolation
baseline is exact on a constant-speed motion, the facing turn and the training windows."""

import numpy as np
import pytest

from eval.lafan import (
    continuous_in_time,
    facing_rotation,
    interpolation,
    joint_frames,
    l2p,
    l2q,
    npss,
    pooled_npss,
    position_std,
    same_hemisphere,
    stats_windows,
    window_metrics,
    zero_velocity,
)
from tests.asf_builder import make_asf
from upm import read_asf
from upm.motion.skeleton import JOINTS, joint_dof_index
from upm.ops.rotations import euler_to_matrix
from upm.transitions.root import heading_deg


@pytest.fixture(scope="module")
def skeleton(tmp_path_factory):
    bones = {
        "lowerback": {"direction": (0, 1, 0), "length": 0.3, "dof": ["rx", "ry", "rz"]},
        "lfemur": {"direction": (0, -1, 0), "length": 0.4, "dof": ["rx", "ry", "rz"]},
        "ltibia": {"direction": (0, -1, 0), "length": 0.4, "dof": ["rx"]},
        "rhumerus": {"direction": (1, 0, 0), "length": 0.3, "dof": ["rx", "ry", "rz"]},
    }
    path = tmp_path_factory.mktemp("lafan") / "lafan.asf"
    path.write_text(make_asf(bones, {"root": ["lowerback", "lfemur", "rhumerus"],
                                     "lfemur": ["ltibia"]}))
    return read_asf(path)


def _unit_quaternions(rng, shape):
    q = rng.normal(size=shape + (4,))
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def _motion(frames: int, rate_deg: float = 3.0):
    """A motion turning at constant speed: every 3-DOF joint about its x axis, the root
    about the vertical, the root moving in a straight line."""
    t = np.arange(frames, dtype=float)
    posture = np.zeros((frames, 63))
    for joint in ("lowerback", "lfemur", "rhumerus"):
        posture[:, joint_dof_index(joint, "rx")] = 10.0 + rate_deg * t
    posture[:, joint_dof_index("ltibia", "rx")] = 5.0 + 0.5 * rate_deg * t
    root = np.zeros((frames, 6))
    root[:, 0] = 0.02 * t
    root[:, 1] = 0.9
    root[:, 2] = -0.01 * t
    root[:, 4] = 30.0 + rate_deg * t
    return posture, root


def test_npss_of_a_window_with_itself_is_zero():
    rng = np.random.default_rng(0)
    window = continuous_in_time(_unit_quaternions(rng, (30, 22))).reshape(30, -1)
    value, power = npss(window, window)
    assert value == 0.0 and power > 0
    other, _ = npss(window, np.roll(window, 7, axis=0) + 0.3)
    assert other > 0.01


def test_npss_of_a_held_frame_against_motion_is_not_zero():
    t = np.arange(15)[:, None]
    truth = np.hstack([np.cos(0.4 * t), np.sin(0.4 * t), np.ones((15, 1))])
    value, _ = npss(truth, np.repeat(truth[:1], 15, axis=0))
    assert value > 0.1


def test_l2q_of_a_sign_flipped_quaternion_is_zero():
    rng = np.random.default_rng(1)
    truth = _unit_quaternions(rng, (5, 22))
    flips = np.where(rng.random((5, 22, 1)) < 0.5, -1.0, 1.0)
    assert l2q(truth * flips, truth) == 0.0
    assert l2q(-truth, truth) == 0.0
    assert same_hemisphere(-truth, truth) == pytest.approx(truth)
    assert l2q(_unit_quaternions(rng, (5, 22)), truth) > 0.5


def test_l2q_is_the_norm_over_all_joints_per_frame_averaged_over_frames():
    truth = np.zeros((2, 3, 4))
    truth[..., 0] = 1.0
    predicted = truth.copy()
    predicted[0, :, :] = [0.0, 1.0, 0.0, 0.0]  # frame 0: every joint a half turn away
    assert l2q(predicted, truth) == pytest.approx(np.sqrt(3 * 2.0) / 2)


def test_l2p_divides_each_coordinate_by_its_deviation():
    truth = np.zeros((4, 22, 3))
    std = np.full((22, 3), 0.5)
    std[3, 1] = 0.1
    predicted = truth.copy()
    predicted[:, 3, 1] = 0.2  # two deviations of that coordinate
    predicted[:2, 0, 0] = 0.5  # one deviation, in half the frames
    assert l2p(predicted, truth, std) == pytest.approx((2 * np.sqrt(5.0) + 2 * 2.0) / 4)
    assert l2p(truth, truth, std) == 0.0


def test_pooled_npss_is_one_power_weighted_average_over_windows_and_features():
    rng = np.random.default_rng(2)
    truths = [continuous_in_time(_unit_quaternions(rng, (15, 6))).reshape(15, -1)
              for _ in range(3)]
    preds = [t + 0.2 * rng.normal(size=t.shape) for t in truths]
    per_window = [npss(t, p) for t, p in zip(truths, preds, strict=True)]
    pooled = pooled_npss([v for v, _ in per_window], [w for _, w in per_window])
    # One average over every (window, feature), weighted by the truth's power.
    emds, weights = [], []
    for t, p in zip(truths, preds, strict=True):
        pt, pp = (np.square(np.real(np.fft.fft(x, axis=0))) for x in (t, p))
        cdf = [np.cumsum(x / x.sum(axis=0), axis=0) for x in (pt, pp)]
        emds.append(np.abs(cdf[1] - cdf[0]).sum(axis=0))
        weights.append(pt.sum(axis=0))
    assert pooled == pytest.approx(np.average(np.concatenate(emds),
                                              weights=np.concatenate(weights)))


def test_interpolation_is_exact_on_a_constant_speed_motion(skeleton):
    posture, root = _motion(12)
    n = 10
    got_posture, got_root = interpolation(skeleton, (posture[0], root[0]),
                                          (posture[n + 1], root[n + 1]), n)
    assert got_root[:, :3] == pytest.approx(root[1:n + 1, :3])
    facing = facing_rotation(skeleton, root[0])
    std = np.ones((22, 3))
    scores = window_metrics(skeleton, facing, std, (posture[1:n + 1], root[1:n + 1]),
                            (got_posture, got_root))
    assert scores["l2p"] == pytest.approx(0.0, abs=1e-9)
    assert scores["l2q"] == pytest.approx(0.0, abs=1e-9)
    assert scores["npss"] == pytest.approx(0.0, abs=1e-9)


def test_zero_velocity_holds_the_last_context_frame_and_falls_behind(skeleton):
    posture, root = _motion(32)
    held = zero_velocity(posture[0], root[0], 3)
    assert (held[0] == posture[0]).all() and (held[1] == root[0]).all()
    facing = facing_rotation(skeleton, root[0])
    std = np.ones((22, 3))
    errors = [window_metrics(skeleton, facing, std, (posture[1:n + 1], root[1:n + 1]),
                             zero_velocity(posture[0], root[0], n))
              for n in (5, 15, 30)]
    assert errors[0]["l2p"] < errors[1]["l2p"] < errors[2]["l2p"]
    assert errors[0]["l2q"] < errors[1]["l2q"] < errors[2]["l2q"]


def test_joint_frames_give_22_joints_and_the_facing_turn_zeroes_the_heading(skeleton):
    posture, root = _motion(3)
    facing = facing_rotation(skeleton, root[1])
    positions, quaternions = joint_frames(skeleton, posture, root, facing)
    assert positions.shape == (3, len(JOINTS) + 1, 3) and quaternions.shape == (3, 22, 4)
    turned = facing @ euler_to_matrix(root[1:2, 3:6], skeleton.root_axis_order)[0]
    assert float(heading_deg(turned)) == pytest.approx(0.0, abs=1e-9)
    # The root's position is turned with everything else: its height is kept.
    assert positions[:, 0, 1] == pytest.approx(root[:, 1])
    # L2Q does not depend on the turn (a fixed rotation is an isometry of quaternions).
    _, plain = joint_frames(skeleton, posture, root)
    _, other = joint_frames(skeleton, posture[::-1], root[::-1])
    _, other_turned = joint_frames(skeleton, posture[::-1], root[::-1], facing)
    assert l2q(other_turned, quaternions) == pytest.approx(l2q(other, plain))


def test_continuous_in_time_removes_sign_jumps():
    rng = np.random.default_rng(3)
    q = np.cumsum(0.05 * rng.normal(size=(20, 4, 4)), axis=0) + [1.0, 0, 0, 0]
    q /= np.linalg.norm(q, axis=-1, keepdims=True)
    jumpy = q * np.where(rng.random((20, 4, 1)) < 0.3, -1.0, 1.0)
    smooth = continuous_in_time(jumpy)
    assert np.einsum("tjc,tjc->tj", smooth[1:], smooth[:-1]).min() > 0
    assert l2q(smooth, q) == 0.0


def test_training_windows_are_the_protocols(skeleton):
    posture, root = _motion(131)
    windows = stats_windows(skeleton, posture, root)
    assert windows.shape == (len(range(0, 131 - 50, 20)), 50, 22, 3)
    # Each window centred on its mean horizontal root position (then turned about y).
    assert windows[:, :, 0, [0, 2]].mean(axis=1) == pytest.approx(np.zeros((5, 2)), abs=1e-12)
    std = position_std([windows, windows[:2]])
    assert std.shape == (22, 3) and (std >= 0).all() and std[0, 1] == pytest.approx(0.0)
