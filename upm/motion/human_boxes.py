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
    HINGE_AXIS,
    JOINT_KIND,
    SAGITTAL_MIRROR,
    ball_angles_deg,
    base_name,
    euler_angles_deg,
    is_right,
    rest_direction,
)
from upm.motion.human_rom import (
    TWIST_MAX_ELEVATION_DEG,
    allowed_elevation_deg,
    box_excess_deg,
    columns_rule,
    euler_names,
    rule_box,
    swing_limits_deg,
)
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
    kind = JOINT_KIND[joint]
    if kind == "ball":
        value = ball_angles_deg(local, rest_direction(skeleton, joint), joint)
        swing = value[:, 0] - allowed_elevation_deg(value[:, 1], swing_limits_deg(joint))
        twist = box_excess_deg(value[:, 2], *rule_box(f"{joint}.twist"))
        twist = np.where(value[:, 0] <= TWIST_MAX_ELEVATION_DEG, twist, 0.0)
        return (swing <= 0) & (twist <= 0)
    value = euler_angles_deg(local, joint)
    inside = np.ones(len(angles_deg), dtype=bool)
    for k, axis in enumerate(euler_names(joint)):
        inside &= box_excess_deg(value[:, k], *rule_box(f"{joint}.{axis}")) <= 0
    return inside


def _hinge_box(skeleton: Skeleton, joint: str) -> tuple[float, float]:
    b = skeleton.bone_index(joint)
    axis = skeleton.axis_matrices[b][:, 0]
    if is_right(joint):
        axis = -SAGITTAL_MIRROR @ axis
    low, high = rule_box(columns_rule(joint, "flexion"))
    if axis @ HINGE_AXIS[base_name(joint)] < 0:
        low, high = -high, -low
    return low, high


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
