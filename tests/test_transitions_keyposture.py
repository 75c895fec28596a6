"""Key postures: the classnn and snap sources, and the key-posture methods' window
(passes through the key at its middle; moves monotonically along A->B with alpha)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.transition_data import synthetic_pair
from upm.core.errors import UsageError
from upm.motion.skeleton import CLASS_SLICES
from upm.ops.angles import angle_diff_deg, angular_distance_sq, interpolate_deg, wrap_deg
from upm.transitions import ClassNearest, NearestPosture, make_problem, transition

KEY_METHODS = ("upm", "som", "classnn", "snap")


@pytest.fixture(scope="module")
def small_source():
    """A classnn/snap pair on a small random set that puts values near +-180."""
    rng = np.random.default_rng(7)
    postures = rng.uniform(-180, 180, size=(400, 63))
    return postures, ClassNearest(postures), NearestPosture(postures)


def _brute_nearest(rows, point):
    return rows[np.argmin(angular_distance_sq(rows, point))]


def test_classnn_is_the_exact_nearest_per_class(small_source):
    postures, classnn, _ = small_source
    rng = np.random.default_rng(0)
    a, b = rng.uniform(-180, 180, (2, 50, 63))
    alpha = rng.uniform(0, 1, 50)
    keys = classnn.key_posture(a, b, alpha)
    c = interpolate_deg(a, b, alpha[:, None])
    for i in range(50):
        for s in CLASS_SLICES.values():
            expected = _brute_nearest(wrap_deg(postures[:, s]), c[i, s])
            assert angular_distance_sq(keys[i, s], c[i, s]) == pytest.approx(
                angular_distance_sq(expected, c[i, s]))
            # ... and it is one training sample's sub-vector
            assert np.isclose(wrap_deg(postures[:, s]), keys[i, s]).all(axis=1).any()


def test_snap_is_the_exact_whole_body_nearest(small_source):
    postures, _, snap = small_source
    rng = np.random.default_rng(1)
    a, b = rng.uniform(-180, 180, (2, 30, 63))
    keys = snap.key_posture(a, b, 0.3)
    c = interpolate_deg(a, b, 0.3)
    for i in range(30):
        np.testing.assert_allclose(keys[i], _brute_nearest(wrap_deg(postures), c[i]))


@settings(max_examples=60, deadline=None)
@given(st.floats(-180, 180), st.floats(-180, 180), st.floats(0, 1))
def test_nearest_across_the_seam(a, b, alpha):
    """Distances are on the circle: 179 is next to -179 (property test on one DOF)."""
    column = np.array([-179.5, -90.0, 0.0, 90.0, 179.5])
    postures = np.zeros((5, 63))
    postures[:, 0] = column
    source = ClassNearest(postures)
    pa, pb = np.zeros(63), np.zeros(63)
    pa[0], pb[0] = a, b
    key = source.key_posture(pa, pb, alpha)[0]
    point = float(interpolate_deg(a, b, alpha))
    distances = np.abs(angle_diff_deg(column, point))
    assert abs(float(angle_diff_deg(key, point))) == pytest.approx(distances.min())


def test_single_and_batched_agree(small_source):
    _, classnn, snap = small_source
    rng = np.random.default_rng(2)
    a, b = rng.uniform(-180, 180, (2, 5, 63))
    for source in (classnn, snap):
        batch = source.key_posture(a, b, 0.4)
        assert batch.shape == (5, 63)
        for i in range(5):
            np.testing.assert_array_equal(source.key_posture(a[i], b[i], 0.4), batch[i])


@pytest.mark.parametrize("args, message", [
    ((np.zeros(62), np.zeros(62), 0.5), "shape"),
    ((np.zeros(63), np.zeros((2, 63)), 0.5), "shape"),
    ((np.zeros(63), np.zeros(63), 1.5), "alpha"),
    ((np.zeros(63), np.zeros(63), float("nan")), "alpha"),
    ((np.full(63, np.nan), np.zeros(63), 0.5), "finite"),
])
def test_bad_key_inputs(small_source, args, message):
    with pytest.raises(UsageError, match=message):
        small_source[1].key_posture(*args)


def test_bad_training_postures():
    with pytest.raises(UsageError, match="shape"):
        ClassNearest(np.zeros((0, 63)))
    with pytest.raises(UsageError, match="finite"):
        NearestPosture(np.full((3, 63), np.inf))


@pytest.mark.parametrize("method", KEY_METHODS)
def test_window_passes_through_the_key_posture(synthetic_catalog, synthetic_sources, method):
    """alpha = 0.5, odd L: the middle window frame is the key posture."""
    before, after = synthetic_pair(synthetic_catalog, 1)
    for frames in (21, 9):
        result = transition(method, before, after, frames, 0.5, synthetic_sources[method])
        assert result.key_time == (frames + 1) / 2
        middle = result.motion.posture_deg[result.a_index + int(result.key_time)]
        np.testing.assert_allclose(angle_diff_deg(middle, result.key_posture_deg), 0, atol=1e-9)


def _position_along(key, a, b):
    """Where the key sits along A->B: its projection on the (short-way) segment, 0 at A."""
    d = angle_diff_deg(b, a)
    return float(np.dot(angle_diff_deg(key, a), d) / np.dot(d, d))


@pytest.mark.parametrize("method", KEY_METHODS)
def test_alpha_moves_the_key_monotonically_from_a_to_b(synthetic_catalog, synthetic_sources,
                                                       method):
    """A and B are training frames (81_02 is in the synthetic train split; the sources
    keep every frame), so for classnn and snap alpha = 0 gives A and alpha = 1 gives B
    exactly; for the maps, the neurons nearest A and B. In between, the key and the
    window's middle frame move along A->B without going back (nearest-neighbour search
    along a segment is monotone in the projection, class by class)."""
    clip = synthetic_catalog.load("81_02")
    before, after = clip.frames(20, 61), clip.frames(100, 140)  # A = 60, B = 100
    source = synthetic_sources[method]
    a, b = before.posture_deg[-1], after.posture_deg[0]
    positions, middles = [], []
    for alpha in np.linspace(0, 1, 11):
        result = transition(method, before, after, 21, alpha, source)
        positions.append(_position_along(result.key_posture_deg, a, b))
        middles.append(_position_along(result.window_posture_deg[10], a, b))
        if alpha in (0, 1):
            end = a if alpha == 0 else b
            expected = source.nearest_neurons(end) if method in ("upm", "som") else end
            np.testing.assert_allclose(angle_diff_deg(result.key_posture_deg, expected), 0,
                                       atol=1e-9)
    assert np.all(np.diff(positions) >= -1e-9), positions
    assert np.all(np.diff(middles) >= -1e-9), middles
    # Maps quantise A and B to neurons within R of them: the key still spans most of A->B.
    assert positions[-1] - positions[0] > (0.6 if method in ("upm", "som") else 0.9)


@pytest.mark.parametrize("turns", [0, 2, -3])
def test_key_posture_is_put_on_the_short_turn(synthetic_catalog, synthetic_sources, turns):
    """A key far round the circle is placed on the turn nearest the alpha-point: clip 1's
    lowerneck.rx given as its angle plus ``turns`` whole turns (the same posture), the
    key follows it there."""
    from upm.transitions.keyposture import key_posture_unwrapped

    before, after = synthetic_pair(synthetic_catalog, 0)
    dof = CLASS_SLICES["global"].start  # lowerneck.rx
    shifted = before.posture_deg.copy()
    shifted[:, dof] += 360.0 * turns
    problem = make_problem(before.replace(posture_deg=shifted), after, 20, 0.5,
                           synthetic_sources["classnn"])
    wrapped, continuous = key_posture_unwrapped(problem)
    point = problem.a_deg + 0.5 * (problem.b_deg - problem.a_deg)
    assert np.all(np.abs(continuous - point) <= 180.0)
    assert abs(continuous[dof] - 360.0 * turns) < 180.0
    np.testing.assert_allclose(angle_diff_deg(continuous, wrapped), 0, atol=1e-9)
