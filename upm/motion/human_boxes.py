"""The human range of motion as one box per ASF DOF: the humanoid's hinge ranges and the
``feasible`` method's constraints.

A hinge joint's (knee, elbow, toes) box is its anatomical range, exactly. A joint of two
or three DOFs has coupled anatomical limits that no box on its Euler angles states, so its
box is the **envelope** of the human region: the smallest box on the joint's ASF Euler
angles that holds every rotation the human range allows, written with the middle Euler angle
(``ry``) within +-90 degrees as CMU writes them (estimated from
:data:`SAMPLES` uniform rotations, widened by :data:`MARGIN_DEG`). The box never cuts off a
human posture; the coupled rules (:mod:`upm.motion.human_rom`) still judge it.
"""

from __future__ import annotations

import numpy as np

from upm.motion.anatomy import (
    JOINT_KIND,
    SAGITTAL_MIRROR,
    hinge_sign,
    is_right,
    joint_angles_deg,
)
from upm.motion.human_rom import columns_rule, joint_excess_deg, rule_box
from upm.motion.skeleton import AXES, JOINTS, Skeleton, joint_dof_index
from upm.ops.rotations import euler_to_matrix

#: Uniform rotations sampled per joint to find its envelope.
SAMPLES = 15_000
#: Degrees added on each side of a sampled envelope.
MARGIN_DEG = 5.0
_CACHE: dict[tuple, np.ndarray] = {}


def _joint_inside(skeleton: Skeleton, joint: str, angles_deg: np.ndarray) -> np.ndarray:
    """Which ASF Euler angles (N, 3) of one joint lie inside its human range, (N,)."""
    c = skeleton.axis_matrices[skeleton.bone_index(joint)]
    local = c @ euler_to_matrix(angles_deg, "XYZ") @ c.T
    if is_right(joint):
        local = SAGITTAL_MIRROR @ local @ SAGITTAL_MIRROR
    excess = joint_excess_deg(joint, joint_angles_deg(skeleton, joint, local))
    return np.all(np.stack(excess) <= 0, axis=0)


def _hinge_box(skeleton: Skeleton, joint: str) -> tuple[float, float]:
    low, high = rule_box(columns_rule(joint, "flexion"))
    return (low, high) if hinge_sign(skeleton, joint) > 0 else (-high, -low)


def human_dof_boxes(skeleton: Skeleton) -> np.ndarray:
    """The human range as a box per posture DOF, (63, 2) degrees ([0, 0] where the ASF
    declares no DOF; at most [-180, 180])."""
    key = (skeleton.source, skeleton.axis_matrices.tobytes(), skeleton.directions.tobytes(),
           tuple(skeleton.dofs))
    if key in _CACHE:
        return _CACHE[key]
    boxes = np.zeros((len(JOINTS) * 3, 2))
    rng = np.random.default_rng(0)
    for joint in JOINTS:
        dofs = skeleton.dofs[skeleton.bone_index(joint)]
        if not dofs:
            continue
        index = [joint_dof_index(joint, d) for d in dofs]
        if JOINT_KIND[joint] == "hinge":
            boxes[index[0]] = _hinge_box(skeleton, joint)
            continue
        angles = np.zeros((SAMPLES, 3))
        columns = [AXES.index(d) for d in dofs]
        angles[:, columns] = rng.uniform(-180.0, 180.0, (SAMPLES, len(columns)))
        if len(dofs) == 3:  # one of the two Euler solutions: the middle angle (ry) in +-90
            angles[:, 1] /= 2.0
        inside = angles[_joint_inside(skeleton, joint, angles)]
        if not len(inside):
            continue
        low = np.maximum(inside[:, columns].min(axis=0) - MARGIN_DEG, -180.0)
        high = np.minimum(inside[:, columns].max(axis=0) + MARGIN_DEG, 180.0)
        boxes[index, 0], boxes[index, 1] = np.round(low, 1), np.round(high, 1)
    boxes.setflags(write=False)
    _CACHE[key] = boxes
    return boxes
