"""The in-betweening task on the real test clips (eval.inbetween): the protocol's windows
and frames, zero velocity's L2P growing with the transition length, interpolation doing
better than holding the pose, the L2P normalisation from the train split."""

from types import SimpleNamespace

import numpy as np
import pytest

from eval.inbetween import (
    FUTURE_FRAMES,
    STEP,
    cached_position_std,
    draw_windows,
    gap_frames,
    score_window,
)
from eval.lafan import INTERPOLATION, LAFAN_LENGTHS, PAST_FRAMES, ZERO_VELOCITY
from eval.study import ALPHA

N_WINDOWS = 24


@pytest.fixture(scope="module")
def test_clips(catalog):
    from eval.realdata import load_test_clips

    return load_test_clips(catalog)


@pytest.fixture(scope="module")
def baseline_scores(catalog, test_clips):
    std = cached_position_std(catalog)
    data = SimpleNamespace(motions=test_clips, sources={})
    windows = draw_windows({n: m.n_frames for n, m in test_clips.items()}, N_WINDOWS, 0)
    rows = [row for w in windows for row in score_window(data, w, std, (), ALPHA)]
    return windows, rows, std


def _mean(rows, length, method, metric):
    return np.mean([v[metric] for n, m, v in rows if n == length and m == method])


def test_windows_leave_the_protocols_context_in_the_clip(test_clips):
    lengths = {n: m.n_frames for n, m in test_clips.items()}
    windows = draw_windows(lengths, 40, 3)
    assert len(windows) == 40 and {w.frames for w in windows} == {gap_frames(30)}
    assert gap_frames(30) == 123 and gap_frames(5) == 23  # (n + 1) / 30 s at 120 fps
    assert "02_03" not in {w.clip for w in windows}  # 173 frames: too short
    for w in windows:
        last_context = w.start - 1
        assert last_context - STEP * (PAST_FRAMES - 1) >= 0
        assert last_context + STEP * (30 + FUTURE_FRAMES) < lengths[w.clip]


def test_zero_velocity_l2p_grows_with_the_transition_length(baseline_scores):
    _, rows, _ = baseline_scores
    l2p = [_mean(rows, n, ZERO_VELOCITY, "l2p") for n in LAFAN_LENGTHS]
    assert l2p[0] < l2p[1] < l2p[2]
    l2q = [_mean(rows, n, ZERO_VELOCITY, "l2q") for n in LAFAN_LENGTHS]
    assert l2q[0] < l2q[1] < l2q[2]


def test_interpolation_beats_holding_the_pose_on_real_motion(baseline_scores):
    _, rows, _ = baseline_scores
    for n in LAFAN_LENGTHS:
        for metric in ("l2p", "l2q"):
            assert _mean(rows, n, INTERPOLATION, metric) < _mean(rows, n, ZERO_VELOCITY,
                                                                 metric), (n, metric)
    assert all(v["target_miss_m"] == 0.0 for _, _, v in rows)


def test_l2p_normalisation_is_a_spread_of_real_positions(baseline_scores):
    _, _, std = baseline_scores
    assert std.shape == (22, 3) and np.isfinite(std).all()
    # Centred and turned 50-frame windows: a few centimetres to a few decimetres per axis.
    assert 0.01 < std.min() and std.max() < 1.0
