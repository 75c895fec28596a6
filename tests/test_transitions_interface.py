"""One interface for every method: the registry, the result, bad input, the AMC."""

import numpy as np
import pytest

from tests.transition_data import pair, synthetic_pair
from upm.core.errors import UsageError
from upm.motion.amc import read_amc, write_amc
from upm.ops.angles import angle_diff_deg
from upm.transitions import (
    KEY_POSTURE_METHODS,
    KINEMATIC_METHODS,
    METHODS,
    PERFORMED_METHODS,
    ClassNearest,
    transition,
)


def test_registry():
    assert set(METHODS) == {"upm", "som", "classnn", "snap", "linear", "slerp", "inertialize",
                            "spacetime", "feasible", "performed"}
    assert set(KEY_POSTURE_METHODS) == {"upm", "som", "classnn", "snap", "feasible"}
    # performed's window is what the humanoid did (tests/test_performed.py)
    assert PERFORMED_METHODS == ("performed",)
    assert set(KINEMATIC_METHODS) == set(METHODS) - {"performed"}
    for name, method in METHODS.items():
        assert method.name == name and method.summary and method.continuity in ("C0", "C1")


@pytest.mark.parametrize("method", KINEMATIC_METHODS)
def test_result_layout(synthetic_catalog, synthetic_sources, method):
    before, after = synthetic_pair(synthetic_catalog, 0)  # two subjects, both at 120 fps
    source = synthetic_sources.get(method)
    result = transition(method, before, after, 12, 0.5, source)
    n1, n2 = before.n_frames, after.n_frames
    assert result.method == method and result.frames == 12 and result.alpha == 0.5
    assert result.window == slice(n1, n1 + 12)
    assert result.motion.n_frames == n1 + 12 + n2
    assert result.a_index == n1 - 1 and result.b_index == n1 + 12
    assert result.window_posture_deg.shape == (12, 63) and result.window_root.shape == (12, 6)
    assert result.key_time == 6.5
    assert np.isfinite(result.seconds) and result.seconds != 0  # the compute time is kept
    assert (result.key_posture_deg is not None) == METHODS[method].needs_key_source
    motion = result.motion
    np.testing.assert_array_equal(motion.posture_deg[:n1], before.posture_deg)
    np.testing.assert_array_equal(motion.root[:n1], before.root)
    np.testing.assert_array_equal(motion.posture_deg[n1 + 12:], after.posture_deg)
    window = result.window_posture_deg
    assert np.all((window >= -180) & (window < 180))
    assert np.all(window[:, ~before.skeleton.declared] == 0)
    assert motion.extra_deg.shape == (motion.n_frames, len(before.skeleton.extra_channels))
    assert motion.skeleton is before.skeleton and motion.fps == before.fps
    assert result.diagnostics["root_scale"] != 1.0  # the other subject, scaled


def test_written_amc_reads_back(synthetic_catalog, synthetic_sources, tmp_path):
    before, after = synthetic_pair(synthetic_catalog, 0)
    result = transition("classnn", before, after, 20, 0.5, synthetic_sources["classnn"])
    path = tmp_path / "t.amc"
    write_amc(path, result.motion)
    back = read_amc(path, before.skeleton, fps=before.fps)
    assert back.n_frames == result.motion.n_frames
    np.testing.assert_allclose(angle_diff_deg(back.posture_deg, result.motion.posture_deg), 0,
                               atol=1e-6)
    np.testing.assert_allclose(back.root, result.motion.root, atol=1e-6)


def test_different_frame_rates_are_resampled(data_dir):
    before, after = pair(data_dir, 2)  # 60_10 (60 fps) into 35_01 (120 fps)
    assert before.fps == 60 and after.fps == 120
    result = transition("linear", before, after, 10)
    assert result.motion.fps == 60
    assert result.diagnostics["resampled_from_fps"] == 120
    assert result.motion.n_frames == before.n_frames + 10 + (after.n_frames - 1) // 2 + 1


def test_a_lower_frame_rate_is_resampled_up(synthetic_catalog):
    before, after = synthetic_pair(synthetic_catalog, 2)  # 81_03 (120 fps) into 82_01 (60)
    assert before.fps == 120 and after.fps == 60
    result = transition("linear", before, after, 10)
    assert result.motion.fps == 120
    assert result.diagnostics["resampled_from_fps"] == 60
    assert result.motion.n_frames == before.n_frames + 10 + 2 * (after.n_frames - 1) + 1
    # B is clip 2's first frame, then every other frame is one of clip 2's own postures.
    resampled = result.motion.posture_deg[result.b_index::2]
    np.testing.assert_allclose(angle_diff_deg(resampled, after.posture_deg), 0, atol=1e-9)


@pytest.mark.parametrize("kwargs, message", [
    ({"method": "nope"}, "no transition method 'nope'"),
    ({"frames": 0}, "window length"),
    ({"frames": 2.5}, "window length"),
    ({"alpha": 1.2}, "alpha"),
    ({"alpha": float("nan")}, "alpha"),
    ({"method": "upm"}, "needs a key-posture source"),
    ({"method": "snap"}, "needs a key-posture source"),
    ({"method": "upm", "key_source": "classnn"}, "expects a 'upm' key source"),
    ({"method": "classnn", "key_source": object()}, "has no key_posture"),
    ({"context": 0}, "context"),
])
def test_bad_input_is_a_usage_error(synthetic_catalog, kwargs, message):
    before, after = synthetic_pair(synthetic_catalog, 1)
    args = {"method": "linear", "frames": 20, "alpha": 0.5, "key_source": None}
    extra = {k: kwargs.pop(k) for k in list(kwargs) if k == "context"}
    args.update(kwargs)
    if args["key_source"] == "classnn":
        args["key_source"] = ClassNearest(before.posture_deg)
    with pytest.raises(UsageError, match=message):
        transition(args["method"], before, after, args["frames"], args["alpha"],
                   args["key_source"], **extra)


def test_empty_clip_is_a_usage_error(synthetic_catalog):
    before, after = synthetic_pair(synthetic_catalog, 1)
    with pytest.raises(UsageError, match="no frames"):
        transition("linear", before.frames(0, 0), after)


def test_short_clips_and_short_windows(synthetic_catalog, synthetic_sources):
    """One-frame clips (a held pose) and one-frame windows work for every method that
    can; velocities of a one-frame clip are zero."""
    before, after = synthetic_pair(synthetic_catalog, 0)
    for method in KINEMATIC_METHODS:
        source = synthetic_sources.get(method)
        for frames in (1, 2, 5):
            result = transition(method, before.frames(-1, None), after.frames(0, 1), frames,
                                0.5, source)
            assert result.motion.n_frames == frames + 2
            assert np.isfinite(result.motion.posture_deg).all()
