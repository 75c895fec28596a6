"""Trained maps are cached by what made them, and come back identical."""

import numpy as np

from upm.maps.map_cache import map_key, trained_map
from upm.motion.skeleton import CLASS_NAMES

CLIPS = ["09_06", "141_01"]


def test_cached_map_is_the_trained_map(catalog, tmp_path, monkeypatch):
    monkeypatch.setenv("UPM_CACHE", str(tmp_path))
    first = trained_map(catalog, "upm", CLIPS)
    files = sorted(p.name for p in (tmp_path / "maps").glob("*.npz"))
    assert len(files) == 1
    again = trained_map(catalog, "upm", CLIPS)  # from the cache this time
    for c in CLASS_NAMES:
        np.testing.assert_array_equal(first.neurons[c], again.neurons[c])
    assert again.provenance["clip_names"] == CLIPS


def test_key_changes_with_kind_params_and_clips(catalog):
    base = map_key(catalog, "upm", CLIPS, {})
    assert map_key(catalog, "upm", CLIPS, {}) == base
    assert map_key(catalog, "som", CLIPS, {}) != base
    assert map_key(catalog, "upm", CLIPS, {"seed": 1}) != base
    assert map_key(catalog, "upm", CLIPS[:1], {}) != base
