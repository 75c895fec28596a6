"""Frame-rate resampling: real 60 fps clips to 120 fps and back."""

import numpy as np
import pytest

from upm.core.errors import UsageError
from upm.motion.resample import resample
from upm.ops.angles import angle_diff_deg
from upm.ops.rotations import euler_to_matrix
from upm.transitions.slerp import rotation_angle_deg


@pytest.mark.parametrize("name", ["60_10", "141_04"])
def test_upsampling_keeps_the_original_frames(catalog, name):
    motion = catalog.load(name)
    up = resample(motion, 120.0)
    assert up.fps == 120.0 and up.n_frames == 2 * motion.n_frames - 1
    assert up.duration_s == pytest.approx(motion.duration_s + 1 / 120 - 1 / 60)
    np.testing.assert_allclose(up.root[::2, :3], motion.root[:, :3], atol=1e-12)
    np.testing.assert_allclose(angle_diff_deg(up.posture_deg[::2], motion.posture_deg), 0,
                               atol=1e-9)
    np.testing.assert_allclose(angle_diff_deg(up.extra_deg[::2], motion.extra_deg), 0, atol=1e-9)
    order = motion.skeleton.root_axis_order
    assert rotation_angle_deg(euler_to_matrix(up.root[::2, 3:], order),
                              euler_to_matrix(motion.root[:, 3:], order)).max() < 1e-9


@pytest.mark.parametrize("name", ["60_10", "141_04"])
def test_new_frames_lie_between_their_neighbours(catalog, name):
    """A new frame lies between its original neighbours: no farther from them than the
    original steps around it (a cubic spline overshoots next to a glitch: 60_10 has a
    57-degree root turn in one frame and 130-degree Euler flips of rfemur.rz), and no
    flip."""
    motion = catalog.load(name)
    up = resample(motion, 120.0)
    order = motion.skeleton.root_axis_order
    r = euler_to_matrix(up.root[:, 3:], order)
    step = rotation_angle_deg(r[:-2:2], r[2::2])
    to_mid = rotation_angle_deg(r[:-2:2], r[1:-1:2])
    assert np.all(to_mid <= np.maximum(0.5 * step, _largest_nearby(step)) + 0.5)
    mid = up.posture_deg[1:-1:2]
    around = np.maximum(np.abs(angle_diff_deg(mid, up.posture_deg[:-2:2])),
                        np.abs(angle_diff_deg(mid, up.posture_deg[2::2])))
    gap = np.abs(angle_diff_deg(up.posture_deg[2::2], up.posture_deg[:-2:2]))
    assert np.all(around <= _largest_nearby(gap) + 0.5)


def _largest_nearby(steps):
    """Per original interval, the largest of it and the two on each side (axis 0): a
    cubic spline's overshoot next to a glitch reaches that far."""
    pad = np.zeros((2,) + steps.shape[1:])
    padded = np.concatenate([pad, steps, pad])
    n = steps.shape[0]
    return np.max(np.stack([padded[k:k + n] for k in range(5)]), axis=0)


def test_down_and_same_rate(walk):
    assert resample(walk, 120.0) is not None and resample(walk, 120.0).n_frames == walk.n_frames
    down = resample(walk, 60.0)
    assert down.n_frames == (walk.n_frames - 1) // 2 + 1
    np.testing.assert_allclose(down.root[:, :3], walk.root[::2, :3], atol=1e-12)


@pytest.mark.parametrize("fps", [0, -5, float("nan"), float("inf")])
def test_bad_rate(walk, fps):
    with pytest.raises(UsageError, match="frame rate"):
        resample(walk, fps)
