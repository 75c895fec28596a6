"""Posture maps: the Uniform Posture Map (Lee & Chung 2001) and the Kohonen SOM it
improves on, one map per joint class; their training, the key-posture search and its
compiled kernels, the safe map file and the cache of maps trained on a data folder.

The names are exported lazily: their modules import scipy and numba.
"""

_LAZY = {
    "UniformPostureMap": "upm.maps.posture_map",
    "KohonenSOM": "upm.maps.som",
    "ClassMaps": "upm.maps.class_maps",
    "load_map": "upm.maps.map_file",
    "MAP_KINDS": "upm.maps.map_file",
    "trained_map": "upm.maps.map_cache",
    "default_radius_deg": "upm.maps.map_size",
}


def __getattr__(name):
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'upm.maps' has no attribute {name!r}")


__all__ = sorted(_LAZY)
