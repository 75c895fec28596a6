"""Uniform Posture Map motion transitions (Lee & Chung 2001): motion data and algorithm.

Pure numpy/scipy: nothing here imports MuJoCo.
"""

from upm.amc import read_amc, write_amc
from upm.asf import read_asf
from upm.errors import DataFileError, UpmError, UsageError
from upm.kinematics import forward_kinematics
from upm.motion import Motion
from upm.skeleton import Skeleton

#: Exported lazily (their modules import scipy.spatial): name -> module.
_LAZY = {
    "UniformPostureMap": "upm.posture_map",
    "KohonenSOM": "upm.som",
    "load_map": "upm.class_maps",
}


def __getattr__(name):
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'upm' has no attribute {name!r}")


__all__ = [
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
    "write_amc",
]
__version__ = "0.1.0"
