"""BVH (Biovision hierarchy) files: reading any hierarchy, forward kinematics, writing.

- :func:`read_bvh` -> :class:`BvhMotion` (a :class:`BvhSkeleton` and a ``(T, C)`` channel
  table), bounded and strict: errors name the file and line.
- :func:`joint_positions`: world positions of every joint and end site, vectorised.
- :func:`write_bvh`: a :class:`BvhMotion` as written by any tool, back to a file.
- :func:`motion_to_bvh` / :func:`motion_from_bvh`: a project :class:`~upm.Motion` on its ASF
  skeleton as BVH (centimetres, y up, the ASF's rest pose, one ``Z Y X`` rotation triple per
  bone) and back, exactly (to the written precision).
"""

from upm.bvh.asf_bvh import motion_from_bvh, motion_to_bvh
from upm.bvh.kinematics import joint_positions
from upm.bvh.reader import BvhMotion, BvhSkeleton, read_bvh
from upm.bvh.writer import write_bvh

__all__ = ["BvhMotion", "BvhSkeleton", "joint_positions", "motion_from_bvh", "motion_to_bvh",
           "read_bvh", "write_bvh"]
