"""Marker dropouts in a motion: bones whose angles read exactly zero for a few frames.

When a bone's markers are lost, CMU's solver writes the bone's angles as exactly 0 (16_15
starts with its left arm at rest for 2 frames, then jumps by 76 degrees). A *dropout* here
is a run of frames in which every angle of a bone reads exactly zero while the bone's
neighbouring frames are at least :data:`DROPOUT_JUMP_DEG` away from zero, no longer than
:data:`MAX_DROPOUT_FRAMES` and not the whole motion. The controller fills them
(:func:`controller.dropouts.fill_dropouts`); :func:`upm.perturb.offset_joint_angles`
keeps them.
"""

from __future__ import annotations

import numpy as np

#: A zero run is a dropout when the bone's angles next to it are this far from zero.
DROPOUT_JUMP_DEG = 10.0
#: Runs longer than this are poses, not dropouts (frames).
MAX_DROPOUT_FRAMES = 30


def dropout_runs(angles, jump=DROPOUT_JUMP_DEG) -> list[tuple[int, int]]:
    """The (start, stop) frames (half-open) of one bone's dropouts.

    Parameters
    ----------
    angles : ndarray, shape (T, k)
        The bone's angles per frame (channels that are always zero may be included).
    jump : float
        :data:`DROPOUT_JUMP_DEG` in the unit of ``angles``.
    """
    angles = np.asarray(angles, dtype=float)
    n = angles.shape[0]
    zero = np.all(angles == 0.0, axis=1)
    edges = np.diff(np.concatenate([[0], zero.astype(np.int8), [0]]))
    out = []
    for start, stop in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1),
                           strict=True):
        if stop - start > MAX_DROPOUT_FRAMES or (start == 0 and stop == n):
            continue
        sides = [i for i in (start - 1, stop) if 0 <= i < n]
        if max(np.abs(angles[i]).max() for i in sides) < jump:
            continue
        out.append((int(start), int(stop)))
    return out


def dropout_mask(posture_deg) -> np.ndarray:
    """Which values of a 21-joint posture are marker dropouts.

    Parameters
    ----------
    posture_deg : ndarray, shape (T, 63)
        Three channels per joint (:mod:`upm.skeleton`), degrees.

    Returns
    -------
    ndarray of bool, shape (T, 63)
    """
    posture = np.asarray(posture_deg, dtype=float)
    mask = np.zeros(posture.shape, dtype=bool)
    for first in range(0, posture.shape[1], 3):
        for start, stop in dropout_runs(posture[:, first:first + 3]):
            mask[start:stop, first:first + 3] = True
    return mask

