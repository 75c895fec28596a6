"""Writing a motion by its file extension: ``.amc`` (Acclaim) or ``.bvh`` (Biovision)."""

from __future__ import annotations

import os
from pathlib import Path

#: The motion formats the commands write, by extension.
MOTION_SUFFIXES = (".amc", ".bvh")


def check_motion_path(path: str | os.PathLike, option: str = "--out") -> None:
    """A one-line UsageError unless ``path`` ends in .amc or .bvh (checked before any
    work is done)."""
    from upm.core.errors import UsageError

    if Path(path).suffix.lower() not in MOTION_SUFFIXES:
        raise UsageError(f"{option} {path}: use a name ending in .amc or .bvh")


def write_motion(path: str | os.PathLike, motion) -> None:
    """Write ``motion`` (on its ASF skeleton) as AMC or BVH by the extension, atomically.

    BVH is written by :func:`upm.bvh.motion_to_bvh` (centimetres, y up, the ASF's rest
    pose); AMC by :func:`upm.motion.amc.write_amc`.
    """
    check_motion_path(path)
    if Path(path).suffix.lower() == ".bvh":
        from upm.bvh import motion_to_bvh, write_bvh

        write_bvh(path, motion_to_bvh(motion))
    else:
        from upm.motion.amc import write_amc

        write_amc(path, motion)
