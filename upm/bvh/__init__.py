"""BVH (Biovision hierarchy) files: reading any hierarchy, forward kinematics, writing.

- :func:`read_bvh` -> :class:`BvhMotion` (a :class:`BvhSkeleton` and a ``(T, C)`` channel
  table), bounded and strict: errors name the file and line.
- :func:`joint_positions`: world positions of every joint and end site, vectorised.
- :func:`write_bvh`: a :class:`BvhMotion` as written by any tool, back to a file.
- :func:`motion_to_bvh` / :func:`motion_from_bvh`: a project :class:`~upm.Motion` on its ASF
  skeleton as BVH (centimetres, y up, the ASF's rest pose, one ``Z Y X`` rotation triple per
  bone) and back, exactly (to the written precision).
- :func:`retarget_cmu`: the CMU 31-joint naming (cgspeed's conversions) onto an ASF.
- :func:`retarget_world`: any figure onto an ASF by each bone's world direction, with a
  :class:`JointMap` (:func:`find_builtin_map`: DAZ-style, Mixamo, 19-joint;
  :func:`read_joint_map`: a user's JSON).
"""

from upm.bvh.asf_bvh import motion_from_bvh, motion_to_bvh
from upm.bvh.joint_maps import JointMap, find_builtin_map, read_joint_map
from upm.bvh.kinematics import joint_positions
from upm.bvh.reader import BvhMotion, BvhSkeleton, read_bvh
from upm.bvh.retarget import retarget_cmu
from upm.bvh.world_retarget import retarget_world
from upm.bvh.writer import write_bvh

__all__ = ["BvhMotion", "BvhSkeleton", "JointMap", "find_builtin_map", "joint_positions",
           "motion_from_bvh", "motion_to_bvh", "read_bvh", "read_joint_map", "retarget_cmu",
           "retarget_world", "write_bvh"]
