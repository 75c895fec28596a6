"""Forward kinematics of ASF skeletons, vectorised over frames.

Convention (Acclaim): a bone's rotation is ``M = Rz(rz) Ry(ry) Rx(rx)`` (x applied first)
in its axis frame ``C``; its rotation relative to its parent is ``L = C M C^T``; its
world rotation is ``R = R_parent L``; its distal end is its parent's distal end plus
``length * R @ direction``. The root's rotation is ``Rz Ry Rx`` of the root angles (in the
root's ``axis`` order) and its position is the root translation. Only the 21 posture
joints are articulated; the other bones keep their rest orientation relative to their
parent.
"""

from __future__ import annotations

import numpy as np

from upm.motion.motion import Motion
from upm.motion.skeleton import JOINTS, Skeleton
from upm.ops.rotations import euler_to_matrix


def _joint_posture_index(skeleton: Skeleton) -> np.ndarray:
    """For each bone, the start index of its 3 posture values, or -1."""
    index = np.full(skeleton.n_bones, -1)
    for j, joint in enumerate(JOINTS):
        index[skeleton.bone_index(joint)] = 3 * j
    return index


def global_transforms(skeleton: Skeleton, posture_deg, root) -> tuple[np.ndarray, np.ndarray]:
    """World rotation and distal-end position of every bone.

    Parameters
    ----------
    skeleton : Skeleton
    posture_deg : array_like, shape (T, 63)
    root : array_like, shape (T, 6)
        tx, ty, tz (metres), rx, ry, rz (degrees).

    Returns
    -------
    rotations : ndarray, shape (T, B, 3, 3)
        World rotation of each bone (for the root, the root orientation).
    positions_m : ndarray, shape (T, B, 3)
        World position of each bone's distal end (for the root, the root position).
    """
    posture = np.atleast_2d(np.asarray(posture_deg, dtype=float))
    root = np.atleast_2d(np.asarray(root, dtype=float))
    n_frames, n_bones = posture.shape[0], skeleton.n_bones
    rotations = np.empty((n_frames, n_bones, 3, 3))
    positions = np.empty((n_frames, n_bones, 3))
    rotations[:, 0] = euler_to_matrix(root[:, 3:6], skeleton.root_axis_order)
    positions[:, 0] = root[:, :3]
    start = _joint_posture_index(skeleton)
    offsets = skeleton.offsets_m
    for b in range(1, n_bones):
        parent = skeleton.parents[b]
        c = skeleton.axis_matrices[b]
        if start[b] >= 0:
            m = euler_to_matrix(posture[:, start[b]:start[b] + 3], "XYZ")
            local = c @ m @ c.T
            rotations[:, b] = rotations[:, parent] @ local
        else:
            rotations[:, b] = rotations[:, parent]
        positions[:, b] = positions[:, parent] + rotations[:, b] @ offsets[b]
    return rotations, positions


def forward_kinematics(motion: Motion) -> np.ndarray:
    """Distal end of every bone of ``motion.skeleton.bone_names``, every frame.

    Parameters
    ----------
    motion : Motion

    Returns
    -------
    ndarray, shape (T, B, 3)
        Metres, ASF world frame (y up); for ``"root"`` the root position.
    """
    return global_transforms(motion.skeleton, motion.posture_deg, motion.root)[1]


def rest_positions(skeleton: Skeleton) -> np.ndarray:
    """Distal end of every bone at rest (zero posture, root at the origin), (B, 3) m."""
    return global_transforms(skeleton, np.zeros((1, 63)), np.zeros((1, 6)))[1][0]


def standing_height_m(skeleton: Skeleton) -> float:
    """Standing height at rest: the vertical span of the rest-pose bone ends, metres."""
    y = rest_positions(skeleton)[:, 1]
    return float(y.max() - y.min())
