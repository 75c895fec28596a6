"""The key-posture source a method needs, from the command line's --map and --data."""

from __future__ import annotations

import os
import warnings

from upm.errors import UsageError


def key_source_for(method: str, map_path, catalog):
    """The key-posture source for ``method``.

    Parameters
    ----------
    method : str
    map_path : path-like or None
        ``--map``: required by ``upm`` and ``som``.
    catalog : upm.catalog.Catalog
        ``classnn`` and ``snap`` are fitted on its train split.

    Returns
    -------
    KeyPostureSource or None
    """
    from upm.transitions import METHODS, ClassNearest, NearestPosture, training_postures
    from upm.transitions.join import get_method

    spec = get_method(method)
    if spec.key_kind in ("upm", "som"):
        if map_path is None:
            raise UsageError(f"--method {method} needs --map MAP.npz (train one with "
                             f"'upm train --kind {spec.key_kind} --out MAP.npz'), or use a "
                             f"method without a map: "
                             f"{', '.join(n for n, m in METHODS.items() if m.key_kind is None)}, "
                             "classnn, snap")
        if not os.path.isfile(map_path):
            raise UsageError(f"--map {map_path}: no such file")
        from upm.class_maps import load_map

        source = load_map(map_path)
        kind = getattr(source, "kind", None)
        if isinstance(kind, str) and kind != spec.key_kind:
            raise UsageError(f"{map_path} holds a {kind!r} map; --method {method} needs a "
                             f"{spec.key_kind!r} one")
        return source
    if map_path is not None:
        warnings.warn(f"--map is not used by --method {method}", stacklevel=2)
    if spec.key_kind == "classnn":
        return ClassNearest(training_postures(catalog, "train"))
    if spec.key_kind == "snap":
        return NearestPosture(training_postures(catalog, "train"))
    return None
