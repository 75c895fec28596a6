"""Marker dropouts in a reference: bones whose angles read exactly zero for a few frames.

When a bone's markers are lost, CMU's solver writes the bone's angles as exactly 0 (16_15
starts with its left arm at rest for 2 frames, then jumps by 76 degrees). A low-pass
filter turns such a jump into a swing of the arm in 40 ms that throws the whole body.
A *dropout* here is a run of frames in which every hinge of a bone reads exactly zero
while the bone's neighbouring frames are at least :data:`DROPOUT_JUMP_DEG` away from
zero; its frames are filled by linear interpolation between the frames around it (held
at the motion's ends).
"""

from __future__ import annotations

import numpy as np

#: A zero run is a dropout when the bone's angles next to it are this far from zero.
DROPOUT_JUMP_DEG = 10.0
#: Runs longer than this are poses, not dropouts (frames).
MAX_DROPOUT_FRAMES = 30


def fill_dropouts(model, qpos) -> tuple[np.ndarray, int]:
    """``qpos`` with bone dropouts filled from the frames around them.

    Parameters
    ----------
    model : mujoco.MjModel
        A humanoid made by :func:`humanoid_xml.build_mjcf`.
    qpos : array_like, shape (T, nq)

    Returns
    -------
    qpos : ndarray, shape (T, nq)
        A filled copy.
    filled : int
        The number of (bone, frame) entries filled.
    """
    from controller.qpos import joint_layout

    out = np.array(qpos, dtype=float, ndmin=2)
    layout = joint_layout(model)
    bones: dict[str, list[int]] = {}
    for name, address in zip(layout.names, layout.qpos_address, strict=True):
        bones.setdefault(name.split(".")[0], []).append(int(address))
    jump = np.deg2rad(DROPOUT_JUMP_DEG)
    n = out.shape[0]
    filled = 0
    for columns in bones.values():
        angles = out[:, columns]
        zero = np.all(angles == 0.0, axis=1)
        for start, stop in _runs(zero):
            if stop - start > MAX_DROPOUT_FRAMES or (start == 0 and stop == n):
                continue
            sides = [i for i in (start - 1, stop) if 0 <= i < n]
            if max(np.abs(angles[i]).max() for i in sides) < jump:
                continue
            before = angles[start - 1] if start > 0 else angles[stop]
            after = angles[stop] if stop < n else angles[start - 1]
            w = (np.arange(start, stop) - start + 1) / (stop - start + 1)
            out[start:stop, columns] = (1 - w)[:, None] * before + w[:, None] * after
            filled += stop - start
    return out, filled


def _runs(mask: np.ndarray):
    """(start, stop) of every run of True in a 1-D bool array."""
    edges = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    return zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1), strict=True)
