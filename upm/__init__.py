"""Uniform Posture Map motion transitions (Lee & Chung 2001): motion data and algorithm.

Pure numpy/scipy: nothing here imports MuJoCo. The few names a user needs::

    import upm
    catalog = upm.Catalog()                       # the clips of $UPM_DATA (or --data)
    walk = catalog.load("02_01")                  # a Motion: (T, 63) postures + (T, 6) root
    posture_map = upm.UniformPostureMap().fit(postures_deg)
    t = upm.transition("upm", walk, run, frames=20, key_source=posture_map)

The rooms: :mod:`upm.motion` (ASF/AMC, skeleton, kinematics, the Motion type, the
catalogue), :mod:`upm.bvh`, :mod:`upm.maps` (UPM and SOM), :mod:`upm.transitions`, and the
command line (:mod:`upm.cli`, :mod:`upm.commands`) on top; :mod:`upm.core` and
:mod:`upm.ops` are the foundation (errors and files; angle and rotation maths).
"""

from upm.core.errors import DataFileError, UpmError, UsageError
from upm.motion.amc import read_amc, write_amc
from upm.motion.asf import read_asf
from upm.motion.catalog import Catalog
from upm.motion.kinematics import forward_kinematics
from upm.motion.motion import Motion
from upm.motion.skeleton import Skeleton

#: Exported lazily (their modules import scipy.spatial and numba): name -> module.
_LAZY = {
    "UniformPostureMap": "upm.maps.posture_map",
    "KohonenSOM": "upm.maps.som",
    "load_map": "upm.maps.map_file",
    "transition": "upm.transitions.join",
}


def __getattr__(name):
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'upm' has no attribute {name!r}")


__all__ = [
    "Catalog",
    "DataFileError",
    "KohonenSOM",
    "Motion",
    "Skeleton",
    "UniformPostureMap",
    "UpmError",
    "UsageError",
    "forward_kinematics",
    "load_map",
    "read_amc",
    "read_asf",
    "transition",
    "write_amc",
]
__version__ = "0.1.0"
