"""A project :class:`~upm.Motion` (on its ASF skeleton) as BVH, and back.

The BVH has one joint per ASF bone, named as in the ASF, placed where the bone turns (its
parent's distal end); a leaf bone's distal end is its ``End Site``. The rest pose is the
ASF's (y up, the bones along their ASF directions; y up is what Blender's BVH import
assumes by default), lengths in **centimetres** (Blender,
Maya and MotionBuilder read BVH in centimetres by convention). Every joint has the
channels ``Zrotation Yrotation Xrotation`` (``R = Rz Ry Rx``): its rotation relative to
its parent, ``C M C^T`` for the 21 posture joints (the ASF axis frame ``C``, the AMC
rotation ``M``), identity for the bones the project does not articulate (so their AMC
values are not carried). The root adds ``Xposition Yposition Zposition`` first.

Reading such a file back onto the same ASF (:func:`motion_from_bvh`) inverts that
exactly: ``M = C^T L C`` decomposed in the AMC's ``x``-first order. Other skeletons go
through :mod:`upm.bvh.retarget` (the CMU 31-joint naming) or
:mod:`upm.bvh.world_retarget` (any figure, with a joint map).
"""

from __future__ import annotations

import numpy as np

from upm.bvh.kinematics import local_rotations
from upm.bvh.reader import BvhMotion, BvhSkeleton
from upm.core.errors import DataFileError
from upm.motion.kinematics import global_transforms
from upm.motion.skeleton import JOINTS
from upm.ops.rotations import (
    _alternate_euler,
    continuous_euler_deg,
    matrix_to_euler_deg,
)

#: Centimetres per metre: the unit written.
CM_PER_M = 100.0
_ROTATION = ("Zrotation", "Yrotation", "Xrotation")
_ROOT = ("Xposition", "Yposition", "Zposition", *_ROTATION)


def _zyx(angles_xyz: np.ndarray) -> np.ndarray:
    return angles_xyz[..., ::-1]


def bvh_skeleton_of(skeleton) -> BvhSkeleton:
    """The BVH hierarchy of an ASF skeleton (centimetres)."""
    n = skeleton.n_bones
    offsets = np.zeros((n, 3))
    for b in range(1, n):
        offsets[b] = skeleton.offsets_m[skeleton.parents[b]] * CM_PER_M
    has_child = np.zeros(n, dtype=bool)
    has_child[skeleton.parents[1:]] = True
    ends = np.full((n, 3), np.nan)
    ends[~has_child] = skeleton.offsets_m[~has_child] * CM_PER_M
    channels = (_ROOT,) + (_ROTATION,) * (n - 1)
    return BvhSkeleton(tuple(skeleton.bone_names), np.asarray(skeleton.parents, dtype=int),
                       offsets, channels, ends)


def motion_to_bvh(motion) -> BvhMotion:
    """A motion as BVH on its own ASF skeleton.

    Parameters
    ----------
    motion : upm.Motion

    Returns
    -------
    BvhMotion
        Values ``(T, 6 + 3 (B - 1))``: root position (cm), then every bone's Z, Y, X
        rotation (degrees), continuous along time.
    """
    skeleton = motion.skeleton
    rotations, _ = global_transforms(skeleton, motion.posture_deg, motion.root)
    n, nb = motion.n_frames, skeleton.n_bones
    values = np.empty((n, 6 + 3 * (nb - 1)))
    values[:, :3] = motion.root[:, :3] * CM_PER_M
    values[:, 3:6] = _zyx(continuous_euler_deg(rotations[:, 0], "XYZ", np.zeros(3)))
    for b in range(1, nb):
        p = skeleton.parents[b]
        local = np.swapaxes(rotations[:, p], -1, -2) @ rotations[:, b]
        values[:, 3 + 3 * b:6 + 3 * b] = _zyx(continuous_euler_deg(local, "XYZ",
                                                                  np.zeros(3)))
    return BvhMotion(bvh_skeleton_of(skeleton), values, 1.0 / motion.fps,
                     motion.name or "")


def motion_from_bvh(bvh: BvhMotion, skeleton, fps: float | None = None, name: str = ""):
    """A BVH written on ``skeleton`` (by :func:`motion_to_bvh` or a tool that kept its
    hierarchy) back as a :class:`~upm.Motion`.

    Raises
    ------
    DataFileError
        If the BVH's joints are not the ASF's bones (another skeleton: not retargeted).
    """
    from upm.motion.motion import Motion

    if tuple(bvh.skeleton.names) != tuple(skeleton.bone_names):
        missing = [b for b in skeleton.bone_names if b not in bvh.skeleton.names]
        raise DataFileError(bvh.source, f"its joints are not the bones of "
                                        f"{skeleton.source or skeleton.name} (e.g. no "
                                        f"{(missing or ['same order'])[0]!r}): only a BVH "
                                        "written on that ASF converts back (other figures: "
                                        "upm convert retargets them)")
    sk = bvh.skeleton
    if any(c != _ROTATION for c in sk.channels[1:]) or sk.channels[0] != _ROOT:
        raise DataFileError(bvh.source, "expected Zrotation Yrotation Xrotation channels on "
                                        "every joint (as upm writes them)")
    local = local_rotations(bvh)
    root = np.empty((bvh.n_frames, 6))
    root[:, :3] = bvh.values[:, :3] / CM_PER_M
    # The root's matrix is the same whatever the order; express it in the ASF's own.
    root[:, 3:] = continuous_euler_deg(local[:, 0], skeleton.root_axis_order, np.zeros(3))
    posture = np.zeros((bvh.n_frames, 63))
    for j, joint in enumerate(JOINTS):
        b = skeleton.bone_index(joint)
        c = skeleton.axis_matrices[b]
        m = c.T @ local[:, b] @ c
        posture[:, 3 * j:3 * j + 3] = _joint_angles(m, skeleton.declared[3 * j:3 * j + 3])
    posture[:, ~skeleton.declared] = 0.0
    return Motion(skeleton=skeleton, posture_deg=posture, root=root,
                  fps=float(fps) if fps else bvh.fps, name=name)


def _joint_angles(matrix: np.ndarray, declared: np.ndarray) -> np.ndarray:
    """AMC angles (about X, Y, Z; ``M = Rz Ry Rx``) of a joint's rotations, ``(T, 3)``.

    Of the two Euler solutions of each frame, the one whose undeclared DOFs are zero when
    the joint has any (the other would need them); else the one continuing the previous
    frame, starting from the principal solution (middle angle within ±90 degrees). Whole
    turns are unwrapped along time.
    """
    if matrix.shape[0] == 0:
        return np.zeros((0, 3))
    angles = continuous_euler_deg(matrix, "XYZ", matrix_to_euler_deg(matrix[0], "XYZ"))
    if not declared.all():
        alternate = _alternate_euler(angles, "XYZ")

        def off(a):
            return np.abs((a[:, ~declared] + 180.0) % 360.0 - 180.0).sum(axis=1)

        angles = np.where((off(alternate) < off(angles))[:, None], alternate, angles)
        angles = np.unwrap(angles, period=360.0, axis=0)
    return angles

