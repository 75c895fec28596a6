"""Motion data: the Acclaim skeleton (ASF) and motion (AMC) formats, the 21-joint posture,
forward kinematics, the :class:`Motion` type (``(T, 63)`` postures + ``(T, 6)`` root), the
clip catalogue of a data folder, resampling, dropout filling and the limit maths."""

from upm.motion.amc import read_amc, write_amc
from upm.motion.asf import read_asf
from upm.motion.catalog import Catalog, ClipInfo, ClipRef, default_data_dir, parse_clip_ref
from upm.motion.kinematics import forward_kinematics, rest_positions, standing_height_m
from upm.motion.motion import Motion
from upm.motion.resample import resample
from upm.motion.skeleton import (
    CLASS_NAMES,
    CLASS_SLICES,
    JOINTS,
    POSTURE_DOF_NAMES,
    POSTURE_SIZE,
    Skeleton,
)

__all__ = [
    "CLASS_NAMES",
    "CLASS_SLICES",
    "JOINTS",
    "POSTURE_DOF_NAMES",
    "POSTURE_SIZE",
    "Catalog",
    "ClipInfo",
    "ClipRef",
    "Motion",
    "Skeleton",
    "default_data_dir",
    "forward_kinematics",
    "parse_clip_ref",
    "read_amc",
    "read_asf",
    "resample",
    "rest_positions",
    "standing_height_m",
    "write_amc",
]
