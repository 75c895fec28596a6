"""BVH takes in the CMU 31-joint naming onto an ASF skeleton's 21-joint posture.

The CMU conversions (cgspeed's, and the ones of this project) keep the ASF's hierarchy
and rest pose under other names (``Hips``, ``LHipJoint``, ``LeftUpLeg`` ...,
:data:`CMU_31`): each BVH joint is the pivot of one ASF bone, with the ASF's rest
directions, and its rotation relative to its parent is the bone's ``L = C M C^T``. So the
posture is ``M = C^T L C`` (decomposed in the AMC's x-first order, the declared DOFs kept)
and the root position is the ``Hips`` translation in the BVH's length unit, found as the
ratio of the BVH's bone offsets to the ASF's bone lengths. Bone lengths may differ from the
ASF's (02_01.bvh is on subject 01's lengths): only rotations are carried.

Skeletons with other rest poses and bone splits (DAZ-style, Mixamo, ...) go through the
world-direction retarget of :mod:`upm.bvh.world_retarget` instead; this module refuses
them naming the joints that are missing.
"""

from __future__ import annotations

import numpy as np

from upm.bvh.asf_bvh import _joint_angles
from upm.bvh.kinematics import local_rotations
from upm.core.errors import DataFileError
from upm.motion.skeleton import JOINTS
from upm.ops.rotations import continuous_euler_deg, matrix_to_euler_deg

#: The CMU 31-joint BVH naming (cgspeed's conversions) -> ASF bone.
CMU_31 = {
    "Hips": "root", "LHipJoint": "lhipjoint", "LeftUpLeg": "lfemur", "LeftLeg": "ltibia",
    "LeftFoot": "lfoot", "LeftToeBase": "ltoes", "RHipJoint": "rhipjoint",
    "RightUpLeg": "rfemur", "RightLeg": "rtibia", "RightFoot": "rfoot",
    "RightToeBase": "rtoes", "LowerBack": "lowerback", "Spine": "upperback",
    "Spine1": "thorax", "Neck": "lowerneck", "Neck1": "upperneck", "Head": "head",
    "LeftShoulder": "lclavicle", "LeftArm": "lhumerus", "LeftForeArm": "lradius",
    "LeftHand": "lwrist", "LeftFingerBase": "lhand", "LeftHandIndex1": "lfingers",
    "LThumb": "lthumb", "RightShoulder": "rclavicle", "RightArm": "rhumerus",
    "RightForeArm": "rradius", "RightHand": "rwrist", "RightFingerBase": "rhand",
    "RightHandIndex1": "rfingers", "RThumb": "rthumb",
}


def added_tpose(bvh) -> bool:
    """Whether frame 0 is an added rest/T-pose frame: every rotation channel a whole
    number of degrees (cgspeed writes 0 and a few round angles there) while frame 1's
    are not. DAZ-style files' added frame is not detected by this rule."""
    sk = bvh.skeleton
    rot = [sk.channel_start[j] + k for j in range(sk.n_joints)
           for k, c in enumerate(sk.channels[j]) if c.endswith("rotation")]
    if bvh.n_frames < 2 or not rot:
        return False
    first, second = bvh.values[0, rot], bvh.values[1, rot]
    return bool(np.all(first == np.round(first)) and not np.all(second == np.round(second)))


def retarget_cmu(bvh, skeleton, fps: float | None = None, drop_tpose: bool | None = None,
                 name: str = ""):
    """A CMU-named BVH take as a :class:`~upm.Motion` on ``skeleton``.

    Parameters
    ----------
    bvh : upm.bvh.BvhMotion
    skeleton : upm.motion.skeleton.Skeleton
    fps : float, optional
        The take's rate (default the BVH's ``Frame Time``; subject 141's conversions say
        120 fps for 60 fps takes: give the catalogue's rate).
    drop_tpose : bool, optional
        Drop frame 0 (default: when :func:`added_tpose` says it was added).

    Raises
    ------
    DataFileError
        If joints of :data:`CMU_31` needed by the 21-joint posture are missing, or the
        hierarchy differs from the ASF's.
    """
    from upm.motion.motion import Motion

    sk = bvh.skeleton
    index = {n: j for j, n in enumerate(sk.names)}
    bone_of = {j: CMU_31[n] for n, j in index.items() if n in CMU_31}
    joint_of = {b: j for j, b in bone_of.items()}
    needed = ["root", *JOINTS]
    missing = [n for n, b in CMU_31.items() if b in needed and n not in index]
    if missing:
        raise DataFileError(bvh.source, f"not a CMU 31-joint BVH: no joint {missing[0]!r} "
                                        f"({len(missing)} of the names upm maps are missing)")
    for j, bone in bone_of.items():
        p = sk.parents[j]
        expected = skeleton.parents[skeleton.bone_index(bone)]
        if p >= 0 and (p not in bone_of or skeleton.bone_index(bone_of[p]) != expected):
            raise DataFileError(bvh.source, f"joint {sk.names[j]!r}: its parent is not the "
                                            f"ASF parent of {bone!r}")
    drop = added_tpose(bvh) if drop_tpose is None else bool(drop_tpose)
    local = local_rotations(bvh)[1 if drop else 0:]
    values = bvh.values[1 if drop else 0:]
    unit_m = _unit_m(bvh, skeleton, bone_of)
    root = np.empty((values.shape[0], 6))
    hips = joint_of["root"]
    start = sk.channel_start[hips]
    axes = {c[0]: start + k for k, c in enumerate(sk.channels[hips]) if c.endswith("position")}
    for a, axis in enumerate("XYZ"):
        root[:, a] = (values[:, axes[axis]] if axis in axes else sk.offsets[hips][a]) * unit_m
    root[:, 3:] = continuous_euler_deg(local[:, hips], skeleton.root_axis_order,
                                       matrix_to_euler_deg(local[0, hips],
                                                           skeleton.root_axis_order))
    posture = np.zeros((values.shape[0], 63))
    for k, joint in enumerate(JOINTS):
        b = skeleton.bone_index(joint)
        c = skeleton.axis_matrices[b]
        m = c.T @ local[:, joint_of[joint]] @ c
        posture[:, 3 * k:3 * k + 3] = _joint_angles(m, skeleton.declared[3 * k:3 * k + 3])
    posture[:, ~skeleton.declared] = 0.0
    return Motion(skeleton=skeleton, posture_deg=posture, root=root,
                  fps=float(fps) if fps else bvh.fps, name=name)


def _unit_m(bvh, skeleton, bone_of) -> float:
    """Metres per BVH length unit: the median ratio of ASF bone length to the BVH offset of
    the joint that bone leads to."""
    ratios = []
    sk = bvh.skeleton
    for j in bone_of:
        p = sk.parents[j]
        if p < 0 or p not in bone_of:
            continue
        length = skeleton.lengths_m[skeleton.bone_index(bone_of[p])]
        offset = float(np.linalg.norm(sk.offsets[j]))
        if length > 0 and offset > 0:
            ratios.append(length / offset)
    if not ratios:
        raise DataFileError(bvh.source, "no bone offsets to find the length unit from")
    return float(np.median(ratios))
