"""The classic Kohonen SOM (the paper's foil): grid, wrap-around, query, save/load."""

import numpy as np
import pytest

from upm.core.errors import DataFileError, UsageError
from upm.maps.class_maps import nearest_distance_deg
from upm.maps.map_file import load_map
from upm.maps.posture_map import UniformPostureMap
from upm.maps.som import (
    KohonenSOM,
    circular_mean_deg,
    default_grid,
    grid_coordinates,
    train_som_class,
)
from upm.motion.skeleton import CLASS_NAMES, CLASS_SLICES
from upm.ops.angles import angle_diff_deg


def test_circular_mean_wraps():
    assert abs(circular_mean_deg(np.array([[170.0], [-170.0]]))[0]) == pytest.approx(180.0)
    assert circular_mean_deg(np.array([[10.0], [-30.0]]))[0] == pytest.approx(-10.0)


def test_default_grid_follows_the_som_toolbox_rule():
    rng = np.random.default_rng(0)
    x = rng.normal(0, 1, (2000, 2)) * np.array([40.0, 10.0])  # 4:1 spread
    rows, cols = default_grid(x)
    assert rows * cols == pytest.approx(5 * 2000**0.54321, rel=0.1)
    assert max(rows, cols) / min(rows, cols) == pytest.approx(4.0, rel=0.35)
    assert grid_coordinates(2, 3).tolist() == [[0, 0], [0, 1], [0, 2], [1, 0], [1, 1], [1, 2]]


def test_som_on_data_across_the_seam_stays_there():
    """A cluster straddling +-180: a SOM that did not wrap would put neurons near 0."""
    rng = np.random.default_rng(1)
    x = np.column_stack([rng.normal(180.0, 8.0, 1000), rng.normal(0.0, 8.0, 1000)])
    w = train_som_class(x, (6, 6))
    assert np.all(np.abs(angle_diff_deg(w[:, 0], 180.0)) < 30.0)
    assert nearest_distance_deg(x, w).mean() < 6.0


def test_som_is_deterministic_and_sized_by_its_grid():
    rng = np.random.default_rng(2)
    x = rng.uniform(-90, 90, (500, 3))
    a = train_som_class(x, (4, 5), epochs=5)
    assert a.shape == (20, 3)
    assert np.array_equal(a, train_som_class(x, (4, 5), epochs=5))
    r1 = train_som_class(x, (4, 5), epochs=5, init="random", seed=1)
    assert not np.array_equal(r1, train_som_class(x, (4, 5), epochs=5, init="random", seed=2))


@pytest.fixture(scope="module")
def som_and_data(synthetic_catalog):
    from upm.maps.class_maps import postures_of_clips

    x, names = postures_of_clips(synthetic_catalog, ["81_02", "82_01"])
    return KohonenSOM(grid=(6, 8), epochs=6).fit(x, clip_names=names), x


def test_som_key_posture_is_made_of_its_neurons(som_and_data):
    som, x = som_and_data
    key = som.key_posture(x[:20], x[-20:], 0.5)
    for c in CLASS_NAMES:
        assert len(som.neurons[c]) == 48
        sub = key[:, CLASS_SLICES[c]]
        assert all(np.any(np.all(som.neurons[c] == row, axis=1)) for row in sub)
    assert np.array_equal(som.key_posture(x[0], x[-1], 0.0), som.nearest_neurons(x[0]))
    with pytest.raises(UsageError, match=r"alpha must be in \[0, 1\]"):
        som.key_posture(x[0], x[-1], 2.0)


def test_som_save_load_and_kind(som_and_data, tmp_path):
    som, x = som_and_data
    path = tmp_path / "som.npz"
    som.save(path)
    loaded = load_map(path)
    assert isinstance(loaded, KohonenSOM) and loaded.grids == som.grids
    a, b = x[:5], x[-5:]
    assert np.array_equal(loaded.key_posture(a, b, 0.4), som.key_posture(a, b, 0.4))
    assert loaded.provenance["clip_names"] == ["81_02", "82_01"]
    with pytest.raises(DataFileError, match="holds a 'som' map"):
        UniformPostureMap.load(path)
    with np.load(path, allow_pickle=False) as data:
        arrays = {k: data[k] for k in data.files}
    arrays["grid_body"] = np.array([5, 5])
    np.savez(tmp_path / "bad.npz", **arrays)
    with pytest.raises(DataFileError, match="grid_body is 5 x 5 but the class has 48"):
        load_map(tmp_path / "bad.npz")


def test_bad_som_parameters():
    with pytest.raises(UsageError, match="grid"):
        KohonenSOM(grid=(0, 4))
    with pytest.raises(UsageError, match="init"):
        KohonenSOM(init="magic")
