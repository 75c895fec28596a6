"""Filling marker dropouts in a reference (:mod:`upm.dropouts`: bones whose angles read
exactly zero for a few frames between frames far from zero).

A low-pass filter turns such a jump into a swing of the arm in 40 ms that throws the whole
body; the dropout's frames are filled by linear interpolation between the frames around it
(held at the motion's ends).
"""

from __future__ import annotations

import numpy as np

from upm.dropouts import DROPOUT_JUMP_DEG, dropout_runs


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
        for start, stop in dropout_runs(angles, jump):
            before = angles[start - 1] if start > 0 else angles[stop]
            after = angles[stop] if stop < n else angles[start - 1]
            w = (np.arange(start, stop) - start + 1) / (stop - start + 1)
            out[start:stop, columns] = (1 - w)[:, None] * before + w[:, None] * after
            filled += stop - start
    return out, filled
