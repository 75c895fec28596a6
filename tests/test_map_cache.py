"""Trained maps are cached by what made them, and come back identical."""

import numpy as np

from upm.maps.map_cache import map_key, trained_map
from upm.motion.skeleton import CLASS_NAMES

CLIPS = ["81_02", "82_01"]  # of the synthetic folder (tests/synthetic.py)


def test_cached_map_is_the_trained_map(synthetic_catalog, tmp_path, monkeypatch):
    monkeypatch.setenv("UPM_CACHE", str(tmp_path))
    first = trained_map(synthetic_catalog, "upm", CLIPS)
    files = sorted(p.name for p in (tmp_path / "maps").glob("*.npz"))
    assert len(files) == 1
    again = trained_map(synthetic_catalog, "upm", CLIPS)  # from the cache this time
    for c in CLASS_NAMES:
        np.testing.assert_array_equal(first.neurons[c], again.neurons[c])
    assert again.provenance["clip_names"] == CLIPS


def test_key_changes_with_kind_params_and_clips(synthetic_catalog):
    base = map_key(synthetic_catalog, "upm", CLIPS, {})
    assert map_key(synthetic_catalog, "upm", CLIPS, {}) == base
    assert map_key(synthetic_catalog, "som", CLIPS, {}) != base
    assert map_key(synthetic_catalog, "upm", CLIPS, {"seed": 1}) != base
    assert map_key(synthetic_catalog, "upm", CLIPS[:1], {}) != base


def test_key_changes_with_a_clips_bytes_and_frame_rate(synthetic_dir, tmp_path):
    import shutil

    from upm.motion.catalog import Catalog

    copy = shutil.copytree(synthetic_dir, tmp_path / "data")
    base = map_key(Catalog(copy), "upm", CLIPS, {})
    amc = copy / "82" / "82_01.amc"
    amc.write_bytes(amc.read_bytes().replace(b"\r\nroot 0 ", b"\r\nroot 1e-9 ", 1))
    changed = map_key(Catalog(copy), "upm", CLIPS, {})
    assert changed != base
    csv = copy / "clips.csv"
    csv.write_text(csv.read_text().replace("82_01,82,60,", "82_01,82,50,"))
    assert map_key(Catalog(copy), "upm", CLIPS, {}) not in (base, changed)
