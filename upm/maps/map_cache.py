"""Trained posture maps cached outside the repository, keyed by what made them.

Training the UPM or the SOM on the train split takes tens of seconds; the study, the
benchmarks and the tests all need the same maps. :func:`trained_map` trains a map once
and keeps it in ``upm.core.cache.cache_dir("maps")`` under a digest of everything it depends
on: the map kind and parameters, the bytes of every training clip and its ASF, the clips'
frame rates, and the source code of the training modules. A lock file makes concurrent
processes (e.g. parallel test workers) wait for one training instead of repeating it.
"""

from __future__ import annotations

import contextlib
import fcntl
import json
from pathlib import Path

from upm.core.cache import cache_dir, digest

#: Modules whose code decides a trained map: a change to any of them retrains.
_TRAINING_MODULES = ("upm.maps.posture_map", "upm.maps.upm_training", "upm.maps.map_size",
                     "upm.maps.som", "upm.maps.class_maps", "upm.maps.angular_search",
                     "upm.ops.angles", "upm.motion.amc", "upm.motion.asf")


def _code_digest() -> str:
    import importlib

    sources = [Path(importlib.import_module(m).__file__).read_bytes() for m in _TRAINING_MODULES]
    return digest(*sources)


def map_key(catalog, kind: str, clip_names: list[str], params: dict) -> str:
    """The cache key of a map: a digest of its kind, parameters, data and code."""
    items: list[bytes | str] = [kind, json.dumps(params, sort_keys=True), _code_digest()]
    for name in clip_names:
        info = catalog.info(name)
        items += [name, str(info.fps), info.amc_path.read_bytes(), info.asf_path.read_bytes()]
    return digest(*items)


@contextlib.contextmanager
def _locked(path: Path):
    with open(path, "w") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


def trained_map(catalog, kind: str = "upm", clip_names: list[str] | None = None,
                progress: bool = False, **params):
    """A map of ``kind`` trained on ``clip_names`` (default: the train split), from the
    cache when an identical one was trained before.

    Parameters
    ----------
    catalog : upm.motion.catalog.Catalog
    kind : {"upm", "som"}
    clip_names : list of str, optional
    progress : bool
        Show training progress bars (stderr, terminals only).
    **params
        Keyword arguments of :class:`~upm.maps.posture_map.UniformPostureMap` or
        :class:`~upm.maps.som.KohonenSOM` (e.g. ``seed``, ``radius_deg``).

    Returns
    -------
    UniformPostureMap or KohonenSOM
    """
    from upm.core.errors import UsageError
    from upm.maps.class_maps import postures_of_clips
    from upm.maps.map_file import load_map
    from upm.maps.posture_map import UniformPostureMap
    from upm.maps.som import KohonenSOM

    classes = {"upm": UniformPostureMap, "som": KohonenSOM}
    if kind not in classes:
        raise UsageError(f"unknown map kind {kind!r} (known: upm, som)")
    names = list(clip_names) if clip_names is not None else catalog.names("train")
    key = map_key(catalog, kind, names, params)
    directory = cache_dir("maps")
    path = directory / f"{kind}-{key}.npz"
    with _locked(directory / f"{kind}-{key}.lock"):
        if path.exists():
            return load_map(path)
        postures, names = postures_of_clips(catalog, names)
        trained = classes[kind](progress=progress, **params).fit(postures, clip_names=names)
        trained.save(path)
    return trained
