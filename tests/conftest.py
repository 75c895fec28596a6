"""Shared fixtures: the real CMU clips in ``$UPM_DATA`` (default ``../shared/data/cmu``),
a synthetic data folder made in the tests, and the test tiers.

Tiers (pytest markers, registered in pyproject.toml): ``unit`` needs no CMU data (small
synthetic skeletons and motions made in the tests: :mod:`tests.synthetic` and the
``synthetic_dir`` / ``synthetic_catalog`` / ``synthetic_maps`` fixtures), ``data`` needs the
clips and is skipped, with the reason, when the data folder is missing; ``physics``
(free-root runs) and ``browser`` (headless Chromium) are marked in their modules. A test
that asks for a data fixture (directly or through another fixture) is ``data``; every
other test not marked ``physics``, ``browser`` or ``clone`` is ``unit``.

``clone`` (registered below) marks tests/test_tiers.py, which copies the checkout to a
temporary folder with no data beside it and runs ``pytest -m unit`` there in a
subprocess: it is never part of the unit tier (it would run itself), and runs with the
whole suite or alone with ``pytest -m clone``.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from hypothesis import HealthCheck, settings

# Hypothesis: reproducible by default ("ci": derandomized, so a run's examples are the
# same on every machine); HYPOTHESIS_PROFILE=explore searches with fresh random examples.
settings.register_profile("ci", derandomize=True, deadline=None, print_blob=True,
                          suppress_health_check=[HealthCheck.too_slow])
settings.register_profile("explore", deadline=None, max_examples=500)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))

REPO = Path(__file__).resolve().parent.parent
DATA_DIR = Path(os.environ.get("UPM_DATA", REPO.parent / "shared" / "data" / "cmu"))
#: The fixtures that read the CMU data: a test needing any of them is in the data tier.
DATA_FIXTURES = frozenset({"data_dir", "catalog", "all_motions", "walk", "model02"})

#: Flat-ground walks and runs (SPEC section 5's self-collision calibration set).
FLAT_WALK_RUN = ("02_01", "02_02", "02_03", "05_01", "09_06", "16_15", "35_01", "141_01")


def have_data() -> bool:
    return (DATA_DIR / "clips.csv").is_file()


#: Markers that keep a test out of the unit tier.
NOT_UNIT = frozenset({"physics", "browser", "data", "clone"})


def pytest_configure(config):
    config.addinivalue_line(
        "markers", "clone: runs the unit tier in a copy of the checkout without data "
        "(tests/test_tiers.py); never part of the unit tier")


def pytest_collection_modifyitems(config, items):
    for item in items:
        marks = {m.name for m in item.iter_markers()}
        needs_data = bool(DATA_FIXTURES & set(getattr(item, "fixturenames", ())))
        if needs_data:
            item.add_marker(pytest.mark.data)
        elif not marks & NOT_UNIT:
            item.add_marker(pytest.mark.unit)


@pytest.fixture(scope="session")
def data_dir() -> Path:
    if not have_data():
        pytest.skip(f"the CMU data is not at {DATA_DIR} (set UPM_DATA to the clips)")
    return DATA_DIR


@pytest.fixture(scope="session")
def catalog(data_dir):
    from upm.motion.catalog import Catalog

    return Catalog(data_dir)


@pytest.fixture(scope="session")
def all_motions(catalog):
    """Every clip of the data directory, read once: {name: Motion}."""
    return {info.name: catalog.load(info.name) for info in catalog}


@pytest.fixture(scope="session")
def walk(catalog):
    return catalog.load("02_01")


@pytest.fixture(scope="session")
def model02(catalog):
    """The MuJoCo humanoid of subject 02, built from its ASF (tests must not modify it)."""
    import mujoco

    from humanoid_xml import build_mjcf

    return mujoco.MjModel.from_xml_string(build_mjcf(catalog.skeleton("02")))


# -- the synthetic data folder (unit tier) ------------------------------------------------


@pytest.fixture(scope="session")
def synthetic_dir(tmp_path_factory) -> Path:
    """A data folder made by :func:`tests.synthetic.write_data_folder`: subjects 81 and
    82 (the generic skeleton at 1.75 m and 1.54 m; 82's files with CRLF line ends), five
    clips (walks, runs, a turn; 82_01 at 60 fps) and a clips.csv (81_01, 81_02, 82_01
    train; 81_03, 82_02 test). Tests must not modify it."""
    from tests.synthetic import write_data_folder

    return write_data_folder(tmp_path_factory.mktemp("synthetic-data"))


@pytest.fixture(scope="session")
def synthetic_catalog(synthetic_dir):
    from upm.motion.catalog import Catalog

    return Catalog(synthetic_dir)


@pytest.fixture(scope="session")
def synthetic_cache(tmp_path_factory) -> Path:
    """The cache folder (``UPM_CACHE``) of what the synthetic fixtures train."""
    return tmp_path_factory.mktemp("synthetic-cache")


@pytest.fixture(scope="session")
def synthetic_maps(synthetic_catalog, synthetic_cache):
    """The UPM and the SOM of the synthetic train split (the study's parameters, through
    :func:`upm.maps.map_cache.trained_map`), and the postures they were trained on:
    ``{"upm": map, "som": map, "postures": (N, 63) degrees}``."""
    from upm.maps.class_maps import postures_of_clips
    from upm.maps.map_cache import trained_map

    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("UPM_CACHE", str(synthetic_cache))
        maps = {kind: trained_map(synthetic_catalog, kind) for kind in ("upm", "som")}
    x, _ = postures_of_clips(synthetic_catalog, synthetic_catalog.names("train"))
    return {**maps, "postures": x}


@pytest.fixture(scope="session")
def synthetic_sources(synthetic_catalog, synthetic_maps, synthetic_cache):
    """The key source of every key-posture method, built by its registered builder from
    the synthetic folder (the maps of ``synthetic_maps``, from the cache; feasible with
    the humanoid's checker): ``{method: source}``."""
    import controller.checks.kinematic_check  # noqa: F401 (registers feasible's checker)
    from upm.transitions import METHODS, KeySourceContext, build_key_source

    context = KeySourceContext(catalog=synthetic_catalog, train_maps=True)
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("UPM_CACHE", str(synthetic_cache))
        return {name: build_key_source(name, context) for name, method in METHODS.items()
                if method.needs_key_source}
