"""Both posture maps trained on the synthetic train split (no CMU data): what the
training promises, and the key posture checked by brute force against its definition
(A and B interpolated the short way per DOF at alpha, then the nearest neuron class by
class: alpha 0 is A's nearest neuron, alpha 1 B's)."""

import numpy as np
import pytest

from upm.maps.angular_search import pairwise_sq_deg
from upm.maps.class_maps import nearest_distance_deg, off_data_share
from upm.maps.map_file import load_map
from upm.motion.skeleton import CLASS_NAMES, CLASS_SLICES
from upm.ops.angles import interpolate_deg, wrap_deg

KINDS = ("upm", "som")


@pytest.fixture(scope="module")
def held_out(synthetic_catalog):
    """Pairs (A, B) of held-out postures: frames of the two test clips, (40, 63) each."""
    a = synthetic_catalog.load("81_03").posture_deg[::4][:40]
    b = synthetic_catalog.load("82_02").posture_deg[::3][:40]
    return a, b


def _brute_key(posture_map, a, b, alpha):
    """The definition, in numpy: per class the neuron nearest the interpolated point;
    also the squared distance it is at, (N, 63) and (N, 4)."""
    point = wrap_deg(interpolate_deg(a, b, np.asarray(alpha, dtype=float)[..., None]))
    key = np.empty_like(point)
    dist_sq = np.empty((len(point), len(CLASS_NAMES)))
    for k, c in enumerate(CLASS_NAMES):
        d2 = pairwise_sq_deg(point[:, CLASS_SLICES[c]], posture_map.neurons[c])
        key[:, CLASS_SLICES[c]] = posture_map.neurons[c][d2.argmin(axis=1)]
        dist_sq[:, k] = d2.min(axis=1)
    return key, dist_sq


def _distance_sq(key, point):
    return np.stack([pairwise_sq_deg(point[i:i + 1, CLASS_SLICES[c]],
                                     key[i:i + 1, CLASS_SLICES[c]])[0, 0]
                     for i in range(len(key)) for c in CLASS_NAMES]).reshape(len(key), -1)


def test_the_upm_covers_its_training_postures_and_stays_on_them(synthetic_maps):
    upm, x = synthetic_maps["upm"], synthetic_maps["postures"]
    assert upm.provenance["clip_names"] == ["81_01", "81_02", "82_01"]
    assert upm.provenance["n_samples"] == len(x) == 180 + 144 + 120
    for c in CLASS_NAMES:
        sub, radius = x[:, CLASS_SLICES[c]], upm.radius_deg[c]
        assert 0 < radius < 30
        assert 10 < len(upm.neurons[c]) < len(x)  # a summary, not a copy
        # Quantisation: every training posture within R of a neuron ...
        assert nearest_distance_deg(sub, upm.neurons[c]).max() <= radius + 1e-9
        assert upm.stats[c]["quantisation_error_max_deg"] <= radius + 1e-9
        # ... and the paper's claim: no neuron farther than R from every posture.
        assert off_data_share(upm.neurons[c], sub, radius) == 0.0


def test_the_som_has_its_grid_of_neurons_near_the_data(synthetic_maps):
    som, x = synthetic_maps["som"], synthetic_maps["postures"]
    for c in CLASS_NAMES:
        rows, cols = som.grids[c]
        assert len(som.neurons[c]) == rows * cols > 10
        assert np.all((som.neurons[c] >= -180) & (som.neurons[c] < 180))
        spread = nearest_distance_deg(x[:, CLASS_SLICES[c]], x[::7, CLASS_SLICES[c]]).max()
        assert nearest_distance_deg(x[:, CLASS_SLICES[c]], som.neurons[c]).mean() < 3 * spread


@pytest.mark.parametrize("kind", KINDS)
def test_alpha_0_and_1_are_the_nearest_neurons_of_a_and_b_class_by_class(synthetic_maps,
                                                                         held_out, kind):
    posture_map = synthetic_maps[kind]
    a, b = held_out
    for alpha, end in ((0.0, a), (1.0, b)):
        key = posture_map.key_posture(a, b, alpha)
        expected, dist_sq = _brute_key(posture_map, end, end, 0.0)
        # The same neuron, or one exactly as near (a tie): never a farther one.
        np.testing.assert_allclose(_distance_sq(key, wrap_deg(end)), dist_sq, rtol=1e-12,
                                   atol=1e-9)
        assert np.mean(np.all(key == expected, axis=1)) > 0.95
    np.testing.assert_array_equal(posture_map.key_posture(a, b, 0.0),
                                  posture_map.nearest_neurons(a))


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("alpha", [0.25, 0.5, 0.8])
def test_the_key_posture_is_the_nearest_neuron_to_the_interpolated_point(synthetic_maps,
                                                                         held_out, kind, alpha):
    posture_map = synthetic_maps[kind]
    a, b = held_out
    key = posture_map.key_posture(a, b, alpha)
    expected, dist_sq = _brute_key(posture_map, a, b, np.full(len(a), alpha))
    point = wrap_deg(interpolate_deg(a, b, alpha))
    np.testing.assert_allclose(_distance_sq(key, point), dist_sq, rtol=1e-12, atol=1e-9)
    assert np.mean(np.all(key == expected, axis=1)) > 0.95
    for c in CLASS_NAMES:  # made of neurons, class by class
        sub = key[:, CLASS_SLICES[c]]
        assert all(np.any(np.all(posture_map.neurons[c] == row, axis=1)) for row in sub)


@pytest.mark.parametrize("kind", KINDS)
def test_a_saved_map_loads_back_the_same(synthetic_maps, held_out, tmp_path, kind):
    posture_map = synthetic_maps[kind]
    path = tmp_path / f"{kind}.npz"
    posture_map.save(path)
    loaded = load_map(path)
    assert type(loaded) is type(posture_map) and loaded.kind == kind
    for c in CLASS_NAMES:
        np.testing.assert_array_equal(loaded.neurons[c], posture_map.neurons[c])
    assert loaded.params == posture_map.params and loaded.stats == posture_map.stats
    assert loaded.provenance == posture_map.provenance
    a, b = held_out
    np.testing.assert_array_equal(loaded.key_posture(a, b, 0.4), posture_map.key_posture(a, b, 0.4))
