"""Shared fixtures: the real CMU clips in ``$UPM_DATA`` (default ``../shared/data/cmu``),
and the test tiers.

Tiers (pytest markers, registered in pyproject.toml): ``unit`` needs no CMU data (small
synthetic skeletons and motions made in the tests), ``data`` needs the clips and is
skipped, with the reason, when the data folder is missing; ``physics`` (free-root runs)
and ``browser`` (headless Chromium) are marked in their modules. A test that asks for a
data fixture (directly or through another fixture) is ``data``; every other test not
marked ``physics`` or ``browser`` is ``unit``.
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


def pytest_collection_modifyitems(config, items):
    for item in items:
        marks = {m.name for m in item.iter_markers()}
        needs_data = bool(DATA_FIXTURES & set(getattr(item, "fixturenames", ())))
        if needs_data:
            item.add_marker(pytest.mark.data)
        elif not marks & {"physics", "browser", "data"}:
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
