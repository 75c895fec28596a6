"""Filling marker dropouts in a reference (:mod:`upm.motion.dropouts`: bones whose angles read
exactly zero for a few frames between frames far from zero).

A low-pass filter turns such a jump into a swing of the arm in 40 ms that throws the whole
body; the dropout's frames are filled by linear interpolation between the frames around it
(held at the motion's ends). A dropout is a run of zeros between frames at least
``dropouts.jump_deg`` from zero (:class:`controller.config.sections.DropoutsConfig`).
"""

from __future__ import annotations

import numpy as np

from controller.config import DEFAULT
from upm.motion.dropouts import dropout_runs, fill_runs


def fill_dropouts(model, qpos, dropouts=DEFAULT.dropouts) -> tuple[np.ndarray, int]:
    """``qpos`` with bone dropouts filled from the frames around them.

    Parameters
    ----------
    model : mujoco.MjModel
        A humanoid made by :func:`humanoid_xml.build_mjcf`.
    qpos : array_like, shape (T, nq)
    dropouts : controller.config.sections.DropoutsConfig

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
    jump = np.deg2rad(dropouts.jump_deg)
    filled = 0
    for columns in bones.values():
        runs = dropout_runs(out[:, columns], jump)
        if runs:
            out[:, columns] = fill_runs(out[:, columns], runs)
            filled += sum(stop - start for start, stop in runs)
    return out, filled
