"""Marker dropouts in a motion: bones whose angles read exactly zero for a few frames.

When a bone's markers are lost, CMU's solver writes the bone's angles as exactly 0 (16_15
starts with its left arm at rest for 2 frames, then jumps by 76 degrees). A *dropout* here
is a run of frames in which every angle of a bone reads exactly zero while the bone's
neighbouring frames are at least :data:`DROPOUT_JUMP_DEG` away from zero, no longer than
:data:`MAX_DROPOUT_FRAMES` and not the whole motion. The controller fills them
(:func:`controller.dropouts.fill_dropouts`), and so does a transition
(:func:`upm.transitions.transition`, :func:`fill_dropouts`): a transition into 16_15 would
otherwise swing the arm to its rest for the window and then 76 degrees back in a frame.
:func:`upm.motion.perturb.offset_joint_angles` keeps them.
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
        Three channels per joint (:mod:`upm.motion.skeleton`), degrees.

    Returns
    -------
    ndarray of bool, shape (T, 63)
    """
    posture = np.asarray(posture_deg, dtype=float)
    mask = np.zeros(posture.shape, dtype=bool)
    for channels, runs in joint_runs(posture):
        for start, stop in runs:
            mask[start:stop, channels] = True
    return mask


def joint_runs(posture_deg) -> list[tuple[slice, list[tuple[int, int]]]]:
    """Each joint's channels in a 21-joint posture (T, 63) and its dropouts
    (:func:`dropout_runs`), for the joints that have any."""
    posture = np.asarray(posture_deg, dtype=float)
    out = []
    for first in range(0, posture.shape[1], 3):
        channels = slice(first, first + 3)
        runs = dropout_runs(posture[:, channels])
        if runs:
            out.append((channels, runs))
    return out


def fill_runs(angles, runs) -> np.ndarray:
    """``angles`` with each run's frames filled by linear interpolation between the frames
    around it (held at the motion's ends).

    Parameters
    ----------
    angles : ndarray, shape (T, k)
        One bone's angles per frame.
    runs : list of (int, int)
        Half-open frame ranges (:func:`dropout_runs`), none the whole motion.

    Returns
    -------
    ndarray, shape (T, k)
        A filled copy.
    """
    out = np.array(angles, dtype=float)
    n = out.shape[0]
    for start, stop in runs:
        before = out[start - 1] if start > 0 else out[stop]
        after = out[stop] if stop < n else out[start - 1]
        w = (np.arange(start, stop) - start + 1) / (stop - start + 1)
        out[start:stop] = (1 - w)[:, None] * before + w[:, None] * after
    return out


def fill_dropouts(posture_deg) -> tuple[np.ndarray, int]:
    """A filled copy (T, 63) of a 21-joint posture's :func:`dropout_mask` values
    (:func:`fill_runs`), and the number of (joint, frame) entries filled."""
    out = np.array(posture_deg, dtype=float)
    filled = 0
    for channels, runs in joint_runs(out):
        out[:, channels] = fill_runs(out[:, channels], runs)
        filled += sum(stop - start for start, stop in runs)
    return out, filled
