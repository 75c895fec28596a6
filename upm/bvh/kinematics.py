"""Forward kinematics of BVH hierarchies, vectorised over frames.

A joint's local rotation is the product of its rotation channels in file order
(``Zrotation Xrotation Yrotation`` is ``Rz @ Rx @ Ry``); its local translation is its
``OFFSET`` with any position channel replacing that axis; world = parent world @ local.
"""

from __future__ import annotations

import numpy as np

from upm.ops.rotations import axis_rotation

_AXIS = {"X": 0, "Y": 1, "Z": 2}


def local_rotations(bvh) -> np.ndarray:
    """Each joint's rotation relative to its parent, ``(T, J, 3, 3)``."""
    skeleton = bvh.skeleton
    n = bvh.n_frames
    out = np.broadcast_to(np.eye(3), (n, skeleton.n_joints, 3, 3)).copy()
    for j, (names, start) in enumerate(zip(skeleton.channels, skeleton.channel_start,
                                           strict=True)):
        r = None
        for k, name in enumerate(names):
            if name.endswith("rotation"):
                m = axis_rotation(bvh.values[:, start + k], name[0])
                r = m if r is None else r @ m
        if r is not None:
            out[:, j] = r
    return out


def joint_positions(bvh) -> tuple[np.ndarray, np.ndarray]:
    """World positions of every joint and end site.

    Parameters
    ----------
    bvh : upm.bvh.BvhMotion

    Returns
    -------
    joints : ndarray, shape (T, J, 3)
        File units.
    end_sites : ndarray, shape (T, J, 3)
        The end site of each joint that has one, NaN elsewhere.
    """
    _, pos, ends = world_transforms(bvh)
    return pos, ends


def world_transforms(bvh) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """World rotation and position of every joint, and its end site.

    Returns
    -------
    rotations : ndarray, shape (T, J, 3, 3)
        Each joint's world rotation (identity everywhere in the rest pose).
    joints : ndarray, shape (T, J, 3)
        File units.
    end_sites : ndarray, shape (T, J, 3)
        NaN for joints without an end site.
    """
    skeleton = bvh.skeleton
    n, nj = bvh.n_frames, skeleton.n_joints
    local = local_rotations(bvh)
    world = np.empty_like(local)
    pos = np.empty((n, nj, 3))
    ends = np.full((n, nj, 3), np.nan)
    for j in range(nj):
        t = np.broadcast_to(skeleton.offsets[j], (n, 3)).copy()
        start = skeleton.channel_start[j]
        for k, name in enumerate(skeleton.channels[j]):
            if name.endswith("position"):
                t[:, _AXIS[name[0]]] = bvh.values[:, start + k]
        p = skeleton.parents[j]
        if p < 0:
            world[:, j], pos[:, j] = local[:, j], t
        else:
            world[:, j] = world[:, p] @ local[:, j]
            pos[:, j] = pos[:, p] + np.einsum("tij,tj->ti", world[:, p], t)
        if np.isfinite(skeleton.end_sites[j]).all():
            ends[:, j] = pos[:, j] + world[:, j] @ skeleton.end_sites[j]
    return world, pos, ends


def rest_positions(skeleton) -> tuple[np.ndarray, np.ndarray]:
    """Joint and end-site positions with every rotation zero and the root at its
    ``OFFSET``: ``(J, 3)`` each (end sites NaN where absent), file units."""
    nj = skeleton.n_joints
    pos = np.zeros((nj, 3))
    for j in range(nj):
        p = skeleton.parents[j]
        pos[j] = skeleton.offsets[j] + (pos[p] if p >= 0 else 0.0)
    return pos, pos + skeleton.end_sites
