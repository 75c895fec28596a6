"""The compiled loops of a transition (upm/transitions/kernels.py) give the numpy code's
results to the last bit (signed zeros included), on values chosen to sit on the edges:
angles on and next to +-180, exact and negative zeros, many turns."""

from __future__ import annotations

import numpy as np
import pytest

from tests.asf_builder import make_asf
from upm.motion.asf import read_asf
from upm.motion.dropouts import fill_dropouts
from upm.motion.motion import Motion
from upm.motion.skeleton import POSTURE_SIZE
from upm.ops.angles import angle_diff_deg, unwrap_deg, wrap_deg
from upm.ops.rotations import euler_to_matrix
from upm.transitions import kernels
from upm.transitions.join import _without_dropouts


def _same(a, b) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes()


def _angles(rng, shape) -> np.ndarray:
    """Degrees with edge values mixed in: +-180 and their neighbours, +-0, whole turns."""
    edges = np.array([180.0, -180.0, np.nextafter(180.0, 0), np.nextafter(-180.0, 0),
                      np.nextafter(-180.0, -np.inf),  # np.mod gives 360: wrap_deg folds it
                      0.0, -0.0, 540.0, -540.0, 360.0, 1251.0, 90.0, -90.0, 1e-300, -1e-300])
    values = rng.uniform(-720.0, 720.0, size=shape)
    mask = rng.random(shape) < 0.2
    values[mask] = rng.choice(edges, size=int(mask.sum()))
    return values


@pytest.fixture
def rng():
    return np.random.default_rng(63)


@pytest.fixture
def skeleton(tmp_path):
    path = tmp_path / "test.asf"
    path.write_text(make_asf({}))
    return read_asf(path)


def test_window_context_is_unwrap_then_the_shift(rng):
    for k1, k2 in ((1, 1), (3, 3), (2, 5)):
        before, after = _angles(rng, (k1, POSTURE_SIZE)), _angles(rng, (k2, POSTURE_SIZE))
        got_before, got_after = kernels.window_context(before, after)
        want_before, want_after = unwrap_deg(before), unwrap_deg(after)
        want_after = want_after + 360.0 * np.round((want_before[-1] - want_after[0]) / 360.0)
        assert _same(got_before, want_before) and _same(got_after, want_after)


def test_wraps_are_wrap_deg(rng):
    posture = _angles(rng, (20, POSTURE_SIZE))
    declared = rng.random(POSTURE_SIZE) < 0.7
    want = wrap_deg(posture)
    want[:, ~declared] = 0.0
    assert _same(kernels.wrap_window(posture, declared), want)
    a, b = posture[0], posture[1]
    got_a, got_b = kernels.wrap_pair(a, b)
    assert _same(got_a, wrap_deg(a)) and _same(got_b, wrap_deg(b))
    extra_a, extra_b = _angles(rng, 9), _angles(rng, 9)
    s = np.arange(1, 21) / 21
    assert _same(kernels.linear_extra(extra_a, extra_b, 20),
                 wrap_deg(extra_a + s[:, None] * wrap_deg(extra_b - extra_a)))


def test_key_on_turn_is_the_key_nearest_the_alpha_point(rng):
    key, a, b = (_angles(rng, POSTURE_SIZE) for _ in range(3))
    for alpha in (0.0, 0.3, 0.5, 1.0):
        wrapped, near, squares, finite = kernels.key_on_turn(key, a, b, alpha)
        point = a + alpha * (b - a)
        want = point + angle_diff_deg(key, point)
        assert finite and _same(wrapped, wrap_deg(key)) and _same(near, want)
        assert _same(squares, (want - point) ** 2)
    key[5] = np.nan
    assert not kernels.key_on_turn(key, a, b, 0.5)[3]


def test_axis_factors_composed_are_euler_to_matrix(rng):
    angles = _angles(rng, (200, 3))
    factors = kernels.axis_factors(angles)
    for order in ("XYZ", "ZYX", "YXZ"):
        first, middle, last = ("XYZ".index(axis) for axis in order)
        got = factors[:, last] @ (factors[:, middle] @ factors[:, first])
        assert _same(got, euler_to_matrix(angles, order))


def test_root_path_is_the_velocity_blend(rng):
    for t1, t2, frames in ((60, 60, 20), (1, 1, 1), (2, 5, 7)):
        before, after = rng.normal(size=(t1, 6)), rng.normal(size=(t2, 6))
        relative = rng.normal(size=(t2, 3))
        window, new_after = np.full((frames, 6), np.nan), np.full((t2, 6), np.nan)
        key_height = kernels.root_path(before, after, relative, frames, 0.3, window, new_after)
        horizontal = slice(0, 3, 2)
        v1 = before[-1, horizontal] - before[-2, horizontal] if t1 > 1 else 0.0
        v2 = relative[1, horizontal] if t2 > 1 else 0.0
        w = np.arange(frames + 1) / frames
        path = before[-1, horizontal] + np.cumsum((1.0 - w)[:, None] * v1 + w[:, None] * v2,
                                                  axis=0)
        assert _same(window[:, horizontal], path[:frames])
        assert _same(new_after[:, horizontal], path[frames] + relative[:, horizontal])
        assert _same(new_after[:, 1], after[:, 1])
        assert key_height == before[-1, 1] + 0.3 * (after[0, 1] - before[-1, 1])


def test_dropout_screen_leaves_the_fill_as_it_was(rng, skeleton):
    posture = rng.uniform(-60.0, 60.0, size=(80, POSTURE_SIZE))
    posture[:, 0:3] = 0.0  # a joint at zero throughout: no dropout
    posture[10:13, 15:18] = 0.0  # a dropout
    posture[0:2, 30:33] = 0.0  # one at the start
    posture[40, 33:36] = [0.0, 0.0, 1e-3]  # not all three zero
    assert kernels.dropout_candidates(posture).tolist() == [5, 10]
    motion = Motion(skeleton=skeleton, posture_deg=posture, root=np.zeros((80, 6)))
    filled, count = _without_dropouts(motion)
    want, want_count = fill_dropouts(posture)
    assert count == want_count == 5 and _same(filled.posture_deg, want)
    clean = Motion(skeleton=skeleton, posture_deg=posture[20:], root=np.zeros((60, 6)))
    assert _without_dropouts(clean) == (clean, 0)


def test_root_wrap_of_one_float_is_wrap_deg(rng):
    from upm.transitions.root import _wrap

    for x in _angles(rng, 2000).tolist():
        assert _same(np.float64(_wrap(x)), wrap_deg(x))
