"""Uniform Posture Map motion transitions (Lee & Chung 2001): motion data and algorithm.

Pure numpy/scipy: nothing here imports MuJoCo.
"""

from upm.amc import read_amc, write_amc
from upm.asf import read_asf
from upm.errors import DataFileError, UpmError, UsageError
from upm.kinematics import forward_kinematics
from upm.motion import Motion
from upm.skeleton import Skeleton

__all__ = [
    "DataFileError",
    "Motion",
    "Skeleton",
    "UpmError",
    "UsageError",
    "forward_kinematics",
    "read_amc",
    "read_asf",
    "write_amc",
]
__version__ = "0.1.0"
