"""Loading a saved posture map of either kind, by the ``kind`` field of its file."""

from __future__ import annotations

import os

from upm.core.errors import DataFileError
from upm.maps.npz_file import read_map_arrays, text_field
from upm.maps.posture_map import UniformPostureMap
from upm.maps.som import KohonenSOM

#: Map classes by the ``kind`` field of a file.
MAP_KINDS: dict[str, type] = {"upm": UniformPostureMap, "som": KohonenSOM}


def load_map(path: str | os.PathLike):
    """Read a saved posture map of either kind (``"upm"`` or ``"som"``)."""
    arrays = read_map_arrays(path)
    kind = text_field(arrays, "kind", path)
    if kind not in MAP_KINDS:
        raise DataFileError(path, f"unknown map kind {kind!r} (known: {', '.join(MAP_KINDS)})")
    return MAP_KINDS[kind]._from_arrays(arrays, path)
